//! Temporal accumulation of the indirect light (`--temporal on`, `ClusterSettings::temporal_alpha`):
//! after the indirect passes of any method (and `upsample`), every pixel's surface point is
//! projected into the previous frame; that frame's accumulated indirect light is read there
//! bilinearly from the taps that show the same surface, and blended with this frame's. The result is
//! an exponential moving average at each surface point over the frames that saw it: the mean of the
//! frames so far while the history is short, then weight α for the new frame
//! (`shaders-wgsl/accumulate.wgsl`; CPU twin `cpu::accumulate`).
//!
//! Same surface: the tap's shading point lies within `DEPTH_TOLERANCE` of the point's depth along the
//! previous view, and their normals within `NORMAL_COS` (the tests of `metrics::instability_world`).
//! A point no tap matches (disoccluded, off the previous image) starts a new history. The indirect
//! light of a diffuse surface does not depend on the view, so the history is valid while the scene,
//! its lights and the settings stay (`render::history`); the direct light is not accumulated (its noise is
//! the accumulation at rest's business, `Renderer::direct_again`).
//!
//! Why: with temporal reuse the SP clusters are anchored to the world, yet the error of a surface
//! point still changes from frame to frame (a re-seeded cluster, a new representative, the pixel
//! grid sliding over the fuzzy weights' edges), which is what the eye sees as flicker
//! (docs/temporal.md, `instability_world`).

use bytemuck::{Pod, Zeroable};

use super::dispatch::{Gpu, Kernel, Run};
use super::pass::Pass;
use super::primary::CameraParams;
use super::scene_gpu::{storage_layout, uniform_layout};
use crate::gpu::GpuContext;

/// A history tap is the same surface when its depth along the previous view is within this fraction
/// of the point's (as `metrics::SAME_SURFACE_DEPTH`) ...
pub const DEPTH_TOLERANCE: f32 = crate::metrics::SAME_SURFACE_DEPTH;
/// ... and the normals' cosine at least this (about 25°, `metrics::SAME_SURFACE_COS`).
pub const NORMAL_COS: f32 = crate::metrics::SAME_SURFACE_COS;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct AccumulateParams {
    /// Width, height, 1 when there is a history (0: none), 1 when the previous camera is this
    /// frame's.
    pub size: [u32; 4],
    /// The previous frame's camera (render units; its `size` is the previous frame's).
    pub prev: CameraParams,
    /// x: α; y: `DEPTH_TOLERANCE`; z: `NORMAL_COS`.
    pub blend: [f32; 4],
}

impl AccumulateParams {
    /// For a frame of camera `cam` whose history was rendered from `prev` (`None`: no history), with
    /// weight `alpha` in (0, 1] for the new frame.
    pub fn new(cam: &CameraParams, prev: Option<&CameraParams>, alpha: f32) -> Self {
        let p = prev.unwrap_or(cam);
        AccumulateParams {
            size: [
                cam.size[0],
                cam.size[1],
                prev.is_some() as u32,
                prev.is_some_and(|p| bytemuck::bytes_of(p) == bytemuck::bytes_of(cam)) as u32,
            ],
            prev: *p,
            blend: [alpha, DEPTH_TOLERANCE, NORMAL_COS, 0.0],
        }
    }

    pub fn pixels(&self) -> u32 {
        self.size[0] * self.size[1]
    }
}

/// Image pixels a submission covers (a few loads a pixel).
const PER_CHUNK: u32 = 1 << 20;

pub struct Accumulate {
    kernel: Kernel,
    params: crate::gpu::persistent::Uniform<AccumulateParams>,
    /// Stands in for the history's indirect light without a history (made once).
    stand_in: std::sync::OnceLock<wgpu::Buffer>,
}

impl Accumulate {
    pub fn new(ctx: &GpuContext) -> Self {
        let entries = [
            uniform_layout(1),
            storage_layout(2, true),
            storage_layout(3, true),
            storage_layout(4, true),
            storage_layout(5, false),
        ];
        Accumulate {
            kernel: Kernel::with_entries(ctx, None, "accumulate", &["accumulate"], &entries, &[]),
            params: crate::gpu::persistent::Uniform::new("accumulate params"),
            stand_in: Default::default(),
        }
    }

    /// Blends `indirect` (this frame's, on `gbuffer`) in place with `history`, the previous frame's
    /// (G-buffer, accumulated indirect light) (`None`: the frame starts one; `indirect` then only
    /// gets w = 1).
    pub fn record(
        &self,
        g: &mut Gpu,
        p: &AccumulateParams,
        gbuffer: &wgpu::Buffer,
        history: Option<(&wgpu::Buffer, &wgpu::Buffer)>,
        indirect: &wgpu::Buffer,
    ) {
        // Bound but not read without a history (`size.z` = 0).
        let (prev_gbuffer, prev_indirect) = history.unwrap_or((gbuffer, indirect));
        // A buffer may not be bound both read-only and read-write: without a history the current
        // frame's buffers stand in through copies of one element.
        let prev_indirect = if std::ptr::eq(prev_indirect, indirect) {
            self.stand_in
                .get_or_init(|| g.ctx.storage("accumulate (no history)", 16))
        } else {
            prev_indirect
        };
        let params = self.params.set(g.ctx, p);
        let bg = self.kernel.bind_group(
            g.ctx,
            &[
                (1, params),
                (2, gbuffer),
                (3, prev_gbuffer),
                (4, prev_indirect),
                (5, indirect),
            ],
        );
        let run = Run {
            label: Pass::Accumulate.name(),
            group: &bg,
            seed: 0,
        };
        self.kernel
            .run(g, run, p.pixels(), PER_CHUNK, &mut |_, _| {});
    }
}
