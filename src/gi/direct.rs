//! Direct light + emission per shading point (`shaders-wgsl/direct.wgsl`); CPU twin in `cpu::direct`.

use bytemuck::{Pod, Zeroable};

use super::dispatch::Kernel;
use super::scene_gpu::{SceneGpu, storage_layout, uniform_layout};
use crate::gpu::{GpuContext, profiler::Profiler};

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct DirectParams {
    pub spp: u32,
    pub _pad: [u32; 3],
}

pub struct Direct {
    kernel: Kernel,
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
        }
    }

    /// Writes emission + direct light for `count` shading points into `radiance` (vec4 per pixel).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        ctx: &GpuContext,
        scene: &SceneGpu,
        profiler: &mut Profiler,
        gbuffer: &wgpu::Buffer,
        radiance: &wgpu::Buffer,
        count: u32,
        spp: u32,
        seed: u32,
    ) {
        let params = ctx.uniform("direct params", &DirectParams { spp, _pad: [0; 3] });
        let bg = self
            .kernel
            .bind_group(ctx, &[(1, &params), (2, gbuffer), (3, radiance)]);
        // About 2^20 shadow rays per submission.
        let per_chunk = ((1u32 << 20) / (spp.max(1) + scene.info.num_lights)).max(1024);
        self.kernel.run(
            ctx,
            profiler,
            "direct",
            scene,
            &bg,
            count,
            per_chunk,
            seed,
            &mut |_, _| {},
        );
    }
}
