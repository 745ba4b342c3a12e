//! The `restir` method (ReSTIR DI: Bitterli, Wyman, Pharr, Shirley, Novák, Jarosz, SIGGRAPH 2020;
//! docs/methods.md) over the frame's VPLs: each pixel resamples M candidates drawn by flux (an
//! alias table built once per VPL set, `alias`) by Eq. (5)'s unshadowed term, traces one shadow ray
//! to its sample, reuses the previous frame's reservoir (with `--temporal on`) and its neighbours'
//! (k of them, n iterations), then shades with its sample's term and weight W and one more shadow
//! ray (`shaders-wgsl/restir.wgsl`, CPU twin `twin`). The passes are `PREPARE` → `INITIAL`
//! → `TEMPORAL` → `SPATIAL` → `SHADE` (`ENTRY`).
//!
//! The VPLs' ids are their indices in the resident set: the history is kept only while that set
//! (`VplKey`: count, seed, bounces and which trace, so a light change drops it), the frame's
//! settings and the knobs stay the same, as the accumulation's history is.

pub mod alias;
pub mod settings;
/// The CPU twin of this module's shader, for tests only: no production code calls it.
pub mod twin;

use std::time::Instant;

use anyhow::Result;
use bytemuck::{Pod, Zeroable};

use self::settings::{Combine, RestirLights};
use super::Method;
use super::{FrameInputs, IndirectMethod, MethodEntry, PendingRays, Tally};
use crate::gi::dispatch::{Gpu, Kernel, Run};
use crate::gi::pass::Pass;
use crate::gi::primary::{CameraParams, SP_BYTES};
use crate::gi::scene_gpu::{SceneGpu, storage_layout, uniform_layout};
use crate::gi::sum::{Each, WordSum, Words};
use crate::gi::vpl_cluster::LightKey;
use crate::gpu::GpuContext;
use crate::gpu::persistent::Uniform;
use crate::settings::FrameSettings;

pub use settings::{RestirLists as Lists, RestirSettings as Settings};

/// The candidates' alias table (CPU, when the VPL set changes) and the frame's buffers.
pub const PREPARE: Pass = Pass::Method("restir_prepare");
/// Initial candidates (RIS) and the visibility of the sample.
pub const INITIAL: Pass = Pass::Method("restir_initial");
/// Temporal reuse (with `--temporal on` and a history).
pub const TEMPORAL: Pass = Pass::Method("restir_temporal");
/// Spatial reuse, its iterations.
pub const SPATIAL: Pass = Pass::Method("restir_spatial");
/// The reservoir's light added to the indirect light.
pub const SHADE: Pass = Pass::Method("restir_shade");

/// Bytes of a reservoir (the VPL, w_sum, M, W).
pub const RESERVOIR_BYTES: u64 = 16;
/// Pixels one submission covers (M candidates and up to k + 2 shadow rays a pixel).
const PER_CHUNK: u32 = 1 << 14;

/// `restir.wgsl`'s uniform.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct RestirParams {
    pub cam: CameraParams,
    pub prev: CameraParams,
    /// width, height, VPLs, candidates M.
    pub dims: [u32; 4],
    /// neighbours k; flags (1: unbiased, 2: a history); the frame's seed; unused.
    pub opts: [u32; 4],
    /// d_min²; the spatial radius in pixels; the confidence cap; the depth tolerance.
    pub tol: [f32; 4],
    /// The normals' cosine tolerance; unused.
    pub tol2: [f32; 4],
}

/// The flag of an unbiased combination in `RestirParams::opts[1]`.
pub const UNBIASED: u32 = 1;
/// The flag of a usable history in `RestirParams::opts[1]`.
pub const HISTORY: u32 = 2;

/// The stage `restir.wgsl` runs (the `Chunk`'s seed: the stage, the spatial iteration above it).
pub fn stage_seed(stage: u32, iteration: u32) -> u32 {
    stage | iteration << 8
}

/// The spatial radius in pixels for a frame `height` lines tall: `restir_radius` is at 1080 lines
/// (at least 1.5 pixels, so that the 8 neighbours can be drawn at tiny sizes).
pub fn radius_px(radius: f32, height: u32) -> f32 {
    (radius * height as f32 / 1080.0).max(1.5)
}

/// The frame's seed: the frame's number in this state and the VPL seed.
pub fn frame_seed(frame: u32, seed: u32) -> u32 {
    crate::gi::rng::rng_seed(frame, seed, 0x7e57)
}

/// What a history must match to be reused: the VPL set (its ids), the frame's settings, the knobs.
#[derive(Clone, Copy, Debug, PartialEq)]
struct HistoryKey {
    lights: LightKey,
    frame: FrameSettings,
    knobs: Settings,
    pixels: u32,
}

/// The last frame's final reservoirs, its G-buffer and camera, and what they were made with
/// (`None`: no usable history, the buffers kept for the next one).
pub struct Past {
    pub reservoirs: wgpu::Buffer,
    pub gbuffer: wgpu::Buffer,
    pub cam: CameraParams,
    key: Option<HistoryKey>,
    pixels: u32,
}

/// The buffers of a frame size: two reservoir buffers (read one, write the other) and the rays each
/// pixel traced.
struct SizeBuffers {
    pixels: u32,
    reservoirs: [wgpu::Buffer; 2],
    rays: wgpu::Buffer,
}

/// What the last frame ran with (tests read it: `Renderer::method_state`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LastFrame {
    pub params: RestirParams,
    /// Whether the temporal pass reused a history.
    pub reused: bool,
    /// Spatial iterations run.
    pub iterations: u32,
}

/// restir's state: its kernel, the alias table of the resident VPLs, the frame's buffers and the
/// last frame's reservoirs.
pub struct RestirMethod {
    kernel: Kernel,
    params: Uniform<RestirParams>,
    table: Option<(LightKey, wgpu::Buffer)>,
    size: Option<SizeBuffers>,
    past: Option<Past>,
    /// This frame: its bind groups (reading reservoirs 0 / 1), the buffer holding the current
    /// reservoirs, its key and whether it ran.
    groups: Vec<wgpu::BindGroup>,
    cur: usize,
    key: Option<HistoryKey>,
    ran: bool,
    frames: u32,
    pub last: Option<LastFrame>,
    /// The pixels' rays summed on the GPU.
    rays: WordSum,
}

impl RestirMethod {
    pub fn new(ctx: &GpuContext, scene: &SceneGpu) -> Self {
        let mut entries = vec![uniform_layout(1)];
        entries.extend((2..=7).map(|b| storage_layout(b, true)));
        entries.extend((8..=10).map(|b| storage_layout(b, false)));
        RestirMethod {
            kernel: Kernel::new(ctx, scene, "restir", &entries, &[]),
            params: Uniform::new("restir params"),
            table: None,
            size: None,
            past: None,
            groups: Vec::new(),
            cur: 0,
            key: None,
            ran: false,
            frames: 0,
            last: None,
            rays: WordSum::new(ctx),
        }
    }

    /// The buffer holding this frame's current (after `SHADE`: final) reservoirs.
    pub fn reservoirs(&self) -> Option<&wgpu::Buffer> {
        self.size.as_ref().map(|s| &s.reservoirs[self.cur])
    }

    /// The last frame's (final reservoirs, G-buffer, camera), when kept.
    pub fn past(&self) -> Option<&Past> {
        self.past.as_ref()
    }

    /// The alias table (made when the VPL set changes), the buffers of the size, the history's
    /// use, the uniform and the bind groups.
    fn prepare(&mut self, g: &mut Gpu, f: &FrameInputs, n: &mut Tally) {
        let ctx = g.ctx;
        let t = Instant::now();
        // The light list: the VPLs themselves, or the VPL clusters (`--restir-lights`).
        let lights = f.lights.expect("the renderer's light list");
        let key = lights.key;
        if self.table.as_ref().is_none_or(|(k, _)| *k != key) {
            let table = alias::build(&lights.list.lights);
            self.table = Some((key, ctx.storage_init("restir alias", &table)));
        }
        n.cpu_ms.push((PREPARE, t.elapsed().as_secs_f64() * 1e3));
        let pixels = f.pixels();
        if self.size.as_ref().is_none_or(|s| s.pixels != pixels) {
            let bytes = pixels as u64 * RESERVOIR_BYTES;
            self.size = Some(SizeBuffers {
                pixels,
                reservoirs: [
                    ctx.storage("restir reservoirs 0", bytes),
                    ctx.storage("restir reservoirs 1", bytes),
                ],
                rays: ctx.storage("restir rays", pixels as u64 * 4),
            });
        }
        if self.past.as_ref().is_none_or(|p| p.pixels != pixels) {
            self.past = Some(Past {
                reservoirs: ctx.storage("restir past reservoirs", pixels as u64 * RESERVOIR_BYTES),
                gbuffer: ctx.storage("restir past gbuffer", pixels as u64 * SP_BYTES),
                cam: f.cam,
                key: None,
                pixels,
            });
        }
        let k = f.method.restir;
        let hk = HistoryKey {
            lights: key,
            frame: *f.frame,
            knobs: k,
            pixels,
        };
        let past = self.past.as_ref().expect("made above");
        let reused = f.cluster.temporal && past.key == Some(hk);
        self.key = f.cluster.temporal.then_some(hk);
        self.frames = self.frames.wrapping_add(1);
        let d_min = f.d_min;
        let flags = match k.restir_combine {
            Combine::Biased => 0,
            Combine::Unbiased => UNBIASED,
        } | if reused { HISTORY } else { 0 };
        let params = RestirParams {
            cam: f.cam,
            prev: past.cam,
            dims: [
                f.cam.size[0],
                f.cam.size[1],
                lights.list.lights.len() as u32,
                k.restir_candidates,
            ],
            opts: [
                k.restir_neighbours,
                flags,
                frame_seed(self.frames, f.frame.seed),
                0,
            ],
            tol: [
                d_min * d_min,
                radius_px(k.restir_radius, f.cam.size[1]),
                k.restir_cap,
                crate::gi::accumulate::DEPTH_TOLERANCE,
            ],
            tol2: [crate::gi::accumulate::NORMAL_COS, 0.0, 0.0, 0.0],
        };
        let uniform = self.params.set(ctx, &params);
        let size = self.size.as_ref().expect("made above");
        let table = &self.table.as_ref().expect("made above").1;
        self.groups = (0..2)
            .map(|read| {
                let buffers = [
                    (1, uniform),
                    (2, f.gbuffer),
                    (3, &past.gbuffer),
                    (4, &lights.list.buffer),
                    (5, table),
                    (6, &size.reservoirs[read]),
                    (7, &past.reservoirs),
                    (8, &size.reservoirs[1 - read]),
                    (9, f.indirect),
                    (10, &size.rays),
                ];
                self.kernel.bind_group(ctx, &buffers)
            })
            .collect();
        self.last = Some(LastFrame {
            params,
            reused,
            iterations: 0,
        });
        self.ran = true;
    }

    /// Runs `stage` over the pixels, reading the current reservoirs and writing the other buffer
    /// (which becomes the current one) unless it is the shade.
    fn stage(&mut self, g: &mut Gpu, pass: Pass, seed: u32, pixels: u32, writes: bool) {
        let run = Run {
            label: pass.name(),
            group: &self.groups[self.cur],
            seed,
        };
        self.kernel.run(g, run, pixels, PER_CHUNK, &mut |_, _| {});
        if writes {
            self.cur = 1 - self.cur;
        }
    }

    /// After the shade: the frame's final reservoirs and G-buffer kept for the next frame (with
    /// `--temporal on`), and the rays the pixels traced summed on the GPU (read only on request).
    fn finish(&mut self, g: &mut Gpu, f: &FrameInputs, n: &mut Tally) {
        let ctx = g.ctx;
        let size = self.size.as_ref().expect("prepared");
        let past = self.past.as_mut().expect("prepared");
        past.key = self.key;
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        if self.key.is_some() {
            let res = &size.reservoirs[self.cur];
            let bytes = f.pixels() as u64 * RESERVOIR_BYTES;
            enc.copy_buffer_to_buffer(res, 0, &past.reservoirs, 0, bytes);
            enc.copy_buffer_to_buffer(f.gbuffer, 0, &past.gbuffer, 0, f.pixels() as u64 * SP_BYTES);
            past.cam = f.cam;
        }
        ctx.queue.submit([enc.finish()]);
        let words = Words {
            items: f.pixels(),
            stride: 1,
            word: 0,
            each: Each::Value,
        };
        let sum = self.rays.record(g, SHADE.name(), &size.rays, words);
        n.pending = Some(std::sync::Arc::new(PendingRays(sum)));
    }
}

impl IndirectMethod for RestirMethod {
    fn record(&mut self, pass: Pass, g: &mut Gpu, f: &FrameInputs, n: &mut Tally) -> Result<()> {
        let pixels = f.pixels();
        match pass {
            PREPARE => self.prepare(g, f, n),
            INITIAL => {
                // Written into buffer 0: read 1, write 0.
                self.cur = 1;
                self.stage(g, pass, stage_seed(0, 0), pixels, true);
            }
            TEMPORAL => {
                if self.last.is_some_and(|l| l.reused) {
                    self.stage(g, pass, stage_seed(1, 0), pixels, true);
                }
            }
            SPATIAL => {
                let k = f.method.restir;
                let iterations = if k.restir_neighbours == 0 {
                    0
                } else {
                    k.restir_iterations
                };
                for it in 0..iterations {
                    self.stage(g, pass, stage_seed(2, it), pixels, true);
                }
                if let Some(l) = &mut self.last {
                    l.iterations = iterations;
                }
            }
            SHADE => {
                self.stage(g, pass, stage_seed(3, 0), pixels, false);
                self.finish(g, f, n);
            }
            _ => unreachable!("{pass} is not restir's"),
        }
        Ok(())
    }

    /// A frame without restir leaves no history.
    fn end_frame(&mut self) {
        if !self.ran
            && let Some(p) = &mut self.past
        {
            p.key = None;
        }
        self.ran = false;
    }

    fn take_past(&mut self) -> Box<dyn std::any::Any> {
        Box::new(self.past.take())
    }

    fn put_past(&mut self, past: Box<dyn std::any::Any>) {
        if let Ok(p) = past.downcast::<Option<Past>>() {
            self.past = *p;
        }
    }
}

/// restir's label in the bench and file names: `M32 k5 n2` (and ` unbiased`).
fn label(m: &super::MethodSettings) -> String {
    let k = &m.restir;
    let base = format!(
        "M{} k{} n{}",
        k.restir_candidates, k.restir_neighbours, k.restir_iterations
    );
    let base = match k.restir_combine {
        Combine::Biased => base,
        Combine::Unbiased => format!("{base} unbiased"),
    };
    match k.restir_lights {
        RestirLights::Vpls => base,
        RestirLights::Clusters => format!("{base} clusters"),
    }
}

/// restir in the registry.
pub const ENTRY: MethodEntry = MethodEntry {
    method: Method::Restir,
    doc: "ReSTIR DI (Bitterli et al. 2020) over the frame's VPLs: M candidates a pixel drawn by \
          flux and resampled by Eq. (5)'s unshadowed term, a shadow ray to the sample, the \
          previous frame's reservoir (--temporal on) and k neighbours' reused (n iterations), \
          biased or unbiased combination, one shadow ray to shade",
    passes: &[PREPARE, INITIAL, TEMPORAL, SPATIAL, SHADE],
    build: |ctx, gpu| Box::new(RestirMethod::new(ctx, gpu)),
    clusters_sps: false,
    vpl_clusters: |m| m.restir.restir_lights == RestirLights::Clusters,
    limits: super::no_limits,
    own_settings: true,
    colour: [227, 119, 194],
    about: "ReSTIR DI: each pixel resamples VPLs drawn by flux and reuses its neighbours' and \
            (--temporal on) the last frame's samples; one or two shadow rays a pixel \
            (docs/methods.md)",
    label,
    series: |m| {
        let k = &m.restir;
        format!(
            "M {} k {} n {}",
            k.restir_candidates, k.restir_neighbours, k.restir_iterations
        )
    },
    short: |m| label(m).replace(' ', "-"),
    report_columns: &[],
};
