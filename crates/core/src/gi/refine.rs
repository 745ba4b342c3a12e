//! The direct light at rest refined on the GPU (`shaders-wgsl/refine.wgsl`): each new estimate is
//! blended into the frame's emission + direct light as a running mean (weight 1 / n), in place, so
//! the viewer's shared display path shows the mean without reading anything back
//! (`Renderer::refine_direct`).

use bytemuck::{Pod, Zeroable};

use super::dispatch::{Gpu, Kernel, Run};
use super::scene_gpu::{storage_layout, uniform_layout};
use crate::gpu::GpuContext;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct RefineParams {
    n: [u32; 4],
}

/// Pixels a submission covers (two loads and a store a pixel).
const PER_CHUNK: u32 = 1 << 20;

pub struct Refine {
    kernel: Kernel,
}

impl Refine {
    pub fn new(ctx: &GpuContext) -> Self {
        let entries = [
            uniform_layout(1),
            storage_layout(2, true),
            storage_layout(3, false),
        ];
        Refine {
            kernel: Kernel::with_entries(ctx, None, "refine", &["refine"], &entries, &[]),
        }
    }

    /// `mean` (the mean of `n` − 1 estimates, a vec4 a pixel) becomes the mean of `n` with
    /// `estimate`, over `pixels`.
    pub fn record(
        &self,
        g: &mut Gpu,
        estimate: &wgpu::Buffer,
        mean: &wgpu::Buffer,
        n: u32,
        pixels: u32,
    ) {
        let params = g.ctx.uniform(
            "refine params",
            &RefineParams {
                n: [n.max(1), 0, 0, 0],
            },
        );
        let bg = self
            .kernel
            .bind_group(g.ctx, &[(1, &params), (2, estimate), (3, mean)]);
        let run = Run {
            label: "refine",
            group: &bg,
            seed: 0,
        };
        self.kernel.run(g, run, pixels, PER_CHUNK, &mut |_, _| {});
    }
}
