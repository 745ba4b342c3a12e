//! `--indirect-scale`: the render-scale G-buffer and the joint bilateral upsampling of the indirect
//! light (`gi::upsample`) against their CPU twin and independent oracles, and whole frames.

mod common;

use fuzzy_vpl::cpu::upsample as twin;
use fuzzy_vpl::gi::pass::Pass;
use fuzzy_vpl::gi::primary::CameraParams;
use fuzzy_vpl::gi::upsample::{UpsampleParams, indirect_size};
use fuzzy_vpl::method::{Method, MethodSettings};
use fuzzy_vpl::render::{RenderSettings, Renderer};
use fuzzy_vpl::scene;
use fuzzy_vpl::settings::{ClusterSettings, FrameSettings};
use glam::Vec3;

const W: u32 = 37;
const H: u32 = 23;
/// Image column of a pole one pixel wide in front of the planes: no representative lands on it.
const POLE: u32 = 11;

/// A synthetic image G-buffer seen from the origin looking down -z: a plane at depth 1 on the left,
/// a plane at depth 3 on the right, a one-pixel pole at depth 0.5, sky in the top rows.
fn synthetic() -> (UpsampleParams, Vec<[f32; 4]>) {
    let cam = scene::Camera::look_at("test", Vec3::ZERO, -Vec3::Z, Vec3::Y, 60f32.to_radians());
    let cp = CameraParams::new(&cam, W, H);
    let p = UpsampleParams::new(&cp, indirect_size(W, H, 0.5));
    let mut g = Vec::new();
    for i in 0..W * H {
        let (x, y) = (i % W, i / W);
        let d = cp.ray(x as f32 + 0.5, y as f32 + 0.5);
        let depth = if x == POLE {
            0.5
        } else if x < W / 2 {
            1.0
        } else {
            3.0
        };
        // Rough planes: each point up to 2% of its depth off along its ray, its normal tilted by up
        // to 0.1 rad, so that the weights' exp and pow see other values than 0 and 1.
        let rough = 1.0 + 0.005 * ((i * 7) % 5) as f32;
        let pos = d * (depth / -d.z) * rough;
        let n = Vec3::new(0.05 * ((i % 3) as f32 - 1.0), 0.0, 1.0).normalize();
        let seen = y >= 3;
        let w = if seen { 1.0 } else { 0.0 };
        g.extend([
            [pos.x * w, pos.y * w, pos.z * w, w],
            [n.x, n.y, n.z, 0.0],
            [0.5, 0.5, 0.5, 1.0],
            [0.0; 4],
        ]);
    }
    (p, g)
}

/// The low-res indirect light: 1 on the near plane, 0 on the far one (by each tap's depth).
fn edge_light(low_gbuffer: &[[f32; 4]]) -> Vec<[f32; 4]> {
    low_gbuffer
        .chunks(4)
        .map(|sp| {
            let v = if -sp[0][2] < 2.0 { 1.0 } else { 0.0 };
            [v, 0.5 * v, 0.25, 0.0]
        })
        .collect()
}

#[test]
fn upsample_kernels_match_cpu_twin_and_oracles() {
    let ctx = common::gpu();
    let s = scene::load("builtin:cornell").unwrap();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let (p, image) = synthetic();
    let geo = fuzzy_vpl::cpu::upsample::Geometry::of(&p);
    assert_eq!(geo.low, (19, 12));
    let low_twin = twin::downsample(&geo, &image);
    // Constant light stays constant on every surface pixel, and 0 on the sky.
    let c = [0.3, 0.5, 0.7, 0.0];
    let constant = vec![c; 19 * 12];
    let (low, gpu) = r.upsample_buffers(&p, &image, &constant).unwrap();
    assert_eq!(
        low, low_twin,
        "the render-scale G-buffer is a copy of representatives"
    );
    let cpu = twin::upsample(&geo, &image, &low_twin, &constant);
    for (i, (g, t)) in gpu.iter().zip(&cpu).enumerate() {
        let seen = image[i * 4][3] > 0.0;
        let want = if seen { c } else { [0.0; 4] };
        for k in 0..3 {
            assert!((g[k] - want[k]).abs() <= 1e-6, "pixel {i}: GPU {g:?}");
            assert!((t[k] - want[k]).abs() <= 1e-6, "pixel {i}: twin {t:?}");
        }
    }
    // An edge between two planes at different depth does not bleed; the pole (no low-res tap of
    // its own) falls back to the tap nearest in depth, the near plane's.
    let light = edge_light(&low_twin);
    let (_, gpu) = r.upsample_buffers(&p, &image, &light).unwrap();
    let cpu = twin::upsample(&geo, &image, &low_twin, &light);
    let mut worst = 0f32;
    for i in 0..(W * H) as usize {
        let (g, t) = (
            Vec3::from_slice(&gpu[i][..3]),
            Vec3::from_slice(&cpu[i][..3]),
        );
        assert!(g.is_finite() && t.is_finite(), "pixel {i}");
        worst = worst.max(common::twin_diff(t, g));
        if image[i * 4][3] == 0.0 {
            assert_eq!(g, Vec3::ZERO, "sky pixel {i}");
            continue;
        }
        let near = -image[i * 4][2] < 2.0;
        let want = if near {
            Vec3::new(1.0, 0.5, 0.25)
        } else {
            Vec3::new(0.0, 0.0, 0.25)
        };
        assert!(
            (g - want).abs().max_element() < 1e-4,
            "pixel {i}: {g} want {want}"
        );
    }
    // Light that differs from tap to tap: the weighted means themselves against the twin.
    let varied: Vec<[f32; 4]> = (0..19 * 12)
        .map(|q| [q as f32 / 228.0, (q % 7) as f32, 1.0 + (q % 3) as f32, 0.0])
        .collect();
    let (_, gpu) = r.upsample_buffers(&p, &image, &varied).unwrap();
    let cpu = twin::upsample(&geo, &image, &low_twin, &varied);
    let pairs = cpu
        .iter()
        .zip(&gpu)
        .map(|(c, g)| (Vec3::from_slice(&c[..3]), Vec3::from_slice(&g[..3])));
    worst = worst.max(common::assert_twins(
        &ctx,
        "upsample",
        "upsample::twin",
        pairs,
    ));
    println!("upsample: worst twin difference {worst:e}");
}

fn frame_settings(scale: f32, method: Method) -> RenderSettings {
    RenderSettings {
        frame: FrameSettings {
            width: 64,
            height: 48,
            vpls: 512,
            direct_samples: 4,
            indirect_scale: scale,
            ..Default::default()
        },
        cluster: ClusterSettings {
            sp_clusters: 96,
            vpl_clusters: 64,
            ..Default::default()
        },
        method: MethodSettings {
            method,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// Below scale 1: the image, its direct light and its shading points at the image's size, bit for
/// bit those of scale 1; the indirect light close to scale 1's; every method runs on the render
/// scale's G-buffer; temporal reuse warm-starts at the render scale.
#[test]
fn frames_at_half_indirect_scale() {
    let ctx = common::gpu();
    let s = scene::load("builtin:cornell").unwrap();
    let cam = s.default_camera();
    let mut r = Renderer::new(&ctx, &s).unwrap();
    let full = r.render(&cam, &frame_settings(1.0, Method::Colom)).unwrap();
    assert!(!full.ran(Pass::Upsample) && !full.timings_ms.contains_key("upsample"));
    let half = r.render(&cam, &frame_settings(0.5, Method::Colom)).unwrap();
    assert!(half.ran(Pass::Upsample) && half.ms(Pass::Upsample) > 0.0);
    assert_eq!((half.width, half.height), (64, 48));
    assert_eq!(
        half.direct, full.direct,
        "the direct light is at the image's size"
    );
    assert_eq!(half.positions, full.positions);
    assert!(common::all_finite(&half.radiance));
    let rel = fuzzy_vpl::metrics::rel_mse(&half.indirect, &full.indirect);
    println!("indirect at scale 0.5 against 1: rel MSE {rel:e}");
    assert!(rel < 0.05, "rel MSE {rel}");
    // The SP labels at the image's size, each image pixel its low-res pixel's.
    let labels = r.sp_labels(&half).unwrap().unwrap();
    assert_eq!(labels.len(), 64 * 48);
    // Temporal reuse: the next frame warm-starts from the render scale's clustering.
    let mut t = frame_settings(0.5, Method::Colom);
    t.cluster.temporal = true;
    r.render(&cam, &t).unwrap();
    let again = r.render(&cam, &t).unwrap();
    assert!(
        common::colom(&again).sp_warm_kept.is_some_and(|k| k > 0),
        "{:?}",
        common::colom(&again).sp_warm_kept
    );
    for m in [Method::Wang, Method::LightCluster, Method::Cvrtgi] {
        let f = r.render(&cam, &frame_settings(0.5, m)).unwrap();
        assert!(f.ran(Pass::Upsample), "{m}");
        assert!(common::all_finite(&f.radiance), "{m}");
        assert!(fuzzy_vpl::metrics::mean_luminance(&f.indirect) > 0.0, "{m}");
    }
    // The reference ignores the scale.
    let mut reference = frame_settings(0.5, Method::Colom);
    reference.reference = true;
    assert!(!Renderer::passes_for(&s, &reference).contains(&Pass::Upsample));
}

#[test]
fn indirect_scale_1_is_the_default_and_bad_scales_are_refused() {
    let dir = common::scratch("indirect-scale");
    let args = |name: &str, extra: &[&str]| {
        let out = dir.join(name).to_string_lossy().into_owned();
        let words = "render builtin:cornell --width 48 --height 36 --vpls 256 --sp-clusters 64 \
                     --vpl-clusters 32";
        let mut a = common::cmd(words, &["-o", &out]);
        a.extend(extra);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    for (name, extra) in [
        ("default.exr", &[][..]),
        ("one.exr", &["--indirect-scale", "1"]),
    ] {
        let a = args(name, extra);
        let (code, _, err) = common::run_cli(&a.iter().map(|s| s.as_str()).collect::<Vec<_>>());
        assert_eq!(code, 0, "{err}");
    }
    let read = |n: &str| std::fs::read(dir.join(n)).unwrap();
    assert_eq!(read("default.exr"), read("one.exr"));
    for bad in ["0", "-0.5", "1.5", "NaN"] {
        let a = args("bad.exr", &["--indirect-scale", bad]);
        common::assert_refused(
            &a.iter().map(|s| s.as_str()).collect::<Vec<_>>(),
            "--indirect-scale",
        );
    }
}
