//! Direct light + emission per shading point (`shaders-wgsl/direct.wgsl`); CPU twin in `cpu::direct`.

use bytemuck::{Pod, Zeroable};

use super::dispatch::Kernel;
use super::dispatch::{Gpu, Run};
use super::pass::Pass;
use super::scene_gpu::{SceneGpu, storage_layout, uniform_layout};
use crate::gpu::GpuContext;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct DirectParams {
    pub spp: u32,
    pub _pad: [u32; 3],
}

/// Shadow rays one invocation traces at most per dispatch: a multiple of the shader's `RNG_BLOCK` (64),
/// so every sub range starts a fresh random stream.
pub const SAMPLES_PER_DISPATCH: u32 = 64;

pub struct Direct {
    kernel: Kernel,
    params: crate::gpu::persistent::Uniform<DirectParams>,
}

impl Direct {
    pub fn new(ctx: &GpuContext, scene: &SceneGpu) -> Self {
        let entries = [
            uniform_layout(1),
            storage_layout(2, true),
            storage_layout(3, false),
        ];
        Direct {
            kernel: Kernel::new(ctx, scene, "direct", &entries, &[]),
            params: crate::gpu::persistent::Uniform::new("direct params"),
        }
    }

    /// Writes emission + direct light for `count` shading points into `radiance` (vec4 per pixel).
    pub fn record(
        &self,
        g: &mut Gpu,
        gbuffer: &wgpu::Buffer,
        radiance: &wgpu::Buffer,
        count: u32,
        spp: u32,
        seed: u32,
    ) {
        let ctx = g.ctx;
        let params = self.params.set(ctx, &DirectParams { spp, _pad: [0; 3] });
        let bg = self
            .kernel
            .bind_group(ctx, &[(1, params), (2, gbuffer), (3, radiance)]);
        // The samples (spp area samples, then the punctual lights) in sub ranges of at most
        // SAMPLES_PER_DISPATCH a pixel: lavapipe stops all loops of a SIMD batch after 65,535 trips
        // (direct.wgsl). About 2^20 shadow rays per submission.
        let samples = spp.saturating_add(g.scene.info.num_lights);
        let per_dispatch = samples.clamp(1, SAMPLES_PER_DISPATCH);
        let per_chunk = ((1u32 << 20) / per_dispatch).max(1024);
        let run = Run {
            label: Pass::Direct.name(),
            group: &bg,
            seed,
        };
        self.kernel.run_2d(
            g,
            run,
            (count, per_chunk),
            (samples.max(1), per_dispatch),
            &mut |_, _| true,
        );
    }
}
