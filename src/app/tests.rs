//! The viewer without a window (its worker starts on lavapipe).

use super::*;
use crate::metrics;
use crate::settings::{Controlled, Gamma, Widget};
use std::time::Duration;

/// A viewer on builtin:cornell with `s`, without a window (its worker starts on lavapipe).
fn viewer(s: UiSettings) -> Viewer {
    let loader: Loader = Arc::new(|spec: &str| Ok(crate::scene::load(spec)?));
    let opts = ViewOptions {
        spec: "builtin:cornell".into(),
        scene: crate::scene::load("builtin:cornell").unwrap(),
        loader,
        width: 64,
        height: 48,
        camera: None,
        settings: s,
        frames: None,
        screenshot: None,
        view: View::Final,
        animate: false,
        stats: None,
        shot_dir: std::env::temp_dir(),
        b: None,
        refs_on_disk: false,
        display_path: DisplayPath::Split,
        offscreen: false,
    };
    Viewer::new(opts, Arc::new(|| {}), None)
}

/// One egui frame of the whole window's UI.
fn draw(v: &mut Viewer) {
    let ctx = egui::Context::default();
    let input = egui::RawInput {
        screen_rect: Some(egui::Rect::from_min_size(
            egui::Pos2::ZERO,
            egui::vec2(1200.0, 2000.0),
        )),
        ..Default::default()
    };
    // The textures it uploads are not applied here: cleared, as egui asks.
    ctx.run_ui(input, |ui| v.ui(ui)).textures_delta.clear();
}

/// Polls until `done` holds (the worker replies on lavapipe within seconds).
fn poll_until(v: &mut Viewer, done: impl Fn(&Viewer) -> bool) {
    // A hang guard, not a speed test: 6,000 polls 20 ms apart (at least 120 s).
    let mut polls = 0;
    while !done(v) {
        polls += 1;
        assert!(polls <= 6000, "no reply after 6,000 polls (120 s)");
        v.poll();
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("fuzzy-vpl-app-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn a_scene_that_fails_to_load_keeps_the_open_one() {
    let d = scratch("trunc");
    // A GLB header that promises more bytes than the file has.
    let glb = d.join("trunc.glb");
    let mut bytes = b"glTF".to_vec();
    bytes.extend(2u32.to_le_bytes());
    bytes.extend(1000u32.to_le_bytes());
    bytes.extend(b"{\"asset\"");
    std::fs::write(&glb, &bytes).unwrap();
    let mut v = viewer(UiSettings::new(&RenderSettings::default()));
    poll_until(&mut v, |v| v.info.is_some());
    let cam = v.cam;
    v.open(glb.display().to_string());
    assert!(v.loading.is_some());
    poll_until(&mut v, |v| v.loading.is_none());
    assert_eq!(v.spec, "builtin:cornell");
    assert_eq!(
        v.info.as_ref().map(|i| i.spec.as_str()),
        Some("builtin:cornell")
    );
    assert_eq!(v.cam, cam);
    assert!(!v.worker_gone);
    assert!(v.status.contains("trunc.glb"), "{}", v.status);
    // The open scene's worker still renders.
    v.schedule();
    poll_until(&mut v, |v| v.latest.is_some());
    // A scene that loads replaces it.
    v.open("builtin:conference".into());
    poll_until(&mut v, |v| v.loading.is_none());
    assert_eq!(v.spec, "builtin:conference");
    assert!(v.info.is_some() && v.latest.is_none());
    assert!(v.status.is_empty(), "{}", v.status);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_bookmarks_file_that_fails_to_load_is_moved_aside_not_overwritten() {
    let d = scratch("bookmarks");
    // Any scene file will do: the built-in Cornell box's GLB, beside its bookmarks file.
    let scene = d.join("t.glb");
    std::fs::write(&scene, crate::scene::builtin::bytes("cornell").unwrap()).unwrap();
    let file = d.join("t.glb.fuzzy-vpl.json");
    std::fs::write(&file, "{ \"bookmarks\": [ truncated").unwrap();
    let mut v = viewer(UiSettings::new(&RenderSettings::default()));
    poll_until(&mut v, |v| v.info.is_some());
    v.open(scene.display().to_string());
    poll_until(&mut v, |v| v.loading.is_none());
    assert_eq!(v.spec, scene.display().to_string());
    assert!(
        v.status.contains("not a fuzzy-vpl bookmarks file"),
        "{}",
        v.status
    );
    v.bookmarks
        .bookmarks
        .push(bookmarks::Bookmark::new("door".into(), &v.cam));
    v.save_bookmarks();
    let aside = d.join("t.glb.fuzzy-vpl.json.bad-1");
    assert_eq!(
        std::fs::read_to_string(&aside).unwrap(),
        "{ \"bookmarks\": [ truncated"
    );
    assert!(v.status.contains("moved to"), "{}", v.status);
    assert_eq!(BookmarksFile::load(&file).unwrap(), v.bookmarks);
    // Later saves write the (now readable) file in place.
    v.save_bookmarks();
    assert!(!d.join("t.glb.fuzzy-vpl.json.bad-2").exists());
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn exr_of_the_reference_view_without_a_reference_is_refused() {
    let d = scratch("refshot");
    let mut s = UiSettings::new(&RenderSettings::default());
    s.frame.vpls = 256;
    s.cluster.vpl_clusters = 32;
    s.cluster.sp_clusters = 64;
    let mut v = viewer(s);
    v.shot_dir = d.clone();
    v.view = View::Reference;
    poll_until(&mut v, |v| v.info.is_some());
    v.schedule();
    poll_until(&mut v, |v| v.latest.is_some());
    v.save_exr();
    assert!(v.last_shot.contains("no reference"), "{}", v.last_shot);
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0);
    // The final view saves under its own name.
    v.view = View::Final;
    v.save_exr();
    assert!(v.last_shot.contains("_final_"), "{}", v.last_shot);
    std::fs::remove_dir_all(&d).unwrap();
}

/// Panel settings for a quick frame with temporal reuse: 256 VPLs in 32 clusters, 64 SP clusters.
fn small_temporal() -> UiSettings {
    let mut s = UiSettings::new(&RenderSettings::default());
    s.frame.vpls = 256;
    s.cluster.vpl_clusters = 32;
    s.cluster.sp_clusters = 64;
    s.cluster.temporal = true;
    s
}

#[test]
fn the_direct_light_accumulates_at_rest() {
    let mut s = small_temporal();
    s.frame.direct_samples = 2;
    let mut v = viewer(s);
    poll_until(&mut v, |v| v.info.is_some());
    v.schedule();
    poll_until(&mut v, |v| {
        v.latest
            .as_ref()
            .and_then(|r| r.refined)
            .is_some_and(|(n, ..)| n >= 3)
    });
    let r = v.latest.as_ref().unwrap();
    let (n, spp, ms) = r.refined.unwrap();
    assert_eq!(spp, n as u64 * 2);
    assert!(ms > 0.0);
    // The image shown is the running mean plus the frame's indirect light.
    for ((p, d), i) in r
        .frame
        .radiance
        .iter()
        .zip(&r.frame.direct)
        .zip(&r.frame.indirect)
    {
        assert_eq!(*p, [d[0] + i[0], d[1] + i[1], d[2] + i[2]]);
    }
    // A change starts a new frame, which accumulates from its own first estimate.
    v.s.frame.seed += 1;
    v.schedule();
    let id = v.pending;
    poll_until(&mut v, |v| {
        v.latest
            .as_ref()
            .is_some_and(|r| r.job.id == id && r.refined.is_some())
    });
}

#[test]
fn lights_move_without_a_restart() {
    let s = small_temporal();
    let mut v = viewer(s);
    poll_until(&mut v, |v| v.info.is_some());
    v.schedule();
    poll_until(&mut v, |v| v.latest.is_some());
    let lum = |v: &Viewer| metrics::mean_luminance(&v.latest.as_ref().unwrap().frame.radiance);
    let before = lum(&v);
    assert!(v.last_relight.is_some(), "the first frame traced the VPLs");
    v.last_relight = None;
    // The ceiling light off, a point light in the middle of the box.
    let bounds = v.info.as_ref().unwrap().bounds;
    let mut set = v.lights.clone();
    set.emitter_scale = 0.0;
    set.lights.push(lights::new_point(bounds));
    v.set_lights(set);
    assert!(v.status.is_empty(), "{}", v.status);
    v.schedule();
    poll_until(&mut v, |v| v.last_relight.is_some());
    let r = v.latest.as_ref().unwrap();
    assert!(r.frame.radiance.iter().flatten().all(|c| c.is_finite()));
    assert!(r.frame.vpls > 0);
    let (trace, cluster) = v.last_relight.unwrap();
    assert!(trace > 0.0 && cluster > 0.0, "{trace} {cluster}");
    assert!(
        (lum(&v) - before).abs() > 1e-3 * before,
        "{} vs {before}",
        lum(&v)
    );
    // Nothing left that emits: the panel says so.
    v.set_lights(lights::LightSet {
        lights: vec![],
        emitter_scale: 0.0,
    });
    assert!(v.status.contains("no light"), "{}", v.status);
}

#[test]
fn auto_gamma_reaches_the_frame_and_the_file_names() {
    let s = UiSettings::new(&RenderSettings::default());
    assert!(s.cluster.gamma.is_auto());
    assert_eq!(s.frame_settings(64, 48).cluster.gamma, Gamma::Auto);
    assert!(s.short().contains("_gauto_"), "{}", s.short());
    // Unticked, the slider's γ is used (a γ from the command line arrives unticked).
    let mut fixed = RenderSettings::default();
    fixed.cluster.gamma = Gamma::Fixed(8);
    let mut s = UiSettings::new(&fixed);
    assert_eq!(s.frame_settings(64, 48).cluster.gamma, Gamma::Fixed(8));
    assert!(s.short().contains("_g8_"), "{}", s.short());
    // The γ control's word ("auto") sets it back.
    assert!(s.cluster.set_control("gamma", "auto".into()));
    assert_eq!(s.frame_settings(64, 48).cluster.gamma, Gamma::Auto);
}

/// The panel's "the paper": on, the frame settings are `--paper`'s for the image's size (point
/// lights, every switch off, clamp 0, the paper's K ratios); off, the switches and the clamp back
/// at their defaults.
#[test]
fn the_paper_toggle_sets_and_clears_the_papers_choices() {
    use crate::settings::{Adaptations, ClusterLight};
    let mut s = UiSettings::new(&RenderSettings::default());
    s.set_paper(true, 160, 120);
    let f = s.frame_settings(160, 120);
    assert!(f.cluster.paper);
    assert_eq!(f.cluster.cluster_light, ClusterLight::Point);
    assert_eq!(f.cluster.adaptations(), Adaptations::none());
    assert_eq!((f.cluster.sp_clusters, f.cluster.vpl_clusters), (208, 2048));
    assert_eq!(f.frame.clamp, 0.0);
    assert!((f.cluster.normal_threshold - 3f32.sqrt() / 2.0).abs() < 1e-6);
    s.set_paper(false, 160, 120);
    let f = s.frame_settings(160, 120);
    let d = ClusterSettings::default();
    assert!(!f.cluster.paper);
    assert_eq!(f.cluster.cluster_light, d.cluster_light);
    assert_eq!(f.cluster.adaptations(), Adaptations::default());
    assert_eq!(f.frame.clamp, FrameSettings::default().clamp);
}

#[test]
fn command_line_values_beyond_the_sliders_survive_the_panel() {
    let fs = RenderSettings {
        frame: FrameSettings {
            vpls: 100_000,
            exposure: Exposure::Fixed(100.0),
            ..Default::default()
        },
        cluster: ClusterSettings {
            sp_clusters: 20_000,
            vpl_clusters: 20_000,
            gamma: Gamma::Fixed(100),
            iterations: 1000,
            weight_exponent: 20.0,
            plane_gate: Some(0.5),
            weighting: Weighting::InverseDistance,
            ..Default::default()
        },
        ..Default::default()
    };
    let s = UiSettings::new(&fs);
    let mut v = viewer(s.clone());
    draw(&mut v);
    draw(&mut v);
    assert_eq!(v.s, s);
}

/// The method selector: every registry entry's method and knobs survive the panel (which draws the entry's
/// section), name the series and the screenshot files, and reach the frame settings.
#[test]
fn the_method_and_its_knobs_survive_the_panel() {
    // The method whose knobs are the paper's `ClusterSettings` is drawn by the clustering controls
    // (other tests).
    for entry in crate::method::REGISTRY.iter().filter(|r| r.own_settings) {
        let mut fs = RenderSettings::default();
        fs.method.method = entry.method;
        let s = UiSettings::new(&fs);
        let mut v = viewer(s.clone());
        draw(&mut v);
        assert_eq!(v.s, s, "{}", entry.method);
        let short = format!("{}-{}_", entry.method, (entry.short)(&s.method));
        assert!(
            s.short().starts_with(&short),
            "{} against {short}",
            s.short()
        );
        assert!(
            s.mode_label().starts_with(entry.method.name()),
            "{}",
            s.mode_label()
        );
        assert!(s.mode_label().contains(&(entry.series)(&s.method)));
        let r = s.frame_settings(64, 48);
        assert_eq!(r.method, fs.method);
    }
}

#[test]
fn gi_size_lowers_the_render_scale_to_what_the_device_holds() {
    assert_eq!(gi_size([640, 480], 0.5, 2_097_152), ((320, 240), None));
    assert_eq!(gi_size([10, 10], 0.1, 2_097_152), ((8, 8), None));
    // 2048x1100 at scale 1 is 2,252,800 pixels: more than lavapipe's binding holds.
    let ((w, h), lower) = gi_size([2048, 1100], 1.0, 2_097_152);
    let lower = lower.expect("lowered");
    assert!(w as u64 * h as u64 <= 2_097_152, "{w}x{h}");
    assert!(lower < 1.0 && lower > 0.95, "{lower}");
    assert!(w > 1900 && h > 1000, "{w}x{h}");
    let ((w, h), lower) = gi_size([16384, 16384], 1.0, 2_097_152);
    assert!(
        w as u64 * h as u64 <= 2_097_152 && lower.is_some(),
        "{w}x{h}"
    );
}

/// The split view's divider follows a left-button drag over it, and the drag does not move the
/// camera; away from the divider the same drag orbits/looks as before.
#[test]
fn the_split_divider_follows_a_drag_and_leaves_the_camera() {
    let mut v = viewer(UiSettings::new(&RenderSettings::default()));
    v.b = Some(v.s.clone());
    v.view = View::Split;
    let ctx = egui::Context::default();
    let screen = egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(1200.0, 800.0));
    let frame = |v: &mut Viewer, events: Vec<egui::Event>| {
        let input = egui::RawInput {
            screen_rect: Some(screen),
            events,
            ..Default::default()
        };
        // The textures it uploads are not applied here: cleared, as egui asks.
        ctx.run_ui(input, |ui| v.ui(ui)).textures_delta.clear();
    };
    frame(&mut v, vec![]);
    // The image area starts right of the 380 px panel: the divider at its middle.
    let (left, width) = (
        super::panel::PANEL_WIDTH,
        1200.0 - super::panel::PANEL_WIDTH,
    );
    let at = |f: f32| egui::pos2(left + width * f, 400.0);
    let cam = v.cam;
    let button = |pressed| egui::Event::PointerButton {
        pos: at(if pressed { 0.5 } else { 0.25 }),
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: Default::default(),
    };
    frame(&mut v, vec![egui::Event::PointerMoved(at(0.5))]);
    frame(&mut v, vec![button(true)]);
    for f in [0.45, 0.4, 0.3, 0.25] {
        frame(&mut v, vec![egui::Event::PointerMoved(at(f))]);
    }
    frame(&mut v, vec![button(false)]);
    assert!((v.split - 0.25).abs() < 0.02, "split {}", v.split);
    assert_eq!(v.cam, cam);
}

/// References are kept per view and per setting that changes the reference: a view's reference
/// comes back when the view does (in memory, and from disk with `--keep-references` in a new
/// viewer), while another camera, VPL count, seed, size, light or direct sample count misses it and
/// a change of clustering does not.
#[test]
fn references_are_kept_per_view_and_per_reference_setting() {
    let dir = std::env::temp_dir().join(format!("fvpl-refs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let spec = dir.join("room.gltf").to_string_lossy().into_owned();
    let mut v = viewer(UiSettings::new(&RenderSettings::default()));
    v.spec = spec.clone();
    v.refs_on_disk = true;
    let (w, h) = (8, 6);
    let s = v.s.frame_settings(w, h);
    let cam = v.cam.to_camera();
    let key = super::ref_key(&cam, &s, &v.lights);
    let image: Vec<[f32; 3]> = (0..w * h).map(|i| [i as f32, 0.5, 1.0]).collect();
    v.keep_reference(key.clone(), image.clone(), 1.0, w, h);
    assert_eq!(v.kept_reference(&key), Some(image.as_slice()));

    // What the reference depends on changes the key; the clustering does not.
    let other = |f: &dyn Fn(&mut RenderSettings)| {
        let mut t = s.clone();
        f(&mut t);
        super::ref_key(&cam, &t, &v.lights)
    };
    for changed in [
        other(&|t| t.frame.vpls += 1),
        other(&|t| t.frame.seed += 1),
        other(&|t| t.frame.width += 1),
        other(&|t| t.frame.direct_samples += 1),
        other(&|t| t.frame.bounces += 1),
    ] {
        assert_ne!(changed, key);
        assert!(v.kept_reference(&changed).is_none());
    }
    let mut moved = cam.clone();
    moved.yfov *= 0.9;
    assert_ne!(super::ref_key(&moved, &s, &v.lights), key);
    let mut lights = v.lights.clone();
    lights.emitter_scale *= 2.0;
    assert_ne!(super::ref_key(&cam, &s, &lights), key);
    assert_eq!(
        other(&|t| {
            t.cluster.sp_clusters += 7;
            t.cluster.fuzziness = 1;
            t.cluster.weighting = Weighting::Hard;
        }),
        key
    );

    // A new viewer on the same scene reads it from disk, once asked to keep references there.
    let mut u = viewer(UiSettings::new(&RenderSettings::default()));
    u.spec = spec;
    assert!(
        !u.load_kept_reference(key.clone(), (w, h)),
        "off by default"
    );
    u.refs_on_disk = true;
    assert!(u.load_kept_reference(key.clone(), (w, h)));
    assert_eq!(u.kept_reference(&key), Some(image.as_slice()));
    // Another size under the same key is a miss (and not looked for again).
    let mut x = viewer(UiSettings::new(&RenderSettings::default()));
    x.spec = u.spec.clone();
    x.refs_on_disk = true;
    assert!(!x.load_kept_reference(key.clone(), (w + 1, h)));
    assert!(x.refs_missing.contains(&key));

    // At most MAX_CACHED_REFS in memory, the oldest dropped first.
    v.refs_on_disk = false;
    for i in 0..MAX_CACHED_REFS {
        v.keep_reference(format!("k{i}"), image.clone(), 1.0, w, h);
    }
    assert_eq!(v.refs.len(), MAX_CACHED_REFS);
    assert!(v.kept_reference(&key).is_none());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_preview_keeps_the_image_size_and_lowers_only_the_indirect_light() {
    let mut ui = UiSettings::new(&RenderSettings::default());
    ui.render_scale = 0.5;
    let rest = ui.frame_settings(640, 480);
    let p = preview_settings(rest.clone());
    // Primary rays and direct light at the image's size: the edges of a moving view stay sharp.
    assert_eq!((p.frame.width, p.frame.height), (640, 480));
    assert_eq!(p.frame.direct_samples, 1);
    assert_eq!(p.frame.indirect_scale, rest.frame.indirect_scale / 2.0);
    let low = |s: &RenderSettings| {
        crate::gi::upsample::indirect_size(s.frame.width, s.frame.height, s.frame.indirect_scale)
    };
    let (lw, lh) = low(&rest);
    assert_eq!(low(&p), (lw / 2, lh / 2));
    // Everything else (the clustering, the method) as at rest.
    assert_eq!(p.cluster, rest.cluster);
    // A tiny window keeps at least 8 indirect pixels a side; a large scale stays within (0, 1].
    let tiny = preview_settings(ui.frame_settings(20, 12));
    let (tw, th) = low(&tiny);
    assert!(tw >= 8 && th >= 8, "{tw}x{th}");
    let mut whole = rest;
    whole.frame.indirect_scale = 1.0;
    assert_eq!(preview_settings(whole).frame.indirect_scale, 0.5);
}

/// The panel driven by events, as a user drives it (egui's harness `egui_kittest`, widgets found by
/// their labels): each view mode, the weightings, each method (a frame of it asked for) and back, a
/// slider moved by its keys, "pin as B" and the split view, W to fly, R to reset, F11 for an EXR
/// and F12 for a PNG.
#[test]
fn the_panel_driven_by_events() {
    let d = scratch("kittest");
    let mut v = viewer(small_temporal());
    v.shot_dir = d.clone();
    poll_until(&mut v, |v| v.info.is_some());
    v.schedule();
    poll_until(&mut v, |v| v.latest.is_some());
    let mut h = panel_harness(v);
    for view in View::ALL {
        click(&mut h, view.name());
        assert_eq!(h.state().view, view, "clicking {:?}", view.name());
    }
    for (label, w) in [
        ("hard", Weighting::Hard),
        ("fuzzy (uniform)", Weighting::Uniform),
        ("weighted", Weighting::InverseDistance),
    ] {
        click(&mut h, label);
        assert_eq!(h.state().s.cluster.weighting, w, "{label}");
    }
    // Each method, the default (the first) last: each asks the worker for a frame of that method.
    let (mut choices, mut sliders) = (0, 0);
    for m in crate::method::Method::ALL.into_iter().rev() {
        let (choice, slider) = drive_method(&mut h, m);
        choices += choice as u32;
        sliders += slider as u32;
    }
    // Three rooms declare a choice today, two an integer slider.
    assert!(
        choices >= 3 && sliders >= 2,
        "{choices} choices, {sliders} sliders"
    );
    drive_settings(&mut h);
    pin_b_and_split(&mut h);
    fly_reset_and_shoot(&mut h);
    std::fs::remove_dir_all(&d).unwrap();
}

/// Every control `ClusterSettings` and `FrameSettings` declare is in the panel under its label
/// (drawn from the declarations); a slider takes the arrow keys once focused, a toggle a click, a
/// word's box a click.
fn drive_settings(h: &mut PanelHarness) {
    use crate::settings::{ClusterSettings, FrameSettings};
    use egui_kittest::kittest::Queryable;
    let labels = ClusterSettings::CONTROLS
        .iter()
        .chain(FrameSettings::CONTROLS);
    for c in labels {
        let found = h.query_all_by_label_contains(c.label).next().is_some();
        assert!(found, "no widget labelled {:?} ({})", c.label, c.name);
    }
    let k = h.state().s.cluster.vpl_clusters;
    press_on(h, "K_VPL", egui::Key::ArrowRight);
    assert!(h.state().s.cluster.vpl_clusters > k, "K_VPL stayed {k}");
    let facing = h.state().s.cluster.visibility_facing;
    click(h, "facing test");
    assert_eq!(h.state().s.cluster.visibility_facing, !facing);
    // The time budget's box: ticked "off" (no budget) at the start; unticked, a budget.
    assert_eq!(h.state().s.cluster.target_ms, None);
    let off = h.query_all_by_label("off").count();
    assert!(
        off >= 3,
        "{off} boxes labelled off (K's, the gate, the budget)"
    );
}

type PanelHarness = egui_kittest::Harness<'static, Viewer>;

/// The whole window's UI over `v` in egui's test harness, two frames run.
fn panel_harness(v: Viewer) -> PanelHarness {
    let mut h = egui_kittest::Harness::builder()
        .with_size(egui::vec2(1200.0, 1400.0))
        .build_ui_state(
            |ui, v: &mut Viewer| {
                v.poll();
                v.ui(ui);
                v.tick();
            },
            v,
        );
    h.run_steps(2);
    h
}

/// Clicks the first widget of a label (the view's "direct" button comes before the direct
/// checkbox).
fn click(h: &mut PanelHarness, label: &str) {
    use egui_kittest::kittest::Queryable;
    h.query_all_by_label(label)
        .next()
        .unwrap_or_else(|| panic!("no widget labelled {label:?}"))
        .click();
    h.run_steps(2);
}

/// Focuses the first widget of a label and presses `key` on it.
fn press_on(h: &mut PanelHarness, label: &str, key: egui::Key) {
    use egui_kittest::kittest::Queryable;
    h.query_all_by_label(label)
        .next()
        .unwrap_or_else(|| panic!("no widget labelled {label:?}"))
        .focus();
    h.run_steps(1);
    h.key_press(key);
    h.run_steps(2);
}

/// Chooses method `m` (a frame of it asked for), finds each of its declared knobs, picks another
/// value of its first choice and moves its first integer slider not at its top by a key. Returns
/// whether it had a choice and such a slider.
fn drive_method(h: &mut PanelHarness, m: crate::method::Method) -> (bool, bool) {
    use egui_kittest::kittest::Queryable;
    let sent = h.state().pending;
    click(h, m.name());
    assert_eq!(h.state().s.method.method, m, "clicking {:?}", m.name());
    assert!(
        h.state().pending > sent,
        "{:?}: no frame asked for",
        m.name()
    );
    let key = h.state().last_sent.clone().unwrap_or_default();
    assert!(
        key.contains(&format!("method: {m:?},")),
        "{:?}: {key}",
        m.name()
    );
    // Its knobs, drawn from their declarations (`knobs!`'s `ui`): every label is there.
    for c in h.state().s.method.controls() {
        let found = h.query_all_by_label(c.label).next().is_some();
        assert!(found, "{m}: no widget labelled {:?}", c.label);
    }
    // A choice is a radio button a value; an integer slider takes the arrow keys.
    let controls = h.state().s.method.controls();
    let choice = controls.iter().find_map(|c| match c.widget {
        Widget::Choice(values) => Some((c.name, values)),
        _ => None,
    });
    if let Some((name, values)) = choice {
        let now = h.state().s.method.knob(name).unwrap();
        let (value, label) = values.iter().find(|(v, _)| *v != now).unwrap();
        click(h, label);
        assert_eq!(
            h.state().s.method.knob(name).as_deref(),
            Some(*value),
            "{m}"
        );
    }
    let slider = controls.iter().find(|c| {
        matches!(c.widget, Widget::Slider(crate::settings::Range { integer: true, hi, .. })
            if h.state().s.method.knob(c.name).unwrap().parse::<f64>().unwrap() < hi)
    });
    if let Some(c) = slider {
        let before: f64 = h.state().s.method.knob(c.name).unwrap().parse().unwrap();
        press_on(h, c.label, egui::Key::ArrowRight);
        let after: f64 = h.state().s.method.knob(c.name).unwrap().parse().unwrap();
        assert!(after > before, "{m}: {} stayed {before}", c.label);
    }
    (choice.is_some(), slider.is_some())
}

/// "pin as B", then the split view, which asks for A's frame with B's beside it.
fn pin_b_and_split(h: &mut PanelHarness) {
    click(h, "pin as B");
    assert!(h.state().b.is_some());
    click(h, View::Split.name());
    assert_eq!(h.state().view, View::Split);
    // The split view asks for A's frame with B's beside it (the job's last part: B's settings; sent
    // already when B was pinned in the A−B view, where the views above ended).
    let key = h.state().last_sent.clone().unwrap_or_default();
    assert!(
        key.contains(" Some(RenderSettings {"),
        "split without B: {key}"
    );
    click(h, View::Final.name());
}

/// W flies forward and R resets to the start view; F11 saves the view as EXR and F12 asks the
/// window for a PNG.
fn fly_reset_and_shoot(h: &mut PanelHarness) {
    h.state_mut().latest.as_ref().expect("a frame");
    let home = h.state().home;
    h.key_down(egui::Key::W);
    h.run_steps(3);
    h.key_up(egui::Key::W);
    h.run_steps(1);
    assert_ne!(h.state().cam, home, "W did not move the camera");
    h.key_press(egui::Key::R);
    h.run_steps(2);
    assert_eq!(h.state().cam, home, "R did not reset the camera");
    h.key_press(egui::Key::F11);
    h.run_steps(2);
    let shot = h.state().last_shot.clone();
    assert!(shot.starts_with("saved") && shot.contains(".exr"), "{shot}");
    h.key_press(egui::Key::F12);
    h.run_steps(2);
    assert!(h.state().png_request.is_some());
}
