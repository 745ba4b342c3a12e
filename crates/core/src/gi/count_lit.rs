//! Lit pixels counted on the GPU (`shaders-wgsl/count_lit.wgsl`): each frame the viewer's shared
//! display path measures adds its count of pixels with a surface hit into its own slot of a ring of
//! counters that stays on the GPU; the ring is read back once, when the stats are written
//! (`motion.lit_fraction_min`), instead of each frame's G-buffer.

use bytemuck::{Pod, Zeroable};

use super::dispatch::{Gpu, Kernel, Run};
use super::scene_gpu::{storage_layout, uniform_layout};
use crate::gpu::GpuContext;

/// Frames the ring holds (their counts are read together).
pub const SLOTS: u32 = 4096;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct CountParams {
    slot: [u32; 4],
}

/// Pixels a submission covers.
const PER_CHUNK: u32 = 1 << 20;

pub struct CountLit {
    kernel: Kernel,
    /// One u32 a slot.
    pub ring: wgpu::Buffer,
    /// The next free slot.
    next: u32,
}

impl CountLit {
    pub fn new(ctx: &GpuContext) -> Self {
        let entries = [
            uniform_layout(1),
            storage_layout(2, true),
            storage_layout(3, false),
        ];
        CountLit {
            kernel: Kernel::with_entries(ctx, None, "count_lit", &["count_lit"], &entries, &[]),
            ring: ctx.storage("lit counts", SLOTS as u64 * 4),
            next: 0,
        }
    }

    /// Counts the valid shading points of `gbuffer` (4 vec4s a pixel, `pixels` of them) into the
    /// next slot, cleared first; returns the slot.
    pub fn record(&mut self, g: &mut Gpu, gbuffer: &wgpu::Buffer, pixels: u32) -> u32 {
        let slot = self.next % SLOTS;
        self.next = self.next.wrapping_add(1);
        let mut enc = g.ctx.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.ring, slot as u64 * 4, Some(4));
        g.ctx.queue.submit([enc.finish()]);
        let params = g.ctx.uniform(
            "count_lit params",
            &CountParams {
                slot: [slot, 0, 0, 0],
            },
        );
        let bg = self
            .kernel
            .bind_group(g.ctx, &[(1, &params), (2, gbuffer), (3, &self.ring)]);
        let run = Run {
            label: "count_lit",
            group: &bg,
            seed: 0,
        };
        self.kernel.run(g, run, pixels, PER_CHUNK, &mut |_, _| {});
        slot
    }
}
