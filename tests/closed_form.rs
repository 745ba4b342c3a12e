//! Closed-form (furnace) tests. The direct-light pass: the light a floor of albedo ρ gets from a sun,
//! a point light, a spot light and a square area emitter, worked in closed form per pixel from the
//! shading point the frame reports. The VPL tracer's particles from that emitter and from the
//! punctual lights against the irradiance they stand for. A closed furnace box: the direct pass, the VPL reference and the path
//! tracer against the bounce sum. Unlike the twin tests (`render`, `reference`) these do not share
//! the light-sampling code they check: a bug in `common/lights.wgsl`'s emitter or punctual sampling,
//! the spot cone, `common/sampling.wgsl`'s triangle sampling or the direct pass's estimator moves
//! the image away from the closed form.
//!
//! The floor is the square [−4, 4]² at y = 0 facing +y, ρ = 0.5; a diffuse surface lit by
//! irradiance E has radiance ρ E / π. The floor's frames are rendered with no VPLs (direct light
//! only). Monte Carlo results are checked on means over pixels (or VPLs) against bounds from their
//! measured spread over seeds.

mod common;

use fuzzy_vpl::render::{RenderSettings, Renderer};
use fuzzy_vpl::scene::{Camera, LightKind, Material, PunctualLight, Scene, Triangle};
use fuzzy_vpl::settings::FrameSettings;
use glam::{Vec2, Vec3, Vec4};

const RHO: f64 = 0.5;
const PI: f64 = std::f64::consts::PI;
const W: u32 = 32;
const H: u32 = 24;

/// The horizontal square [cx − s, cx + s] × [cz − s, cz + s] at height y, facing +y (`up`) or −y.
fn square(cx: f32, cz: f32, s: f32, y: f32, up: bool, material: u32) -> [Triangle; 2] {
    let v = |x: f32, z: f32| Vec3::new(cx + x * s, y, cz + z * s);
    let n = if up { Vec3::Y } else { Vec3::NEG_Y };
    let tri = |p: [Vec3; 3]| Triangle {
        // Wound so that the geometric normal is `n`.
        p: if up { p } else { [p[0], p[2], p[1]] },
        n: [n; 3],
        uv: [Vec2::ZERO; 3],
        color: [Vec4::ONE; 3],
        material,
    };
    [
        tri([v(-1.0, -1.0), v(-1.0, 1.0), v(1.0, 1.0)]),
        tri([v(-1.0, -1.0), v(1.0, 1.0), v(1.0, -1.0)]),
    ]
}

/// The floor, with `extra` triangles (material 1, emissive `le`) and punctual `lights`.
fn floor_scene(extra: &[Triangle], le: f32, lights: Vec<PunctualLight>) -> Scene {
    let mut triangles = square(0.0, 0.0, 4.0, 0.0, true, 0).to_vec();
    triangles.extend_from_slice(extra);
    for t in &triangles {
        let g = t.geometric_normal();
        assert!(g.dot(t.n[0]) > 0.99, "winding: {g} against {}", t.n[0]);
    }
    Scene {
        name: "floor".into(),
        triangles,
        materials: vec![
            Material {
                base_color: Vec4::new(RHO as f32, RHO as f32, RHO as f32, 1.0),
                ..Material::default()
            },
            Material {
                name: "emitter".into(),
                base_color: Vec4::new(0.0, 0.0, 0.0, 1.0),
                emissive: Vec3::splat(le),
                ..Material::default()
            },
        ],
        lights,
        ..Default::default()
    }
}

/// A camera at height `y` above the origin looking straight down.
fn down_from(y: f32) -> Camera {
    Camera::look_at("down", Vec3::new(0.0, y, 0.0), Vec3::ZERO, Vec3::Z, 1.2)
}

/// The seeds a furnace or particle test averages over: `FVPL_FURNACE_SEEDS`, 4 by default.
fn furnace_seeds() -> u32 {
    std::env::var("FVPL_FURNACE_SEEDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(4u32)
}

/// One seed of a furnace test through `cam`: the reference frame with 4096 VPLs and 16 direct
/// samples (its radiance finite) and 64 paths a pixel traced: (direct, indirect, path-traced).
fn furnace_frames(r: &mut Renderer, cam: &Camera, seed: u32) -> [Vec<[f32; 3]>; 3] {
    let rs = RenderSettings {
        reference: true,
        frame: FrameSettings {
            vpls: 4096,
            ..direct_only(16, seed).frame
        },
        ..Default::default()
    };
    let f = r.render(cam, &rs).unwrap();
    assert!(common::all_finite(&f.radiance));
    let pt = r.path_trace(cam, &rs, 64).unwrap();
    [f.direct, f.indirect, pt.radiance]
}

/// One seed of a particle test: an 8 × 6 reference frame with 16,384 VPLs seen `down_from(0.5)`
/// (its radiance finite); the VPLs stay in `r`.
fn particles_frame(r: &mut Renderer, seed: u32) {
    let rs = RenderSettings {
        reference: true,
        frame: FrameSettings {
            width: 8,
            height: 6,
            vpls: 16384,
            ..direct_only(1, seed).frame
        },
        ..Default::default()
    };
    let f = r.render(&down_from(0.5), &rs).unwrap();
    assert!(common::all_finite(&f.radiance));
}

/// The punctual tests' spot light: I = 5 cd at height 2 pointing down, cone angles `inner` and
/// `outer` rad from its axis.
fn spot_down(inner: f64, outer: f64) -> PunctualLight {
    PunctualLight {
        kind: LightKind::Spot {
            inner_cone: inner as f32,
            outer_cone: outer as f32,
        },
        position: Vec3::new(0.0, 2.0, 0.0),
        direction: Vec3::NEG_Y,
        color: Vec3::ONE,
        intensity: 5.0,
    }
}

fn direct_only(samples: u32, seed: u32) -> RenderSettings {
    RenderSettings {
        frame: FrameSettings {
            width: W,
            height: H,
            vpls: 0,
            seed,
            direct_samples: samples,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// Each pixel's (shading point, radiance) of a frame of `r` from `cam`; every pixel finite and on
/// the floor.
fn floor_pixels(
    r: &mut Renderer,
    cam: &Camera,
    rs: &RenderSettings,
) -> Vec<(glam::DVec3, [f32; 3])> {
    let f = r.render(cam, rs).unwrap();
    assert!(common::all_finite(&f.radiance));
    f.positions
        .iter()
        .zip(&f.radiance)
        .map(|(p, c)| {
            assert!(p[3] > 0.0 && p[1].abs() < 1e-5, "not on the floor: {p:?}");
            (glam::DVec3::new(p[0] as f64, 0.0, p[2] as f64), *c)
        })
        .collect()
}

/// The worst difference of each pixel's radiance (grey: every channel) from `want` of its point,
/// relative to the brightest pixel's closed form; asserts it within `bound`.
fn assert_closed_form(
    name: &str,
    px: &[(glam::DVec3, [f32; 3])],
    want: impl Fn(glam::DVec3) -> f64,
    bound: f64,
) {
    let wants: Vec<f64> = px.iter().map(|(p, _)| want(*p)).collect();
    let peak = wants.iter().cloned().fold(0.0, f64::max);
    assert!(peak > 0.0, "{name}: nothing lit");
    let mut worst = (0.0f64, 0usize);
    for (i, ((_, c), w)) in px.iter().zip(&wants).enumerate() {
        for ch in c {
            let d = (*ch as f64 - w).abs() / peak;
            if d > worst.0 {
                worst = (d, i);
            }
        }
    }
    let (d, i) = worst;
    println!(
        "{name}: worst {d:.2e} of the peak {peak:.4} at pixel {i} ({:?} against {:.6}), bound {bound:.0e}",
        px[i].1, wants[i]
    );
    assert!(
        d <= bound,
        "{name}: pixel {i} {:?}, closed form {}",
        px[i].1,
        wants[i]
    );
}

/// A sun of E = 3 lux (irradiance at normal incidence) whose rays come down 60° from the vertical:
/// every floor point gets E cos 60° = 1.5, radiance ρ · 1.5 / π = 0.2387. Measured on lavapipe:
/// at most 1.34e-7 of the peak (f32 rounding); bound 1.4e-6 (10×, a margin for GPUs, as the
/// oracles').
#[test]
fn sun_on_a_floor_is_e_cos_theta() {
    let t = 60f32.to_radians();
    let sun = PunctualLight {
        kind: LightKind::Directional,
        position: Vec3::ZERO,
        direction: Vec3::new(t.sin(), -t.cos(), 0.0),
        color: Vec3::ONE,
        intensity: 3.0,
    };
    let ctx = common::gpu();
    let s = floor_scene(&[], 0.0, vec![sun]);
    let px = floor_pixels(
        &mut Renderer::new(&ctx, &s).unwrap(),
        &down_from(1.0),
        &direct_only(1, 1),
    );
    assert_closed_form("sun", &px, |_| RHO / PI * 3.0 * 0.5, 1.4e-6);
}

/// A point light of I = 2 cd at height 1.5 and a spot light of I = 5 cd at height 2 pointing down,
/// cone angles 0.3 (inner) and 0.6 rad (outer) from its axis. A floor point at horizontal distance r
/// from the light's foot, d² = h² + r², cos θ = h / d, gets E = I cos θ / d² (inverse square,
/// Lambert), times the spot's glTF falloff t² with t = clamp((cos α − cos 0.6) / (cos 0.3 − cos 0.6),
/// 0, 1), α the angle off its axis (here α = θ): inside the inner cone 1, outside the outer 0. The
/// camera (height 1.5, field of view 1.2 rad) sees all three zones of the spot. Measured on
/// lavapipe: at most 2.1e-7 (point) and 1.13e-6 (spot: t² amplifies the rounding of cos α by
/// 2t / (cos 0.3 − cos 0.6) ≈ 15) of the peak; bounds 10×: 2.2e-6 and 1.2e-5.
#[test]
fn point_and_spot_lights_are_inverse_square_and_the_gltf_cone() {
    let point = PunctualLight {
        kind: LightKind::Point,
        position: Vec3::new(0.0, 1.5, 0.0),
        direction: Vec3::NEG_Y,
        color: Vec3::ONE,
        intensity: 2.0,
    };
    let ctx = common::gpu();
    let s = floor_scene(&[], 0.0, vec![point]);
    let px = floor_pixels(
        &mut Renderer::new(&ctx, &s).unwrap(),
        &down_from(1.0),
        &direct_only(1, 1),
    );
    let lambert = |i: f64, h: f64, p: glam::DVec3| {
        let d2 = h * h + p.x * p.x + p.z * p.z;
        i * (h / d2.sqrt()) / d2
    };
    assert_closed_form("point", &px, |p| RHO / PI * lambert(2.0, 1.5, p), 2.2e-6);

    let (inner, outer) = (0.3f64, 0.6f64);
    let spot = spot_down(inner, outer);
    let s = floor_scene(&[], 0.0, vec![spot]);
    let px = floor_pixels(
        &mut Renderer::new(&ctx, &s).unwrap(),
        &down_from(1.5),
        &direct_only(1, 1),
    );
    let cone = |p: glam::DVec3| {
        let cos_a = 2.0 / (4.0 + p.x * p.x + p.z * p.z).sqrt();
        let t = ((cos_a - outer.cos()) / (inner.cos() - outer.cos())).clamp(0.0, 1.0);
        t * t
    };
    let zones = px.iter().fold([0; 3], |mut z, (p, _)| {
        let c = cone(*p);
        z[if c == 1.0 {
            0
        } else if c > 0.0 {
            1
        } else {
            2
        }] += 1;
        z
    });
    println!("spot: {zones:?} pixels inside the inner cone, between, outside the outer");
    assert!(zones.iter().all(|&n| n > 20), "{zones:?}");
    assert_closed_form(
        "spot",
        &px,
        |p| RHO / PI * lambert(5.0, 2.0, p) * cone(p),
        1.2e-5,
    );
}

/// ∫∫ cos θ cos θ' / d² dA over the rectangle [0, x] × [0, z] (signed: odd in each) parallel to a
/// point's surface at height h above its corner: ½ [a / √(1 + a²) · atan(b / √(1 + a²)) + b / √(1 +
/// b²) · atan(a / √(1 + b²))] with a = x / h, b = z / h (π × the form factor from a differential
/// area to a parallel rectangle, e.g. Howell's catalogue, case B-3).
fn corner(x: f64, z: f64, h: f64) -> f64 {
    let (a, b) = (x / h, z / h);
    let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
    0.5 * (a / sa * (b / sa).atan() + b / sb * (a / sb).atan())
}

/// The same integral over [x0, x1] × [z0, z1] (relative to the point's foot).
fn rect(x0: f64, x1: f64, z0: f64, z1: f64, h: f64) -> f64 {
    corner(x1, z1, h) - corner(x0, z1, h) - corner(x1, z0, h) + corner(x0, z0, h)
}

/// The closed form above against the integral done numerically (midpoint rule, 1000² cells), for a
/// point under a square's centre, under its edge and beside it: a wrong oracle would pass nothing
/// below.
#[test]
fn the_rectangle_integral_is_right() {
    let numeric = |x0: f64, x1: f64, z0: f64, z1: f64, h: f64| {
        let n = 1000;
        let (dx, dz) = ((x1 - x0) / n as f64, (z1 - z0) / n as f64);
        let mut s = 0.0;
        for i in 0..n {
            for j in 0..n {
                let (x, z) = (x0 + (i as f64 + 0.5) * dx, z0 + (j as f64 + 0.5) * dz);
                let d2 = x * x + z * z + h * h;
                s += h * h / (d2 * d2) * dx * dz;
            }
        }
        s
    };
    for (x0, x1, z0, z1, h) in [
        (-0.25, 0.25, -0.25, 0.25, 1.0),
        (0.0, 0.5, -0.25, 0.25, 1.0),
        (0.3, 0.8, 0.1, 0.6, 0.7),
    ] {
        let (c, n) = (rect(x0, x1, z0, z1, h), numeric(x0, x1, z0, z1, h));
        assert!((c / n - 1.0).abs() < 1e-6, "{c} against {n}");
    }
    // A small square far away: its area × cos² / d², with cos = h / d.
    let (c, d2) = (rect(2.0, 2.001, 0.0, 0.001, 1.0), 1.0 + 2.0005f64 * 2.0005);
    assert!((c / (1e-6 / (d2 * d2)) - 1.0).abs() < 1e-3);
}

/// A square emitter of radiance L_e = 4 (side 0.5, area A = 0.25: power Φ = π A L_e = π), at
/// height 1 facing down over the floor. A floor point gets E = L_e ∫∫ cos θ cos θ' / d² dA
/// (`rect`), radiance ρ E / π. The direct pass estimates it with 16 samples of the emitter a pixel;
/// the test takes the mean over the pixels of the ratio pixel / closed form, per seed.
///
/// Tolerance from the spread: over 16 seeds (1–16) on lavapipe the per-seed mean ratio was 1.00009
/// with σ = 1.45e-3 (`SIGMA`); the 4 seeds averaged here must be within 4 σ / √4 = 2.9e-3 of 1 (an
/// unbiased estimator is, with probability > 0.9999). Each pixel is also within a factor 2 of its
/// closed form (measured: 1.24 at worst, 16 samples). `FVPL_FURNACE_SEEDS=16` measures again.
#[test]
fn a_square_emitter_gives_the_closed_form_irradiance() {
    let (half, h, le) = (0.25f32, 1.0f32, 4.0f32);
    let s = floor_scene(&square(0.0, 0.0, half, h, false, 1), le, Vec::new());
    let want = |p: glam::DVec3| {
        let (hh, hf) = (h as f64, half as f64);
        RHO / PI * le as f64 * rect(-hf - p.x, hf - p.x, -hf - p.z, hf - p.z, hh)
    };
    let seeds = furnace_seeds();
    let ctx = common::gpu();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let mut means = Vec::new();
    let mut worst_pixel = 1.0f64;
    for seed in 1..=seeds {
        let px = floor_pixels(&mut r, &down_from(0.5), &direct_only(16, seed));
        let ratios: Vec<f64> = px.iter().map(|(p, c)| c[1] as f64 / want(*p)).collect();
        for r in &ratios {
            let off = r.max(1.0 / r);
            worst_pixel = worst_pixel.max(off);
        }
        means.push(ratios.iter().sum::<f64>() / ratios.len() as f64);
    }
    let m = means.iter().sum::<f64>() / means.len() as f64;
    let sd =
        (means.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (means.len() - 1) as f64).sqrt();
    println!(
        "square emitter: per-seed mean ratios {means:.5?}: mean {m:.5}, σ {sd:.2e}; worst pixel factor {worst_pixel:.3}"
    );
    assert!(worst_pixel < 2.0, "a pixel off by a factor {worst_pixel}");
    let bound = 4.0 * SIGMA / (seeds as f64).sqrt();
    assert!(
        (m - 1.0).abs() <= bound,
        "mean ratio {m} over {seeds} seeds, bound 1 ± {bound}"
    );
}

/// σ of the per-seed mean ratio of `a_square_emitter_gives_the_closed_form_irradiance`, measured
/// over seeds 1–16 on lavapipe.
const SIGMA: f64 = 1.45e-3;

/// Two square emitters of unequal power and area (A: side 0.4 at (−0.6, 0), 1 above the floor, L_e
/// 6, power ∝ 0.96; B: side 1.2 at (0.7, 0.2), 1.4 above, L_e 0.5, power ∝ 0.72: A is chosen with
/// probability 0.57 and has 1/9 of B's area), seen from a camera whose view holds floor lit mostly
/// by A on one side and mostly by B on the other: every pixel against the sum of the two
/// closed forms, the mean ratio over each half of the image separately. Light selection picks an
/// emitter by power (`emitter_index`) and divides by its probability and area (`sample_emitter`'s
/// pdf): a pdf that takes another emitter's power or area, or power for area, or an index off by
/// one, moves light from one half to the other.
///
/// Tolerance from the spread (`FVPL_FURNACE_SEEDS=16`): over seeds 1–16 on lavapipe the per-seed
/// mean ratios of the two halves had σ `TWO_EMITTER_SIGMA`; the mean of the 4 seeds here must be
/// within 4 σ / √4 of 1. Each pixel also within a factor 2.
#[test]
fn two_emitters_of_unequal_power_and_area_give_the_sum_of_their_closed_forms() {
    let (a, b) = (
        (-0.6f32, 0.0f32, 0.2f32, 1.0f32, 6.0f32),
        (0.7, 0.2, 0.6, 1.4, 0.5),
    );
    let mut tris = square(a.0, a.1, a.2, a.3, false, 1).to_vec();
    tris.extend(square(b.0, b.1, b.2, b.3, false, 2));
    let mut s = floor_scene(&tris, a.4, Vec::new());
    s.materials.push(Material {
        name: "emitter b".into(),
        base_color: Vec4::new(0.0, 0.0, 0.0, 1.0),
        emissive: Vec3::splat(b.4),
        ..Material::default()
    });
    let one = |p: glam::DVec3, (cx, cz, half, h, le): (f32, f32, f32, f32, f32)| {
        let (cx, cz, hf, hh) = (cx as f64, cz as f64, half as f64, h as f64);
        RHO / PI
            * le as f64
            * rect(
                cx - hf - p.x,
                cx + hf - p.x,
                cz - hf - p.z,
                cz + hf - p.z,
                hh,
            )
    };
    let want = |p: glam::DVec3| one(p, a) + one(p, b);
    let seeds = furnace_seeds();
    let ctx = common::gpu();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    assert_eq!(r.gpu.emitters.len(), 4, "two squares, two triangles each");
    let cam = Camera::look_at(
        "down",
        Vec3::new(0.05, 0.8, 0.1),
        Vec3::new(0.05, 0.0, 0.1),
        Vec3::Z,
        1.2,
    );
    let mut means = [Vec::new(), Vec::new()];
    let mut worst_pixel = 1.0f64;
    let mut share = [(0.0f64, 0usize); 2];
    for seed in 1..=seeds {
        let px = floor_pixels(&mut r, &cam, &direct_only(16, seed));
        let mut sums = [(0.0f64, 0usize); 2];
        for (p, c) in &px {
            let wa = one(*p, a) / want(*p);
            let side = usize::from(wa < 0.5);
            let ratio = c[1] as f64 / want(*p);
            worst_pixel = worst_pixel.max(ratio.max(1.0 / ratio));
            sums[side].0 += ratio;
            sums[side].1 += 1;
            share[side].0 += wa;
            share[side].1 += 1;
        }
        for k in 0..2 {
            assert!(sums[k].1 > 50, "side {k}: {} pixels", sums[k].1);
            means[k].push(sums[k].0 / sums[k].1 as f64);
        }
    }
    println!(
        "two emitters: worst pixel factor {worst_pixel:.3}; A's mean share of the closed form on each side {:.3}, {:.3}",
        share[0].0 / share[0].1 as f64,
        share[1].0 / share[1].1 as f64
    );
    assert!(worst_pixel < 2.0, "a pixel off by a factor {worst_pixel}");
    for (k, x) in means.iter().enumerate() {
        let m = x.iter().sum::<f64>() / x.len() as f64;
        let sd = (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (x.len() - 1) as f64).sqrt();
        let side = ["lit mostly by A", "lit mostly by B"][k];
        println!(
            "two emitters, pixels {side}: per-seed mean ratios {x:.5?}: mean {m:.5}, σ {sd:.2e}"
        );
        let bound = 4.0 * TWO_EMITTER_SIGMA[k] / (seeds as f64).sqrt();
        assert!(
            (m - 1.0).abs() <= bound,
            "two emitters, pixels {side}: mean ratio {m} over {seeds} seeds, bound 1 ± {bound}"
        );
    }
}

/// σ of the per-seed mean ratios of the two halves of
/// `two_emitters_of_unequal_power_and_area_give_the_sum_of_their_closed_forms`, measured over
/// seeds 1–16 on lavapipe.
const TWO_EMITTER_SIGMA: [f64; 2] = [2.20e-3, 2.69e-3];

/// The inside of the cube [−1, 1]³: every face emits L_e and reflects with albedo ρ, facing in.
fn furnace_box(le: f32, rho: Vec3) -> Scene {
    let mut triangles = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let inward = -sign * Vec3::AXES[axis];
            let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
            let c = |a: f32, b: f32| sign * Vec3::AXES[axis] + a * u + b * v;
            let mut quad = [
                [c(-1.0, -1.0), c(1.0, -1.0), c(1.0, 1.0)],
                [c(-1.0, -1.0), c(1.0, 1.0), c(-1.0, 1.0)],
            ];
            for p in &mut quad {
                if (p[1] - p[0]).cross(p[2] - p[0]).dot(inward) < 0.0 {
                    p.swap(1, 2);
                }
                triangles.push(Triangle {
                    p: *p,
                    n: [inward; 3],
                    uv: [Vec2::ZERO; 3],
                    color: [Vec4::ONE; 3],
                    material: 0,
                });
            }
        }
    }
    Scene {
        name: "furnace".into(),
        triangles,
        materials: vec![Material {
            name: "furnace".into(),
            base_color: rho.extend(1.0),
            emissive: Vec3::splat(le),
            ..Material::default()
        }],
        ..Default::default()
    }
}

/// The furnace: a closed box whose every surface emits L_e = 1 and reflects ρ = 0.5, seen from its
/// centre. With B = 8 bounces (the default) the radiance everywhere is L_e Σ_{k=0}^{B+1} ρ^k: the
/// emission (k = 0), the direct pass's one reflection of the emitters (k = 1, every direction sees
/// an emitter: irradiance π L_e), and the VPLs' k = 2 … B + 1 (a VPL after d + 1 reflections, d <
/// B, lights the pixel through one more); the path tracer's B + 1 vertices with next-event
/// estimation sum the same k = 0 … B + 1. The pixels see the walls at least 0.32 from an edge, so the
/// G-term clamp (0.069 here) drops nothing: VPLs that near lie in the pixel's own plane.
///
/// Checked per seed on the image means (every pixel has the same closed form): the direct frame
/// (emission + direct) against L_e (1 + ρ) = 1.5, the VPL reference's indirect against
/// L_e (ρ² − ρ^{B+2}) / (1 − ρ) = 0.498047, the path tracer (64 samples) against 1.998047.
/// Tolerances from the spread: over seeds 1–16 on lavapipe the per-seed mean ratios were 1.00022
/// (σ 4.67e-3), 0.99612 (σ 1.50e-2) and 1.00036 (σ 4.46e-3) (`FURNACE_SIGMA`); the mean of the 4
/// seeds here must be within 4 σ / √4 of 1. A furnace does not see how directions are sampled (every
/// direction sees the same radiance); `emitted_particles_land_by_the_closed_form` does.
#[test]
fn a_closed_furnace_gives_the_bounce_sum_in_every_pass() {
    let (le, rho) = (1.0f64, 0.5f64);
    let s = furnace_box(le as f32, Vec3::splat(rho as f32));
    let b = fuzzy_vpl::gi::vpl_trace::MAX_DEPTH as i32;
    let sum = |from: i32, to: i32| (from..=to).map(|k| le * rho.powi(k)).sum::<f64>();
    let want = [sum(0, 1), sum(2, b + 1), sum(0, b + 1)];
    let ctx = common::gpu();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let cam = Camera::look_at("in", Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 1.2);
    let seeds = furnace_seeds();
    let mean = |img: &[[f32; 3]]| {
        assert!(common::all_finite(img));
        img.iter().map(|c| c[1] as f64).sum::<f64>() / img.len() as f64
    };
    let mut ratios = vec![Vec::new(); 3];
    for seed in 1..=seeds {
        for (i, img) in furnace_frames(&mut r, &cam, seed).iter().enumerate() {
            ratios[i].push(mean(img) / want[i]);
        }
    }
    for (i, name) in ["direct", "VPL indirect", "path tracer"].iter().enumerate() {
        let x = &ratios[i];
        let m = x.iter().sum::<f64>() / x.len() as f64;
        let sd = (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (x.len() - 1) as f64).sqrt();
        println!(
            "furnace {name}: closed form {:.6}, per-seed mean ratios {x:.5?}: mean {m:.5}, σ {sd:.2e}",
            want[i]
        );
        let bound = 4.0 * FURNACE_SIGMA[i] / (seeds as f64).sqrt();
        assert!(
            (m - 1.0).abs() <= bound,
            "furnace {name}: mean ratio {m} over {seeds} seeds, bound 1 ± {bound}"
        );
    }
}

/// σ of the per-seed mean ratios of the furnace (direct, VPL indirect, path tracer), measured over
/// seeds 1–16 on lavapipe.
const FURNACE_SIGMA: [f64; 3] = [4.67e-3, 1.50e-2, 4.46e-3];

/// The furnace per channel: the same box with albedo ρ = (0.3, 0.5, 0.7), each channel of the
/// direct frame, the VPL reference's indirect and the path tracer against its own closed form
/// (L_e (1 + ρ_c), L_e Σ_{k=2}^{B+1} ρ_c^k, L_e Σ_{k=0}^{B+1} ρ_c^k). The channels' sums differ by
/// 1.6× (direct red against blue) to 9.7× (indirect), so an albedo or a flux whose channels are
/// swapped, or one channel's albedo used for all, is off by far more than the noise.
///
/// Tolerance from the spread (`FVPL_FURNACE_SEEDS=16`): over seeds 1–16 on lavapipe the per-seed
/// mean ratios had at most the σ in `COLOURED_SIGMA` (per pass, the largest of the channels); the
/// mean of the 4 seeds must be within 4 σ / √4 of 1 in every channel.
#[test]
fn a_coloured_furnace_gives_each_channels_bounce_sum() {
    let (le, rho) = (1.0f64, [0.3f64, 0.5, 0.7]);
    let s = furnace_box(
        le as f32,
        Vec3::new(rho[0] as f32, rho[1] as f32, rho[2] as f32),
    );
    let b = fuzzy_vpl::gi::vpl_trace::MAX_DEPTH as i32;
    let sum = |r: f64, from: i32, to: i32| (from..=to).map(|k| le * r.powi(k)).sum::<f64>();
    let want = |c: usize| {
        [
            sum(rho[c], 0, 1),
            sum(rho[c], 2, b + 1),
            sum(rho[c], 0, b + 1),
        ]
    };
    let ctx = common::gpu();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let cam = Camera::look_at("in", Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 1.2);
    let seeds = furnace_seeds();
    let mean = |img: &[[f32; 3]], c: usize| {
        assert!(common::all_finite(img));
        img.iter().map(|x| x[c] as f64).sum::<f64>() / img.len() as f64
    };
    // ratios[pass][channel]: per-seed mean ratios.
    let mut ratios = vec![vec![Vec::new(); 3]; 3];
    for seed in 1..=seeds {
        let [direct, indirect, traced] = furnace_frames(&mut r, &cam, seed);
        for c in 0..3 {
            let got = [mean(&direct, c), mean(&indirect, c), mean(&traced, c)];
            for (i, pass) in ratios.iter_mut().enumerate() {
                pass[c].push(got[i] / want(c)[i]);
            }
        }
    }
    for (i, name) in ["direct", "VPL indirect", "path tracer"].iter().enumerate() {
        for (c, ch) in ["red", "green", "blue"].iter().enumerate() {
            let x = &ratios[i][c];
            let m = x.iter().sum::<f64>() / x.len() as f64;
            let sd =
                (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (x.len() - 1) as f64).sqrt();
            println!(
                "coloured furnace {name} {ch} (ρ {}): closed form {:.6}, per-seed mean ratios {x:.5?}: mean {m:.5}, σ {sd:.2e}",
                rho[c],
                want(c)[i]
            );
            let bound = 4.0 * COLOURED_SIGMA[i] / (seeds as f64).sqrt();
            assert!(
                (m - 1.0).abs() <= bound,
                "coloured furnace {name} {ch}: mean ratio {m} over {seeds} seeds, bound 1 ± {bound}"
            );
        }
    }
}

/// σ of the per-seed mean ratios of the coloured furnace (direct, VPL indirect, path tracer; the
/// largest of the three channels), measured over seeds 1–16 on lavapipe.
const COLOURED_SIGMA: [f64; 3] = [5.76e-3, 1.67e-2, 7.66e-3];

/// The square emitter's particles (the VPL tracer's first hits, `vpl_trace.wgsl`: a point by
/// `sample_emitter`, a direction by `cosine_hemisphere`, the path tracer's bounce sampling too):
/// over the floor the VPLs' flux stands for ρ times the irradiance, so the flux of the VPLs in a
/// region R sums to ρ ∫_R E dA (E in closed form, `rect`, integrated numerically). Every VPL here is
/// a first hit: a particle bounced off the floor escapes upwards or meets the emitter's back, whose
/// albedo is 0. Regions: the centre [−0.5, 0.5]², the ring out to [−1.5, 1.5]², the rest of the
/// floor; and the halves x > 0 and z > 0, which by symmetry hold half the floor's flux. A cosine
/// sampling that leans to the normal or away from it, or one that favours an azimuth, or emitter
/// points not uniform, moves flux between them.
///
/// Tolerance from the spread: with 16,384 VPLs, over seeds 1–16 on lavapipe the per-seed ratios
/// were 1.00005, 0.99743, 1.00420, 1.00121, 1.00114 (σ in `PARTICLE_SIGMA`; the floor catches 95%
/// of the emitter's ρΦ); the mean of the 4 seeds here must be within 4 σ / √4 of 1.
#[test]
fn emitted_particles_land_by_the_closed_form() {
    let (half, h, le) = (0.25f64, 1.0f64, 4.0f64);
    let s = floor_scene(
        &square(0.0, 0.0, half as f32, h as f32, false, 1),
        le as f32,
        Vec::new(),
    );
    // ρ ∫ E over [x0, x1] × [z0, z1] (midpoint rule, cells of 0.01: measured 1e-5 from 0.005).
    let flux_over = |x0: f64, x1: f64, z0: f64, z1: f64| {
        let c = 0.01;
        let (nx, nz) = (
            ((x1 - x0) / c).round() as i32,
            ((z1 - z0) / c).round() as i32,
        );
        let mut sum = 0.0;
        for i in 0..nx {
            for j in 0..nz {
                let (x, z) = (x0 + (i as f64 + 0.5) * c, z0 + (j as f64 + 0.5) * c);
                sum += le * rect(-half - x, half - x, -half - z, half - z, h) * c * c;
            }
        }
        RHO * sum
    };
    let centre = flux_over(-0.5, 0.5, -0.5, 0.5);
    let inner3 = flux_over(-1.5, 1.5, -1.5, 1.5);
    let floor = flux_over(-4.0, 4.0, -4.0, 4.0);
    let want = [centre, inner3 - centre, floor - inner3, 0.5, 0.5];
    let ctx = common::gpu();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    assert_eq!((r.geometry_scale, r.output_scale), (1.0, 1.0));
    let seeds = furnace_seeds();
    let mut ratios = vec![Vec::new(); 5];
    for seed in 1..=seeds {
        particles_frame(&mut r, seed);
        let vpls = &r.vpl_set.as_ref().unwrap().set.vpls;
        let mut got = [0f64; 5];
        for v in vpls {
            let p = Vec3::new(v.pos[0], v.pos[1], v.pos[2]);
            assert!(p.y.abs() < 1e-4, "a VPL off the floor: {p}");
            got[region(p.x as f64, p.z as f64)] += v.flux[1] as f64;
            got[3] += if p.x > 0.0 { v.flux[1] as f64 } else { 0.0 };
            got[4] += if p.z > 0.0 { v.flux[1] as f64 } else { 0.0 };
        }
        let all = got[0] + got[1] + got[2];
        (got[3], got[4]) = (got[3] / all, got[4] / all);
        for i in 0..5 {
            ratios[i].push(got[i] / want[i]);
        }
    }
    for (i, name) in [
        "centre",
        "ring",
        "outside",
        "x > 0 (share)",
        "z > 0 (share)",
    ]
    .iter()
    .enumerate()
    {
        let x = &ratios[i];
        let m = x.iter().sum::<f64>() / x.len() as f64;
        let sd = (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (x.len() - 1) as f64).sqrt();
        println!(
            "particles {name}: closed form {:.6}, per-seed ratios {x:.5?}: mean {m:.5}, σ {sd:.2e}",
            want[i]
        );
        let bound = 4.0 * PARTICLE_SIGMA[i] / (seeds as f64).sqrt();
        assert!(
            (m - 1.0).abs() <= bound,
            "particles {name}: mean ratio {m} over {seeds} seeds, bound 1 ± {bound}"
        );
    }
}

/// σ of the per-seed ratios of `emitted_particles_land_by_the_closed_form` (centre, ring, outside,
/// the halves x > 0 and z > 0), measured over seeds 1–16 on lavapipe.
const PARTICLE_SIGMA: [f64; 5] = [1.21e-2, 6.01e-3, 1.61e-2, 9.39e-3, 8.64e-3];

/// The VPL tracer's particles from the punctual lights (`vpl_trace.wgsl`: the sun's disc of
/// parallel rays, the point light's uniform sphere, the spot's uniform cone weighted by the glTF
/// falloff, each with its power) against the irradiance of the direct-light tests above: over the
/// floor the first hits' flux in a region R sums to ρ ∫_R E dA (E in closed form, integrated
/// numerically; the regions as in `emitted_particles_land_by_the_closed_form`). A particle bounced
/// off the floor escapes: every VPL is a first hit.
///
/// Tolerance from the spread: with 16,384 VPLs, over seeds 1–16 on lavapipe the mean per-seed ratios
/// were 0.981–1.019 (sun 1.019, 1.004, 1.0003; point 1.014, 0.990, 0.997; spot 1.006, 0.996; σ in
/// `PUNCTUAL_SIGMA`); the mean of the 4 seeds here must be within 4 σ / √4 of 1. The spot's outer
/// cone (radius 1.37 on the floor) lies inside the ring: nothing may land outside it.
#[test]
fn punctual_particles_carry_the_lights_power() {
    let t = 60f32.to_radians();
    let (inner, outer) = (0.3f64, 0.6f64);
    let lights = [
        PunctualLight {
            kind: LightKind::Directional,
            position: Vec3::ZERO,
            direction: Vec3::new(t.sin(), -t.cos(), 0.0),
            color: Vec3::ONE,
            intensity: 3.0,
        },
        PunctualLight {
            kind: LightKind::Point,
            position: Vec3::new(0.0, 1.5, 0.0),
            direction: Vec3::NEG_Y,
            color: Vec3::ONE,
            intensity: 2.0,
        },
        spot_down(inner, outer),
    ];
    let lambert = |i: f64, h: f64, x: f64, z: f64| {
        let d2 = h * h + x * x + z * z;
        i * (h / d2.sqrt()) / d2
    };
    let cone = |x: f64, z: f64| {
        let cos_a = 2.0 / (4.0 + x * x + z * z).sqrt();
        let t = ((cos_a - outer.cos()) / (inner.cos() - outer.cos())).clamp(0.0, 1.0);
        t * t
    };
    let irradiance: [&dyn Fn(f64, f64) -> f64; 3] = [
        &|_, _| 3.0 * 0.5,
        &|x, z| lambert(2.0, 1.5, x, z),
        &|x, z| lambert(5.0, 2.0, x, z) * cone(x, z),
    ];
    let names = ["sun", "point", "spot"];
    let seeds = furnace_seeds();
    let ctx = common::gpu();
    for (l, light) in lights.into_iter().enumerate() {
        // ρ ∫ E over the three regions (midpoint rule, cells of 0.01).
        let mut want = [0f64; 3];
        let c = 0.01;
        for i in 0..800 {
            for j in 0..800 {
                let (x, z) = (-4.0 + (i as f64 + 0.5) * c, -4.0 + (j as f64 + 0.5) * c);
                want[region(x, z)] += RHO * irradiance[l](x, z) * c * c;
            }
        }
        let s = floor_scene(&[], 0.0, vec![light]);
        let mut r = Renderer::new(&ctx, &s).unwrap();
        assert_eq!((r.geometry_scale, r.output_scale), (1.0, 1.0));
        let mut ratios = vec![Vec::new(); 3];
        for seed in 1..=seeds {
            particles_frame(&mut r, seed);
            let mut got = [0f64; 3];
            for v in &r.vpl_set.as_ref().unwrap().set.vpls {
                assert!(v.pos[1].abs() < 1e-4, "a VPL off the floor: {:?}", v.pos);
                got[region(v.pos[0] as f64, v.pos[2] as f64)] += v.flux[1] as f64;
            }
            for i in 0..3 {
                if want[i] == 0.0 {
                    // Outside the spot's outer cone: no particle at all.
                    assert_eq!(got[i], 0.0, "{} particles in region {i}", names[l]);
                } else {
                    ratios[i].push(got[i] / want[i]);
                }
            }
        }
        for (i, reg) in ["centre", "ring", "outside"].iter().enumerate() {
            let x = &ratios[i];
            if x.is_empty() {
                continue;
            }
            let m = x.iter().sum::<f64>() / x.len() as f64;
            let sd =
                (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (x.len() - 1) as f64).sqrt();
            println!(
                "{} particles {reg}: closed form {:.6}, per-seed ratios {x:.5?}: mean {m:.5}, σ {sd:.2e}",
                names[l], want[i]
            );
            let bound = 4.0 * PUNCTUAL_SIGMA[l][i] / (seeds as f64).sqrt();
            assert!(
                (m - 1.0).abs() <= bound,
                "{} particles {reg}: mean ratio {m} over {seeds} seeds, bound 1 ± {bound}",
                names[l]
            );
        }
    }
}

/// The region of a floor point: 0 the centre [−0.5, 0.5]², 1 the ring out to [−1.5, 1.5]², 2 the
/// rest.
fn region(x: f64, z: f64) -> usize {
    let m = x.abs().max(z.abs());
    if m < 0.5 {
        0
    } else if m < 1.5 {
        1
    } else {
        2
    }
}

/// σ of the per-seed ratios of `punctual_particles_carry_the_lights_power` (sun, point, spot ×
/// centre, ring, outside), measured over seeds 1–16 on lavapipe.
const PUNCTUAL_SIGMA: [[f64; 3]; 3] = [
    [4.95e-2, 2.47e-2, 7.56e-3],
    [2.98e-2, 1.10e-2, 1.46e-2],
    // Nothing lands outside the spot's outer cone (checked exactly).
    [1.48e-2, 8.52e-3, 0.0],
];
