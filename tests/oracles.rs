//! Independent oracles for the paper's math (issue 22): every expected value here is worked by hand or
//! in closed form, never by a CPU twin, so a bug written into both a kernel and its twin fails here.
//! The GPU passes are driven on constructed inputs (a few points, two pixels, three lights); the
//! bounds are the f32 rounding of the hand-computed values, measured on lavapipe (Mesa 22.3.6).
//!
//! Eq. (5) `gpu_reference_is_eq5_in_closed_form`, Eq. (6) + (8) / (9) `gpu_shading_is_eq6_by_hand`,
//! Eq. (7) `eq7_distance_on_chosen_pairs` and the gated point of the k-means oracle, Eq. (10)
//! `eq10_weights_closed_form` and `gpu_final_assignment_has_the_closed_form_weights`, Alg. 1 / 2 on a
//! point set with a known optimum (same test), the G-term clamp (the near light of the Eq. 5 and 6
//! tests), the visibility pass (step 5) on one occluder quad with the radiance through its matrix
//! (`gpu_visibility_matrix_and_its_radiance_by_hand`), the light list's flux sums, the camera's
//! frustum corners, EXR / PNG round trips.

mod common;

use common::cornell_gpu;

use std::f32::consts::PI;

use fuzzy_vpl::bvh::SceneBvh;
use fuzzy_vpl::cpu::kmeans::{Centroid, Point, eq7_dist, eq10_weights};
use fuzzy_vpl::cpu::vpl::{eq5_cluster_radiance, eq5_vpl_radiance};
use fuzzy_vpl::export;
use fuzzy_vpl::gi::dispatch::Gpu;
use fuzzy_vpl::gi::kmeans::{KMeans, KMeansSettings};
use fuzzy_vpl::gi::primary::{CameraParams, ShadingPoint};
use fuzzy_vpl::gi::reference::{GatherInputs, Reference};
use fuzzy_vpl::gi::scene_gpu::SceneGpu;
use fuzzy_vpl::gi::vpl_cluster;
use fuzzy_vpl::gi::vpl_trace::{Vpl, VplSet};
use fuzzy_vpl::gpu::{GpuContext, profiler::Profiler};
use fuzzy_vpl::method::colom::shade::{Shade, ShadeInputs, ShadeParams};
use fuzzy_vpl::method::colom::visibility::{Previous, VisInputs, Visibility};
use fuzzy_vpl::render::Renderer;
use fuzzy_vpl::scene::{self, Camera};
use fuzzy_vpl::settings::{ClusterLight, Gamma};
use glam::Vec3;

/// `a` within `rel` of `b` (relative, with an absolute floor of `rel` × 1e-3 for values near 0).
fn close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-3)
}

fn close3(a: [f32; 3], b: [f32; 3], rel: f32) -> bool {
    let worst = (0..3)
        .map(|i| (a[i] - b[i]).abs() / b[i].abs().max(1e-3))
        .fold(0f32, f32::max);
    println!("relative difference {worst:e} (bound {rel:e})");
    (0..3).all(|i| close(a[i], b[i], rel))
}

// ---------------------------------------------------------------------------------------------
// Eq. (7) and Eq. (10) on the CPU: chosen pairs, closed-form weights.

fn pt(p: [f32; 3], n: [f32; 3]) -> Point {
    Point {
        pos: Vec3::from(p),
        valid: true,
        nrm: Vec3::from(n).normalize(),
    }
}

fn ctr(p: [f32; 3], n: [f32; 3]) -> Centroid {
    Centroid {
        pos: Vec3::from(p),
        valid: true,
        nrm: Vec3::from(n).normalize(),
    }
}

/// Eq. (7): the Euclidean distance where the normals agree (n·n_c > n_t), else infinite.
#[test]
fn eq7_distance_on_chosen_pairs() {
    let up = [0.0, 0.0, 1.0];
    let p = pt([1.0, 1.0, 0.0], up);
    // A 3-4-5 triangle: exactly 5.
    assert_eq!(eq7_dist(&p, &ctr([4.0, 5.0, 0.0], up), 0.866), 5.0);
    assert_eq!(eq7_dist(&p, &ctr([1.0, 1.0, 0.0], up), 0.866), 0.0);
    // Normals 29° apart agree at n_t = cos 30°, 31° apart do not.
    let tilt = |deg: f32| [deg.to_radians().sin(), 0.0, deg.to_radians().cos()];
    assert_eq!(eq7_dist(&p, &ctr([1.0, 4.0, 4.0], tilt(29.0)), 0.866), 5.0);
    assert_eq!(
        eq7_dist(&p, &ctr([1.0, 4.0, 4.0], tilt(31.0)), 0.866),
        f32::MAX
    );
    // Perpendicular and opposite normals never agree at n_t ≥ 0; the test is strict (n·n_c = n_t
    // does not agree).
    assert_eq!(
        eq7_dist(&p, &ctr([1.0, 1.0, 0.0], [1.0, 0.0, 0.0]), 0.0),
        f32::MAX
    );
    assert_eq!(
        eq7_dist(&p, &ctr([1.0, 1.0, 0.0], [0.0, 0.0, -1.0]), 0.5),
        f32::MAX
    );
    assert_eq!(eq7_dist(&p, &ctr([1.0, 1.0, 3.0], up), 1.0), f32::MAX);
    assert_eq!(eq7_dist(&p, &ctr([1.0, 1.0, 3.0], up), 0.999), 3.0);
    // n_t = -1 lets every normal but the exact opposite through.
    assert_eq!(
        eq7_dist(&p, &ctr([1.0, 3.0, 1.0], [1.0, 0.0, 0.0]), -1.0),
        5f32.sqrt()
    );
}

/// Eq. (10): w_f = (1/d_f) / Σ 1/d_j, generalised to d^-p; a zero distance takes the whole weight,
/// a negative distance is an unused slot.
#[test]
fn eq10_weights_closed_form() {
    let w = |d: &[f32], p: f32| eq10_weights(d, p);
    // Distances 1 and 2: weights 2/3 and 1/3 (f32 rounding of each: within 1 ulp).
    let x = w(&[1.0, 2.0], 1.0);
    assert!(
        close(x[0], 2.0 / 3.0, 2e-7) && close(x[1], 1.0 / 3.0, 2e-7),
        "{x:?}"
    );
    // 1, 2, 4: 4/7, 2/7, 1/7; the order of the slots does not matter.
    let x = w(&[2.0, 4.0, 1.0], 1.0);
    let want = [2.0 / 7.0, 1.0 / 7.0, 4.0 / 7.0];
    assert!((0..3).all(|i| close(x[i], want[i], 3e-7)), "{x:?}");
    // Scale-free: distances 1e-20 and 2e-20 (their reciprocals' sum would overflow nothing but
    // 1/d² would) and 1e20, 2e20 give the same 2/3, 1/3.
    for s in [1e-20f32, 1e20] {
        let x = w(&[s, 2.0 * s], 1.0);
        assert!(
            close(x[0], 2.0 / 3.0, 2e-7) && close(x[1], 1.0 / 3.0, 2e-7),
            "{s}: {x:?}"
        );
    }
    // A zero distance: (1, 0, ...) at its slot, whatever the others.
    assert_eq!(w(&[0.0, 1.0, 2.0], 1.0), vec![1.0, 0.0, 0.0]);
    assert_eq!(w(&[3.0, 0.0, 2.0], 1.0), vec![0.0, 1.0, 0.0]);
    assert_eq!(w(&[0.0, 0.0], 1.0), vec![1.0, 0.0]);
    // Unused slots (negative) get 0 and leave the others normalised.
    assert_eq!(w(&[1.0, -1.0], 1.0), vec![1.0, 0.0]);
    let x = w(&[1.0, -1.0, 2.0], 1.0);
    assert!(close(x[0], 2.0 / 3.0, 2e-7) && x[1] == 0.0 && close(x[2], 1.0 / 3.0, 2e-7));
    // p = 2: 1 and 1/4 → 0.8, 0.2; p = 0: uniform.
    let x = w(&[1.0, 2.0], 2.0);
    assert!(close(x[0], 0.8, 2e-7) && close(x[1], 0.2, 3e-7), "{x:?}");
    assert_eq!(w(&[1.0, 2.0, 4.0, 8.0], 0.0), vec![0.25; 4]);
}

// ---------------------------------------------------------------------------------------------
// Alg. 1 / 2 and Eq. (7), (10) on the GPU: a point set with a known optimum.

fn push(data: &mut Vec<[f32; 4]>, p: [f32; 3], n: [f32; 3]) {
    data.push([p[0], p[1], p[2], 1.0]);
    data.push([n[0], n[1], n[2], 0.0]);
}

/// Three clusters whose optimum is known: A around a = (2, 2, 0) and B around b = (5, 2, 0), normals
/// +z; C around c = (2, 6, 2), normal +x. Every cluster is its centre, four points at ±0.25 about it
/// and two points mirrored about it, so each mean is its centre exactly (dyadic coordinates in a
/// frame of 16: the fixed-point sums are exact). Data order: A, B, C, each starting at its centre,
/// so the strata's first points are the centres (K = 3, γ = 1).
/// - q = (3, 2, 0) (in A) lies at 1 from a and 2 from b: F = 2 weights 2/3, 1/3; (4, 2, 0) in B
///   the mirror: 1/3 for A, 2/3 for B.
/// - the centres lie on their centroids: distance 0, weights (1, 0).
/// - a + (0.25, 0, 0): distances 0.25 and 2.75: weights 11/12, 1/12.
/// - g = (2, 2.5, 0) with normal +x (in C) is nearer to a and b than to c but its normal disagrees
///   with theirs (Eq. 7): its only slot is C, weight 1, the second slot unused.
/// - t = (3.5, 2, 0) lies 1.5 from a and from b (exact): the tie goes to the lower index (A), then
///   weights 1/2, 1/2; had it gone to B, both means would move.
///
/// Nine points a cluster (indices 0–8, 9–17, 18–26).
fn known_optimum() -> Vec<[f32; 4]> {
    let mut d = Vec::new();
    let z = [0.0, 0.0, 1.0];
    let x = [1.0, 0.0, 0.0];
    for c in [[2.0, 2.0, 0.0], [5.0, 2.0, 0.0]] {
        push(&mut d, c, z);
        for o in [[0.25, 0.0], [-0.25, 0.0], [0.0, 0.25], [0.0, -0.25]] {
            push(&mut d, [c[0] + o[0], c[1] + o[1], 0.0], z);
        }
        push(&mut d, [c[0] + 1.0, c[1], 0.0], z);
        push(&mut d, [c[0] - 1.0, c[1], 0.0], z);
        // A: the tie (3.5, 2, 0), 1.5 from a and b, and its mirror; B: a pair at ±0.5 in y.
        let pair = if c[0] == 2.0 { [1.5, 0.0] } else { [0.0, 0.5] };
        // B's pair is tilted ±16° about x (normals (0, ±0.28, 0.96)): B's mean normal is +z only
        // once normalised (length 0.991 before).
        let tilt = |y: f32| if c[0] == 2.0 { z } else { [0.0, y, 0.96] };
        push(&mut d, [c[0] + pair[0], c[1] + pair[1], 0.0], tilt(0.28));
        push(&mut d, [c[0] - pair[0], c[1] - pair[1], 0.0], tilt(-0.28));
    }
    let c = [2.0, 6.0, 2.0];
    push(&mut d, c, x);
    for o in [[0.25, 0.0], [-0.25, 0.0], [0.0, 0.25], [0.0, -0.25]] {
        push(&mut d, [c[0], c[1] + o[0], c[2] + o[1]], x);
    }
    // g and its mirror 2c − g.
    push(&mut d, [2.0, 2.5, 0.0], x);
    push(&mut d, [2.0, 9.5, 4.0], x);
    push(&mut d, [c[0], c[1] + 0.5, c[2]], x);
    push(&mut d, [c[0], c[1] - 0.5, c[2]], x);
    d
}

struct Fuzzy {
    centroids: Vec<[f32; 4]>,
    normals: Vec<[f32; 4]>,
    assign: Vec<u32>,
    weights: Vec<f32>,
    reps: Vec<u32>,
    iterations_run: u32,
}

fn run_kmeans(ctx: &GpuContext, data: &[[f32; 4]], s: &KMeansSettings) -> Fuzzy {
    let m = data.len() as u32 / 2;
    let frame = (Vec3::ZERO, Vec3::splat(16.0));
    let c = common::kmeans_on_cornell(ctx, &KMeans::new(), "oracle", (data, 2), s, frame);
    let f = c.params.f as usize;
    let raw: Vec<[f32; 4]> = ctx
        .read_buffer(&c.centroids, c.params.k as usize * 2)
        .unwrap();
    let reps: Vec<u32> = ctx.read_buffer(&c.reps, c.params.k as usize * 2).unwrap();
    Fuzzy {
        centroids: raw.chunks(2).map(|c| c[0]).collect(),
        normals: raw.chunks(2).map(|c| c[1]).collect(),
        assign: ctx.read_buffer(&c.assign, m as usize * f).unwrap(),
        weights: ctx.read_buffer(&c.weights, m as usize * f).unwrap(),
        reps: reps.chunks(2).map(|r| r[1]).collect(),
        iterations_run: c.counters(ctx).unwrap().iterations_run,
    }
}

fn oracle_settings(f: u32, p: f32, to_reps: bool) -> KMeansSettings {
    KMeansSettings {
        k: 3,
        f,
        gamma: Gamma::Fixed(1),
        normal_threshold: 0.866,
        iterations: 10,
        seed: 3,
        weights_to_reps: to_reps,
        weight_exponent: p,
        plane_gate_deg: None,
        adapt: Default::default(),
    }
}

/// Alg. 1 and 2 on the GPU reach the known optimum and write Eq. (10)'s closed-form weights (with
/// centroid distances and with representative distances, which are the same points here), p = 1
/// and 2, F = 2 and 1. Measured on lavapipe: centroids exact, weights within 1 ulp of the f32 of
/// 2/3 (bound 2e-7 relative).
#[test]
fn gpu_final_assignment_has_the_closed_form_weights() {
    let ctx = common::gpu();
    let data = known_optimum();
    const Q: usize = 5; // (3, 2, 0)
    const QB: usize = 15; // (4, 2, 0)
    const TIE: usize = 7; // (3.5, 2, 0)
    const NEAR: usize = 1; // a + (0.25, 0, 0)
    const G: usize = 23; // (2, 2.5, 0), normal +x
    const NONE: u32 = u32::MAX;
    for to_reps in [false, true] {
        let r = run_kmeans(&ctx, &data, &oracle_settings(2, 1.0, to_reps));
        let tag = format!("weights to reps {to_reps}");
        // Alg. 1: the optimum, reached in the first iteration, stopped after the second.
        let want = [[2.0, 2.0, 0.0], [5.0, 2.0, 0.0], [2.0, 6.0, 2.0]];
        for (k, w) in want.iter().enumerate() {
            assert_eq!(r.centroids[k][..3], w[..], "{tag}: centroid {k}");
            assert!(r.centroids[k][3] > 0.0, "{tag}: centroid {k} invalid");
            // The mean normal, normalised: +z (A, B) and +x (C). Measured: within 1e-7.
            let n = Vec3::new(r.normals[k][0], r.normals[k][1], r.normals[k][2]);
            let want_n = if k == 2 { Vec3::X } else { Vec3::Z };
            assert!(
                (n - want_n).length() < 1e-6,
                "{tag}: centroid {k} normal {n}"
            );
        }
        assert_eq!(r.iterations_run, 2, "{tag}");
        // Representatives: the member nearest its centroid, the centre itself.
        assert_eq!(r.reps, vec![0, 9, 18], "{tag}");
        let slot = |m: usize| (&r.assign[2 * m..2 * m + 2], &r.weights[2 * m..2 * m + 2]);
        // Every point's nearest cluster is its own (Eq. 7 on the data order).
        for m in 0..27 {
            assert_eq!(r.assign[2 * m], (m / 9) as u32, "{tag}: point {m}");
        }
        // Distance 0: the whole weight, for every centre.
        for (m, other) in [(0, 1), (9, 0)] {
            let (a, w) = slot(m);
            assert_eq!(a[1], other, "{tag}: centre {m}");
            assert_eq!(w, [1.0, 0.0], "{tag}: centre {m} on its centroid");
        }
        // Distances 1 and 2.
        let (a, w) = slot(Q);
        assert_eq!(a, [0, 1], "{tag}");
        assert!(
            close(w[0], 2.0 / 3.0, 2e-7) && close(w[1], 1.0 / 3.0, 2e-7),
            "{tag}: {w:?}"
        );
        let (a, w) = slot(QB);
        assert_eq!(a, [1, 0], "{tag}");
        assert!(
            close(w[0], 2.0 / 3.0, 2e-7) && close(w[1], 1.0 / 3.0, 2e-7),
            "{tag}: {w:?}"
        );
        // 0.25 and 2.75: 11/12, 1/12.
        let (a, w) = slot(NEAR);
        assert_eq!(a, [0, 1], "{tag}");
        assert!(
            close(w[0], 11.0 / 12.0, 2e-7) && close(w[1], 1.0 / 12.0, 3e-7),
            "{tag}: {w:?}"
        );
        // The tie: lower index first, equal weights.
        let (a, w) = slot(TIE);
        assert_eq!(a, [0, 1], "{tag}: the tie");
        assert_eq!(w, [0.5, 0.5], "{tag}: the tie");
        // Eq. (7): the +x point near a and b has only C.
        let (a, w) = slot(G);
        assert_eq!(a, [2, NONE], "{tag}");
        assert_eq!(w, [1.0, 0.0], "{tag}");
        // Every point's weights sum to 1.
        for m in 0..27 {
            let (_, w) = slot(m);
            assert!(
                (w[0] + w[1] - 1.0).abs() <= 1.2e-7,
                "{tag}: point {m}: {w:?}"
            );
        }
    }
    // p = 2: 1 and 1/4 → 0.8, 0.2.
    let r = run_kmeans(&ctx, &data, &oracle_settings(2, 2.0, false));
    let w = &r.weights[2 * Q..2 * Q + 2];
    assert!(
        close(w[0], 0.8, 2e-7) && close(w[1], 0.2, 3e-7),
        "p = 2: {w:?}"
    );
    // F = 1 (hard): the nearest cluster, weight 1.
    let r = run_kmeans(&ctx, &data, &oracle_settings(1, 1.0, false));
    for m in 0..27 {
        assert_eq!(
            (r.assign[m], r.weights[m]),
            ((m / 9) as u32, 1.0),
            "F = 1: point {m}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Eq. (5) and Eq. (6) with (8) / (9) on the GPU: two pixels, three lights, by hand.

/// A shading point as the G-buffer holds it (4 vec4s).
type Sp = [[f32; 4]; 4];

fn sp(p: Vec3, n: [f32; 3], albedo: [f32; 3]) -> Sp {
    [
        [p.x, p.y, p.z, 1.0],
        [n[0], n[1], n[2], 0.0],
        [albedo[0], albedo[1], albedo[2], 0.0],
        [0.0; 4],
    ]
}

fn light(p: Vec3, n: [f32; 3], flux: [f32; 3]) -> Vpl {
    Vpl {
        pos: [p.x, p.y, p.z, 1.0],
        nrm: [n[0], n[1], n[2], 0.0],
        flux: [flux[0], flux[1], flux[2], 0.0],
    }
}

const DOWN: [f32; 3] = [0.0, 0.0, -1.0];
const UP: [f32; 3] = [0.0, 0.0, 1.0];
/// π²: a VPL of flux π² lights a surface of albedo ρ with I ρ/π G = ρ G (I = flux/π).
const PI2: f32 = PI * PI;
/// d_min² of the clamp: d_min 0.2.
const DMIN2: f32 = 0.04;

/// Two pixels at o and o + (1, 0, 0), facing +z, and three lights facing −z: L0 at height 1 above
/// pixel 0, L1 at height 1 above pixel 1 (flux π²·(1, 2, 3)), L2 at height 0.1 above pixel 0,
/// nearer than d_min = 0.2. With flux π² the term is ρ cos cos / max(d², d_min²):
/// - pixel 0 (ρ 0.5): L0 0.5; L1 (d² 2, cosines 1/√2) 0.5 · 0.25 · (1, 2, 3); L2 clamped:
///   0.5 / 0.04 = 12.5 (50 without the clamp).
/// - pixel 1 (ρ (1, 0.5, 0.25)): L0 0.25 ρ; L1 ρ · (1, 2, 3); L2 (d² 1.01, cosines 0.1/√1.01)
///   ρ · 0.01 / 1.01².
fn two_pixels_three_lights(o: Vec3) -> (Vec<Sp>, Vec<Vpl>, [[[f32; 3]; 3]; 2]) {
    let ex = Vec3::X;
    let sps = vec![sp(o, UP, [0.5; 3]), sp(o + ex, UP, [1.0, 0.5, 0.25])];
    let lights = vec![
        light(o + Vec3::Z, DOWN, [PI2; 3]),
        light(o + ex + Vec3::Z, DOWN, [PI2, 2.0 * PI2, 3.0 * PI2]),
        light(o + 0.1 * Vec3::Z, DOWN, [PI2; 3]),
    ];
    let g2 = 0.01 / (1.01f32 * 1.01);
    let terms = [
        [[0.5; 3], [0.125, 0.25, 0.375], [12.5; 3]],
        [
            [0.25, 0.125, 0.0625],
            [1.0, 1.0, 0.75],
            [g2, 0.5 * g2, 0.25 * g2],
        ],
    ];
    (sps, lights, terms)
}

/// The G-term clamp and the cosines of Eq. (5)'s terms, on the CPU: the hand values above
/// (measured ≤ 9.5e-8 relative: f32 rounding of π² / π / π; bound 1e-6).
#[test]
fn vpl_term_by_hand() {
    let (sps, lights, terms) = two_pixels_three_lights(Vec3::ZERO);
    for (i, s) in sps.iter().enumerate() {
        for (j, l) in lights.iter().enumerate() {
            let t = eq5_vpl_radiance(
                Vec3::new(s[0][0], s[0][1], s[0][2]),
                Vec3::new(s[1][0], s[1][1], s[1][2]),
                Vec3::new(s[2][0], s[2][1], s[2][2]),
                l,
                DMIN2,
            );
            assert!(
                close3(t.into(), terms[i][j], 1e-6),
                "pixel {i} light {j}: {t}"
            );
        }
    }
    // Facing away (either cosine ≤ 0) gives 0.
    let p = Vec3::ZERO;
    let back = light(Vec3::Z, UP, [1.0; 3]);
    assert_eq!(
        eq5_vpl_radiance(p, Vec3::Z, Vec3::ONE, &back, DMIN2),
        Vec3::ZERO
    );
    let below = light(-Vec3::Z, UP, [1.0; 3]);
    assert_eq!(
        eq5_vpl_radiance(p, Vec3::Z, Vec3::ONE, &below, DMIN2),
        Vec3::ZERO
    );
    // Both cosines negative (a light under the surface facing away): their product is positive, the
    // term still 0.
    let away = light(-Vec3::Z, DOWN, [1.0; 3]);
    assert_eq!(
        eq5_vpl_radiance(p, Vec3::Z, Vec3::ONE, &away, DMIN2),
        Vec3::ZERO
    );
    // Grazing: the light in the pixel's plane gives 0.
    let side = light(Vec3::X, [-1.0, 0.0, 0.0], [1.0; 3]);
    assert_eq!(
        eq5_vpl_radiance(p, Vec3::Z, Vec3::ONE, &side, DMIN2),
        Vec3::ZERO
    );
}

/// Eq. (6) with Ṽ of Eq. (9) and (8) on the GPU shading pass: two pixels, three lights, F = 2, two
/// SP-cluster rows (row 0 sees L0 and L1, row 1 sees L0 and L2). Pixel 0 in rows (0, 1) with
/// weights (0.75, 0.25): Ṽ = 1, 0.75, 0.25 (Eq. 9) or 1, 0.5, 0.5 (Eq. 8); pixel 1 in row 1 alone
/// (second slot unused): Ṽ = 1, 0, 1. Measured on lavapipe: at most 2.2e-7 relative from the hand
/// values (the f32 rounding of π², 1/π and inverseSqrt); bound 2e-6 (a 10× margin for GPUs).
#[test]
fn gpu_shading_is_eq6_by_hand() {
    let ctx = common::gpu();
    let (_sc, gpu) = cornell_gpu(&ctx);
    let (sps, lights, t) = two_pixels_three_lights(Vec3::ZERO);
    let gbuffer = ctx.storage_init("gbuffer", &sps);
    let lights_buf = ctx.storage_init("lights", &lights);
    let bits = ctx.storage_init("bits", &[0b011u32, 0b101]);
    let assign = ctx.storage_init("assign", &[0u32, 1, 1, u32::MAX]);
    let weights = ctx.storage_init("weights", &[0.75f32, 0.25, 1.0, 0.0]);
    let shade = Shade::new();
    let sum = |vs: [f32; 3], px: usize| -> [f32; 3] {
        let mut s = [0f32; 3];
        for (j, v) in vs.iter().enumerate() {
            for c in 0..3 {
                s[c] += t[px][j][c] * v;
            }
        }
        s
    };
    for (weighted, v0) in [(1u32, [1.0, 0.75, 0.25]), (0, [1.0, 0.5, 0.5])] {
        let indirect = ctx.storage("indirect", 2 * 16);
        let mut prof = Profiler::new(&ctx);
        let mut g = Gpu {
            ctx: &ctx,
            scene: &gpu,
            profiler: &mut prof,
        };
        shade.record(
            &mut g,
            &ShadeInputs {
                gbuffer: &gbuffer,
                lights: &lights_buf,
                bits: &bits,
                assign: &assign,
                weights: &weights,
                indirect: &indirect,
                params: ShadeParams {
                    num_lights: 3,
                    words: 1,
                    f: 2,
                    weighted,
                    d_min2: DMIN2,
                    width: 2,
                    height: 1,
                    _pad: 0,
                },
                light: ClusterLight::Spread,
            },
        );
        let out: Vec<[f32; 4]> = ctx.read_buffer(&indirect, 2).unwrap();
        let want = [sum(v0, 0), sum([1.0, 0.0, 1.0], 1)];
        for px in 0..2 {
            let got = [out[px][0], out[px][1], out[px][2]];
            assert!(
                close3(got, want[px], 2e-6),
                "weighted {weighted}, pixel {px}: {got:?}, by hand {:?}",
                want[px]
            );
        }
    }
}

/// The shading pass over a one-pixel G-buffer and one light (`inputs`: G-buffer, lights), F = 1,
/// the pixel's one SP cluster seeing the light: the pixel's indirect light.
fn shade_one_light(
    g: &mut Gpu,
    shade: &Shade,
    inputs: (&wgpu::Buffer, &wgpu::Buffer),
    d_min2: f32,
    light: ClusterLight,
) -> Vec<[f32; 4]> {
    let ctx = g.ctx;
    let indirect = ctx.storage("indirect", 16);
    shade.record(
        g,
        &ShadeInputs {
            gbuffer: inputs.0,
            lights: inputs.1,
            bits: &ctx.storage_init("bits", &[1u32]),
            assign: &ctx.storage_init("assign", &[0u32]),
            weights: &ctx.storage_init("weights", &[1.0f32]),
            indirect: &indirect,
            params: ShadeParams {
                num_lights: 1,
                words: 1,
                f: 1,
                weighted: 1,
                d_min2,
                width: 1,
                height: 1,
                _pad: 0,
            },
            light,
        },
    );
    ctx.read_buffer(&indirect, 1).unwrap()
}

/// `shade_one_light`'s CPU twin: Eq. (6) at `p` with F = 1, the one SP cluster seeing `light`;
/// with `cull`, the twin's tile cull over a tile of `p` alone.
fn twin_one_light(
    p: &ShadingPoint,
    light: &Vpl,
    d_min2: f32,
    cl: ClusterLight,
    cull: bool,
) -> Vec3 {
    use fuzzy_vpl::cpu::shade::{Bits, Slots, TileBounds, eq6_indirect};
    let tile = if cull { TileBounds::of([p]) } else { None };
    let bits = Bits {
        bits: &[1],
        words: 1,
    };
    let slots = Slots {
        assign: &[0],
        weights: &[1.0],
        weighted: true,
    };
    eq6_indirect(
        p,
        std::slice::from_ref(light),
        &bits,
        &slots,
        d_min2,
        cl,
        tile.as_ref(),
    )
}

/// The shade pass's tile cull, by hand (docs/clustering.md, "Lights no point of a tile can see"):
/// one pixel at the origin facing +z (albedo 1) and one light of flux π² at (1, 0, h) facing −x,
/// so Eq. (5)'s term is cos_p cos_v / d² ≈ h. At h = 1e-6 the point's cosine is within the slack
/// (1e-5 of the largest coordinate, 1 here): the cull drops the light (exactly 0), the walk without
/// it gives h. At h = 1e-3 both give h. Measured on lavapipe: 0 and h to 1e-6 relative.
#[test]
fn gpu_tile_cull_drops_only_lights_in_the_tiles_plane() {
    let ctx = common::gpu();
    let (_sc, gpu) = cornell_gpu(&ctx);
    let mut prof = Profiler::new(&ctx);
    let mut g = Gpu {
        ctx: &ctx,
        scene: &gpu,
        profiler: &mut prof,
    };
    let gbuffer = ctx.storage_init("gbuffer", &[sp(Vec3::ZERO, UP, [1.0; 3])]);
    for h in [1e-6f32, 1e-3] {
        let lights = ctx.storage_init(
            "lights",
            &[light(Vec3::new(1.0, 0.0, h), [-1.0, 0.0, 0.0], [PI2; 3])],
        );
        let d2 = 1.0 + h * h;
        let want = h / d2 / d2;
        for cull in [false, true] {
            let shade = Shade::with_options(0, cull);
            let got = shade_one_light(
                &mut g,
                &shade,
                (&gbuffer, &lights),
                0.0,
                ClusterLight::Point,
            );
            if cull && h < 1e-5 {
                assert_eq!(got[0][..3], [0.0; 3], "h {h}: culled");
            } else {
                for x in &got[0][..3] {
                    assert!(
                        ((x - want) / want).abs() < 1e-5,
                        "h {h} cull {cull}: {x}, by hand {want}"
                    );
                }
            }
        }
    }
}

/// The shade pass walks each light as it stores it (`cpu::shade::stored_light`; docs/bvh.md,
/// "Lights in two texels": the normal as a 32-bit octahedral code, within `OCT_ERROR` = 1.4e-4 rad,
/// the spread's s and r² rounded to 2^-12), and so does its CPU twin. One pixel at the origin
/// facing +z (albedo 1) and one light of flux π²:
/// - a point light at (1, 0, 1) whose normal is nearly perpendicular to the way to the pixel
///   (cos_v ≈ 2e-3), so that the code's rounding moves Eq. (5)'s term by 0.13 %. Its octahedral
///   coordinates lie more than 20 ulp from a rounding tie of the code, so any division within
///   WGSL's 2.5 ulp gives the twin's code;
/// - a spread light straight above the pixel at height √2, facing it (an axis: an exact code), s
///   0.3 and r² 2.5 + 2^-11 > d² = 2, whose rounded s (1229 / 4096) and r² (2.5 + 2^-10) move
///   the term by about 6e-5.
///
/// The pass agrees with Eq. (5) of the stored light to 1e-4 and 2e-6 relative (measured on
/// lavapipe: 0 and 1.9e-7; a cosine of 2e-3 makes the first 500× as sensitive to a GPU's rounding:
/// one ulp of an inverseSqrt moves it by 1.6e-5), and lies more than 10× that from Eq. (5) of the
/// light as given (measured: 1.3e-3 and 6.0e-5): a pass or twin walking the given light fails.
#[test]
fn gpu_shade_reads_each_light_as_stored() {
    use fuzzy_vpl::cpu::shade::stored_light;
    use fuzzy_vpl::cpu::vpl::eq5_cluster_light;
    let ctx = common::gpu();
    let (_sc, gpu) = cornell_gpu(&ctx);
    let mut prof = Profiler::new(&ctx);
    let mut g = Gpu {
        ctx: &ctx,
        scene: &gpu,
        profiler: &mut prof,
    };
    let pixel = sp(Vec3::ZERO, UP, [1.0; 3]);
    let gbuffer = ctx.storage_init("gbuffer", &[pixel]);
    let spoint = ShadingPoint::from_gpu(&pixel);
    // Along the plane perpendicular to the way to the pixel, (−1, 0, 1) and +y, tilted 2e-3 to it.
    let to_pixel = Vec3::new(-1.0, 0.0, -1.0).normalize();
    let n = (Vec3::new(-1.0, 0.0, 1.0).normalize() + 0.3 * Vec3::Y + 2e-3 * to_pixel).normalize();
    let grazing = light(Vec3::new(1.0, 0.0, 1.0), n.to_array(), [PI2; 3]);
    // oct_encode's n.xy / l1 (l1 as the f32 sum both sides compute) × 2^14, in f64: its distance
    // from a tie (k + 1/2) in ulps of the f32 quotient.
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    for c in [n.x, n.y] {
        let e = c as f64 / l1 as f64;
        let ulp = (e as f32).abs().next_up() - (e as f32).abs();
        let from_tie = ((e * 16384.0).fract().abs() - 0.5).abs() / (ulp as f64 * 16384.0);
        assert!(
            n.z > 0.0 && from_tie > 20.0,
            "{c}: {from_tie} ulp from a tie"
        );
    }
    let mut spread = light(Vec3::new(0.0, 0.0, 2f32.sqrt()), DOWN, [PI2; 3]);
    spread.flux[3] = 0.3;
    spread.nrm[3] = 2.5 + 2f32.powi(-11);
    let mut worst = [0f32; 2];
    for (k, (given, cl, bound)) in [
        (grazing, ClusterLight::Point, 1e-4f32),
        (spread, ClusterLight::Spread, 2e-6),
    ]
    .into_iter()
    .enumerate()
    {
        let term =
            |v: &Vpl| eq5_cluster_light(spoint.pos, spoint.normal, spoint.albedo, v, 0.0, cl).x;
        let (want, as_given) = (term(&stored_light(&given)), term(&given));
        let lights = ctx.storage_init("lights", &[given]);
        let got = shade_one_light(&mut g, &Shade::new(), (&gbuffer, &lights), 0.0, cl);
        let twin = twin_one_light(&spoint, &given, 0.0, cl, false);
        assert_eq!(twin.x, want, "{cl}: the twin walks the stored light");
        for x in &got[0][..3] {
            let rel = ((x - want) / want).abs();
            worst[k] = worst[k].max(rel);
            assert!(rel < bound, "{cl}: pass {x}, stored light {want} ({rel:e})");
        }
        let apart = ((as_given - want) / want).abs();
        assert!(
            apart > 10.0 * bound,
            "{cl}: given {as_given}, stored {want}: only {apart:e} apart"
        );
        println!("{cl}: stored and given {apart:e} apart");
    }
    println!("worst relative difference from the stored light's term: {worst:?}");
}

/// Eq. (5) on the GPU reference pass, closed form: the two pixels and three lights above, far
/// outside the Cornell box (nothing between them: every term counts), and a pixel under the box
/// with a light above it (the box between them: V = 0), next to the same pair beside the box
/// (V = 1: ρ / d²). Measured on lavapipe: at most 1.2e-7 relative from the hand values; bound 2e-6.
#[test]
fn gpu_reference_is_eq5_in_closed_form() {
    let ctx = common::gpu();
    let (sc, gpu) = cornell_gpu(&ctx);
    let (lo, hi) = sc.bounds();
    let o = hi + (hi - lo);
    let (sps, lights, t) = two_pixels_three_lights(o);
    let reference = Reference::new(&ctx, &gpu);
    let run = |sps: &[Sp], lights: &[Vpl]| -> Vec<[f32; 4]> {
        let gbuffer = ctx.storage_init("gbuffer", sps);
        let vpls = ctx.storage_init("vpls", lights);
        let indirect = ctx.storage("indirect", sps.len() as u64 * 16);
        let mut prof = Profiler::new(&ctx);
        let mut g = Gpu {
            ctx: &ctx,
            scene: &gpu,
            profiler: &mut prof,
        };
        reference.record(
            &mut g,
            &GatherInputs {
                gbuffer: &gbuffer,
                lights: &vpls,
                num_lights: lights.len() as u32,
                indirect: &indirect,
                pixels: sps.len() as u32,
                d_min: DMIN2.sqrt(),
                label: "reference",
                light: ClusterLight::Spread,
            },
            &mut |_, _| true,
        );
        ctx.read_buffer(&indirect, sps.len()).unwrap()
    };
    let mut out = run(&sps, &lights);
    // Under / over the box along y (the Cornell box's up), and the same pair beside it along x.
    let c = 0.5 * (lo + hi);
    let h = hi.y - lo.y + 2.0;
    let (yu, yd) = ([0.0, 1.0, 0.0], [0.0, -1.0, 0.0]);
    let beside = Vec3::new(hi.x - lo.x + 1.0, 0.0, 0.0);
    for shift in [Vec3::ZERO, beside] {
        let base = Vec3::new(c.x, lo.y - 1.0, c.z) + shift;
        out.extend(run(
            &[sp(base, yu, [0.5; 3])],
            &[light(base + Vec3::new(0.0, h, 0.0), yd, [PI2; 3])],
        ));
    }
    // A light under pixel 0's plane facing away from it: both cosines negative, nothing between
    // them; Eq. (5) gives 0 (cos⁺ of both), not the positive product of the two negative cosines.
    out.extend(run(&sps[..1], &[light(o - Vec3::Z, DOWN, [PI2; 3])]));
    let got = |i: usize| [out[i][0], out[i][1], out[i][2]];
    assert_eq!(
        got(4),
        [0.0; 3],
        "a light behind the pixel facing away lights it"
    );
    for (px, terms) in t.iter().enumerate() {
        let mut want = [0f32; 3];
        for term in terms {
            for ch in 0..3 {
                want[ch] += term[ch];
            }
        }
        assert!(
            close3(got(px), want, 2e-6),
            "pixel {px}: {:?}, by hand {want:?}",
            got(px)
        );
    }
    // The pixel under the box (its own dispatch) gets 0, the one beside it 0.5 / h².
    assert_eq!(
        got(2),
        [0.0; 3],
        "the box does not shadow the pixel under it"
    );
    let beside_want = 0.5 / (h * h);
    assert!(
        close3(got(3), [beside_want; 3], 2e-6),
        "beside: {:?}, by hand {beside_want}",
        got(3)
    );
}

// ---------------------------------------------------------------------------------------------
// Step 5, the visibility pass, on the GPU: the bit matrix and the radiance it lets through, by hand.

/// The occluder: one quad, [-1, 1] × [-0.5, 1.5] at z = 2, facing −z (both sides block shadow
/// rays). Its diagonal runs from (−1, −0.5) to (1, 1.5): the shadow rays below cross z = 2 at
/// (0, 0) and (0.5, 0), inside a triangle, away from every edge.
fn occluder_quad() -> scene::Scene {
    let v = |x: f32, y: f32| Vec3::new(x, y, 2.0);
    let tri = |p: [Vec3; 3]| scene::Triangle {
        p,
        n: [-Vec3::Z; 3],
        uv: [glam::Vec2::ZERO; 3],
        color: [glam::Vec4::ONE; 3],
        material: 0,
    };
    scene::Scene {
        name: "occluder".into(),
        triangles: vec![
            tri([v(-1.0, -0.5), v(1.0, 1.5), v(1.0, -0.5)]),
            tri([v(-1.0, -0.5), v(-1.0, 1.5), v(1.0, 1.5)]),
        ],
        materials: vec![scene::Material::default()],
        ..Default::default()
    }
}

/// A representative as the visibility pass reads it (kmeans.wgsl `rep_points`): position with
/// w = 1 (a cluster with a representative) or 0 (none), normal with w = 1 where a warm start kept it.
fn rep(p: Vec3, n: [f32; 3], valid: bool, kept: bool) -> [[f32; 4]; 2] {
    [
        [p.x, p.y, p.z, valid as u32 as f32],
        [n[0], n[1], n[2], kept as u32 as f32],
    ]
}

/// P0 = the origin facing +z under the occluder, P1 = (0, 0, 2.5) facing +z above it; 37 lights of
/// flux π² (2 bit words a row, the second one partial):
/// - c0 (0, 0, 1.6) facing −z: between P0 and the occluder. P0 sees it (d = 1.6; a shadow ray
///   running on past it by half its length would hit the quad); it is under P1's plane.
/// - c1 (0, 0, 3) facing −z: above the occluder. Shadowed from P0; P1 sees it (d = 0.5).
/// - c2 (0, 0, 1.5) facing +z: above P0, nothing between, but facing away (n_l · (l − p) > 0): 0.
/// - c3 (0, 0, −1) facing +z, towards P0, but under P0's plane (n · (l − p) < 0): 0.
/// - c4 (1, 0, 0) facing −x: in P0's plane (n · (l − p) = 0, grazing): 0.
/// - c5 (2, 0, 1.5) facing P0 (normal −(0.8, 0, 0.6)): the segment passes z = 2 nowhere (it stays
///   below), P0 sees it: d = 2.5, cos at P0 1.5/2.5 = 0.6, at c5 1.
/// - c6 (0.6, 0, 2.4) facing P0: the segment crosses z = 2 at x = 0.5, inside the quad: shadowed;
///   under P1's plane.
/// - c7 … c35: copies of c1 (P1 sees them, P0 does not); c36 a copy of c0 (the last, partial word).
fn occluder_lights() -> Vec<Vpl> {
    let toward_origin = |p: Vec3| {
        let n = -p.normalize();
        [n.x, n.y, n.z]
    };
    let c5 = Vec3::new(2.0, 0.0, 1.5);
    let c6 = Vec3::new(0.6, 0.0, 2.4);
    let mut l = vec![
        light(1.6 * Vec3::Z, DOWN, [PI2; 3]),
        light(3.0 * Vec3::Z, DOWN, [PI2; 3]),
        light(1.5 * Vec3::Z, UP, [PI2; 3]),
        light(-Vec3::Z, UP, [PI2; 3]),
        light(Vec3::X, [-1.0, 0.0, 0.0], [PI2; 3]),
        light(c5, toward_origin(c5), [PI2; 3]),
        light(c6, toward_origin(c6), [PI2; 3]),
    ];
    while l.len() < 36 {
        l.push(l[1]);
    }
    l.push(l[0]);
    l
}

/// The occluder quad (`occluder_quad`) uploaded on `ctx`, with `lights` (`occluder_lights` for
/// most tests): the scene, the lights' buffer and their number.
fn occluder_upload(ctx: &GpuContext, lights: &[Vpl]) -> (SceneGpu, wgpu::Buffer, u32) {
    let sc = occluder_quad();
    let bvh = SceneBvh::build(&sc).unwrap();
    let buf = ctx.storage_init("lights", lights);
    (SceneGpu::upload(ctx, &sc, &bvh), buf, lights.len() as u32)
}

/// The shading pass with F = 1 (weight 1, 2 words a row of `bits`) over the G-buffer's pixels,
/// pixel m in cluster `assign[m]`, lit by `lights` (buffer, number) as spread lights: each pixel's
/// indirect light.
fn shade_by_cluster(
    g: &mut Gpu,
    gbuffer: &wgpu::Buffer,
    lights: (&wgpu::Buffer, u32),
    bits: &[u32],
    assign: &[u32],
) -> Vec<[f32; 4]> {
    let ctx = g.ctx;
    let pixels = assign.len();
    let bits_buf = ctx.storage_init("bits", bits);
    let indirect = ctx.storage("indirect", pixels as u64 * 16);
    Shade::new().record(
        g,
        &ShadeInputs {
            gbuffer,
            lights: lights.0,
            bits: &bits_buf,
            assign: &ctx.storage_init("assign", assign),
            weights: &ctx.storage_init("weights", &vec![1.0f32; pixels]),
            indirect: &indirect,
            params: ShadeParams {
                num_lights: lights.1,
                words: 2,
                f: 1,
                weighted: 1,
                d_min2: DMIN2,
                width: pixels as u32,
                height: 1,
                _pad: 0,
            },
            light: ClusterLight::Spread,
        },
    );
    ctx.read_buffer(&indirect, pixels).unwrap()
}

/// Runs the visibility pass over `reps` and `lights`: the bit matrix, row by row.
fn run_visibility(
    ctx: &GpuContext,
    gpu: &SceneGpu,
    reps: &[[[f32; 4]; 2]],
    lights: &wgpu::Buffer,
    num_lights: u32,
    previous: Option<&Previous>,
    facing: bool,
) -> Vec<u32> {
    let vis = Visibility::new(ctx, gpu);
    let rep_points = ctx.storage_init("rep points", reps);
    let mut prof = Profiler::new(ctx);
    let mut g = Gpu {
        ctx,
        scene: gpu,
        profiler: &mut prof,
    };
    let inputs = VisInputs {
        rep_points: &rep_points,
        lights,
        num_lights,
        k_sp: reps.len() as u32,
        previous,
        facing,
    };
    let (bits, words) = vis.record(&mut g, &inputs);
    ctx.read_buffer(&bits, (inputs.k_sp * words) as usize)
        .unwrap()
}

/// The paper's V, the default: pure visibility. On the occluder quad of
/// `gpu_visibility_matrix_and_its_radiance_by_hand`, P0's row has every light nothing blocks,
/// whether or not the pair faces each other: c0, c5 and c36 as with the facing test, and also c2
/// (facing away), c3 (under P0's plane) and c4 (grazing), whose shadow rays (along +z below the
/// quad, along −z and along +x) meet nothing: words (0x3d, 0x10); a row without a representative
/// stays (0, 0). The radiance through that matrix is the same 0.438625: Eq. (6) gives c2, c3 and c4
/// nothing through their own cosines. The setting's default is off (a test in `crates/core/src/settings`).
#[test]
fn gpu_visibility_is_pure_visibility_by_default() {
    let ctx = common::gpu();
    let (gpu, lights_buf, n) = occluder_upload(&ctx, &occluder_lights());
    let reps = [
        rep(Vec3::ZERO, UP, true, false),
        rep(Vec3::ZERO, UP, false, false),
    ];
    let facing = fuzzy_vpl::settings::ClusterSettings::default().visibility_facing;
    assert!(!facing, "the paper's V is pure visibility");
    let bits = run_visibility(&ctx, &gpu, &reps, &lights_buf, n, None, facing);
    let want: [u32; 4] = [0x3d, 0x10, 0, 0];
    assert_eq!(bits, want, "bits {bits:08x?}, by hand {want:08x?}");
    let mut prof = Profiler::new(&ctx);
    let mut g = Gpu {
        ctx: &ctx,
        scene: &gpu,
        profiler: &mut prof,
    };
    let gbuffer = ctx.storage_init("gbuffer", &[sp(Vec3::ZERO, UP, [0.5; 3])]);
    let got = shade_by_cluster(&mut g, &gbuffer, (&lights_buf, n), &bits, &[0]);
    for c in 0..3 {
        let rel = (got[0][c] - 0.438625).abs() / 0.438625;
        assert!(rel < 2e-6, "radiance {:?}, by hand 0.438625", got[0]);
    }
}

/// The visibility pass answers a light under a representative's plane from the triangle the
/// representative lies on (`surface_under`, `shadow_ray_blocked_by` in the WGSL) before walking the
/// BVH: the bits must be those of a plain shadow ray. On the occluder quad (z = 2, x in [−1, 1]):
/// P0 at the origin (no surface under it), P2 = (0, 0, 2) on the quad, P3 = (0.9999, 0, 2) on it
/// 1e-4 from its edge, all facing +z (exactly on the edge the probe would miss: a ray along a box's
/// face misses the box, as in the twin); lights a (0, 0, 1) facing +z, b (3, 0, 1.9) facing −x,
/// c (0, 0, 3) facing −z, d (0, 0, −1) facing +z (bits 0–3). e ≥ 8e-6 is the rays' offset. By
/// hand, pure visibility:
/// - P0: a, b and d are free (nothing under the quad; d lies under P0's plane and no surface is
///   under P0), c is behind the quad: 0b1011.
/// - P2: a, b and d lie under its plane, and their rays cross z = 2 within 30e of the origin,
///   inside the quad: blocked; c is free: 0b0100.
/// - P3: a's and d's rays cross z = 2 at x < 0.9999, inside: blocked. b's ray crosses it at
///   x ≈ 0.9999 + 20e > 1, outside the quad: the triangle under P3 does not block it and nothing
///   else does, so b is visible; c is free: 0b0110.
///
/// With the facing test (`--visibility-facing on`): P0 keeps b (a faces away, c is blocked, d is
/// under its plane): 0b0010; P2 and P3 keep c: 0b0100.
#[test]
fn gpu_visibility_under_a_representative_is_plain_visibility() {
    let ctx = common::gpu();
    let lights = [
        light(Vec3::new(0.0, 0.0, 1.0), UP, [PI2; 3]),
        light(Vec3::new(3.0, 0.0, 1.9), [-1.0, 0.0, 0.0], [PI2; 3]),
        light(Vec3::new(0.0, 0.0, 3.0), DOWN, [PI2; 3]),
        light(Vec3::new(0.0, 0.0, -1.0), UP, [PI2; 3]),
    ];
    let (gpu, buf, n) = occluder_upload(&ctx, &lights);
    let reps = [
        rep(Vec3::ZERO, UP, true, false),
        rep(Vec3::new(0.0, 0.0, 2.0), UP, true, false),
        rep(Vec3::new(0.9999, 0.0, 2.0), UP, true, false),
    ];
    for (facing, want) in [
        (false, [0b1011u32, 0b0100, 0b0110]),
        (true, [0b0010, 0b0100, 0b0100]),
    ] {
        let bits = run_visibility(&ctx, &gpu, &reps, &buf, n, None, facing);
        assert_eq!(
            bits, want,
            "facing {facing}: bits {bits:?}, by hand {want:?}"
        );
    }
}

/// The visibility pass (step 5) with the facing test (`--visibility-facing on`, not the paper's) on
/// one occluder quad and the lights of `occluder_lights`, and the radiance the shading pass lets
/// through its matrix. Rows: P0 (row 0), the same point without a
/// representative (row 1: the pass writes 0 without tracing), P1 (row 2). By hand (bit c of word
/// c / 32):
/// - row 0: c0, c5, c36 → words (0x21, 0x10);
/// - row 1: (0, 0);
/// - row 2: c1, c7 … c35 → (0xffff_ff82, 0xf); nothing past light 36 in the partial word.
///
/// Radiance (F = 1, weight 1; flux π², ρ = 0.5: a term is ρ cos cos / d²): P0 in row 0 gets
/// c0 0.5 / 2.56 = 0.1953125 + c5 0.5 · 0.6 / 6.25 = 0.048 + c36 0.1953125 = 0.438625; the same
/// point in row 1 0; P1 in row 2 gets 30 lights at d = 0.5, each 0.5 / 0.25 = 2: 60. The reference
/// pass (Eq. 5, its own shadow rays) on the same points: 0.438625, 0.438625, 60.
///
/// The early exits: the cosine tests (c2 facing away, c3 under the plane, c4 grazing: nothing
/// blocks their shadow rays, so without the tests their bits would be set), no representative
/// (row 1), and the
/// warm start's copied rows, checked with a previous matrix of marker words unlike the traced
/// ones: a row is copied only when its index is below the previous matrix's rows, it has a
/// representative, that representative was kept (normal w = 1), and the previous matrix has as many
/// words a row. The remaining exit, invocations past the chunk's end, writes past the matrix, which
/// wgpu's bounds checks drop: not observable here (`bits` holds exactly the 3 × 2 words read back).
/// Measured on lavapipe: bits exact, radiance at most 6.8e-8 relative from the hand values (the
/// f32 rounding of π² and 1/π); bound 2e-6 as the other GPU oracles.
#[test]
fn gpu_visibility_matrix_and_its_radiance_by_hand() {
    let ctx = common::gpu();
    let (gpu, lights_buf, n) = occluder_upload(&ctx, &occluder_lights());
    let (p0, p1) = (Vec3::ZERO, Vec3::new(0.0, 0.0, 2.5));
    let reps = |kept: [bool; 3]| {
        vec![
            rep(p0, UP, true, kept[0]),
            rep(p0, UP, false, kept[1]),
            rep(p1, UP, true, kept[2]),
        ]
    };
    let traced: [u32; 6] = [0x21, 0x10, 0, 0, 0xffff_ff82, 0xf];
    let bits = run_visibility(&ctx, &gpu, &reps([false; 3]), &lights_buf, n, None, true);
    assert_eq!(
        bits, traced,
        "bit matrix (rows of 2 words): {bits:08x?}, by hand {traced:08x?}"
    );

    // The radiance through that matrix (shading pass, F = 1) and without it (reference pass).
    let sps = vec![
        sp(p0, UP, [0.5; 3]),
        sp(p0, UP, [0.5; 3]),
        sp(p1, UP, [0.5; 3]),
    ];
    let want = [0.438625f32, 0.0, 60.0];
    let gbuffer = ctx.storage_init("gbuffer", &sps);
    let mut prof = Profiler::new(&ctx);
    let mut g = Gpu {
        ctx: &ctx,
        scene: &gpu,
        profiler: &mut prof,
    };
    let shaded = shade_by_cluster(&mut g, &gbuffer, (&lights_buf, n), &bits, &[0, 1, 2]);
    let reference_out = ctx.storage("reference", 3 * 16);
    Reference::new(&ctx, &gpu).record(
        &mut g,
        &GatherInputs {
            gbuffer: &gbuffer,
            lights: &lights_buf,
            num_lights: n,
            indirect: &reference_out,
            pixels: 3,
            d_min: DMIN2.sqrt(),
            label: "reference",
            light: ClusterLight::Spread,
        },
        &mut |_, _| true,
    );
    let reference: Vec<[f32; 4]> = ctx.read_buffer(&reference_out, 3).unwrap();
    for px in 0..3 {
        let got = [shaded[px][0], shaded[px][1], shaded[px][2]];
        assert!(
            got.iter().all(|c| c.is_finite()) && close3(got, [want[px]; 3], 2e-6),
            "shaded pixel {px}: {got:?}, by hand {}",
            want[px]
        );
        let r = [reference[px][0], reference[px][1], reference[px][2]];
        let w = if px == 1 { want[0] } else { want[px] };
        assert!(
            r.iter().all(|c| c.is_finite()) && close3(r, [w; 3], 2e-6),
            "reference pixel {px}: {r:?}, by hand {w}"
        );
    }

    // The warm start's rows: a previous matrix of markers, so that a copied word cannot be mistaken
    // for a traced one.
    let marks: [u32; 6] = [
        0xa5a5_0001,
        0xa5a5_0002,
        0xa5a5_0003,
        0xa5a5_0004,
        0xa5a5_0005,
        0xa5a5_0006,
    ];
    let prev = |rows: u32, words: u32| Previous {
        bits: ctx.storage_init("previous bits", &marks).into(),
        rows,
        words,
    };
    // (name, kept flags, previous rows, previous words a row, the matrix by hand)
    type Case<'a> = (&'a str, [bool; 3], u32, u32, [u32; 6]);
    let cases: [Case; 4] = [
        // Every row kept, the previous matrix 2 rows of 2 words: row 0 copied; row 1 has no
        // representative (0, not the markers); row 2 is past the previous rows (traced).
        (
            "2 previous rows",
            [true; 3],
            2,
            2,
            [marks[0], marks[1], 0, 0, traced[4], traced[5]],
        ),
        // 3 previous rows: row 2 copied too; row 0 not kept (w ≠ 1) is traced.
        (
            "3 previous rows, row 0 not kept",
            [false, true, true],
            3,
            2,
            [traced[0], traced[1], 0, 0, marks[4], marks[5]],
        ),
        // A previous matrix of another row length (other lights): nothing copied.
        ("1 word a previous row", [true; 3], 3, 1, traced),
        // More previous rows than representatives: as 3.
        (
            "5 previous rows",
            [true; 3],
            5,
            2,
            [marks[0], marks[1], 0, 0, marks[4], marks[5]],
        ),
    ];
    for (name, kept, rows, words, want) in cases {
        let p = prev(rows, words);
        let got = run_visibility(&ctx, &gpu, &reps(kept), &lights_buf, n, Some(&p), true);
        assert_eq!(got, want, "{name}: {got:08x?}, by hand {want:08x?}");
    }
}

// ---------------------------------------------------------------------------------------------
// The light list, the camera, the image files.

/// The VPL-cluster light list carries every VPL's flux: per channel its sum equals the VPLs' sum
/// (f64 sums of f32 fluxes, rounded once to f32 per cluster: measured 1 ulp; bound 1e-6 relative),
/// and each light is one of the VPLs (a representative, on a real surface).
#[test]
fn light_list_flux_sums_to_the_vpls_flux() {
    let ctx = common::gpu();
    let (_sc, gpu) = cornell_gpu(&ctx);
    let mut r = common::Rand(7);
    let vpls: Vec<Vpl> = (0..600)
        .map(|i| {
            let p = Vec3::new(r.f32(), r.f32(), 0.0) * 4.0;
            let n = if i % 3 == 0 { [1.0, 0.0, 0.0] } else { UP };
            light(p, n, [r.f32(), 2.0 * r.f32(), 0.5 * r.f32()])
        })
        .collect();
    let set = VplSet {
        buffer: ctx.storage_init("vpls", &vpls),
        vpls: vpls.clone(),
        paths: 600,
    };
    let s = KMeansSettings {
        k: 40,
        ..oracle_settings(1, 1.0, false)
    };
    let mut prof = Profiler::new(&ctx);
    let frame = (Vec3::ZERO, Vec3::splat(4.0));
    let mut g = Gpu {
        ctx: &ctx,
        scene: &gpu,
        profiler: &mut prof,
    };
    let list = vpl_cluster::cluster(&mut g, &KMeans::new(), &set, &s, frame, None).unwrap();
    assert!(
        list.lights.len() > 20 && list.lights.len() <= 40,
        "{}",
        list.lights.len()
    );
    for ch in 0..3 {
        let a: f64 = vpls.iter().map(|v| v.flux[ch] as f64).sum();
        let b: f64 = list.lights.iter().map(|v| v.flux[ch] as f64).sum();
        assert!(
            (a - b).abs() <= 1e-6 * a,
            "channel {ch}: VPLs {a}, lights {b}"
        );
    }
    // Each light is a member VPL's position and normal; the other members' share of its flux and
    // their mean squared distance (`Spread`) are finite and within [0, 1) and [0, 32) (the frame is 4
    // wide).
    for l in &list.lights {
        assert!(
            vpls.iter()
                .any(|v| v.pos == l.pos && v.nrm[..3] == l.nrm[..3]),
            "{l:?}"
        );
        assert!((0.0..1.0).contains(&l.flux[3]), "{l:?}");
        assert!((0.0..32.0).contains(&l.nrm[3]), "{l:?}");
    }
    assert!(
        list.lights
            .iter()
            .any(|l| l.flux[3] > 0.0 && l.nrm[3] > 0.0)
    );
    let back: Vec<Vpl> = ctx.read_buffer(&list.buffer, list.lights.len()).unwrap();
    assert_eq!(
        bytemuck::cast_slice::<Vpl, u8>(&back),
        bytemuck::cast_slice::<Vpl, u8>(&list.lights)
    );
}

/// `set`'s VPLs clustered into one VPL-cluster light (K_VPL 1) by the GPU.
fn one_cluster(g: &mut Gpu, set: &VplSet) -> vpl_cluster::LightList {
    let s = KMeansSettings {
        k: 1,
        ..oracle_settings(1, 1.0, false)
    };
    let frame = (Vec3::splat(-1.0), Vec3::splat(5.0));
    let list = vpl_cluster::cluster(g, &KMeans::new(), set, &s, frame, None).unwrap();
    assert_eq!(list.lights.len(), 1);
    list
}

/// `vpls` (one light path each) as one cluster (`one_cluster`) on `gpu`: the VPL set and its light
/// list.
fn one_cluster_of(
    ctx: &GpuContext,
    gpu: &SceneGpu,
    vpls: &[Vpl],
) -> (VplSet, vpl_cluster::LightList) {
    let set = VplSet {
        buffer: ctx.storage_init("vpls", vpls),
        vpls: vpls.to_vec(),
        paths: vpls.len() as u32,
    };
    let mut prof = Profiler::new(ctx);
    let mut g = Gpu {
        ctx,
        scene: gpu,
        profiler: &mut prof,
    };
    let list = one_cluster(&mut g, &set);
    (set, list)
}

/// The near-field spike of a VPL-cluster light (Sponza's, docs/methods.md "Indirect light, per
/// method"), by hand: VPLs A (0,0,0), C (1,0,0), B (4,0,0), normals +y, flux 1 each, as one cluster
/// (K = 1): the representative is C, nearest the centroid (5/3, 0, 0); the other members' share is
/// 2/3 and their mean squared distance from C (1 + 9) / 2 = 5. At p = (1, 0.1, 0) facing down the
/// members give I ρ G = 1/0.01 (C) + 0.0098 (A) + 0.0001 (B) ≈ 100.01 (times 1/π · ρ); C carrying
/// the summed flux 3 as a point gives 300, three times too much; with the spread 300/3 + 300 · 2/3
/// · 0.01/5 = 100.4. Beyond r = √5 the light is the point's (up to rounding).
#[test]
fn a_cluster_light_spread_over_its_members_has_no_near_field_spike() {
    let ctx = common::gpu();
    let (_sc, gpu) = cornell_gpu(&ctx);
    let up = [0.0, 1.0, 0.0];
    let vpls: Vec<Vpl> = [0.0, 1.0, 4.0]
        .iter()
        .map(|&x| light(Vec3::new(x, 0.0, 0.0), up, [1.0; 3]))
        .collect();
    let (_, list) = one_cluster_of(&ctx, &gpu, &vpls);
    let l = list.lights[0];
    assert_eq!(l.pos, vpls[1].pos, "the representative is C");
    assert_eq!(l.flux, [3.0, 3.0, 3.0, 2.0 / 3.0]);
    assert_eq!(l.nrm, [0.0, 1.0, 0.0, 5.0]);
    let (n, albedo, d_min2) = (Vec3::NEG_Y, Vec3::splat(PI), 1e-4);
    let members = |p: Vec3| -> f32 {
        vpls.iter()
            .map(|v| eq5_vpl_radiance(p, n, albedo, v, d_min2).x)
            .sum()
    };
    let near = Vec3::new(1.0, 0.1, 0.0);
    let (want, got) = (
        members(near),
        eq5_cluster_radiance(near, n, albedo, &l, d_min2).x,
    );
    // I ρ G with I = flux/π, ρ = 1: the hand values over π.
    assert!((want * PI - 100.01).abs() < 0.01, "members {}", want * PI);
    assert!(
        (got * PI - 100.4).abs() < 0.01,
        "cluster light {}",
        got * PI
    );
    let point = eq5_vpl_radiance(near, n, albedo, &l, d_min2).x;
    assert!(
        (point * PI - 300.0).abs() < 0.01,
        "as a point {}",
        point * PI
    );
    let far = Vec3::new(1.0, 3.0, 0.0);
    let (a, b) = (
        eq5_cluster_radiance(far, n, albedo, &l, d_min2).x,
        eq5_vpl_radiance(far, n, albedo, &l, d_min2).x,
    );
    assert!((a - b).abs() <= 1e-6 * b, "beyond r: {a} against {b}");
}

/// `--cluster-light point|spread` on one VPL cluster of two VPLs, by hand, on the GPU (the VPL
/// clustering, the shading pass and the gather) and the CPU twin. In the occluder scene (its quad at
/// z = 2 is above everything here): A at the origin and B at (2, 0, 0), both facing +z, flux π²·1
/// and π²·3 (r + g + b: 3π² and 9π²). K_VPL = 1: the centroid is their midpoint and A, at index 0,
/// is the representative (the nearest member; with the frame (−1, 5) the fixed-point mean lies a
/// hair nearer A). Its light: position A, flux π²·4, the other members' share 9/12 = 0.75, their
/// mean squared distance from A r² = 4. The pixel P = (0, 0, 1) faces −z, albedo 0.5; d² = 1 >
/// d_min² = 0.04, both cosines 1, so a term of flux π²·a is a · 0.5 · G:
/// - point (the paper's Eq. 6): 4 · 0.5 · 1 = **2**;
/// - spread: 2 · (1 − 0.75) + 2 · (1 / max(1, 4)) · 0.75 = 0.5 + 0.375 = **0.875**;
/// - the two VPLs unclustered: A 1 · 0.5 · 1 = 0.5, B (d² 5, cosines 1/√5: G = 1/25) 3 · 0.5 / 25 =
///   0.06: **0.56** either way (a VPL has no spread).
///
/// Measured on lavapipe: exactly the hand values (relative difference 0); bound 2e-6 as the other
/// GPU oracles.
#[test]
fn a_two_vpl_cluster_as_point_or_spread_light_by_hand() {
    let ctx = common::gpu();
    let sc = occluder_quad();
    let bvh = SceneBvh::build(&sc).unwrap();
    let gpu = SceneGpu::upload(&ctx, &sc, &bvh);
    let (a, b) = (Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0));
    let vpls = vec![light(a, UP, [PI2; 3]), light(b, UP, [3.0 * PI2; 3])];
    let (set, list) = one_cluster_of(&ctx, &gpu, &vpls);
    let mut prof = Profiler::new(&ctx);
    let mut g = Gpu {
        ctx: &ctx,
        scene: &gpu,
        profiler: &mut prof,
    };
    let l = list.lights[0];
    assert_eq!(l.pos, vpls[0].pos, "the representative is A");
    let f4 = 4.0 * PI2;
    assert!(
        l.flux[..3].iter().all(|&x| (x - f4).abs() <= 1e-6 * f4),
        "{:?}",
        l.flux
    );
    assert_eq!((l.flux[3], l.nrm[3]), (0.75, 4.0));

    let pixel = sp(Vec3::new(0.0, 0.0, 1.0), DOWN, [0.5; 3]);
    let gbuffer = ctx.storage_init("gbuffer", &[pixel]);
    let worst = std::cell::Cell::new(0f32);
    let close = |got: f32, want: f32, what: &str| {
        let rel = (got - want).abs() / want;
        worst.set(worst.get().max(rel));
        assert!(
            rel < 2e-6,
            "{what}: {got}, by hand {want} (relative {rel:e})"
        );
    };
    for (cl, want) in [(ClusterLight::Point, 2.0f32), (ClusterLight::Spread, 0.875)] {
        // The shading pass (F = 1, the one SP cluster sees the light).
        let got = shade_one_light(&mut g, &Shade::new(), (&gbuffer, &list.buffer), DMIN2, cl);
        for x in &got[0][..3] {
            close(*x, want, &format!("shade, {cl}"));
        }
        // The gather (VPL clusters only: every pixel traces its own shadow ray to the light).
        let gathered = ctx.storage("gathered", 16);
        Reference::new(&ctx, &gpu).record(
            &mut g,
            &GatherInputs {
                gbuffer: &gbuffer,
                lights: &list.buffer,
                num_lights: 1,
                indirect: &gathered,
                pixels: 1,
                d_min: DMIN2.sqrt(),
                label: "gather",
                light: cl,
            },
            &mut |_, _| true,
        );
        let got: Vec<[f32; 4]> = ctx.read_buffer(&gathered, 1).unwrap();
        for x in &got[0][..3] {
            close(*x, want, &format!("gather, {cl}"));
        }
        // The CPU twin of the shading pass.
        let spoint = ShadingPoint::from_gpu(&pixel);
        let twin = twin_one_light(&spoint, &list.lights[0], DMIN2, cl, true);
        for c in 0..3 {
            close(twin[c], want, &format!("CPU twin, {cl}"));
        }
        // The two VPLs themselves: 0.56 whichever light mode.
        let raw = ctx.storage("raw", 16);
        Reference::new(&ctx, &gpu).record(
            &mut g,
            &GatherInputs {
                gbuffer: &gbuffer,
                lights: &set.buffer,
                num_lights: 2,
                indirect: &raw,
                pixels: 1,
                d_min: DMIN2.sqrt(),
                label: "reference",
                light: cl,
            },
            &mut |_, _| true,
        );
        let got: Vec<[f32; 4]> = ctx.read_buffer(&raw, 1).unwrap();
        for x in &got[0][..3] {
            close(*x, 0.56, &format!("unclustered, {cl}"));
        }
    }
    println!(
        "worst relative difference from the hand values: {:e}",
        worst.get()
    );
}

/// The camera's frustum: the rays through the corner pixels' centres make the angles the vertical
/// field of view and the aspect give, worked from tan(yfov/2) by hand: for a camera looking down −z
/// with +y up, pixel (x, y) of a w × h image looks along (sx·t·w/h, sy·t, −1), sx = (2x+1)/w − 1,
/// sy = 1 − (2y+1)/h, t = tan(yfov/2). Checked on `CameraParams::ray` and on the GPU's primary
/// rays (the G-buffer positions of a tiny frame lie on those rays: measured sine of the angle
/// ≤ 1e-6; bound 2e-5).
#[test]
fn camera_rays_at_the_frustum_corners() {
    let (w, h) = (8u32, 6u32);
    let yfov = 1.0f32; // radians
    let t = (0.5f32).tan();
    let hand = |x: u32, y: u32| {
        let sx = (2 * x + 1) as f32 / w as f32 - 1.0;
        let sy = 1.0 - (2 * y + 1) as f32 / h as f32;
        Vec3::new(sx * t * w as f32 / h as f32, sy * t, -1.0).normalize()
    };
    let corners = [(0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1)];
    // CPU: an axis-aligned camera.
    let cam = Camera::look_at("t", Vec3::ZERO, -Vec3::Z, Vec3::Y, yfov);
    let cp = CameraParams::new(&cam, w, h);
    for &(x, y) in &corners {
        let d = cp.ray(x as f32 + 0.5, y as f32 + 0.5).normalize();
        assert!(
            (d - hand(x, y)).length() < 1e-6,
            "({x}, {y}): {d} vs {}",
            hand(x, y)
        );
    }
    // The top-left corner is up and left: a sign or axis swap shows here.
    let d = hand(0, 0);
    assert!(d.x < 0.0 && d.y > 0.0);
    // GPU: from the Cornell box's centre towards the back wall (the default camera's direction).
    let ctx = common::gpu();
    let sc = scene::load("builtin:cornell").unwrap();
    let (lo, hi) = sc.bounds();
    let eye = 0.5 * (lo + hi);
    let look = sc.default_camera().forward();
    let cam = Camera::look_at("t", eye, eye + look, Vec3::Y, yfov);
    let mut r = Renderer::new(&ctx, &sc).unwrap();
    let fs = common::gbuffer_settings(w, h);
    r.render(&cam, &fs).unwrap();
    let g = r.last_gbuffer().unwrap();
    let rc = r.to_render_units(&cam);
    // The camera's basis in world space (look_at: right = f × up).
    let f = rc.forward();
    let right = f.cross(Vec3::Y).normalize();
    let up = right.cross(f);
    for &(x, y) in &corners {
        let px = (y * w + x) as usize;
        let p = g[4 * px];
        assert!(p[3] > 0.0, "corner ({x}, {y}) sees nothing");
        let d = (Vec3::new(p[0], p[1], p[2]) - rc.eye()).normalize();
        let c = hand(x, y);
        let want = right * c.x + up * c.y - f * c.z;
        assert!(
            d.cross(want).length() < 2e-5 && d.dot(want) > 0.0,
            "({x}, {y}): {d} vs {want}"
        );
    }
}

/// EXR holds linear radiance: a write / read round trip gives every value back in its channel
/// (distinct R, G, B per pixel, values across 1e-6 … 1e6; exact: f32 EXR).
#[test]
fn exr_round_trip_by_value_and_channel() {
    let dir = common::scratch("oracle-exr");
    let path = dir.join("a.exr");
    let (w, h) = (5u32, 3u32);
    let img: Vec<[f32; 3]> = (0..w * h)
        .map(|i| {
            let i = i as f32;
            [1.0 + i, 1000.0 + 0.5 * i, 1e-6 * (i + 1.0)]
        })
        .collect();
    let mut img = img;
    img[0] = [1e6, 0.0, 0.25];
    export::write_exr(&path, w, h, &img).unwrap();
    let (rw, rh, back) = export::read_exr(&path).unwrap();
    assert_eq!((rw, rh), (w, h));
    assert_eq!(back, img);
    let _ = std::fs::remove_dir_all(dir);
}

/// PNG is radiance × exposure, clamped, sRGB-encoded, in R, G, B order: linear 0, 1, 0.5 and 0.001
/// are 0, 255, 188 (1.055·0.5^(1/2.4) − 0.055 = 0.7354) and 3 (12.92·0.001 = 0.0129); exposure 2
/// makes 0.25 into 188; values over 1 and NaN / negative are 255 and 0.
#[test]
fn png_round_trip_by_value_and_channel() {
    assert_eq!(
        export::linear_to_srgb(0.5),
        1.055 * 0.5f32.powf(1.0 / 2.4) - 0.055
    );
    assert!((export::linear_to_srgb(0.5) - 0.735_356_6).abs() < 1e-6);
    assert!((export::linear_to_srgb(0.001) - 0.01292).abs() < 1e-9);
    let dir = common::scratch("oracle-png");
    let path = dir.join("a.png");
    let img = [[0.0, 1.0, 0.5], [0.001, 7.0, f32::NAN], [0.25, -1.0, 0.125]];
    export::write_image(&path, 3, 1, &img, 2.0).unwrap();
    let back = image::open(&path).unwrap().into_rgb8();
    assert_eq!(back.dimensions(), (3, 1));
    // Exposure 2: 0 → 0, 2 → 255, 1 → 255; 0.002 → 12.92·0.002 → 7; 14 → 255; NaN → 0;
    // 0.5 → 188; −2 → 0; 0.25 → 137 (1.055·0.25^(1/2.4) − 0.055 = 0.5371).
    assert_eq!(
        back.into_raw(),
        vec![0, 255, 255, 7, 255, 0, 188, 0, 137],
        "R, G, B of three pixels"
    );
    let _ = std::fs::remove_dir_all(dir);
}
