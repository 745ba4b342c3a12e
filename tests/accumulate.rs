//! Temporal accumulation of the indirect light (`gi::accumulate`, docs/temporal.md "Accumulation"):
//! the kernel against hand-worked reprojections with each of its rejections, against its CPU twin,
//! and in whole frames.

mod common;

use fuzzy_vpl::cpu::accumulate as twin;
use fuzzy_vpl::gi::accumulate::AccumulateParams;
use fuzzy_vpl::gi::pass::Pass;
use fuzzy_vpl::gi::primary::CameraParams;
use fuzzy_vpl::render::{RenderSettings, Renderer};
use fuzzy_vpl::scene;
use fuzzy_vpl::settings::{ClusterSettings, FrameSettings};
use glam::Vec3;

const W: u32 = 16;
const H: u32 = 12;
/// Depth of the plane the views see.
const DEPTH: f32 = 5.0;
/// Side of a pixel on that plane: a 90° vertical field of view spans 2 × DEPTH over H pixels.
const PIXEL: f32 = 2.0 * DEPTH / H as f32;

/// A W×H view from `eye` down −Z with a 90° vertical field of view.
fn view(eye: Vec3) -> CameraParams {
    let cam = scene::Camera::look_at("c", eye, eye - Vec3::Z, Vec3::Y, 90f32.to_radians());
    CameraParams::new(&cam, W, H)
}

/// The G-buffer (4 vec4s a pixel) of `cam` looking at the plane z = −DEPTH (normal +Z), with the
/// pixels `(pixel, depth, normal)` of `odd` seeing another plane, z = −depth, instead.
fn gbuffer(cam: &CameraParams, odd: &[(u32, f32, Vec3)]) -> Vec<[f32; 4]> {
    let eye = cam.eye_point();
    let mut g = Vec::new();
    for i in 0..W * H {
        let d = cam.ray((i % W) as f32 + 0.5, (i / W) as f32 + 0.5);
        let (depth, n) = odd
            .iter()
            .find(|o| o.0 == i)
            .map_or((DEPTH, Vec3::Z), |o| (o.1, o.2));
        // On the plane z = −depth (world).
        let p = eye + d * ((eye.z + depth) / -d.z);
        g.extend([
            [p.x, p.y, p.z, 1.0],
            [n.x, n.y, n.z, 0.0],
            [0.5, 0.5, 0.5, 1.0],
            [0.0; 4],
        ]);
    }
    g
}

/// History of `frames` frames: pixel j holds (j, 2j, 0).
fn history(frames: f32) -> Vec<[f32; 4]> {
    (0..W * H)
        .map(|j| [j as f32, 2.0 * j as f32, 0.0, frames])
        .collect()
}

/// A pixel of a G-buffer row, indirect light or history.
type Px = [f32; 4];

const CUR: [f32; 4] = [100.0, 50.0, 7.0, 0.0];

fn close(a: [f32; 4], b: [f32; 4]) -> bool {
    a.iter()
        .zip(b)
        .all(|(x, y)| (x - y).abs() <= 1e-4 * (1.0 + y.abs()))
}

/// The kernel on the GPU and its twin on the same data, which must agree bit for bit on lavapipe.
fn run(
    r: &mut Renderer,
    p: &AccumulateParams,
    g: &[[f32; 4]],
    prev: Option<(&[Px], &[Px])>,
    indirect: &[[f32; 4]],
) -> Vec<[f32; 4]> {
    let gpu = r.accumulate_buffers(p, g, indirect, prev).unwrap();
    let (pg, ph) = prev.unwrap_or((g, indirect));
    let cpu = twin::accumulate(p, g, pg, ph, indirect);
    common::assert_twins(
        r.ctx,
        "accumulate",
        "accumulate::twin",
        (gpu.iter().zip(&cpu)).flat_map(|(a, b)| {
            [
                (Vec3::from_slice(&b[..3]), Vec3::from_slice(&a[..3])),
                (Vec3::splat(b[3]), Vec3::splat(a[3])),
            ]
        }),
    );
    gpu
}

/// The previous camera a quarter pixel to the left: every point lands a quarter pixel right of its
/// pixel centre there, so its history is 3/4 of its own pixel's plus 1/4 of the right neighbour's.
#[test]
fn a_quarter_pixel_move_blends_two_taps_by_hand() {
    let ctx = common::gpu();
    let sc = scene::load("builtin:cornell").unwrap();
    let mut r = Renderer::new(&ctx, &sc).unwrap();
    let cam = view(Vec3::ZERO);
    let prev = view(Vec3::new(-0.25 * PIXEL, 0.0, 0.0));
    let (row, col) = (5u32, 7u32);
    let occluded = row * W + 3 + 1; // pixel (4, 5) of the previous frame: a nearer surface
    let turned = row * W + 9 + 1; // pixel (10, 5): the plane's depth, but facing +X
    let g = gbuffer(&cam, &[]);
    let pg = gbuffer(&prev, &[(occluded, 3.0, Vec3::Z), (turned, DEPTH, Vec3::X)]);
    let cur = vec![CUR; (W * H) as usize];
    let alpha = 0.2;
    let p = AccumulateParams::new(&cam, Some(&prev), alpha);
    // One frame of history: its mean with the new frame (α = max(1/2, 0.2)).
    let out = run(&mut r, &p, &g, Some((&pg, &history(1.0))), &cur);
    let j = (row * W + col) as f32;
    let hist = [
        0.75 * j + 0.25 * (j + 1.0),
        2.0 * (0.75 * j + 0.25 * (j + 1.0)),
    ];
    let want = [
        0.5 * hist[0] + 0.5 * CUR[0],
        0.5 * hist[1] + 0.5 * CUR[1],
        0.5 * CUR[2],
        2.0,
    ];
    let got = out[(row * W + col) as usize];
    assert!(close(got, want), "{got:?} vs {want:?}");
    // Rejected taps leave the other one alone (its weight renormalised): a nearer surface, another
    // orientation, and the image's edge.
    for (x, why) in [(3u32, "depth"), (9, "normal"), (W - 1, "edge")] {
        let i = row * W + x;
        let h = i as f32;
        let want = [0.5 * h + 0.5 * CUR[0], h + 0.5 * CUR[1], 0.5 * CUR[2], 2.0];
        let got = out[i as usize];
        assert!(close(got, want), "{why}: {got:?} vs {want:?}");
    }
    // A long history: weight α for the new frame, and the count capped at 1/α.
    let out = run(&mut r, &p, &g, Some((&pg, &history(9.0))), &cur);
    let want = [
        0.8 * hist[0] + 0.2 * CUR[0],
        0.8 * hist[1] + 0.2 * CUR[1],
        0.2 * CUR[2],
        5.0,
    ];
    let got = out[(row * W + col) as usize];
    assert!(close(got, want), "{got:?} vs {want:?}");
    // Three frames: α = max(1/4, 0.2); the count goes to 4.
    let out = run(&mut r, &p, &g, Some((&pg, &history(3.0))), &cur);
    let got = out[(row * W + col) as usize];
    let want = [
        0.75 * hist[0] + 0.25 * CUR[0],
        0.75 * hist[1] + 0.25 * CUR[1],
        0.25 * CUR[2],
        4.0,
    ];
    assert!(close(got, want), "{got:?} vs {want:?}");
}

/// Where nothing may be blended the frame's own light passes unchanged, with a history of one.
#[test]
fn no_history_no_surface_and_points_behind_the_eye_start_afresh() {
    let ctx = common::gpu();
    let sc = scene::load("builtin:cornell").unwrap();
    let mut r = Renderer::new(&ctx, &sc).unwrap();
    let cam = view(Vec3::ZERO);
    let mut g = gbuffer(&cam, &[]);
    // Pixel 0 sees nothing.
    g[0] = [0.0; 4];
    let cur: Vec<[f32; 4]> = (0..W * H).map(|i| [i as f32, 1.0, 2.0, 0.0]).collect();
    let fresh = |o: &[[f32; 4]]| (o.iter().zip(&cur)).all(|(a, c)| a[..3] == c[..3] && a[3] == 1.0);
    let none = AccumulateParams::new(&cam, None, 0.5);
    assert!(fresh(&run(&mut r, &none, &g, None, &cur)));
    // The previous camera beyond the plane looking away: every point is behind its eye.
    let behind = {
        let c = scene::Camera::look_at(
            "b",
            Vec3::new(0.0, 0.0, -10.0),
            Vec3::new(0.0, 0.0, -11.0),
            Vec3::Y,
            1.5,
        );
        CameraParams::new(&c, W, H)
    };
    let p = AccumulateParams::new(&cam, Some(&behind), 0.5);
    let pg = gbuffer(&behind, &[]);
    assert!(fresh(&run(
        &mut r,
        &p,
        &g,
        Some((&pg, &history(4.0))),
        &cur
    )));
    // The same camera: each pixel reads its own history (no bilinear mix of its neighbours), except
    // pixel 0, which sees nothing.
    let same = AccumulateParams::new(&cam, Some(&cam), 0.5);
    assert_eq!(same.size[3], 1);
    let h = history(1.0);
    let out = run(&mut r, &same, &g, Some((&g, &h)), &cur);
    for (i, o) in out.iter().enumerate().skip(1) {
        let want = [0, 1, 2].map(|c| 0.5 * h[i][c] + 0.5 * cur[i][c]);
        assert_eq!(o[..3], want, "pixel {i}");
        assert_eq!(o[3], 2.0);
    }
    assert_eq!(out[0], [0.0, 1.0, 2.0, 1.0]);
}

/// GPU against twin on a view that moves and turns over a scene of two depths, with histories of
/// every length.
#[test]
fn accumulation_matches_its_twin_on_a_moving_view() {
    let ctx = common::gpu();
    let sc = scene::load("builtin:cornell").unwrap();
    let mut r = Renderer::new(&ctx, &sc).unwrap();
    let cam = view(Vec3::ZERO);
    let prev = {
        let eye = Vec3::new(2.37 * PIXEL, -0.21 * PIXEL, 0.3);
        let c = scene::Camera::look_at(
            "p",
            eye,
            eye + Vec3::new(0.03, 0.01, -1.0),
            Vec3::Y,
            90f32.to_radians(),
        );
        CameraParams::new(&c, W, H)
    };
    // A nearer box over the middle columns in both frames.
    let boxed = |c: &CameraParams| {
        let odd: Vec<_> = (0..W * H)
            .filter(|i| (6..10).contains(&(i % W)))
            .map(|i| (i, 3.0, Vec3::new(0.0, 0.1, 1.0).normalize()))
            .collect();
        gbuffer(c, &odd)
    };
    let (g, pg) = (boxed(&cam), boxed(&prev));
    let mut rng = common::Rand(7);
    let h: Vec<[f32; 4]> = (0..W * H)
        .map(|_| {
            [
                rng.f32(),
                rng.f32(),
                rng.f32(),
                1.0 + (rng.next_u32() % 8) as f32,
            ]
        })
        .collect();
    let cur: Vec<[f32; 4]> = (0..W * H)
        .map(|_| [rng.f32(), rng.f32(), rng.f32(), 0.0])
        .collect();
    let p = AccumulateParams::new(&cam, Some(&prev), 0.3);
    let out = run(&mut r, &p, &g, Some((&pg, &h)), &cur);
    // Some pixels blended, some started afresh (the box's edges), none lost.
    let blended = out.iter().filter(|o| o[3] > 1.0).count();
    assert!(
        blended > (W * H / 2) as usize && blended < (W * H) as usize,
        "{blended}"
    );
    assert!(out.iter().all(|o| o.iter().all(|v| v.is_finite())));
}

fn small(temporal: bool, alpha: f32) -> RenderSettings {
    RenderSettings {
        frame: FrameSettings {
            width: 48,
            height: 36,
            vpls: 256,
            direct_samples: 1,
            ..Default::default()
        },
        cluster: ClusterSettings {
            vpl_clusters: 32,
            sp_clusters: 24,
            temporal,
            temporal_alpha: alpha,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// The pass runs only with temporal reuse on, α below 1 and a clustered frame; without it a frame
/// is what it was.
#[test]
fn the_pass_runs_with_temporal_reuse_and_leaves_other_frames_alone() {
    let sc = scene::load("builtin:cornell").unwrap();
    let has = |s: &RenderSettings| Renderer::passes_for(&sc, s).contains(&Pass::Accumulate);
    assert!(has(&small(true, 0.7)));
    assert!(!has(&small(false, 0.7)));
    assert!(!has(&small(true, 1.0)));
    assert!(!has(&RenderSettings {
        reference: true,
        ..small(true, 0.7)
    }));
    // The first frame has no history: the image is the one without the pass, bit for bit.
    let ctx = common::gpu();
    let mut r = Renderer::new(&ctx, &sc).unwrap();
    let cam = sc.default_camera();
    let on = r.render(&cam, &small(true, 0.7)).unwrap();
    r.forget_past();
    let off = r.render(&cam, &small(false, 0.7)).unwrap();
    assert!(on.ran(Pass::Accumulate) && !off.ran(Pass::Accumulate));
    assert!(common::all_finite(&on.radiance));
    assert_eq!(on.radiance, off.radiance);
}
