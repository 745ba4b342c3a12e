//! The indirect light at the render scale (`--indirect-scale S < 1`, `FrameSettings::indirect_scale`):
//! the primary rays and the direct light run at the image's size; `downsample` builds the render-scale
//! G-buffer from the image's, one representative shading point a low-res pixel (the image pixel that
//! holds the low-res pixel's centre), the indirect passes of any method run on it unchanged, and the
//! `upsample` pass brings their light to every image pixel with joint bilateral weights
//! (`shaders-wgsl/upsample.wgsl`; CPU twin `cpu::upsample`).
//!
//! Why representatives rather than low-res primary rays of their own: no ray is traced twice, every
//! low-res shading point is a surface the image shows (a thin object seen only between the image's
//! pixel centres cannot take indirect light the image never uses), and the representative pixels
//! match a low-res tap exactly (plane distance 0, same normal).
//!
//! Weights of the 2×2 low-res taps around an image pixel: bilinear × exp(-(d / s)²) × max(0,
//! n·n_q)^8, d the tap's distance from the pixel's tangent plane and s the low-res pixel's
//! footprint at the pixel's depth: taps on the same plane keep their bilinear weight, taps across a
//! depth or orientation edge drop out. Where none is left (an edge the low-res G-buffer missed), the
//! pixel takes the tap of the surrounding 3×3 nearest in depth; a pixel that sees nothing gets 0.

use bytemuck::{Pod, Zeroable};

use super::dispatch::{Gpu, Kernel, Run};
use super::pass::Pass;
use super::primary::CameraParams;
use super::scene_gpu::{storage_layout, uniform_layout};
use crate::gpu::GpuContext;

/// The low-res size of a `width` × `height` image at indirect scale `scale` (each side rounded, at
/// least 1); the image's own size at scale 1.
pub fn indirect_size(width: u32, height: u32, scale: f32) -> (u32, u32) {
    if scale >= 1.0 {
        return (width, height);
    }
    let side = |s: u32| ((s as f64 * scale as f64).round() as u32).clamp(1, s);
    (side(width), side(height))
}

/// The low-res pixel an image pixel `i` lies in (nearest): what per-pixel data of the render-scale
/// G-buffer (SP cluster labels) is shown with at the image's size.
pub fn low_pixel(i: u32, image: (u32, u32), low: (u32, u32)) -> u32 {
    let x = ((i % image.0) as u64 * low.0 as u64 / image.0 as u64) as u32;
    let y = ((i / image.0) as u64 * low.1 as u64 / image.1 as u64) as u32;
    y * low.0 + x
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct UpsampleParams {
    /// Image width, height; low-res width, height.
    pub size: [u32; 4],
    /// xyz: the eye; w: the angle a low-res pixel spans.
    pub eye: [f32; 4],
}

impl UpsampleParams {
    /// For the image camera `image` (render units) and a low-res size.
    pub fn new(image: &CameraParams, low: (u32, u32)) -> Self {
        let up = glam::Vec3::from_slice(&image.up[..3]).length();
        let mut eye = image.eye;
        eye[3] = 2.0 * up / low.1 as f32;
        UpsampleParams {
            size: [image.size[0], image.size[1], low.0, low.1],
            eye,
        }
    }

    pub fn image_pixels(&self) -> u32 {
        self.size[0] * self.size[1]
    }

    pub fn low_pixels(&self) -> u32 {
        self.size[2] * self.size[3]
    }
}

/// The two kernels of `upsample.wgsl`.
pub struct Upsample {
    down: Kernel,
    up: Kernel,
    down_params: crate::gpu::persistent::Uniform<UpsampleParams>,
    up_params: crate::gpu::persistent::Uniform<UpsampleParams>,
}

/// What a `Renderer` keeps of this pass: its kernels (built on first use) and the last frame's
/// low-res size (`None`: its indirect light was at the image's size).
#[derive(Default)]
pub struct Upsampler {
    kernels: std::cell::OnceCell<Upsample>,
    pub last_low: Option<(u32, u32)>,
}

impl Upsampler {
    pub fn get(&self, ctx: &GpuContext) -> &Upsample {
        self.kernels.get_or_init(|| Upsample::new(ctx))
    }
}

/// Image pixels a submission covers (cheap kernels: a few loads a pixel).
const PER_CHUNK: u32 = 1 << 20;

impl Upsample {
    pub fn new(ctx: &GpuContext) -> Self {
        let base = [
            uniform_layout(1),
            storage_layout(2, true),
            storage_layout(3, false),
        ];
        let mut all = base.to_vec();
        all.extend([storage_layout(4, true), storage_layout(5, false)]);
        let kernel = |entry: &'static str, layout: &[wgpu::BindGroupLayoutEntry]| {
            Kernel::with_entries(ctx, None, "upsample", &[entry], layout, &[])
        };
        Upsample {
            down: kernel("downsample", &base),
            up: kernel("upsample", &all),
            down_params: crate::gpu::persistent::Uniform::new("downsample params"),
            up_params: crate::gpu::persistent::Uniform::new("upsample params"),
        }
    }

    /// Fills `low_gbuffer` with each low-res pixel's representative shading point of
    /// `image_gbuffer` (timed with the primary rays: together they are the frame's G-buffers).
    pub fn downsample(
        &self,
        g: &mut Gpu,
        p: &UpsampleParams,
        image_gbuffer: &wgpu::Buffer,
        low_gbuffer: &wgpu::Buffer,
    ) {
        let params = self.down_params.set(g.ctx, p);
        let bg = self
            .down
            .bind_group(g.ctx, &[(1, params), (2, image_gbuffer), (3, low_gbuffer)]);
        let run = Run {
            label: Pass::Primary.name(),
            group: &bg,
            seed: 0,
        };
        self.down
            .run(g, run, p.low_pixels(), PER_CHUNK, &mut |_, _| {});
    }

    /// Writes every image pixel's indirect light (`image_indirect`, vec4 a pixel) from the low-res
    /// `low_indirect` of `low_gbuffer`'s shading points.
    pub fn upsample(
        &self,
        g: &mut Gpu,
        p: &UpsampleParams,
        gbuffers: (&wgpu::Buffer, &wgpu::Buffer),
        low_indirect: &wgpu::Buffer,
        image_indirect: &wgpu::Buffer,
    ) {
        let params = self.up_params.set(g.ctx, p);
        let bg = self.up.bind_group(
            g.ctx,
            &[
                (1, params),
                (2, gbuffers.0),
                (3, gbuffers.1),
                (4, low_indirect),
                (5, image_indirect),
            ],
        );
        let run = Run {
            label: Pass::Upsample.name(),
            group: &bg,
            seed: 0,
        };
        self.up
            .run(g, run, p.image_pixels(), PER_CHUNK, &mut |_, _| {});
    }
}
