//! restir (ReSTIR DI over the VPLs, `method::restir`, docs/methods.md): each stage of
//! `restir.wgsl` against its CPU twin (`method::restir::twin`) on small frames, the unbiased combination's
//! mean over seeds against the exact Eq. (5) sum (the reference, every VPL with its shadow ray) on
//! hand-placed VPLs and on the built-in scenes, the history's life, and convergence with temporal
//! reuse on a static camera.

mod common;

use common::shading_points;

use fuzzy_vpl::gi::pass::Pass;
use fuzzy_vpl::gi::primary::ShadingPoint;
use fuzzy_vpl::gi::vpl_trace::{ResidentVpls, Vpl, VplKey, VplSet};
use fuzzy_vpl::method::restir::settings::Combine;
use fuzzy_vpl::method::restir::twin::{Reservoir, Stages};
use fuzzy_vpl::method::restir::{self, RestirMethod, alias};
use fuzzy_vpl::method::{Method, MethodSettings};
use fuzzy_vpl::metrics;
use fuzzy_vpl::render::{RenderSettings, Renderer};
use fuzzy_vpl::scene::{self, Camera, Scene};
use fuzzy_vpl::settings::{ClusterSettings, FrameSettings};
use glam::Vec3;

/// The tests of this file one at a time: `restir_steady_frames_make_no_buffer` counts the buffers
/// made by the whole process.
fn serial() -> std::sync::MutexGuard<'static, ()> {
    static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

fn settings(w: u32, h: u32, vpls: u32) -> RenderSettings {
    RenderSettings {
        frame: FrameSettings {
            width: w,
            height: h,
            vpls,
            direct_samples: 1,
            ..Default::default()
        },
        method: MethodSettings {
            method: Method::Restir,
            ..Default::default()
        },
        cluster: ClusterSettings::default(),
        ..Default::default()
    }
}

fn state<'r>(r: &'r Renderer) -> &'r RestirMethod {
    r.method_state::<RestirMethod>(Method::Restir).unwrap()
}

/// The last frame's final reservoirs.
fn reservoirs(r: &Renderer, pixels: usize) -> Vec<Reservoir> {
    let b = state(r).reservoirs().unwrap();
    let raw: Vec<[u32; 4]> = r.ctx.read_buffer(b, pixels).unwrap();
    raw.into_iter().map(Reservoir::from_gpu).collect()
}

/// How far two reservoirs are apart: `None` when their samples differ, else the largest relative
/// difference of w_sum, M and W.
fn res_diff(c: &Reservoir, g: &Reservoir) -> Option<f32> {
    if c.y != g.y {
        return None;
    }
    let rel = |a: f32, b: f32| (a - b).abs() / a.abs().max(b.abs()).max(1e-30);
    Some(rel(c.w_sum, g.w_sum).max(rel(c.m, g.m)).max(rel(c.w, g.w)))
}

/// Counts the reservoirs whose samples differ, and of the others those whose W is 0 on one side
/// only (the CPU's and the GPU's traversals disagree on a shadow ray), and the worst relative
/// difference of the rest.
fn compare(what: &str, cpu: &[Reservoir], gpu: &[Reservoir]) -> (usize, f32) {
    let mut differ = 0;
    let mut worst = 0f32;
    for (i, (c, g)) in cpu.iter().zip(gpu).enumerate() {
        assert!(
            c.w.is_finite() && g.w.is_finite() && g.w_sum.is_finite(),
            "{what}: pixel {i}: CPU {c:?}, GPU {g:?}"
        );
        let shadow = c.y == g.y && (c.w == 0.0) != (g.w == 0.0);
        match res_diff(c, g) {
            Some(_) if shadow => {
                println!("{what}: pixel {i}: a shadow ray differs: CPU {c:?}, GPU {g:?}");
                differ += 1;
            }
            Some(d) => worst = worst.max(d),
            None => differ += 1,
        }
    }
    println!(
        "{what}: {differ} of {} samples or shadow rays differ, worst relative w_sum/M/W {worst:.2e}",
        cpu.len()
    );
    (differ, worst)
}

fn rooms() -> impl Iterator<Item = (&'static str, Scene)> {
    ["builtin:cornell", "builtin:conference"]
        .into_iter()
        .map(|n| (n, scene::load(n).unwrap()))
}

/// The stages of the last frame as its twin sees them.
fn stages<'a>(
    r: &'a Renderer,
    cs: &'a fuzzy_vpl::cpu::shading::CpuScene<'a>,
    sps: &'a [ShadingPoint],
    prev_sps: &'a [ShadingPoint],
    table: &'a [[u32; 4]],
) -> Stages<'a> {
    Stages {
        cs,
        sps,
        prev_sps,
        vpls: &r.vpl_set.as_ref().unwrap().set.vpls,
        table,
        params: state(r).last.unwrap().params,
    }
}

/// The initial candidates (RIS by flux, p̂ the unshadowed term, the sample's shadow ray), the
/// spatial reuse (biased and unbiased, 1 and 2 iterations) and the shade against the CPU twin on
/// both built-in rooms at 24×18 with 256 VPLs: the twin's chain from its own initial reservoirs
/// against the GPU's final ones, and the twin's shade of the GPU's final reservoirs. Measured on
/// lavapipe (Mesa 22.3.6): no sample and no shadow ray differs in any stage; w_sum, M and W within
/// 4.8e-7 relative (f32 sums in another order); the shaded light within 1.3e-7 of twin_diff.
#[test]
fn restir_stages_match_cpu_twin() {
    let _serial = serial();
    let ctx = common::gpu();
    for (name, s) in rooms() {
        let mut r = Renderer::new(&ctx, &s).unwrap();
        let (w, h) = (24u32, 18u32);
        let n = (w * h) as usize;
        let cam = s.default_camera();
        for (combine, iterations) in [
            (Combine::Biased, 0),
            (Combine::Biased, 1),
            (Combine::Unbiased, 1),
            (Combine::Biased, 2),
        ] {
            let what = format!("{name} {combine} n{iterations}");
            let mut fs = settings(w, h, 256);
            fs.method.restir.restir_combine = combine;
            fs.method.restir.restir_iterations = iterations;
            fs.method.restir.restir_radius = 200.0;
            let f = r.render(&cam, &fs).unwrap();
            assert!(f.ran(restir::SHADE), "{what}");
            assert!(common::all_finite(&f.radiance), "{what}");
            assert_eq!(state(&r).last.unwrap().iterations, iterations, "{what}");
            let gpu = reservoirs(&r, n);
            let sps = shading_points(&r);
            let cs = common::cpu_scene(&r, &s);
            let table = alias::build(&r.vpl_set.as_ref().unwrap().set.vpls);
            let st = stages(&r, &cs, &sps, &sps, &table);
            let (initial, mut rays): (Vec<Reservoir>, Vec<u32>) =
                (0..n as u32).map(|i| st.initial(i)).unzip();
            if iterations == 0 {
                let (differ, worst) = compare(&format!("{what} initial"), &initial, &gpu);
                assert!(differ == 0 && worst < 1e-6, "{what}: {differ}, {worst}");
                assert!(initial.iter().any(|c| c.w > 0.0), "{what}: no sample seen");
                assert!(
                    initial.iter().any(|c| c.y != u32::MAX && c.w == 0.0),
                    "{what}: no sample hidden"
                );
            } else {
                // The last iteration from the CPU's chain up to it: the chain's earlier reservoirs
                // from the twin (a different draw would show as differing samples).
                let mut input = initial;
                for it in 0..iterations {
                    let (next, r): (Vec<Reservoir>, Vec<u32>) =
                        (0..n as u32).map(|i| st.spatial(i, &input, it)).unzip();
                    rays.extend(r);
                    input = next;
                }
                let (differ, worst) = compare(&format!("{what} spatial"), &input, &gpu);
                assert!(differ == 0 && worst < 1e-6, "{what}: {differ}, {worst}");
                let reused = input.iter().filter(|c| c.m > 32.0).count();
                let valid = sps.iter().filter(|p| p.valid).count();
                println!("{what}: {reused} of {valid} pixels reused a neighbour");
                assert!(reused > valid / 3, "{what}: {reused} of {valid} reused");
            }
            // The shade of the GPU's final reservoirs.
            let pairs = (0..n as u32).map(|i| {
                let (c, _) = st.shade(i, &gpu[i as usize]);
                (c, Vec3::from(f.indirect[i as usize]))
            });
            let worst = pairs
                .map(|(c, g)| {
                    assert!(c.is_finite() && g.is_finite(), "{what}");
                    common::twin_diff(c, g)
                })
                .fold(0f32, f32::max);
            println!("{what} shade: worst twin_diff {worst:.2e}");
            assert!(worst < 3e-7, "{what} shade: {worst}");
            // The shadow rays the frame counted: the direct light's, then the twin's of each stage
            // (its chain's: the same samples) and of the shade.
            rays.extend((0..n as u32).map(|i| st.shade(i, &gpu[i as usize]).1));
            let valid = sps.iter().filter(|p| p.valid).count() as u64;
            let direct = valid * (fs.frame.direct_samples + r.gpu.info.num_lights) as u64;
            let twin: u64 = rays.iter().map(|&r| r as u64).sum();
            assert_eq!(f.shadow_rays - direct, twin, "{what}: indirect shadow rays");
        }
    }
}

/// The temporal reuse against its twin: two frames on a static camera with `--temporal on`
/// (accumulation off, α = 1), no spatial reuse; the second frame's reservoirs are the twin's
/// combination of its initial ones with the first frame's final ones, each pixel reusing its own
/// (the same view), M capped at cap × M. Measured on lavapipe: no sample or shadow ray differs,
/// w_sum/M/W within 4.7e-7 relative.
#[test]
fn restir_temporal_matches_cpu_twin() {
    let _serial = serial();
    let ctx = common::gpu();
    let s = scene::load("builtin:cornell").unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let (w, h) = (24u32, 18u32);
    let n = (w * h) as usize;
    let cam = s.default_camera();
    for combine in [Combine::Biased, Combine::Unbiased] {
        let mut fs = reusing(settings(w, h, 256));
        fs.method.restir.restir_iterations = 0;
        fs.method.restir.restir_cap = 2.0;
        fs.method.restir.restir_combine = combine;
        let mut prev = Vec::new();
        for frame in 0..3 {
            let f = r.render(&cam, &fs).unwrap();
            assert!(common::all_finite(&f.radiance));
            let last = state(&r).last.unwrap();
            assert_eq!(last.reused, frame > 0, "{combine} frame {frame}");
            let gpu = reservoirs(&r, n);
            if frame > 0 {
                let sps = shading_points(&r);
                let cs = common::cpu_scene(&r, &s);
                let table = alias::build(&r.vpl_set.as_ref().unwrap().set.vpls);
                let st = stages(&r, &cs, &sps, &sps, &table);
                let initial: Vec<Reservoir> = (0..n as u32).map(|i| st.initial(i).0).collect();
                let twin: Vec<Reservoir> = (0..n as u32)
                    .map(|i| st.temporal(i, &initial, &prev).0)
                    .collect();
                let (differ, worst) = compare(&format!("{combine} temporal {frame}"), &twin, &gpu);
                assert!(differ == 0 && worst < 1e-6, "{differ}, {worst}");
                // The confidence cap: the previous M counts at most 2 × 32 (M: 64, then 96).
                let valid = sps.iter().filter(|p| p.valid).count();
                let want = 32.0 + (32.0 * frame as f32).min(64.0);
                let capped = gpu.iter().filter(|c| c.m == want).count();
                assert_eq!(capped, valid, "{combine} frame {frame}: M {want}");
            }
            prev = gpu;
        }
    }
}

/// The history lives while the VPL set and the settings do: reused on the next frame with
/// `--temporal on`, dropped when `--vpls` changes, when the lights move (`set_lights` traces the
/// VPLs again: same count, another trace), after a frame of another method, after `forget_past`
/// and with `--temporal off`.
#[test]
fn restir_history_is_dropped_when_the_vpls_change() {
    let _serial = serial();
    let ctx = common::gpu();
    let s = scene::load("builtin:cornell").unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let cam = s.default_camera();
    let fs = reusing(settings(16, 12, 64));
    let reused = |r: &mut Renderer, fs: &RenderSettings| {
        let f = r.render(&cam, fs).unwrap();
        assert!(common::all_finite(&f.radiance));
        state(r).last.unwrap().reused
    };
    assert!(!reused(&mut r, &fs), "the first frame");
    assert!(reused(&mut r, &fs), "the same VPLs");
    let mut more = fs.clone();
    more.frame.vpls = 65;
    assert!(!reused(&mut r, &more), "--vpls changed");
    assert!(reused(&mut r, &more), "the same again");
    let lights = r.scene.lights.clone();
    r.set_lights(&lights, 1.0);
    assert!(!reused(&mut r, &more), "the lights moved");
    assert!(reused(&mut r, &more));
    let mut other = more.clone();
    other.method.method = Method::Colom;
    r.render(&cam, &other).unwrap();
    assert!(!reused(&mut r, &more), "a frame of another method between");
    assert!(reused(&mut r, &more));
    r.forget_past();
    assert!(
        !reused(&mut r, &more),
        "forget_past (a camera path run's start)"
    );
    let mut off = more.clone();
    off.cluster.temporal = false;
    assert!(!reused(&mut r, &off), "--temporal off");
    assert!(
        !reused(&mut r, &more),
        "no history kept with --temporal off"
    );
}

/// Frames at a steady size make no buffer (the rule: resources made once per size), with temporal
/// reuse and both combinations; a new size or VPL set makes them again.
#[test]
fn restir_steady_frames_make_no_buffer() {
    let _serial = serial();
    use fuzzy_vpl::gpu::traffic::buffers_made;
    let ctx = common::gpu();
    let s = scene::load("builtin:cornell").unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let cam = s.default_camera();
    let mut fs = reusing(settings(16, 12, 64));
    for combine in [Combine::Biased, Combine::Unbiased] {
        fs.method.restir.restir_combine = combine;
        r.render(&cam, &fs).unwrap();
        r.render(&cam, &fs).unwrap();
        let made = buffers_made();
        for _ in 0..3 {
            let f = r.render(&cam, &fs).unwrap();
            assert!(common::all_finite(&f.radiance));
        }
        assert_eq!(
            buffers_made(),
            made,
            "{combine}: steady frames made buffers"
        );
    }
}

/// Mean and standard error of the mean of `xs`.
fn mean_se(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// `frames` frames of `fs` (a new seed each: the state's frame count) at `cam`, with the mean
/// luminance of each one's indirect light and their per-pixel sum.
fn seeds(
    r: &mut Renderer,
    cam: &Camera,
    fs: &RenderSettings,
    frames: usize,
) -> (Vec<f64>, Vec<Vec3>) {
    let mut lums = Vec::new();
    let mut sum = Vec::new();
    for _ in 0..frames {
        let f = r.render(cam, fs).unwrap();
        assert!(common::all_finite(&f.radiance) && common::all_finite(&f.indirect));
        lums.push(metrics::mean_luminance(&f.indirect));
        sum.resize(f.indirect.len(), Vec3::ZERO);
        for (s, p) in sum.iter_mut().zip(&f.indirect) {
            *s += Vec3::from(*p);
        }
    }
    (lums, sum)
}

/// The oracle: on the Cornell box lit by four hand-placed VPLs (ceiling, two walls, floor; the
/// exact Eq. (5) sum is the reference's gather, every VPL with its shadow ray), the mean over 16
/// seeds of the unbiased estimator (4 candidates, 1 spatial iteration of 5 neighbours, no temporal
/// reuse) matches it: the image's mean indirect luminance within 3 standard errors, and per pixel
/// at least 90% of the lit pixels within 3 of their own standard errors.
#[test]
fn restir_unbiased_mean_is_the_exact_sum_on_hand_placed_vpls() {
    let _serial = serial();
    let ctx = common::gpu();
    let s = scene::load("builtin:cornell").unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    assert_eq!(r.geometry_scale, 1.0);
    let cam = s.default_camera();
    let (w, h) = (32u32, 24u32);
    let mut fs = settings(w, h, 4);
    fs.method.restir.restir_candidates = 4;
    fs.method.restir.restir_iterations = 1;
    fs.method.restir.restir_radius = 100.0;
    fs.method.restir.restir_combine = Combine::Unbiased;
    // A first frame traces 4 VPLs; they are replaced by hand-placed ones (a new trace number, so
    // that the lights and restir's table are made again from them).
    r.render(&cam, &fs).unwrap();
    let (lo, hi) = s.bounds();
    let at = |x: f32, y: f32, z: f32| lo + (hi - lo) * Vec3::new(x, y, z);
    let vpl = |p: Vec3, n: Vec3, flux: [f32; 3]| Vpl {
        pos: p.extend(0.0).into(),
        nrm: n.extend(0.0).into(),
        flux: [flux[0], flux[1], flux[2], 0.0],
    };
    let scale = 0.05 * s.extent() * s.extent();
    let hand = vec![
        vpl(at(0.5, 0.98, 0.5), -Vec3::Y, [scale, scale, scale]),
        vpl(
            at(0.02, 0.5, 0.4),
            Vec3::X,
            [2.0 * scale, 0.2 * scale, 0.2 * scale],
        ),
        vpl(
            at(0.98, 0.3, 0.6),
            -Vec3::X,
            [0.2 * scale, scale, 0.2 * scale],
        ),
        vpl(
            at(0.3, 0.02, 0.7),
            Vec3::Y,
            [0.5 * scale, 0.5 * scale, scale],
        ),
    ];
    let old = r.vpl_set.take().unwrap();
    r.vpl_set = Some(ResidentVpls {
        set: VplSet {
            buffer: ctx.storage_init("hand-placed VPLs", &hand),
            vpls: hand.clone(),
            paths: old.set.paths,
        },
        key: VplKey {
            trace: 1000,
            ..old.key
        },
        ms: 0.0,
    });
    let reference = RenderSettings {
        reference: true,
        ..fs.clone()
    };
    let refl = r.render(&cam, &reference).unwrap();
    assert_eq!(r.vpl_set.as_ref().unwrap().set.vpls, hand);
    let exact = metrics::mean_luminance(&refl.indirect);
    let frames = 16;
    let (lums, sum) = seeds(&mut r, &cam, &fs, frames);
    let (mean, se) = mean_se(&lums);
    println!("hand-placed VPLs: exact {exact:.5}, unbiased mean {mean:.5} ± {se:.5} (16 seeds)");
    assert!(exact > 0.0 && se > 0.0);
    assert!((mean - exact).abs() <= 3.0 * se, "{mean} ± {se} vs {exact}");
    // Per pixel, from a second set of 16 frames for the spread.
    let mut sq = vec![0f64; sum.len()];
    let mut sum2 = vec![Vec3::ZERO; sum.len()];
    for _ in 0..frames {
        let f = r.render(&cam, &fs).unwrap();
        for (i, p) in f.indirect.iter().enumerate() {
            let l = metrics::luminance(*p) as f64;
            sq[i] += l * l;
            sum2[i] += Vec3::from(*p);
        }
    }
    let (mut lit, mut within) = (0, 0);
    for i in 0..sum.len() {
        let m = metrics::luminance((sum2[i] / frames as f32).into()) as f64;
        let var = (sq[i] / frames as f64 - m * m).max(0.0) * frames as f64 / (frames - 1) as f64;
        let e = metrics::luminance(refl.indirect[i]) as f64;
        if e <= 0.0 {
            continue;
        }
        lit += 1;
        let se = (var / frames as f64).sqrt();
        if (m - e).abs() <= 3.0 * se + 1e-6 * e {
            within += 1;
        }
    }
    println!("hand-placed VPLs: {within} of {lit} lit pixels within 3 standard errors");
    assert!(
        lit > 100 && within as f64 >= 0.9 * lit as f64,
        "{within} of {lit}"
    );
}

/// The target: the unbiased variant's mean over 16 seeds is within 3 standard errors of
/// the reference's mean luminance on the built-in rooms (32×24, 256 VPLs, defaults otherwise: 32
/// candidates, 2 spatial iterations of 5 neighbours; no temporal reuse, so that the frames are
/// independent).
#[test]
fn restir_unbiased_mean_is_the_reference_on_the_built_in_rooms() {
    let _serial = serial();
    let ctx = common::gpu();
    for (name, s) in rooms() {
        assert_unbiased_mean_is_the_reference(&ctx, name, &s);
    }
}

/// `s`'s unbiased mean over 16 seeds (32×24, 256 VPLs) within 3 standard errors of the reference's
/// mean luminance (`name` in the messages).
fn assert_unbiased_mean_is_the_reference(ctx: &fuzzy_vpl::gpu::GpuContext, name: &str, s: &Scene) {
    let mut r = Renderer::new(ctx, s).unwrap();
    let cam = s.default_camera();
    let mut fs = settings(32, 24, 256);
    fs.method.restir.restir_combine = Combine::Unbiased;
    let reference = RenderSettings {
        reference: true,
        ..fs.clone()
    };
    let refl = r.render(&cam, &reference).unwrap();
    let exact = metrics::mean_luminance(&refl.indirect);
    let (lums, _) = seeds(&mut r, &cam, &fs, 16);
    let (mean, se) = mean_se(&lums);
    println!("{name}: reference {exact:.5}, unbiased mean {mean:.5} ± {se:.5} (16 seeds)");
    assert!(
        (mean - exact).abs() <= 3.0 * se,
        "{name}: {mean} ± {se} vs {exact}"
    );
}

/// `--restir-lights clusters`: restir over the resident VPL clusters (step 2 runs, its lights the
/// clusters as point lights). Its unbiased mean over 16 seeds is the gather of the same clusters
/// as point lights (`--cluster-light point`, every pixel × every cluster with its own shadow ray)
/// within 3 standard errors, on the Cornell box (32×24, 256 VPLs in 32 clusters).
#[test]
fn restir_over_vpl_clusters_is_the_gather_of_the_clusters() {
    let _serial = serial();
    let ctx = common::gpu();
    let s = scene::load("builtin:cornell").unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let cam = s.default_camera();
    let mut fs = settings(32, 24, 256);
    fs.cluster.vpl_clusters = 32;
    fs.cluster.sp_clusters = 0;
    fs.cluster.cluster_light = fuzzy_vpl::settings::ClusterLight::Point;
    fs.method.restir.restir_combine = Combine::Unbiased;
    fs.method.restir.restir_lights = fuzzy_vpl::method::restir::settings::RestirLights::Clusters;
    let gather = RenderSettings {
        method: MethodSettings::default(),
        ..fs.clone()
    };
    let g = r.render(&cam, &gather).unwrap();
    assert!(g.ran(Pass::Gather) && g.ran(Pass::VplCluster));
    assert_eq!(g.vpl_clusters_used, 32);
    let exact = metrics::mean_luminance(&g.indirect);
    let f = r.render(&cam, &fs).unwrap();
    assert!(f.ran(Pass::VplCluster) && f.ran(restir::SHADE));
    assert_eq!(f.vpl_clusters_used, 32);
    let (lums, _) = seeds(&mut r, &cam, &fs, 16);
    let (mean, se) = mean_se(&lums);
    println!("cornell, 32 VPL clusters: gather {exact:.5}, restir unbiased {mean:.5} ± {se:.5}");
    assert!((mean - exact).abs() <= 3.0 * se, "{mean} ± {se} vs {exact}");
}

/// Temporal reuse on a static camera brings the frame nearer the reference: on the conference
/// room at 64×48 with 1024 VPLs, the relative MSE of the 32nd frame with `--temporal on` (α = 1:
/// restir's reuse alone, no accumulation) is at most 0.6 of the first frame's (measured 0.46 on
/// lavapipe). Not the 0.25: the reservoirs' confidence cap bounds what the reuse adds, and
/// a frame stays one sample a pixel (docs/methods.md, "restir", measures 160×120 and 4096 VPLs);
/// the accumulation reaches it (the next test).
#[test]
fn restir_temporal_reuse_converges_on_a_static_camera() {
    let _serial = serial();
    let errs = rel_mse_by_frame("builtin:conference", (64, 48, 1024), 32, 1.0);
    println!("conference 64x48, 1024 VPLs, α 1, rel MSE by frame: {errs:.4?}");
    assert!(errs[31] <= 0.6 * errs[0], "{} vs {}", errs[31], errs[0]);
}

/// The convergence target at a test's size: with `--temporal on` and the accumulation's α
/// at 1 / frames (the plain mean of the frames) besides restir's own reuse, the conference room at
/// 80×60 with 1024 VPLs has, after 32 frames of a static camera, at most 0.35 of the first frame's
/// rel MSE. Measured on lavapipe: 0.203 (the default seed, 1); seeds 2–7 0.264, 0.163, 0.130,
/// 0.119, 0.209, 0.165; with α 0.7 (the default) 0.424, α 1 (restir's reuse alone) 0.479. The
/// issue's size, 160×120 with 4096 VPLs, measures 0.130 (docs/methods.md, "restir"); 64×48 measures
/// 0.40, its error held up by a few pixels whose sample seldom changes. Fails if restir stops
/// converging: a reservoir that keeps its sample (a broken cap or history) or a bias that does not
/// average out.
#[test]
fn restir_converges_with_accumulation_on_a_static_camera() {
    let _serial = serial();
    let frames = 32;
    let errs = rel_mse_by_frame(
        "builtin:conference",
        (80, 60, 1024),
        frames,
        1.0 / frames as f32,
    );
    println!("conference 80x60, 1024 VPLs, α 1/{frames}, rel MSE by frame: {errs:.4?}");
    let ratio = errs[frames - 1] / errs[0];
    assert!(
        ratio <= 0.35,
        "frame {frames} / frame 1: {ratio} ({errs:?})"
    );
}

/// The relative MSE against the reference of the same VPLs of `frames` frames of restir (its
/// defaults, biased) on `scene`'s default camera at `(width, height, vpls)`, with `--temporal on`
/// and the accumulation's α `alpha` (1: restir's reuse alone); every frame's pixels finite.
fn rel_mse_by_frame(
    scene: &str,
    (w, h, vpls): (u32, u32, u32),
    frames: usize,
    alpha: f32,
) -> Vec<f64> {
    let ctx = common::gpu();
    let s = scene::load(scene).unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let cam = s.default_camera();
    let mut fs = settings(w, h, vpls);
    fs.cluster.temporal = true;
    fs.cluster.temporal_alpha = alpha;
    let reference = RenderSettings {
        reference: true,
        ..fs.clone()
    };
    let refl = r.render(&cam, &reference).unwrap();
    assert!(common::all_finite(&refl.radiance));
    (0..frames)
        .map(|_| {
            let f = r.render(&cam, &fs).unwrap();
            assert!(common::all_finite(&f.radiance));
            metrics::rel_mse(&f.radiance, &refl.radiance)
        })
        .collect()
}

/// A measurement (not run by default; docs/methods.md quotes it): rel MSE, MSE and mean luminance
/// by frame of restir with temporal reuse on a static camera against the reference, for the
/// scene, size, VPL count, combination, frames and the accumulation's α in `FVPL_RESTIR`
/// (`scene,width,height,vpls,combine,frames[,alpha[,seed]]`; default
/// `builtin:conference,64,48,1024,biased,32,1`, α 1: restir's temporal reuse alone):
/// `FVPL_RESTIR=builtin:conference,160,120,4096,biased,32 cargo test --release --test restir
/// measure_restir_convergence -- --ignored --nocapture`.
#[test]
#[ignore]
fn measure_restir_convergence() {
    let _serial = serial();
    let spec = std::env::var("FVPL_RESTIR")
        .unwrap_or_else(|_| "builtin:conference,64,48,1024,biased,32".into());
    let v: Vec<&str> = spec.split(',').collect();
    let (w, h, vpls): (u32, u32, u32) = (
        v[1].parse().unwrap(),
        v[2].parse().unwrap(),
        v[3].parse().unwrap(),
    );
    let frames: usize = v[5].parse().unwrap();
    let ctx = common::gpu();
    let s = scene::load(v[0]).unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let cam = s.default_camera();
    let mut fs = settings(w, h, vpls);
    fs.cluster.temporal = true;
    fs.cluster.temporal_alpha = v.get(6).map_or(1.0, |a| a.parse().unwrap());
    if let Some(seed) = v.get(7) {
        fs.frame.seed = seed.parse().unwrap();
    }
    fs.method.restir.restir_combine = settings_combine(v[4]);
    let reference = RenderSettings {
        reference: true,
        ..fs.clone()
    };
    let t = std::time::Instant::now();
    let refl = r.render(&cam, &reference).unwrap();
    println!("reference: {:.1} s wall", t.elapsed().as_secs_f64());
    let lum_ref = metrics::mean_luminance(&refl.radiance);
    let mut first = None;
    for i in 0..frames {
        let f = r.render(&cam, &fs).unwrap();
        assert!(common::all_finite(&f.radiance));
        let rel = metrics::rel_mse(&f.radiance, &refl.radiance);
        let first = *first.get_or_insert(rel);
        println!(
            "{spec} frame {}: rel MSE {rel:.4e} ({:.3} of the first), MSE {:.4e}, mean luminance {:.5} (reference {lum_ref:.5})",
            i + 1,
            rel / first,
            metrics::mse(&f.radiance, &refl.radiance),
            metrics::mean_luminance(&f.radiance)
        );
    }
}

/// `fs` with temporal reuse at α 1 (restir's own reuse, no accumulation).
fn reusing(mut fs: RenderSettings) -> RenderSettings {
    fs.cluster.temporal = true;
    fs.cluster.temporal_alpha = 1.0;
    fs
}

fn settings_combine(s: &str) -> Combine {
    fuzzy_vpl::method::restir::settings::parse_combine(s).unwrap()
}

/// The unbiased mean on the third built-in, `builtin:dense-3m` (the conference room with a 3.0
/// M-triangle rug), as on the other two; ignored by default (its BVH takes a while on lavapipe's
/// CPU): `cargo test --release --test restir dense -- --ignored --nocapture`.
#[test]
#[ignore]
fn restir_unbiased_mean_is_the_reference_on_dense_3m() {
    let _serial = serial();
    let ctx = common::gpu();
    let s = scene::load("builtin:dense-3m").unwrap();
    assert_unbiased_mean_is_the_reference(&ctx, "builtin:dense-3m", &s);
}
