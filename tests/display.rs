//! The viewer's display pass (`app::display`, `shaders-wgsl/display.wgsl`) against its CPU twin
//! (`app::twin`) on every view it draws, and against hand-worked values; the library's frame on
//! the GPU (`Renderer::render_gpu`, `render_to_texture`) against the frame read back, and what
//! crosses the bus (`gpu::traffic`).

mod common;

use common::draw_display as draw;

use fuzzy_vpl::app::display::{Display, DisplayInputs, Images};
use fuzzy_vpl::app::twin;
use fuzzy_vpl::app::views::View;
use fuzzy_vpl::exposure::Exposure;
use fuzzy_vpl::gpu::{GpuContext, read_texture, traffic::Traffic};
use fuzzy_vpl::render::{RenderSettings, Renderer};
use fuzzy_vpl::settings::{ClusterSettings, Weighting};
use fuzzy_vpl::{Frame, scene};

/// The bytes and buffers this file's frame test counts are the process's (`gpu::traffic`): its tests
/// run one at a time.
fn serial() -> std::sync::MutexGuard<'static, ()> {
    static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

const W: u32 = 48;
const H: u32 = 36;

/// `common::display_frame`: W × H.
fn settings(weighting: Weighting) -> RenderSettings {
    common::display_frame(weighting)
}

/// A vec4 buffer of `img` on the device.
fn upload(ctx: &GpuContext, img: &[[f32; 3]]) -> wgpu::Buffer {
    let v: Vec<[f32; 4]> = img.iter().map(|p| [p[0], p[1], p[2], 0.0]).collect();
    ctx.storage_init("image", &v)
}

fn gpu_images(f: &fuzzy_vpl::GpuFrame) -> Images<'_> {
    Images {
        direct: &f.buffers.radiance,
        indirect: f.buffers.image_indirect(),
        scale: f.output_scale,
    }
}

fn cpu_images(f: &Frame) -> twin::Images<'_> {
    twin::Images {
        direct: &f.direct,
        indirect: &f.indirect,
    }
}

/// Every view, auto and fixed exposure, the direct light on and off, against the twin on a
/// clustered frame of each built-in room (B hard, the reference a render of the unclustered frame,
/// synthetic labels with misses). Measured on lavapipe (Mesa 22.3.6): every channel equal, the
/// auto exposure within 1.8e-7 relative (f32 tree sums against f64). The bounds allow 1 of 255 on
/// 0.2% of the channels (sRGB's pow and the ramp's log10 may round at an 8-bit step otherwise on
/// another driver) and 4e-6 on the exposure.
#[test]
fn display_matches_cpu_twin_on_every_view() {
    let _serial = serial();
    let ctx = common::gpu();
    let mut d = Display::new(&ctx.device);
    for name in ["builtin:cornell", "builtin:conference"] {
        let sc = scene::load(name).unwrap();
        let cam = sc.default_camera();
        let mut r = Renderer::new(&ctx, &sc).unwrap();
        let a = r
            .render_gpu(&cam, &settings(Weighting::InverseDistance))
            .unwrap();
        let b = r.render_gpu(&cam, &settings(Weighting::Hard)).unwrap();
        let reference = r
            .render(
                &cam,
                &RenderSettings {
                    reference: true,
                    ..settings(Weighting::Hard)
                },
            )
            .unwrap();
        let (fa, fb): (Frame, Frame) = (a.read(&ctx).unwrap(), b.read(&ctx).unwrap());
        for f in [&fa, &fb, &reference] {
            assert!(common::all_finite(&f.radiance));
        }
        let labels: Vec<u32> = (0..W * H)
            .map(|i| if i % 11 == 0 { u32::MAX } else { i % 37 })
            .collect();
        let labels_gpu = ctx.storage_init("labels", &labels);
        let ref_gpu = upload(&ctx, &reference.radiance);
        let (mut worst_e, mut differing, mut channels) = (0f32, 0usize, 0usize);
        for view in View::ALL.into_iter().filter(|v| *v != View::Flip) {
            for (exposure, direct_on) in [
                (Exposure::Auto, true),
                (Exposure::Fixed(0.8), true),
                (Exposure::Auto, false),
            ] {
                let inputs = DisplayInputs {
                    size: (W, H),
                    view,
                    a: gpu_images(&a),
                    b: Some(gpu_images(&b)),
                    reference: Some(&ref_gpu),
                    labels: Some(&labels_gpu),
                    exposure,
                    direct_on,
                    split: 0.37,
                };
                let (gpu, e_gpu) = draw(&ctx, &mut d, &inputs);
                let (cpu, e_cpu) = twin::display(
                    view,
                    cpu_images(&fa),
                    Some(cpu_images(&fb)),
                    Some(&reference.radiance),
                    Some(&labels),
                    exposure,
                    direct_on,
                    0.37,
                    (W, H),
                );
                worst_e = worst_e.max((e_gpu / e_cpu - 1.0).abs());
                assert_eq!(gpu.len(), cpu.len());
                for (i, (g, c)) in gpu.iter().zip(&cpu).enumerate() {
                    let diff = (*g as i32 - *c as i32).abs();
                    assert!(
                        diff <= 1,
                        "{name} {view:?} {exposure:?} direct {direct_on}: pixel {} channel {}: GPU {g} CPU {c}",
                        i / 4,
                        i % 4
                    );
                    differing += (diff > 0) as usize;
                }
                channels += gpu.len();
            }
        }
        println!(
            "twin display {name}: exposure worst {worst_e:.2e}, {differing} of {channels} channels differ by 1"
        );
        assert!(worst_e < 4e-6, "{name}: exposure off by {worst_e}");
        assert!(
            differing * 500 <= channels,
            "{name}: {differing} of {channels} channels differ"
        );
    }
}

/// Hand-worked: a 4 × 1 image of greys 0.01, 0.1, 1 and 10 (the direct light; the indirect light 0,
/// render units × 2 = the scene's): its log-average is (0.02 · 0.2 · 2 · 20)^(1/4) = 0.632456, so
/// the auto exposure is 0.18 / 0.632456 = 0.284605; the final view shows grey 0.02 × 0.284605 =
/// 0.0056921 as sRGB 1.055 · 0.0056921^(1/2.4) − 0.055 = 0.067443 → ⌊17.20 + 0.5⌋ = 17 (of 255),
/// 0.2 → 0.056921 → 0.264613 → 67, 2 → 0.569210 → 0.779238 → 199, and 20 saturates at 255. With exposure 1 fixed, the
/// indirect view (all 0) is black and the error view of x = 2 against a reference 1 is red.
#[test]
fn display_by_hand() {
    let _serial = serial();
    let ctx = common::gpu();
    let mut d = Display::new(&ctx.device);
    let direct = upload(&ctx, &[[0.01; 3], [0.1; 3], [1.0; 3], [10.0; 3]]);
    let zero = upload(&ctx, &[[0.0; 3]; 4]);
    let reference = upload(&ctx, &[[1.0; 3]; 4]);
    let a = Images {
        direct: &direct,
        indirect: &zero,
        scale: 2.0,
    };
    let inputs = |view, exposure| DisplayInputs {
        size: (4, 1),
        view,
        a,
        b: None,
        reference: Some(&reference),
        labels: None,
        exposure,
        direct_on: true,
        split: 0.5,
    };
    let (img, e) = draw(&ctx, &mut d, &inputs(View::Final, Exposure::Auto));
    assert!((e / 0.284_605 - 1.0).abs() < 1e-5, "exposure {e}");
    let greys: Vec<u8> = img.chunks(4).map(|p| p[0]).collect();
    assert_eq!(greys, [17, 67, 199, 255]);
    assert!(
        img.chunks(4)
            .all(|p| p[0] == p[1] && p[1] == p[2] && p[3] == 255)
    );
    let (img, e) = draw(&ctx, &mut d, &inputs(View::Indirect, Exposure::Fixed(1.0)));
    assert_eq!(e, 1.0);
    assert!(img.chunks(4).all(|p| p[..3] == [0, 0, 0]));
    // Error of 20 against 1: (19² / 1.01) ≈ 357 per channel, log10 > 0: the ramp's red end.
    let (img, _) = draw(&ctx, &mut d, &inputs(View::Error, Exposure::Fixed(1.0)));
    let red = [0.9f32, 0.1, 0.05].map(|c| (c * 255.0 + 0.5) as u8);
    assert_eq!(img[12..15], red);
    // Split at 0.5 of 4 columns: A in the first two (no B given: B is A).
    let (img, _) = draw(&ctx, &mut d, &inputs(View::Split, Exposure::Auto));
    assert_eq!(
        img.chunks(4).map(|p| p[0]).collect::<Vec<_>>(),
        [17, 67, 199, 255]
    );
}

/// The other methods' counts stay on the GPU: restir's and lightcluster's per-pixel shadow rays
/// summed there (`gi::sum`), wang's clusters used. A frame reads nothing back, its counts on
/// request read a few bytes (8; wang's 32), and they give the shadow rays and SP clusters used
/// `render` counts for the same frame of another renderer.
#[test]
fn method_counts_stay_on_the_gpu() {
    let _serial = serial();
    let ctx = common::gpu();
    let sc = scene::load("builtin:cornell").unwrap();
    let cam = sc.default_camera();
    for m in [
        fuzzy_vpl::method::Method::Restir,
        fuzzy_vpl::method::Method::LightCluster,
        fuzzy_vpl::method::Method::Wang,
    ] {
        let mut s = settings(Weighting::InverseDistance);
        s.method.method = m;
        // The second frame of each renderer (restir seeds its frames by their count).
        let reference = {
            let mut r = Renderer::new(&ctx, &sc).unwrap();
            drop(r.render_gpu(&cam, &s).unwrap());
            r.render(&cam, &s).unwrap()
        };
        let mut r = Renderer::new(&ctx, &sc).unwrap();
        drop(r.render_gpu(&cam, &s).unwrap());
        let before = Traffic::now();
        let g = r.render_gpu(&cam, &s).unwrap();
        assert_eq!(Traffic::now().since(before).read_back, 0, "{m}");
        let before = Traffic::now();
        let (_, rays) = g.counts(&ctx.device, &ctx.queue).unwrap();
        let read = Traffic::now().since(before).read_back;
        assert!(read == 8 || read == 32, "{m}: {read} bytes");
        assert!(rays > 0, "{m}");
        let f = g.read(&ctx).unwrap();
        assert!(common::all_finite(&f.radiance), "{m}");
        assert_eq!(f.radiance, reference.radiance, "{m}");
        assert_eq!(f.shadow_rays, reference.shadow_rays, "{m}");
        assert_eq!(f.sp_clusters_used, reference.sp_clusters_used, "{m}");
    }
}

/// The frame on the GPU: `render_gpu` reads nothing back, with temporal reuse too (the clusterings'
/// counts stay on the GPU until `counts` asks for them), `GpuFrame::read` gives `render`'s images bit
/// for bit, the frame's buffers are reused once released (no allocation at a steady size), and
/// `render_to_texture` writes the final radiance bit for bit on the GPU, into a storage texture and
/// into a copy-destination one.
#[test]
fn frame_on_the_gpu_reads_nothing_back_and_matches_render() {
    let _serial = serial();
    let ctx = common::gpu();
    let sc = scene::load("builtin:cornell").unwrap();
    let cam = sc.default_camera();
    let s = settings(Weighting::InverseDistance);
    let image_bytes = (W * H) as u64 * 16;
    let reference = {
        let mut r = Renderer::new(&ctx, &sc).unwrap();
        r.render(&cam, &s).unwrap()
    };
    let mut r = Renderer::new(&ctx, &sc).unwrap();
    // Resident work (VPLs, their clusters) first; then frames at a steady size.
    drop(r.render_gpu(&cam, &s).unwrap());
    let before = Traffic::now();
    let g = r.render_gpu(&cam, &s).unwrap();
    let moved = Traffic::now().since(before);
    assert_eq!(
        moved.read_back, 0,
        "render_gpu read back {} bytes (an image is {image_bytes})",
        moved.read_back
    );
    // The counts the GPU keeps, on request: the same as render's.
    let before = Traffic::now();
    let (meta, _) = g.counts(&ctx.device, &ctx.queue).unwrap();
    assert!(Traffic::now().since(before).read_back < 128);
    assert!(meta.sp_clusters_used > 0);
    assert_eq!(
        (
            meta.sp_clusters_used,
            common::colom(&meta).sp_iterations,
            common::colom(&meta).sp_warm_kept
        ),
        (
            reference.sp_clusters_used,
            common::colom(&reference).sp_iterations,
            common::colom(&reference).sp_warm_kept
        )
    );
    let before = Traffic::now();
    let f = g.read(&ctx).unwrap();
    assert!(Traffic::now().since(before).read_back >= image_bytes * 6);
    assert!(common::all_finite(&f.radiance));
    assert_eq!(f.radiance, reference.radiance);
    assert_eq!(f.shading_points, reference.shading_points);
    assert_eq!(f.shadow_rays, reference.shadow_rays);
    // With temporal reuse (warm-started clusterings, visibility rows copied) neither.
    let temporal = RenderSettings {
        cluster: ClusterSettings {
            temporal: true,
            ..s.cluster.clone()
        },
        ..s.clone()
    };
    let mut t = Renderer::new(&ctx, &sc).unwrap();
    drop(t.render_gpu(&cam, &temporal).unwrap());
    let before = Traffic::now();
    let warm = t.render_gpu(&cam, &temporal).unwrap();
    assert_eq!(Traffic::now().since(before).read_back, 0);
    let (meta, _) = warm.counts(&ctx.device, &ctx.queue).unwrap();
    assert!(
        common::colom(&meta).sp_warm_kept.is_some()
            && common::colom(&meta).visibility_rows_reused > 0,
        "{meta:?}"
    );
    drop(warm);
    // At a steady size a frame makes no buffer (the clusterings' sets, the visibility matrices,
    // the passes' uniforms and textures are kept), with temporal reuse and without.
    for settings in [&temporal, &s] {
        drop(t.render_gpu(&cam, settings).unwrap());
        drop(t.render_gpu(&cam, settings).unwrap());
        let made = fuzzy_vpl::gpu::traffic::buffers_made();
        for _ in 0..3 {
            drop(t.render_gpu(&cam, settings).unwrap());
        }
        assert_eq!(
            fuzzy_vpl::gpu::traffic::buffers_made(),
            made,
            "steady frames made buffers (temporal {})",
            settings.cluster.temporal
        );
    }
    drop(g);
    for _ in 0..4 {
        drop(r.render_gpu(&cam, &s).unwrap());
    }
    let made = r.frame_sets_made();
    for _ in 0..4 {
        drop(r.render_gpu(&cam, &s).unwrap());
    }
    assert_eq!(
        r.frame_sets_made(),
        made,
        "frames at a steady size allocate"
    );
    assert!(made <= 3, "{made} frame sets");
    for usage in [
        wgpu::TextureUsages::STORAGE_BINDING,
        wgpu::TextureUsages::COPY_DST,
    ] {
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("host"),
            size: wgpu::Extent3d {
                width: W,
                height: H,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: usage | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let mut r = Renderer::new(&ctx, &sc).unwrap();
        r.render_to_texture(&cam, &s, &texture).unwrap();
        let bytes = read_texture(&ctx.device, &ctx.queue, &texture).unwrap();
        let texels: Vec<[f32; 3]> = bytes
            .chunks_exact(16)
            .map(|t| {
                let p: [f32; 4] = bytemuck::pod_read_unaligned(t);
                assert_eq!(p[3], 1.0);
                [p[0], p[1], p[2]]
            })
            .collect();
        assert_eq!(texels, reference.radiance, "{usage:?}");
    }
}

/// The shared path's reprojection (`app::reproject_gpu`) against its CPU twin (`cpu::reproject`) on
/// a displayed frame of each room seen from cameras moved by a step forward, a turn and a step
/// back (magnified, shifted, minified: holes filled, splats growing), and an oracle: from the
/// frame's own camera every pixel keeps its colour. Measured on lavapipe: every channel equal.
#[test]
fn reprojection_matches_cpu_twin() {
    let _serial = serial();
    use fuzzy_vpl::app::reproject_gpu::Reproject;
    use fuzzy_vpl::gi::primary::CameraParams;
    let ctx = common::gpu();
    let mut d = Display::new(&ctx.device);
    let mut rp = Reproject::new(&ctx.device);
    for name in ["builtin:cornell", "builtin:conference"] {
        let sc = scene::load(name).unwrap();
        let cam = sc.default_camera();
        let mut r = Renderer::new(&ctx, &sc).unwrap();
        let g = r
            .render_gpu(&cam, &settings(Weighting::InverseDistance))
            .unwrap();
        let inputs = DisplayInputs {
            size: (W, H),
            view: View::Final,
            a: gpu_images(&g),
            b: None,
            reference: None,
            labels: None,
            exposure: Exposure::Auto,
            direct_on: true,
            split: 0.5,
        };
        let (shown, _) = draw(&ctx, &mut d, &inputs);
        let gbuffer: Vec<[f32; 4]> = ctx
            .read_buffer(g.buffers.image_gbuffer(), (W * H * 4) as usize)
            .unwrap();
        let units =
            |c: &scene::Camera| CameraParams::new(&c.with_eye_scaled(g.geometry_scale), W, H);
        let diag = (sc.bounds().1 - sc.bounds().0).length();
        let moved = |forward: f32, turn: f32| {
            let mut c = cam.clone();
            let f = c.forward();
            c.transform = glam::Mat4::from_translation(c.eye() + f * forward * diag)
                * glam::Mat4::from_rotation_y(turn)
                * glam::Mat4::from_translation(-c.eye())
                * c.transform;
            c
        };
        let old = units(&cam);
        for (k, new_cam) in [
            cam.clone(),
            moved(0.05, 0.0),
            moved(0.0, 0.08),
            moved(-0.05, -0.05),
        ]
        .iter()
        .enumerate()
        {
            let new = units(new_cam);
            let mut enc = ctx.device.create_command_encoder(&Default::default());
            let image = &d.target().unwrap().texture;
            rp.record(
                &ctx.device,
                &ctx.queue,
                &mut enc,
                image,
                g.buffers.image_gbuffer(),
                (&old, &new),
            );
            ctx.queue.submit([enc.finish()]);
            let gpu = read_texture(&ctx.device, &ctx.queue, &rp.target().unwrap().texture).unwrap();
            let cpu = fuzzy_vpl::cpu::reproject::reproject(&shown, &gbuffer, &old, &new);
            let differing = gpu.iter().zip(&cpu).filter(|(a, b)| a != b).count();
            println!(
                "twin reproject {name} camera {k}: {differing} of {} channels differ",
                gpu.len()
            );
            assert_eq!(differing, 0, "{name} camera {k}");
            if k == 0 {
                assert_eq!(gpu, shown, "{name}: the frame's own camera moves nothing");
            } else {
                assert_ne!(gpu, shown, "{name} camera {k}: the image did not move");
            }
        }
    }
}
