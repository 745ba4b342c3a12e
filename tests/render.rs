//! Headless rendering on the built-in scenes: finite, lit, GPU equal to the CPU twin, scale-free.

mod common;

use fuzzy_vpl::gi::primary::CameraParams;
use fuzzy_vpl::gi::primary::ShadingPoint;
use fuzzy_vpl::metrics::mean_luminance;
use fuzzy_vpl::render::{Frame, RenderSettings, Renderer};
use fuzzy_vpl::scene::{self, Scene};
#[allow(unused_imports)]
use fuzzy_vpl::settings::{ClusterSettings, FrameSettings, Gamma};
use glam::{Mat4, Vec3};

fn settings(w: u32, h: u32, spp: u32) -> RenderSettings {
    RenderSettings {
        frame: FrameSettings {
            width: w,
            height: h,
            seed: 7,
            direct_samples: spp,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// (CPU twin, GPU) direct light of every pixel of frame `f` of `r`, rendered with seed 7 and `spp`
/// samples (the CPU twin shades the GPU's own shading points).
fn direct_pairs(r: &Renderer, s: &Scene, f: &Frame, spp: u32) -> Vec<(Vec3, Vec3)> {
    let gbuf = r.last_gbuffer().unwrap();
    let cpu = common::cpu_scene(r, s);
    (0..f.direct.len())
        .map(|px| {
            let g = ShadingPoint::from_gpu(&gbuf[px * 4..px * 4 + 4]);
            (cpu.direct(&g, px as u32, 7, spp), Vec3::from(f.direct[px]))
        })
        .collect()
}

#[test]
fn cornell_128_is_finite_and_lit() {
    let ctx = common::gpu();
    let s = scene::load("builtin:cornell").unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let f = r
        .render(&s.default_camera(), &settings(128, 128, 8))
        .unwrap();
    assert!(common::all_finite(&f.radiance));
    let lum = mean_luminance(&f.radiance);
    assert!(lum > 0.02, "mean luminance {lum}");
    assert!(f.shading_points > 128 * 128 * 8 / 10);
    assert!(f.timings_ms["frame"] > 0.0);
}

/// The G-buffer and direct light of the GPU equal their CPU twins (same random numbers, obvhs rays).
#[test]
fn gpu_primary_and_direct_match_cpu_twin() {
    let ctx = common::gpu();
    for name in ["cornell", "conference"] {
        let s = scene::load(&format!("builtin:{name}")).unwrap();
        let mut r = Renderer::new(&ctx, &s).unwrap();
        let (w, h, spp) = (48u32, 36u32, 4u32);
        let cam = s.default_camera();
        let f = r.render(&cam, &settings(w, h, spp)).unwrap();
        let gbuf = r.last_gbuffer().unwrap();
        let cpu = common::cpu_scene(&r, &s);
        let cp = CameraParams::new(&cam, w, h);
        let ext = s.extent();
        assert!(common::all_finite(&f.radiance), "{name}");
        // The shading points: hit or miss alike everywhere; position (over the scene's size),
        // normal (1 − cos), albedo and emission as far apart as the worst pixel (bounds in
        // common::BOUNDS).
        let (mut valid_differ, mut worst) = (0, [0f32; 4]);
        let mut pairs = Vec::new();
        for px in 0..w * h {
            let g = ShadingPoint::from_gpu(&gbuf[px as usize * 4..px as usize * 4 + 4]);
            let c = cpu.primary(&cp, px);
            if g.valid != c.valid {
                valid_differ += 1;
            } else if g.valid {
                let d = [
                    (g.pos - c.pos).length() / ext,
                    1.0 - g.normal.dot(c.normal),
                    (g.albedo - c.albedo).abs().max_element(),
                    (g.emission - c.emission).abs().max_element(),
                ];
                for i in 0..4 {
                    worst[i] = worst[i].max(d[i]);
                }
            }
            // Direct light from the GPU's own SP, so the two differ only in the shading kernel.
            pairs.push((
                cpu.direct(&g, px, 7, spp),
                Vec3::from(f.direct[px as usize]),
            ));
        }
        println!(
            "{name}: {valid_differ} hit / miss differ; worst position {:.3e}, normal {:.3e}, albedo {:.3e}, emission {:.3e}",
            worst[0], worst[1], worst[2], worst[3]
        );
        let n = (w * h) as usize;
        common::assert_differ(&ctx, "render::hit_miss_differ", name, valid_differ, n);
        for (i, what) in ["position", "normal", "albedo", "emission"]
            .iter()
            .enumerate()
        {
            let key = format!("render::sp_{what}");
            common::assert_measure(
                &ctx,
                &key,
                &format!("{name}: shading point {what}"),
                worst[i],
            );
        }
        common::assert_twins(&ctx, &format!("{name} direct"), "render::direct", pairs);
    }
}

/// Anti-aliasing at rest traces the primary rays through a sub-pixel offset of the pixel centres
/// (`CameraParams::with_jitter`): the jittered G-buffer equals the CPU twin's rays through the same
/// offsets, at the centred twin's bounds, and at an edge of the Cornell box's geometry some pixels
/// change surface (the offset is really applied).
#[test]
fn jittered_primary_rays_match_cpu_twin() {
    let ctx = common::gpu();
    let s = scene::load("builtin:cornell").unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let (w, h) = (48u32, 36u32);
    let cam = s.default_camera();
    r.render(&cam, &settings(w, h, 1)).unwrap();
    let centred = r.last_gbuffer().unwrap();
    let ext = s.extent();
    let jitters = [[0.3f32, -0.2f32], [-0.45, 0.45]];
    let traced: Vec<Vec<[f32; 4]>> = jitters
        .iter()
        .map(|&j| r.jittered_gbuffer(j).unwrap())
        .collect();
    let cpu = common::cpu_scene(&r, &s);
    for (jitter, gbuf) in jitters.into_iter().zip(traced) {
        let cp = CameraParams::new(&cam, w, h).with_jitter(jitter);
        let (mut worst, mut moved) = (0f32, 0);
        for px in 0..(w * h) as usize {
            let g = ShadingPoint::from_gpu(&gbuf[px * 4..px * 4 + 4]);
            let c = cpu.primary(&cp, px as u32);
            assert_eq!(g.valid, c.valid, "pixel {px}: hit / miss");
            if g.valid {
                assert!(g.pos.is_finite() && g.normal.is_finite());
                worst = worst.max((g.pos - c.pos).length() / ext);
            }
            let old = ShadingPoint::from_gpu(&centred[px * 4..px * 4 + 4]);
            moved += (old.pos != g.pos) as u32;
        }
        println!("jitter {jitter:?}: worst position {worst:.3e}, {moved} pixels moved");
        let what = format!("jitter {jitter:?}: position");
        common::assert_measure(&ctx, "render::sp_position", &what, worst);
        assert!(
            moved as usize > (w * h) as usize / 2,
            "{jitter:?}: {moved} moved"
        );
    }
}

/// Thousands of area-light samples per pixel give the same direct light as the CPU twin, not a
/// fraction of it: lavapipe ends every loop of a SIMD batch after 65,535 trips in all, so 8192 samples
/// in one invocation kept only about 2,000 of them (the image got darker as samples were added) until
/// the samples were split into sub ranges of `SAMPLES_PER_DISPATCH`.
#[test]
fn direct_light_with_thousands_of_samples_matches_cpu_twin() {
    let ctx = common::gpu();
    let s = scene::load("builtin:cornell").unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let (w, h, spp) = (8u32, 6u32, 8192u32);
    let cam = s.default_camera();
    let f = r.render(&cam, &settings(w, h, spp)).unwrap();
    assert!(common::all_finite(&f.radiance));
    let pairs = direct_pairs(&r, &s, &f, spp);
    let lit = pairs.iter().filter(|(l, _)| l.max_element() > 0.01).count() as u32;
    common::assert_twins(
        &ctx,
        "direct, 8192 samples",
        "render::direct_8192_samples",
        pairs,
    );
    assert!(lit * 2 > w * h, "only {lit} pixels lit");
}

/// The scale tests' frame: 64 × 48, 4 direct samples, 512 VPLs, K_VPL 64, K_SP 96.
fn scale_settings() -> RenderSettings {
    let mut rs = settings(64, 48, 4);
    rs.frame.vpls = 512;
    rs.cluster.vpl_clusters = 64;
    rs.cluster.sp_clusters = 96;
    rs
}

fn scaled(mut s: Scene, k: f32) -> Scene {
    let vertices = s.triangles.iter_mut().flat_map(|t| t.p.iter_mut());
    vertices.for_each(|p| *p *= k);
    for l in &mut s.lights {
        l.position *= k;
    }
    for c in &mut s.cameras {
        c.transform = Mat4::from_scale(Vec3::splat(k)) * c.transform;
        c.transform.x_axis /= k;
        c.transform.y_axis /= k;
        c.transform.z_axis /= k;
    }
    s
}

/// Direct light from area lights is invariant to the scene's unit: the same room at 1e-4 and 1e4
/// renders the same image.
#[test]
fn rendering_is_scale_free() {
    let ctx = common::gpu();
    let base = scene::load("builtin:conference").unwrap();
    let mut lums = Vec::new();
    for k in [1.0, 1e-4, 1e4] {
        let s = scaled(base.clone(), k);
        let mut r = Renderer::new(&ctx, &s).unwrap();
        let f = r.render(&s.default_camera(), &settings(64, 48, 8)).unwrap();
        assert!(common::all_finite(&f.radiance), "scale {k}");
        lums.push(mean_luminance(&f.radiance));
    }
    println!("mean luminance at 1, 1e-4, 1e4: {lums:?}");
    for l in &lums[1..] {
        assert!((l / lums[0] - 1.0).abs() < 0.02, "{lums:?}");
    }
}

/// Light transport is linear in the emitted power: emitters scaled by 1e-40 (below f32's normal range,
/// where 1 / power overflowed and the image came out at f32::MAX) and by 1e30 give the same image
/// scaled by the factor, finite; so does a point light whose colour is 1e-40 (its intensity is folded into
/// the colour when normalised).
#[test]
fn extreme_light_power_scales_the_image_linearly() {
    let ctx = common::gpu();
    let s = {
        let mut rs = settings(24, 18, 4);
        rs.frame.vpls = 256;
        rs.cluster.vpl_clusters = 64;
        rs.cluster.sp_clusters = 48;
        rs
    };
    let lum = |scene: &Scene| {
        let f = Renderer::new(&ctx, scene)
            .unwrap()
            .render(&scene.default_camera(), &s)
            .unwrap();
        assert!(common::all_finite(&f.radiance));
        mean_luminance(&f.radiance) as f64
    };
    let base = scene::load("builtin:cornell").unwrap();
    let lum0 = lum(&base);
    for k in [1e-40f64, 1e30] {
        let mut sk = base.clone();
        sk.scale_light_power(k);
        let ratio = lum(&sk) / (lum0 * k);
        println!("area light x {k:e}: luminance ratio {ratio}");
        assert!(
            (ratio - 1.0).abs() < 1e-2,
            "area light x {k:e}: ratio {ratio}"
        );
    }
    let point = |colour: &str| {
        let mut s = base.clone();
        for m in &mut s.materials {
            m.emissive = Vec3::ZERO;
        }
        s.lights.push(
            fuzzy_vpl::scene::extra_lights::parse_point(&format!("0.28,0.45,0.28,3,{colour}"))
                .unwrap(),
        );
        lum(&s)
    };
    let ratio = point("1e-40,1e-40,1e-40") / (point("1,1,1") * 1e-40);
    println!("point light of colour 1e-40: luminance ratio {ratio}");
    assert!(
        (ratio - 1.0).abs() < 1e-2,
        "point light of colour 1e-40: ratio {ratio}"
    );
}

/// Direct light in sub ranges that cross from area samples into punctual lights, and lights alone
/// (no emitters), equals the CPU twin on every pixel: each sub range takes its own share of the
/// samples and lights once (a mutant that lets every sub range take all lights fails here).
#[test]
fn direct_light_sub_ranges_with_many_lights_match_cpu_twin() {
    let ctx = common::gpu();
    let cases = [
        (true, 100u32, 70u32),
        (false, 1, 150),
        (true, 16, 60),
        (true, 64, 1),
        (true, 130, 3),
    ];
    for (with_area, spp, nl) in cases {
        let mut s = scene::load("builtin:cornell").unwrap();
        if !with_area {
            for m in &mut s.materials {
                m.emissive = Vec3::ZERO;
            }
        }
        for i in 0..nl {
            let x = 0.05 + 0.45 * ((i % 7) as f32 / 6.0);
            let z = 0.05 + 0.45 * (((i / 7) % 7) as f32 / 6.0);
            let y = 0.1 + 0.4 * ((i / 49) as f32 / 3.0);
            let spec = format!("{x},{y},{z},{}", 0.002 * (1 + i) as f32);
            s.lights
                .push(fuzzy_vpl::scene::extra_lights::parse_point(&spec).unwrap());
        }
        let mut r = Renderer::new(&ctx, &s).unwrap();
        let (w, h) = (8u32, 6u32);
        let cam = s.default_camera();
        let fs = {
            let mut rs = settings(w, h, spp);
            rs.frame.vpls = 0;
            rs
        };
        let f = r.render(&cam, &fs).unwrap();
        assert!(common::all_finite(&f.radiance));
        let pairs = direct_pairs(&r, &s, &f, spp);
        let lit = pairs.iter().filter(|(l, _)| l.max_element() > 0.01).count() as u32;
        common::assert_twins(
            &ctx,
            &format!("direct, area {with_area}, {spp} samples, {nl} lights"),
            "render::direct_many_lights",
            pairs,
        );
        assert!(lit * 2 > w * h, "only {lit} pixels lit");
    }
}

/// A closed room (the cube −1..1, two triangles a wall) lit by a point light, and in front of the
/// back wall a quad (a square turned 45°) split along its vertical diagonal x = 0. At an odd width the
/// centre pixel column's rays have x exactly 0 (the camera sits on x = 0 looking down −z): they run
/// exactly through the quad's shared edge. A non-watertight triangle test (Möller–Trumbore as before,
/// which also rejected −0.0 barycentrics) left a dotted black crack there; every primary ray must hit
/// and every pixel be lit.
#[test]
fn quad_diagonal_on_the_centre_line_has_no_crack() {
    use fuzzy_vpl::scene::{LightKind, Material, PunctualLight, Triangle};
    let ctx = common::gpu();
    let mut triangles = Vec::new();
    let mut quad = |a: Vec3, b: Vec3, c: Vec3, d: Vec3| {
        for p in [[a, b, c], [a, c, d]] {
            let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
            triangles.push(Triangle {
                p,
                n: [n; 3],
                uv: [glam::Vec2::ZERO; 3],
                color: [glam::Vec4::ONE; 3],
                material: 0,
            });
        }
    };
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    // The room's six walls, facing inwards.
    quad(
        v(-1., -1., -1.),
        v(1., -1., -1.),
        v(1., 1., -1.),
        v(-1., 1., -1.),
    );
    quad(
        v(-1., -1., 1.),
        v(-1., 1., 1.),
        v(1., 1., 1.),
        v(1., -1., 1.),
    );
    quad(
        v(-1., -1., -1.),
        v(-1., 1., -1.),
        v(-1., 1., 1.),
        v(-1., -1., 1.),
    );
    quad(
        v(1., -1., -1.),
        v(1., -1., 1.),
        v(1., 1., 1.),
        v(1., 1., -1.),
    );
    quad(
        v(-1., -1., -1.),
        v(-1., -1., 1.),
        v(1., -1., 1.),
        v(1., -1., -1.),
    );
    quad(
        v(-1., 1., -1.),
        v(1., 1., -1.),
        v(1., 1., 1.),
        v(-1., 1., 1.),
    );
    // The quad: its first two triangles share the edge from (0, −0.5) to (0, 0.5).
    quad(
        v(0., -0.5, -0.5),
        v(0.5, 0., -0.5),
        v(0., 0.5, -0.5),
        v(-0.5, 0., -0.5),
    );
    let s = Scene {
        name: "crack-room".into(),
        triangles,
        materials: vec![Material::default()],
        lights: vec![PunctualLight {
            kind: LightKind::Point,
            position: v(0.3, 0.6, 0.5),
            direction: Vec3::NEG_Z,
            color: Vec3::ONE,
            intensity: 1.0,
        }],
        ..Default::default()
    };
    let cam = fuzzy_vpl::scene::Camera::look_at("c", v(0., 0., 0.9), v(0., 0., -1.), Vec3::Y, 1.2);
    let (w, h) = (161u32, 121u32);
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let fs = {
        let mut rs = settings(w, h, 4);
        rs.frame.vpls = 1024;
        rs
    };
    let f = r.render(&cam, &fs).unwrap();
    assert!(common::all_finite(&f.radiance));
    let gbuf = r.last_gbuffer().unwrap();
    let misses: Vec<u32> = (0..w * h)
        .filter(|&px| !ShadingPoint::from_gpu(&gbuf[px as usize * 4..px as usize * 4 + 4]).valid)
        .collect();
    assert!(
        misses.is_empty(),
        "{} primary rays miss (cracks), e.g. pixels {:?}",
        misses.len(),
        &misses[..misses.len().min(8)]
    );
    let black = f
        .radiance
        .iter()
        .filter(|c| c[0] + c[1] + c[2] <= 0.0)
        .count();
    assert_eq!(black, 0, "{black} black pixels");
}

/// Any finite scale renders the image of the unscaled room: conference and Cornell scaled by 1e-30,
/// 1e-15, 1e-12, 1e12, 1e15 and 1e30 (used to: black at 1e±12, walls lost at 1e10) against scale 1
/// (the renderer scales the geometry by a power of two into a unit frame, `Scene::geometry_scale`),
/// clustered
/// frame with indirect light. Tolerance: rel_mse ≤ 1e-3 and mean luminance within 0.5% (the scaled
/// coordinates are rounded to f32, which moves VPLs and samples by an ulp; measured below).
#[test]
fn any_finite_scale_renders_the_unscaled_image() {
    let ctx = common::gpu();
    for name in ["cornell", "conference"] {
        let base = scene::load(&format!("builtin:{name}")).unwrap();
        let fs = scale_settings();
        let render = |k: f32| {
            let s = scaled(base.clone(), k);
            let mut r = Renderer::new(&ctx, &s).unwrap();
            let f = r.render(&s.default_camera(), &fs).unwrap();
            assert!(common::all_finite(&f.radiance), "{name} at {k}");
            f.radiance
        };
        let one = render(1.0);
        let l1 = mean_luminance(&one);
        for k in [1e-30f32, 1e-15, 1e-12, 1e12, 1e15, 1e30] {
            let img = render(k);
            let lk = mean_luminance(&img);
            let rel = fuzzy_vpl::metrics::rel_mse(&img, &one);
            println!("{name} at {k:e}: mean luminance {lk:.5} (1: {l1:.5}), rel_mse {rel:.2e}");
            assert!((lk / l1 - 1.0).abs() < 5e-3, "{name} at {k}: {lk} vs {l1}");
            assert!(rel <= 1e-3, "{name} at {k}: rel_mse {rel}");
        }
    }
}

/// A mesh whose per-triangle data exceed one storage binding (lavapipe: 128 MiB, 2.1 M triangles of
/// 64 bytes of shading data; it used to panic with a wgpu validation error) renders: a flat grid of
/// 2,205,000 triangles on y = 0 seen from above. Closed-form oracle: a pixel's G-buffer point is valid
/// exactly when its ray meets the plane inside the grid's square (pixels within 1e-3 of the edge
/// skipped), and then lies on the plane where the ray meets it (within 1e-5).
#[test]
fn a_mesh_past_one_storage_binding_renders() {
    use fuzzy_vpl::scene::{LightKind, Material, PunctualLight, Triangle};
    let ctx = common::gpu();
    let n = 1050usize;
    let v = |i: usize, j: usize| {
        Vec3::new(
            i as f32 / n as f32 * 2.0 - 1.0,
            0.0,
            j as f32 / n as f32 * 2.0 - 1.0,
        )
    };
    let mut triangles = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            for p in [
                [v(i, j), v(i, j + 1), v(i + 1, j)],
                [v(i + 1, j), v(i, j + 1), v(i + 1, j + 1)],
            ] {
                triangles.push(Triangle {
                    p,
                    n: [Vec3::Y; 3],
                    uv: [glam::Vec2::ZERO; 3],
                    color: [glam::Vec4::ONE; 3],
                    material: 0,
                });
            }
        }
    }
    if ctx.max_binding() <= 128 << 20 {
        assert!(
            triangles.len() as u64 * 64 > ctx.max_binding(),
            "the mesh fits one binding"
        );
    }
    let s = Scene {
        name: "grid".into(),
        triangles,
        materials: vec![Material::default()],
        lights: vec![PunctualLight {
            kind: LightKind::Directional,
            position: Vec3::ZERO,
            direction: Vec3::new(-0.3, -1.0, -0.2).normalize(),
            color: Vec3::ONE,
            intensity: 1.0,
        }],
        ..Default::default()
    };
    let cam =
        fuzzy_vpl::scene::Camera::look_at("c", Vec3::new(0.1, 2.0, 0.2), Vec3::ZERO, Vec3::Z, 1.0);
    let (w, h) = (40u32, 30u32);
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let f = r
        .render(&cam, &{
            let mut rs = settings(w, h, 1);
            rs.frame.vpls = 0;
            rs
        })
        .unwrap();
    assert!(common::all_finite(&f.radiance));
    let gbuf = r.last_gbuffer().unwrap();
    let p = CameraParams::new(&cam, w, h);
    let (mut hits, mut checked) = (0, 0);
    for px in 0..(w * h) as usize {
        let x = (px as u32 % w) as f64 + 0.5;
        let y = (px as u32 / w) as f64 + 0.5;
        let sx = 2.0 * x / w as f64 - 1.0;
        let sy = 1.0 - 2.0 * y / h as f64;
        let v3 = |a: [f32; 4]| glam::DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
        let d = v3(p.forward) + sx * v3(p.right) + sy * v3(p.up);
        let eye = v3(p.eye);
        let t = -eye.y / d.y;
        let q = eye + t * d;
        let inside = t > 0.0 && q.x.abs().max(q.z.abs()) < 1.0 - 1e-3;
        let outside = t <= 0.0 || q.x.abs().max(q.z.abs()) > 1.0 + 1e-3;
        let sp = ShadingPoint::from_gpu(&gbuf[px * 4..px * 4 + 4]);
        if inside {
            assert!(
                sp.valid,
                "pixel {px}: the ray meets the grid at {q} but misses"
            );
            assert!(
                (sp.pos.as_dvec3() - q).length() < 1e-5,
                "pixel {px}: {} vs {q}",
                sp.pos
            );
            hits += 1;
        } else if outside {
            assert!(!sp.valid, "pixel {px}: hit {} outside the grid", sp.pos);
        }
        checked += 1;
    }
    assert!(
        hits > (w * h) as usize / 4,
        "only {hits} of {checked} pixels see the grid"
    );
    assert!(mean_luminance(&f.radiance) > 0.0);
}

/// Lights set on a renderer (the viewer's moving lights, `Renderer::set_lights`) are in the caller's
/// units like cameras: the conference room at 1e12 (rendered in a unit frame scaled by 2^-43) lit by
/// a point light given at 1e12 units with intensity × 1e24 renders the image of the unscaled room
/// with the unscaled light, and `Frame::positions` come back in the caller's units. Tolerance as in
/// `any_finite_scale_renders_the_unscaled_image`.
#[test]
fn lights_set_at_any_scale_are_in_the_callers_units() {
    use fuzzy_vpl::scene::{LightKind, PunctualLight};
    let ctx = common::gpu();
    let base = scene::load("builtin:conference").unwrap();
    let (lo, hi) = base.bounds();
    let light = |k: f32| PunctualLight {
        kind: LightKind::Point,
        position: 0.5 * (lo + hi) * k,
        direction: Vec3::NEG_Y,
        color: Vec3::ONE,
        intensity: 2.0 * (hi - lo).length_squared() * k * k,
    };
    let fs = scale_settings();
    let render = |k: f32| {
        let s = scaled(base.clone(), k);
        let mut r = Renderer::new(&ctx, &s).unwrap();
        r.set_lights(&[light(k)], 0.0);
        let f = r.render(&s.default_camera(), &fs).unwrap();
        assert!(common::all_finite(&f.radiance), "scale {k}");
        (r.geometry_scale, f)
    };
    let (g1, one) = render(1.0);
    let (gk, big) = render(1e12);
    assert_eq!(g1, 1.0);
    assert!(gk < 1e-12 && gk.log2().fract() == 0.0, "{gk}");
    let (l1, lk) = (mean_luminance(&one.radiance), mean_luminance(&big.radiance));
    let rel = fuzzy_vpl::metrics::rel_mse(&big.radiance, &one.radiance);
    println!("point light set at 1e12: mean luminance {lk:.5} (1: {l1:.5}), rel_mse {rel:.2e}");
    assert!(l1 > 0.01, "the room is dark: {l1}");
    assert!((lk / l1 - 1.0).abs() < 5e-3, "{lk} vs {l1}");
    assert!(rel <= 1e-3, "rel_mse {rel}");
    // G-buffer positions in the caller's units: 1e12 × those of the unscaled room (f32 rounding of
    // the scaled input: 1e-5 relative to the room's size).
    let size = (hi - lo).length();
    let mut compared = 0;
    for (a, b) in one.positions.iter().zip(&big.positions) {
        if a[3] > 0.0 && b[3] > 0.0 {
            let d = (Vec3::new(b[0], b[1], b[2]) / 1e12 - Vec3::new(a[0], a[1], a[2])).length();
            assert!(d <= 1e-5 * size, "{a:?} vs {b:?}");
            compared += 1;
        }
    }
    assert!(compared > 1000, "{compared}");
}

/// Every method's passes, `--paper` and the reference run on a device that allows exactly
/// `gpu::MIN_STORAGE_BUFFERS` storage buffers per shader stage, the fewest `GpuContext` accepts
/// (a host program's device may have no more): a pipeline binding more fails its validation, which
/// is fatal.
#[test]
fn every_method_runs_with_the_fewest_storage_buffers_accepted() {
    use fuzzy_vpl::gpu::{GpuContext, MIN_STORAGE_BUFFERS, required_limits, wanted_features};
    let instance = fuzzy_vpl::gpu::instance();
    let adapter =
        pollster::block_on(instance.request_adapter(&Default::default())).expect("an adapter");
    let limits = wgpu::Limits {
        max_storage_buffers_per_shader_stage: MIN_STORAGE_BUFFERS,
        ..required_limits(&adapter.limits())
    };
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("fewest storage buffers"),
        required_features: adapter.features() & wanted_features(),
        required_limits: limits,
        ..Default::default()
    }))
    .expect("a device");
    let ctx = GpuContext::from_device(instance, adapter, device, queue).unwrap();
    let s = scene::load("builtin:cornell").unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    for entry in fuzzy_vpl::method::REGISTRY {
        for paper in [false, true] {
            let mut fs = settings(16, 12, 4);
            fs.frame.vpls = 512;
            fs.method.method = entry.method;
            fs.cluster.vpl_clusters = 64;
            fs.cluster.sp_clusters = 24;
            if paper {
                let given = |id: &str| ["sp_clusters", "vpl_clusters"].contains(&id);
                fuzzy_vpl::settings::paper::apply(&mut fs.frame, &mut fs.cluster, &given);
            }
            let f = r.render(&s.default_camera(), &fs).unwrap();
            assert!(common::all_finite(&f.radiance), "{}", entry.method);
        }
    }
    let mut fs = settings(16, 12, 4);
    fs.frame.vpls = 512;
    fs.reference = true;
    let f = r.render(&s.default_camera(), &fs).unwrap();
    assert!(common::all_finite(&f.radiance), "reference");
}
