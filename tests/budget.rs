//! `--target-ms` with a budget that binds: the controller (`render::budget::fit`) must lower K from its
//! start to meet a budget below both the default settings' frame and its own first frame, and the
//! settings it settles on must take the budget within ±25% on lavapipe. (Its model fitting,
//! `Split::of`, and its steps on a known time model are unit tests in `src/gi/budget.rs`.)
//!
//! Sizes: conference at 160×120 with 4096 VPLs. Measured on lavapipe (2-core VM, load 2–2.5 from
//! another session's work): the default settings (K_SP 3072, K_VPL 1024) take 770–850 ms a frame,
//! the controller's start (K_SP 192, K_VPL 1000) 170–197 ms, of which ~46 ms primary rays and direct
//! light and ~20 ms SP clustering do not shrink with K. Half the start's time (85–100 ms) binds
//! (K_VPL must fall 3–4×, to 230–350) yet stays well above the fewest clusters' frame (~70 ms), so K
//! alone can meet it and one slow frame does not push the controller to its bounds; frames of
//! ~100 ms are long enough that scheduling jitter is a few percent of them. The budget is taken from
//! the start's measured time, so a slower (loaded) machine gets a budget that binds just as much.
//! Measured in 7 runs: the chosen settings −9% to +9% from the budget after 2 or 3 frames (the ±10%
//! the controller stops at), the test ~3 s.

mod common;

use std::sync::Mutex;

use fuzzy_vpl::render::budget::{self, Budget};
use fuzzy_vpl::render::pipeline::{RenderSettings, Renderer};
use fuzzy_vpl::scene;
use fuzzy_vpl::settings::FrameSettings;

/// The tests here take turns on the device: the budget's frames are timed, and the other test
/// rendering beside them shares lavapipe's two cores (in a run where the budget test failed, the
/// chosen settings' frames took 68.8, 87.4 and 93.4 ms against a budget of 64.6).
static DEVICE: Mutex<()> = Mutex::new(());

#[test]
fn a_budget_that_binds_moves_k_and_lands_within_25_percent() {
    let _turn = DEVICE.lock().unwrap_or_else(|e| e.into_inner());
    let ctx = common::gpu();
    let s = scene::load("builtin:conference").unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let cam = s.default_camera();
    let (w, h, vpls) = (160u32, 120u32, 4096u32);
    let defaults = RenderSettings {
        frame: FrameSettings {
            width: w,
            height: h,
            vpls,
            ..Default::default()
        },
        ..Default::default()
    };
    // The frame time of the default settings and of the controller's start (the faster of two
    // frames each: the first may wait for the resident VPL work).
    let fastest = |r: &mut Renderer, st: &RenderSettings| -> f64 {
        (0..2)
            .map(|_| {
                let f = r.render(&cam, st).unwrap();
                assert!(common::all_finite(&f.radiance));
                f.frame_ms()
            })
            .fold(f64::INFINITY, f64::min)
    };
    let start = Budget::new(1.0, &defaults).start(&defaults);
    let default_ms = fastest(&mut r, &defaults);
    let start_ms = fastest(&mut r, &start);
    let target = 0.5 * start_ms;
    println!(
        "default settings {default_ms:.1} ms, start (K_SP {}, K_VPL {}) {start_ms:.1} ms, budget {target:.1} ms",
        start.cluster.sp_clusters, start.cluster.vpl_clusters
    );
    assert!(target < default_ms, "the budget does not bind");

    let (chosen, b, last) = budget::fit(&mut r, &cam, &defaults, target).unwrap();
    assert!(common::all_finite(&last.radiance));
    println!(
        "chose K_SP {}, K_VPL {}, {} direct samples; steps {:?}",
        chosen.cluster.sp_clusters,
        chosen.cluster.vpl_clusters,
        chosen.frame.direct_samples,
        b.steps
    );
    // K moved down from the start, K_SP on the line.
    assert!(b.steps.len() >= 2, "{:?}", b.steps);
    assert!(
        chosen.cluster.vpl_clusters < start.cluster.vpl_clusters,
        "{:?}",
        b.steps
    );
    assert_eq!(
        chosen.cluster.sp_clusters,
        budget::k_sp_on_line(chosen.cluster.vpl_clusters, w * h, vpls)
    );
    // The settings it chose take the budget within ±25%: the median of the controller's last frame
    // and two more frames of them (one slow frame of a loaded machine is not the settings' time).
    let mut t = vec![last.frame_ms()];
    t.extend((0..2).map(|_| r.render(&cam, &chosen).unwrap().frame_ms()));
    t.sort_by(f64::total_cmp);
    let off = t[1] / target - 1.0;
    println!(
        "frames of the chosen settings {t:.1?} ms: median {:+.1}%",
        100.0 * off
    );
    assert!(
        off.abs() <= 0.25,
        "the chosen settings take {t:?} ms against a budget of {target:.1} ms: {:?}",
        b.steps
    );
}

/// The viewer's frames under a time budget (`render::timed::FrameLoop::stepping_budget`): the first
/// frame runs at the controller's start, each next frame at the K's the last one chose, and a
/// budget far below any frame's time moves them down; a loop that does not step the budget (`render`,
/// `bench`) renders the settings as given. Cornell 64×48, 1024 VPLs (frames of tens of ms against a
/// 1 ms budget).
#[test]
fn the_frame_loop_steps_the_viewers_budget() {
    use fuzzy_vpl::render::timed::FrameLoop;
    let _turn = DEVICE.lock().unwrap_or_else(|e| e.into_inner());
    let ctx = common::gpu();
    let s = scene::load("builtin:cornell").unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let cam = s.default_camera();
    let mut rs = RenderSettings {
        frame: FrameSettings {
            width: 64,
            height: 48,
            vpls: 1024,
            ..Default::default()
        },
        ..Default::default()
    };
    rs.cluster.target_ms = Some(1.0);
    let ks = |s: &RenderSettings| (s.cluster.sp_clusters, s.cluster.vpl_clusters);
    let start = budget::Controller::new(&rs).unwrap().ks();
    let mut frames = FrameLoop::stepping_budget();
    let (f, ran) = frames.next(&mut r, &cam, &rs).unwrap();
    assert!(f.radiance.iter().flatten().all(|c| c.is_finite()));
    assert_eq!(ks(&ran), start);
    let next = frames.next_ks().unwrap();
    assert!(next.1 < start.1, "{start:?} -> {next:?}");
    let (_, ran) = frames.next(&mut r, &cam, &rs).unwrap();
    assert_eq!(ks(&ran), next);
    // Without a budget, or in a loop that does not step one, the settings are as given.
    let mut plain = FrameLoop::default();
    let (_, ran) = plain.next(&mut r, &cam, &rs).unwrap();
    assert_eq!((ks(&ran), plain.next_ks()), (ks(&rs), None));
    rs.cluster.target_ms = None;
    let (_, ran) = frames.next(&mut r, &cam, &rs).unwrap();
    assert_eq!((ks(&ran), frames.next_ks()), (ks(&rs), None));
}
