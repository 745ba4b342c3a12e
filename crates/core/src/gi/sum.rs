//! One word of each item of a buffer summed on the GPU (`shaders-wgsl/sum_words.wgsl`) into a
//! 64-bit total in one slot of a ring that stays on the GPU: the word's value (`Each::Value`: a
//! method's per-pixel counts, the shadow rays each pixel traced) or 1 where the word, an f32, is
//! positive (`Each::Positive`: the viewer's lit pixels, the G-buffer's `pos.w > 0`). Each total is
//! one number the frame leaves where it is and that is read back only on request
//! (`PendingSum::read`, `read_all` for many at once: the stats, the viewer's counts, the bench),
//! never while a frame is recorded. CPU twin: `sum_words_cpu`.

use bytemuck::{Pod, Zeroable};

use super::dispatch::{Gpu, Kernel, Run};
use super::scene_gpu::{storage_layout, uniform_layout};
use crate::gpu::GpuContext;
use crate::gpu::persistent::Uniform;

/// Totals the ring of `WordSum::new` holds: a frame's pending total is exact while fewer than
/// this many later sums were recorded by the same `WordSum` before it is read.
pub const SLOTS: u32 = 64;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct SumParams {
    /// The words an item spans, the word summed, the slot, what each item adds (`Each`).
    words: [u32; 4],
}

/// Items a submission covers.
const PER_CHUNK: u32 = 1 << 20;

/// The kernel and its ring of totals (2 u32 a slot: low, high).
pub struct WordSum {
    kernel: Kernel,
    params: Uniform<SumParams>,
    ring: wgpu::Buffer,
    slots: u32,
    next: u32,
}

/// What an item adds to the total (`SumParams.words.w`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Each {
    /// The word's value.
    Value = 0,
    /// 1 where the word, read as an f32, is positive (NaN is not), else 0: a count of items.
    Positive = 1,
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
    /// What the word adds.
    pub each: Each,
}

/// A total left on the GPU: its ring and slot.
#[derive(Clone, Debug)]
pub struct PendingSum {
    ring: wgpu::Buffer,
    slot: u32,
}

impl WordSum {
    /// A ring of `SLOTS` totals.
    pub fn new(ctx: &GpuContext) -> Self {
        Self::with_slots(ctx, SLOTS)
    }

    /// A ring of `slots` totals (at least 1).
    pub fn with_slots(ctx: &GpuContext, slots: u32) -> Self {
        let slots = slots.max(1);
        let entries = [
            uniform_layout(1),
            storage_layout(2, true),
            storage_layout(3, false),
        ];
        WordSum {
            kernel: Kernel::with_entries(ctx, None, "sum_words", &["sum_words"], &entries, &[]),
            params: Uniform::new("sum_words params"),
            ring: ctx.storage("word sums", slots as u64 * 8),
            slots,
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
        let slot = self.next % self.slots;
        self.next = self.next.wrapping_add(1);
        let mut enc = g.ctx.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.ring, slot as u64 * 8, Some(8));
        g.ctx.queue.submit([enc.finish()]);
        if w.items > 0 {
            let params = self.params.set(
                g.ctx,
                &SumParams {
                    words: [w.stride, w.word, slot, w.each as u32],
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
        Ok(read_all(device, queue, std::slice::from_ref(self))?[0])
    }
}

/// The totals of `pending`, in order, read back together: one copy of 8 bytes a total into one
/// staging buffer and one wait for the GPU (on request only).
pub fn read_all(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    pending: &[PendingSum],
) -> anyhow::Result<Vec<u64>> {
    if pending.is_empty() {
        return Ok(Vec::new());
    }
    let bytes = pending.len() as u64 * 8;
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("word sums (read back)"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = device.create_command_encoder(&Default::default());
    for (i, p) in pending.iter().enumerate() {
        enc.copy_buffer_to_buffer(&p.ring, p.slot as u64 * 8, &staging, i as u64 * 8, 8);
    }
    queue.submit([enc.finish()]);
    let totals = crate::gpu::mapped(device, &staging, "word sums", |view| {
        bytemuck::cast_slice::<u8, u32>(view)
            .chunks_exact(2)
            .map(|w| w[0] as u64 | (w[1] as u64) << 32)
            .collect()
    })?;
    crate::gpu::traffic::read_back(bytes);
    Ok(totals)
}

/// The CPU twin of `sum_words.wgsl`: what word `w.word` of each item of `data` adds (`w.each`),
/// summed.
pub fn sum_words_cpu(data: &[u32], w: Words) -> u64 {
    (0..w.items as usize)
        .map(|i| data[i * w.stride as usize + w.word as usize])
        .map(|v| match w.each {
            Each::Value => v as u64,
            Each::Positive => (f32::from_bits(v) > 0.0) as u64,
        })
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
            each: Each::Value,
        };
        assert_eq!(sum_words_cpu(&data, w), 321);
    }

    /// The twin's count of positive f32 words against a hand-worked one: the lit pixels of four
    /// shading points (16 words, `pos.w` the fourth), two of them lit; a negative, a NaN and a -0
    /// count as unlit.
    #[test]
    fn the_twin_counts_positive_words() {
        let w3 = |v: f32| {
            let mut p = [0f32; 16];
            p[3] = v;
            p
        };
        let points = [w3(1.0), w3(0.0), w3(0.5), w3(-1.0), w3(f32::NAN), w3(-0.0)];
        let data: Vec<u32> = points.iter().flatten().map(|x| x.to_bits()).collect();
        let w = Words {
            items: points.len() as u32,
            stride: 16,
            word: 3,
            each: Each::Positive,
        };
        assert_eq!(sum_words_cpu(&data, w), 2);
    }

    /// The GPU's sum equals the twin's, a total past 2^32 included (the carry into the high
    /// word), a count of positive words included, and each slot keeps its own total; read one by
    /// one and all together (`read_all`).
    #[test]
    fn the_gpu_sum_is_the_twins() {
        let Ok(ctx) = GpuContext::new_headless() else {
            eprintln!("no adapter: the GPU sum is left unchecked");
            return;
        };
        let sc = crate::scene::load("builtin:cornell").unwrap();
        let bvh = crate::bvh::SceneBvh::build(&sc).unwrap();
        let scene = crate::gi::scene_gpu::SceneGpu::upload(&ctx, &sc, &bvh);
        // A ring of 3 slots for 4 sums: the fourth wraps onto the first's slot.
        let mut sum = WordSum::with_slots(&ctx, 3);
        let mut profiler = crate::gpu::profiler::Profiler::new(&ctx);
        let cases: Vec<(Vec<u32>, Words)> = vec![
            // 3000 pixels of one word, counts 0..=12 (a frame's rays, one word a pixel).
            (
                (0..3000u32).map(|i| i * 7 % 13).collect(),
                Words {
                    items: 3000,
                    stride: 1,
                    word: 0,
                    each: Each::Value,
                },
            ),
            // 200 items of 8 words, the third summed (a state of 8 words a pixel).
            (
                (0..1600u32).map(|i| i * 31 % 97).collect(),
                Words {
                    items: 200,
                    stride: 8,
                    word: 2,
                    each: Each::Value,
                },
            ),
            // 70 words of 2^31 + 5: past 2^32 within one workgroup and across groups.
            (
                vec![(1u32 << 31) + 5; 70],
                Words {
                    items: 70,
                    stride: 1,
                    word: 0,
                    each: Each::Value,
                },
            ),
            // 1000 shading points of 16 words, `pos.w` (the fourth) 1, 0, -1, NaN or 0.25: the
            // lit pixels counted (the viewer's lit fraction).
            (
                (0..16000u32)
                    .map(|i| match (i % 16, i / 16 % 5) {
                        (3, 0) => 1f32,
                        (3, 1) => 0.0,
                        (3, 2) => -1.0,
                        (3, 3) => f32::NAN,
                        (3, _) => 0.25,
                        (_, k) => k as f32,
                    })
                    .map(f32::to_bits)
                    .collect(),
                Words {
                    items: 1000,
                    stride: 16,
                    word: 3,
                    each: Each::Positive,
                },
            ),
        ];
        let mut pending = Vec::new();
        let mut read = Vec::new();
        for (data, w) in &cases {
            let buffer = ctx.storage_init("sum test data", data);
            let mut g = Gpu {
                ctx: &ctx,
                scene: &scene,
                profiler: &mut profiler,
            };
            let p = sum.record(&mut g, "sum test", &buffer, *w);
            read.push(p.read(&ctx.device, &ctx.queue).unwrap());
            pending.push(p);
        }
        let twins: Vec<u64> = cases.iter().map(|(d, w)| sum_words_cpu(d, *w)).collect();
        assert_eq!(read, twins);
        // The last three together (the first's slot holds the fourth's total now).
        let all = read_all(&ctx.device, &ctx.queue, &pending[1..]).unwrap();
        assert_eq!(all, twins[1..]);
        // 1000 points: 200 each of w = 1, 0, -1, NaN, 0.25; 400 lit.
        assert_eq!(twins[3], 400);
        assert_eq!(
            sum_words_cpu(&cases[2].0, cases[2].1),
            70 * ((1u64 << 31) + 5)
        );
    }
}
