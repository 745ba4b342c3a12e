//! The FLIP pass (`app::flip`, `shaders-wgsl/flip.wgsl`) against NVIDIA's FLIP (`metrics::flip_map`,
//! `metrics::flip`: the C++ of the `nv-flip` crate, the oracle) and against its CPU twin
//! (`metrics::ldr_flip`), on small images; and the display pass's FLIP view against the viewer's CPU FLIP
//! view (`views::flip`).

mod common;

use fuzzy_vpl::app::display::{Display, DisplayInputs, Images};
use fuzzy_vpl::app::flip::{Flip, FlipInputs};
use fuzzy_vpl::app::views::{self, View};
use fuzzy_vpl::exposure::Exposure;
use fuzzy_vpl::gpu::GpuContext;
use fuzzy_vpl::metrics;

const W: u32 = 64;
const H: u32 = 48;

/// A vec4 buffer of `img` on the device.
fn upload(ctx: &GpuContext, img: &[[f32; 3]]) -> wgpu::Buffer {
    let v: Vec<[f32; 4]> = img.iter().map(|p| [p[0], p[1], p[2], 0.0]).collect();
    ctx.storage_init("image", &v)
}

/// A named image pair (name, x, reference).
type Pair = (&'static str, Vec<[f32; 3]>, Vec<[f32; 3]>);

/// Test pairs of `w` × `h`.
fn pairs(w: u32, h: u32) -> Vec<Pair> {
    let (w, h) = (w as usize, h as usize);
    let mut rnd = common::Rand(0x9e37_79b9_7f4a_7c15);
    let grad: Vec<[f32; 3]> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 / w as f32, (i / w) as f32 / h as f32);
            [x, y * y, 0.3 + 0.5 * x * y]
        })
        .collect();
    let noisy: Vec<[f32; 3]> = grad
        .iter()
        .map(|p| p.map(|c| (c + 0.15 * (rnd.f32() - 0.5)).max(0.0)))
        .collect();
    let pattern = |shift: usize| -> Vec<[f32; 3]> {
        (0..w * h)
            .map(|i| {
                let (x, y) = (i % w + shift, i / w);
                if x % 11 == 5 && y % 9 == 4 {
                    [1.0, 1.0, 0.9]
                } else if (x / 8 + y / 6) % 2 == 0 {
                    [0.7, 0.25, 0.08]
                } else {
                    [0.04, 0.09, 0.35]
                }
            })
            .collect()
    };
    let offset: Vec<[f32; 3]> = grad.iter().map(|p| [p[0] + 0.08, p[1], p[2]]).collect();
    // Values a frame may hold: ±∞, negative, far over 1 (NaN in the reference only: A's NaN goes
    // through the GPU's `min` with f32::MAX, whose NaN rule is the driver's).
    let hostile: Vec<[f32; 3]> = noisy
        .iter()
        .enumerate()
        .map(|(i, p)| match i % 13 {
            1 => [p[0], f32::INFINITY, p[2]],
            2 => [p[0], p[1], f32::NEG_INFINITY],
            3 => [-1.0, p[1], 40.0],
            _ => *p,
        })
        .collect();
    let hostile_ref: Vec<[f32; 3]> = grad
        .iter()
        .enumerate()
        .map(|(i, p)| match i % 7 {
            0 => [f32::NAN, p[1], p[2]],
            1 => [p[0], f32::INFINITY, -3.0],
            _ => *p,
        })
        .collect();
    vec![
        ("gradient vs noisy", noisy, grad.clone()),
        ("edges and points vs shifted", pattern(1), pattern(0)),
        ("constant offset", offset, grad.clone()),
        ("identical", grad.clone(), grad.clone()),
        ("hostile values", hostile, hostile_ref),
    ]
}

/// FLIP of `x` against `reference` on the GPU at `exposure`, A given as `x / 2` with scale 2 (the
/// frame's factor to scene units; exact in binary): the map and the mean read back.
fn gpu_flip(
    ctx: &GpuContext,
    f: &mut Flip,
    x: &[[f32; 3]],
    reference: &[[f32; 3]],
    (w, h): (u32, u32),
    exposure: f32,
) -> (Vec<f32>, f32) {
    let half: Vec<[f32; 3]> = x.iter().map(|p| p.map(|c| c * 0.5)).collect();
    let direct = upload(ctx, &half);
    let zero = upload(ctx, &vec![[0.0; 3]; x.len()]);
    let reference = upload(ctx, reference);
    let e = ctx.storage_init("exposure", &[exposure]);
    let inputs = FlipInputs {
        size: (w, h),
        a: Images {
            direct: &direct,
            indirect: &zero,
            scale: 2.0,
        },
        reference: &reference,
        exposure: &e,
    };
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    f.record(&ctx.device, &ctx.queue, &mut enc, &inputs, None);
    ctx.queue.submit([enc.finish()]);
    let map: Vec<f32> = ctx.read_buffer(f.map().unwrap(), x.len()).unwrap();
    let mean: Vec<f32> = ctx.read_buffer(f.mean().unwrap(), 1).unwrap();
    (map, mean[0])
}

fn max_mean_abs(a: &[f32], b: &[f32]) -> (f32, f64) {
    assert_eq!(a.len(), b.len());
    let d = a.iter().zip(b).map(|(x, y)| (x - y).abs());
    let max = d.clone().fold(0.0f32, f32::max);
    let mean = d.map(|v| v as f64).sum::<f64>() / a.len().max(1) as f64;
    (max, mean)
}

/// The GPU map against NVIDIA's FLIP and the CPU twin on each pair at exposures 1 and 1.7 (the
/// latter saturating), 64 × 48 and 37 × 23 (a partial row tile, a size that is no multiple of
/// anything); the mean against `metrics::flip`; identical images give 0 everywhere; every value
/// finite and in [0, 1]. Measured on lavapipe (Mesa 22.3.6, this 2-core VM): GPU map against
/// nv-flip max abs 4.56e-5 (edges vs shifted, exposure 1.7), mean abs at most 9.4e-7 a pair, the
/// mean within 1.0e-7; the GPU against the twin the same (max 4.56e-5); the twin against nv-flip
/// 1.1e-8 (bit-equal on 19 of 20 cases). The tone map is bit-exact (8-bit steps searched, FLIP's
/// linear values from a table); what is left is the GPU's pow/exp2/log2 and fused multiply-adds.
/// The bounds sit just above the measured figures.
#[test]
fn flip_pass_matches_nv_flip() {
    let ctx = common::gpu();
    let mut f = Flip::new(&ctx.device);
    let (mut worst, mut worst_mean_abs, mut worst_mean, mut worst_twin) = (0f32, 0f64, 0f64, 0f32);
    for size in [(W, H), (37, 23)] {
        for (name, x, reference) in pairs(size.0, size.1) {
            for exposure in [1.0f32, 1.7] {
                let (map, mean) = gpu_flip(&ctx, &mut f, &x, &reference, size, exposure);
                assert!(
                    map.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)),
                    "{name}: a value off [0, 1]"
                );
                assert!(mean.is_finite());
                let p = metrics::FlipInputs {
                    x: &x,
                    reference: &reference,
                    width: size.0,
                    height: size.1,
                    exposure,
                };
                let (nv, twin) = (metrics::flip_map(p), metrics::ldr_flip::flip_map(p));
                let (max, mean_abs) = max_mean_abs(&map, &nv);
                let (twin_max, _) = max_mean_abs(&twin, &nv);
                let (gpu_twin, _) = max_mean_abs(&map, &twin);
                let nv_mean = metrics::flip(&x, &reference, size.0, size.1, exposure);
                let mean_err = (mean as f64 - nv_mean).abs();
                println!(
                    "{size:?} {name} e {exposure}: GPU vs nv-flip max abs {max:.2e}, mean abs \
                     {mean_abs:.2e}; mean {mean:.6} vs {nv_mean:.6} ({mean_err:.2e}); twin vs \
                     nv-flip max abs {twin_max:.2e}; GPU vs twin {gpu_twin:.2e}"
                );
                assert!(gpu_twin <= 6e-5, "{name}: GPU off its twin by {gpu_twin}");
                if name == "identical" {
                    assert!(map.iter().all(|&v| v == 0.0), "identical images: not 0");
                    assert_eq!(mean, 0.0);
                }
                worst = worst.max(max);
                worst_mean_abs = worst_mean_abs.max(mean_abs);
                worst_mean = worst_mean.max(mean_err);
                worst_twin = worst_twin.max(twin_max);
            }
        }
    }
    println!(
        "worst: GPU map max abs {worst:.2e}, mean abs {worst_mean_abs:.2e}, mean {worst_mean:.2e}; \
         twin {worst_twin:.2e}"
    );
    assert!(worst <= 6e-5, "GPU map off nv-flip by {worst}");
    assert!(
        worst_mean_abs <= 1.5e-6,
        "GPU map off nv-flip by {worst_mean_abs} on average"
    );
    assert!(worst_mean <= 2e-7, "GPU mean off by {worst_mean}");
    assert!(worst_twin <= 5e-8, "twin off nv-flip by {worst_twin}");
}

/// The pass on a device with WebGPU's default limits (the split display path's window device: 8
/// storage buffers a stage, 16 KiB of workgroup memory, 128 MiB a binding): it fits them and gives
/// the same map as on the project's device (lavapipe: bit-equal).
#[test]
fn flip_pass_runs_under_default_limits() {
    use wgpu::util::DeviceExt;
    let ctx = common::gpu();
    let (device, queue) = pollster::block_on(ctx.adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("default limits"),
        required_limits: wgpu::Limits::default().using_resolution(ctx.adapter.limits()),
        ..Default::default()
    }))
    .unwrap();
    let buffer = |data: &[u8]| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: data,
            usage: wgpu::BufferUsages::STORAGE,
        })
    };
    let vec4 = |img: &[[f32; 3]]| -> Vec<[f32; 4]> {
        img.iter().map(|p| [p[0], p[1], p[2], 0.0]).collect()
    };
    let (_, x, reference) = pairs(W, H).swap_remove(1);
    let (direct, zero, ref_buf) = (
        buffer(bytemuck::cast_slice(&vec4(&x))),
        buffer(&vec![0u8; x.len() * 16]),
        buffer(bytemuck::cast_slice(&vec4(&reference))),
    );
    let exposure = buffer(bytemuck::cast_slice(&[1.0f32; 64]));
    let mut f = Flip::new(&device);
    let mut enc = device.create_command_encoder(&Default::default());
    f.record(
        &device,
        &queue,
        &mut enc,
        &FlipInputs {
            size: (W, H),
            a: Images {
                direct: &direct,
                indirect: &zero,
                scale: 1.0,
            },
            reference: &ref_buf,
            exposure: &exposure,
        },
        None,
    );
    queue.submit([enc.finish()]);
    let map: Vec<f32> =
        fuzzy_vpl::gpu::read_buffer(&device, &queue, f.map().unwrap(), x.len()).unwrap();
    let (on_ctx, _) = gpu_flip(
        &ctx,
        &mut Flip::new(&ctx.device),
        &x,
        &reference,
        (W, H),
        1.0,
    );
    assert!(map.iter().all(|v| v.is_finite()));
    let (max, _) = max_mean_abs(&map, &on_ctx);
    println!("default limits vs the project's device: max abs {max:.2e}");
    assert!(max <= 1e-6, "{max}");
}

/// The display pass's FLIP view (the FLIP pass's map in magma) against the viewer's CPU FLIP view
/// (`views::flip`: nv-flip's map through its magma LUT) on a clustered frame of the Cornell box
/// against its reference, fixed and automatic exposure, and on the test pairs; the FLIP view
/// without a reference draws the final view. Measured on lavapipe: 2 of 18 816 pixels differ (a
/// FLIP value at a LUT step: the neighbouring magma entry, by 2 and 3 in a channel), none on the
/// Cornell box at a fixed exposure; the mean within 1.6e-8 of nv-flip's. Bounds: a channel by 4,
/// one pixel in 2000, the mean 2e-7.
#[test]
fn display_flip_view_matches_views_flip() {
    use fuzzy_vpl::render::{RenderSettings, Renderer};
    use fuzzy_vpl::settings::ClusterSettings;
    let ctx = common::gpu();
    let mut d = Display::new(&ctx.device);
    let draw = |d: &mut Display, inputs: &DisplayInputs| common::draw_display(&ctx, d, inputs);
    let compare = |name: &str, gpu: &[u8], cpu: &[u8]| -> (usize, i32) {
        assert_eq!(gpu.len(), cpu.len());
        let mut differing = 0;
        let mut worst = 0;
        for (g, c) in gpu.chunks(4).zip(cpu.chunks(4)) {
            let d = (0..4)
                .map(|k| (g[k] as i32 - c[k] as i32).abs())
                .max()
                .unwrap();
            differing += (d > 0) as usize;
            worst = worst.max(d);
        }
        println!(
            "{name}: {differing} of {} pixels differ, worst channel by {worst}",
            gpu.len() / 4
        );
        (differing, worst)
    };
    let (mut differing, mut pixels, mut worst) = (0usize, 0usize, 0i32);
    // A rendered frame: A clustered, the reference its unclustered render.
    let (w, h) = (48u32, 36u32);
    let sc = fuzzy_vpl::scene::load("builtin:cornell").unwrap();
    let cam = sc.default_camera();
    let s = common::display_frame(ClusterSettings::default().weighting);
    assert_eq!((s.frame.width, s.frame.height), (w, h));
    let mut r = Renderer::new(&ctx, &sc).unwrap();
    let a = r.render_gpu(&cam, &s).unwrap();
    let reference = r
        .render(
            &cam,
            &RenderSettings {
                reference: true,
                ..s.clone()
            },
        )
        .unwrap();
    let fa = a.read(&ctx).unwrap();
    assert!(common::all_finite(&fa.radiance) && common::all_finite(&reference.radiance));
    let ref_gpu = upload(&ctx, &reference.radiance);
    let images = Images {
        direct: &a.buffers.radiance,
        indirect: a.buffers.image_indirect(),
        scale: a.output_scale,
    };
    for exposure in [Exposure::Fixed(0.8), Exposure::Auto] {
        let inputs = DisplayInputs {
            size: (w, h),
            view: View::Flip,
            a: images,
            b: None,
            reference: Some(&ref_gpu),
            labels: None,
            exposure,
            direct_on: true,
            split: 0.5,
        };
        let (gpu, e) = draw(&mut d, &inputs);
        let cpu = views::flip(&fa.radiance, &reference.radiance, w, h, e);
        let (dp, dw) = compare(&format!("cornell {exposure:?}"), &gpu, &cpu);
        differing += dp;
        pixels += (w * h) as usize;
        worst = worst.max(dw);
        // The pass's mean against nv-flip's at the exposure the display used.
        let mean: Vec<f32> = ctx
            .read_buffer(d.flip().unwrap().mean().unwrap(), 1)
            .unwrap();
        let nv = metrics::flip(&fa.radiance, &reference.radiance, w, h, e);
        println!("cornell {exposure:?}: mean {} vs nv-flip {nv}", mean[0]);
        assert!((mean[0] as f64 - nv).abs() <= 2e-7);
    }
    // Without a reference: the final view.
    let inputs = DisplayInputs {
        size: (w, h),
        view: View::Flip,
        a: images,
        b: None,
        reference: None,
        labels: None,
        exposure: Exposure::Fixed(0.8),
        direct_on: true,
        split: 0.5,
    };
    let (gpu, _) = draw(&mut d, &inputs);
    let fin = views::tonemap(&views::final_image(&fa.direct, &fa.indirect, true), 0.8);
    let (dp, _) = compare("no reference: final view", &gpu, &fin);
    assert!(dp * 500 <= (w * h) as usize);
    // The test pairs, fixed exposure.
    for (name, x, reference) in pairs(W, H) {
        let direct = upload(&ctx, &x);
        let zero = upload(&ctx, &vec![[0.0; 3]; x.len()]);
        let ref_gpu = upload(&ctx, &reference);
        let inputs = DisplayInputs {
            size: (W, H),
            view: View::Flip,
            a: Images {
                direct: &direct,
                indirect: &zero,
                scale: 1.0,
            },
            b: None,
            reference: Some(&ref_gpu),
            labels: None,
            exposure: Exposure::Fixed(1.0),
            direct_on: true,
            split: 0.5,
        };
        let (gpu, _) = draw(&mut d, &inputs);
        let cpu = views::flip(&x, &reference, W, H, 1.0);
        let (dp, dw) = compare(name, &gpu, &cpu);
        differing += dp;
        pixels += (W * H) as usize;
        worst = worst.max(dw);
    }
    println!("display FLIP view: {differing} of {pixels} pixels differ, worst channel by {worst}");
    assert!(worst <= 4, "a magma colour off by {worst}");
    assert!(
        differing * 2000 <= pixels,
        "{differing} of {pixels} pixels differ"
    );
}
