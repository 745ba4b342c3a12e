//! Batch ray queries on the GPU (closest hit and any hit) for the traversal tests and benchmark.

use anyhow::Result;
use bytemuck::{Pod, Zeroable};

use super::dispatch::Kernel;
use super::dispatch::{Gpu, Run};
use super::scene_gpu::{SceneGpu, storage_layout, uniform_layout};
use crate::gpu::{GpuContext, profiler::Profiler};

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuRay {
    /// xyz origin, w tmin.
    pub o: [f32; 4],
    /// xyz direction, w tmax.
    pub d: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Params {
    mode: u32,
    _pad: [u32; 3],
}

/// A GPU query result: closest hit (t, BVH slot, barycentrics) or occlusion.
#[derive(Clone, Copy, Debug)]
pub struct GpuHit {
    pub t: f32,
    /// BVH slot (`u32::MAX` on a miss).
    pub slot: u32,
    pub u: f32,
    pub v: f32,
}

pub struct Raycast {
    kernel: Kernel,
}

impl Raycast {
    pub fn new(ctx: &GpuContext, scene: &SceneGpu) -> Self {
        let entries = [
            uniform_layout(1),
            storage_layout(2, true),
            storage_layout(3, false),
        ];
        Raycast {
            kernel: Kernel::new(ctx, scene, "raycast", &entries, &[]),
        }
    }

    fn run(
        &self,
        ctx: &GpuContext,
        scene: &SceneGpu,
        profiler: &mut Profiler,
        rays: &[GpuRay],
        mode: u32,
    ) -> Result<Vec<[u32; 4]>> {
        let params = ctx.uniform("raycast params", &Params { mode, _pad: [0; 3] });
        let rays_buf = ctx.storage_init("rays", rays);
        let out = ctx.storage("hits", (rays.len() * 16) as u64);
        let bg = self
            .kernel
            .bind_group(ctx, &[(1, &params), (2, &rays_buf), (3, &out)]);
        let label = if mode == 0 {
            "raycast_closest"
        } else {
            "raycast_any"
        };
        let mut g = Gpu {
            ctx,
            scene,
            profiler,
        };
        let run = Run {
            label,
            group: &bg,
            seed: 0,
        };
        self.kernel
            .run(&mut g, run, rays.len() as u32, 1 << 16, &mut |_, _| {});
        ctx.read_buffer(&out, rays.len())
    }

    pub fn closest(
        &self,
        ctx: &GpuContext,
        scene: &SceneGpu,
        profiler: &mut Profiler,
        rays: &[GpuRay],
    ) -> Result<Vec<GpuHit>> {
        Ok(self
            .run(ctx, scene, profiler, rays, 0)?
            .into_iter()
            .map(|h| GpuHit {
                t: f32::from_bits(h[0]),
                slot: h[1],
                u: f32::from_bits(h[2]),
                v: f32::from_bits(h[3]),
            })
            .collect())
    }

    pub fn occluded(
        &self,
        ctx: &GpuContext,
        scene: &SceneGpu,
        profiler: &mut Profiler,
        rays: &[GpuRay],
    ) -> Result<Vec<bool>> {
        Ok(self
            .run(ctx, scene, profiler, rays, 1)?
            .into_iter()
            .map(|h| h[0] != 0)
            .collect())
    }
}
