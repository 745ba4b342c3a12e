//! One word of each item of a buffer summed on the GPU (`shaders-wgsl/sum_words.wgsl`) into a
//! 64-bit total in one slot of a ring that stays on the GPU: a method's per-pixel counts (the
//! shadow rays each pixel traced) become one number the frame leaves where it is and that is read
//! back only on request (`PendingSum::read`: the stats, the viewer's counts, the bench), never while
//! a frame is recorded. CPU twin: `sum_words_cpu`.

use bytemuck::{Pod, Zeroable};

use super::dispatch::{Gpu, Kernel, Run};
use super::scene_gpu::{storage_layout, uniform_layout};
use crate::gpu::GpuContext;
use crate::gpu::persistent::Uniform;

/// Totals the ring holds: a frame's pending total is exact while fewer than this many later
/// sums were recorded by the same `WordSum` before it is read.
pub const SLOTS: u32 = 64;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct SumParams {
    /// The words an item spans, the word summed, the slot, unused.
    words: [u32; 4],
}

/// Items a submission covers.
const PER_CHUNK: u32 = 1 << 20;

/// The kernel and its ring of totals (2 u32 a slot: low, high).
pub struct WordSum {
    kernel: Kernel,
    params: Uniform<SumParams>,
    ring: wgpu::Buffer,
    next: u32,
}

/// Which word of which items `WordSum::record` sums.
#[derive(Clone, Copy, Debug)]
pub struct Words {
    /// Items in the buffer.
    pub items: u32,
    /// u32 words an item spans.
    pub stride: u32,
    /// The word of an item summed (< `stride`).
    pub word: u32,
}

/// A total left on the GPU: its ring and slot.
#[derive(Clone, Debug)]
pub struct PendingSum {
    ring: wgpu::Buffer,
    slot: u32,
}

impl WordSum {
    pub fn new(ctx: &GpuContext) -> Self {
        let entries = [
            uniform_layout(1),
            storage_layout(2, true),
            storage_layout(3, false),
        ];
        WordSum {
            kernel: Kernel::with_entries(ctx, None, "sum_words", &["sum_words"], &entries, &[]),
            params: Uniform::new("sum_words params"),
            ring: ctx.storage("word sums", SLOTS as u64 * 8),
            next: 0,
        }
    }

    /// Records the sum of word `w.word` of each of the `w.items` items of `data` into the next
    /// slot (cleared first), timed under `label` (the pass whose counts they are); nothing is read
    /// back.
    pub fn record(
        &mut self,
        g: &mut Gpu,
        label: &str,
        data: &wgpu::Buffer,
        w: Words,
    ) -> PendingSum {
        assert!(w.word < w.stride, "word {} of {}", w.word, w.stride);
        let slot = self.next % SLOTS;
        self.next = self.next.wrapping_add(1);
        let mut enc = g.ctx.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.ring, slot as u64 * 8, Some(8));
        g.ctx.queue.submit([enc.finish()]);
        if w.items > 0 {
            let params = self.params.set(
                g.ctx,
                &SumParams {
                    words: [w.stride, w.word, slot, 0],
                },
            );
            let bg = self
                .kernel
                .bind_group(g.ctx, &[(1, params), (2, data), (3, &self.ring)]);
            let run = Run {
                label,
                group: &bg,
                seed: 0,
            };
            self.kernel.run(g, run, w.items, PER_CHUNK, &mut |_, _| {});
        }
        PendingSum {
            ring: self.ring.clone(),
            slot,
        }
    }
}

impl PendingSum {
    /// The total, read back (a wait for the GPU and 8 bytes: on request only).
    pub fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> anyhow::Result<u64> {
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("word sum (read back)"),
            size: 8,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(&self.ring, self.slot as u64 * 8, &staging, 0, 8);
        queue.submit([enc.finish()]);
        let words = crate::gpu::mapped(device, &staging, "a word sum", |view| {
            let w = bytemuck::cast_slice::<u8, u32>(view);
            [w[0], w[1]]
        })?;
        crate::gpu::traffic::read_back(8);
        Ok(words[0] as u64 | (words[1] as u64) << 32)
    }
}

/// The CPU twin of `sum_words.wgsl`: the sum of word `w.word` of each item of `data`.
pub fn sum_words_cpu(data: &[u32], w: Words) -> u64 {
    (0..w.items as usize)
        .map(|i| data[i * w.stride as usize + w.word as usize] as u64)
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shader_validates() {
        crate::gpu::shader::validate("sum_words").unwrap();
    }

    /// The twin against a hand-worked sum: word 2 of three 8-word items.
    #[test]
    fn the_twin_sums_one_word_an_item() {
        let mut data = vec![7u32; 24];
        (data[2], data[10], data[18]) = (1, 20, 300);
        let w = Words {
            items: 3,
            stride: 8,
            word: 2,
        };
        assert_eq!(sum_words_cpu(&data, w), 321);
    }

    /// The GPU's sum equals the twin's, a total past 2^32 included (the carry into the high
    /// word), and each slot keeps its own total.
    #[test]
    fn the_gpu_sum_is_the_twins() {
        let Ok(ctx) = GpuContext::new_headless() else {
            eprintln!("no adapter: the GPU sum is left unchecked");
            return;
        };
        let sc = crate::scene::load("builtin:cornell").unwrap();
        let bvh = crate::bvh::SceneBvh::build(&sc).unwrap();
        let scene = crate::gi::scene_gpu::SceneGpu::upload(&ctx, &sc, &bvh);
        let mut sum = WordSum::new(&ctx);
        let mut profiler = crate::gpu::profiler::Profiler::new(&ctx);
        let cases: Vec<(Vec<u32>, Words)> = vec![
            // 3000 pixels of one word, counts 0..=12 (a frame's rays, one word a pixel).
            (
                (0..3000u32).map(|i| i * 7 % 13).collect(),
                Words {
                    items: 3000,
                    stride: 1,
                    word: 0,
                },
            ),
            // 200 items of 8 words, the third summed (a state of 8 words a pixel).
            (
                (0..1600u32).map(|i| i * 31 % 97).collect(),
                Words {
                    items: 200,
                    stride: 8,
                    word: 2,
                },
            ),
            // 70 words of 2^31 + 5: past 2^32 within one workgroup and across groups.
            (
                vec![(1u32 << 31) + 5; 70],
                Words {
                    items: 70,
                    stride: 1,
                    word: 0,
                },
            ),
        ];
        let mut pending = Vec::new();
        for (data, w) in &cases {
            let buffer = ctx.storage_init("sum test data", data);
            let mut g = Gpu {
                ctx: &ctx,
                scene: &scene,
                profiler: &mut profiler,
            };
            pending.push(sum.record(&mut g, "sum test", &buffer, *w));
        }
        for ((data, w), p) in cases.iter().zip(&pending) {
            let got = p.read(&ctx.device, &ctx.queue).unwrap();
            assert_eq!(got, sum_words_cpu(data, *w), "{w:?}");
        }
        assert_eq!(
            sum_words_cpu(&cases[2].0, cases[2].1),
            70 * ((1u64 << 31) + 5)
        );
    }
}
