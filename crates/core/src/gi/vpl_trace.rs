//! Step 1: VPL tracing (`shaders-wgsl/vpl_trace.wgsl`). Light paths are traced in waves; path k writes
//! its VPLs to its own slots, and the host keeps the first N VPLs in path order, so the result depends
//! only on the seed. Fluxes are divided by the number of paths that contributed. VPLs are resident:
//! traced once per scene / light change.

use anyhow::Result;
use bytemuck::{Pod, Zeroable};

use super::dispatch::Kernel;
use super::dispatch::{Gpu, Run};
use super::pass::Pass;
use super::scene_gpu::{SceneGpu, storage_layout, uniform_layout};
use crate::gpu::GpuContext;
use crate::scene::{LightKind, Scene};

pub use crate::settings::MAX_DEPTH;

/// A VPL as `common/vpl.wgsl` lays it out.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct Vpl {
    pub pos: [f32; 4],
    pub nrm: [f32; 4],
    pub flux: [f32; 4],
}

/// Bytes of one `Vpl` on the GPU.
pub const VPL_BYTES: u64 = std::mem::size_of::<Vpl>() as u64;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct TraceParams {
    max_depth: u32,
    num_sources: u32,
    radius: f32,
    path_base: u32,
    center: [f32; 4],
}

/// Light sources by power: entry 0 is all emissive triangles together, then each punctual light.
/// Returns (cdf, probability) per source.
pub fn source_table(scene: &Scene, gpu: &SceneGpu) -> Vec<[f32; 4]> {
    let (lo, hi) = scene.bounds();
    let radius = 0.5 * (hi - lo).length();
    let mean = |c: glam::Vec3| (c.x + c.y + c.z) / 3.0;
    let mut power = vec![std::f32::consts::PI * gpu.info.emit_power];
    for l in &scene.lights {
        let i = mean(l.color) * l.intensity;
        power.push(match l.kind {
            LightKind::Point => 4.0 * std::f32::consts::PI * i,
            LightKind::Spot { outer_cone, .. } => {
                2.0 * std::f32::consts::PI * (1.0 - outer_cone.cos()) * i
            }
            LightKind::Directional => std::f32::consts::PI * radius * radius * i,
        });
    }
    let total: f64 = power.iter().map(|&p| p.max(0.0) as f64).sum();
    let mut acc = 0.0f64;
    power
        .iter()
        .map(|&p| {
            let p = if total > 0.0 {
                p.max(0.0) as f64 / total
            } else {
                0.0
            };
            acc += p;
            [acc as f32, p as f32, 0.0, 0.0]
        })
        .collect()
}

/// The resident VPLs.
pub struct VplSet {
    pub buffer: wgpu::Buffer,
    pub vpls: Vec<Vpl>,
    /// Light paths whose VPLs were kept (the flux normaliser).
    pub paths: u32,
}

pub struct VplTrace {
    kernel: Kernel,
}

impl VplTrace {
    pub fn new(ctx: &GpuContext, scene: &SceneGpu) -> Self {
        let entries = [
            uniform_layout(1),
            storage_layout(2, true),
            storage_layout(3, false),
            storage_layout(4, false),
        ];
        VplTrace {
            kernel: Kernel::new(ctx, scene, "vpl_trace", &entries, &[]),
        }
    }

    /// Traces light paths from the lights of `scene` (uploaded as `g.scene`) until `n` VPLs exist
    /// (or the lights reach nothing) and keeps the first `n`.
    pub fn trace(
        &self,
        g: &mut Gpu,
        scene: &Scene,
        n: u32,
        seed: u32,
        max_depth: u32,
    ) -> Result<VplSet> {
        let (ctx, gpu) = (g.ctx, g.scene);
        let max_depth = max_depth.clamp(1, 64);
        let sources = source_table(scene, gpu);
        let has_power = sources.iter().any(|s| s[1] > 0.0);
        let mut vpls: Vec<Vpl> = Vec::new();
        let mut paths = 0u32;
        let (lo, hi) = scene.bounds();
        let center = 0.5 * (lo + hi);
        let radius = (0.5 * (hi - lo).length()).max(1e-30);
        let cdf = ctx.storage_init("source cdf", &sources);
        // A wave's output (max_depth VPLs of 48 bytes a path) must fit one storage binding: with few
        // paths reaching a surface (a light far outside the scene) the next wave grows to 2^20 paths,
        // 384 MiB at 8 bounces, which the device refuses.
        let binding = ctx.max_binding();
        let max_wave = (binding / (max_depth as u64 * VPL_BYTES)).clamp(1, 1 << 20) as u32;
        let mut wave = (n / 2).max(256).min(max_wave);
        let mut base = 0u32;
        // Give up when 64 paths per requested VPL found nothing (lights that hit no surface).
        while has_power && (vpls.len() as u32) < n && base < n.saturating_mul(64).max(1 << 16) {
            let params = ctx.uniform(
                "vpl trace params",
                &TraceParams {
                    max_depth,
                    num_sources: sources.len() as u32,
                    radius,
                    path_base: base,
                    center: center.extend(0.0).into(),
                },
            );
            let out = ctx.storage("wave vpls", wave as u64 * max_depth as u64 * VPL_BYTES);
            let lens = ctx.storage("path lengths", wave as u64 * 4);
            let bg = self
                .kernel
                .bind_group(ctx, &[(1, &params), (2, &cdf), (3, &out), (4, &lens)]);
            let run = Run {
                label: Pass::VplTrace.name(),
                group: &bg,
                seed,
            };
            self.kernel.run(g, run, wave, 1 << 14, &mut |_, _| {});
            let lens: Vec<u32> = ctx.read_buffer(&lens, wave as usize)?;
            let out: Vec<Vpl> = ctx.read_buffer(&out, (wave * max_depth) as usize)?;
            for (k, &len) in lens.iter().enumerate() {
                if vpls.len() as u32 >= n {
                    break;
                }
                paths += 1;
                let take = (len.min(max_depth) as usize).min(n as usize - vpls.len());
                let first = k * max_depth as usize;
                vpls.extend_from_slice(&out[first..first + take]);
            }
            base += wave;
            let per_path = vpls.len().max(1) as f32 / paths.max(1) as f32;
            wave = (((n as usize).saturating_sub(vpls.len()) as f32 / per_path * 1.1) as u32)
                .clamp(256, 1 << 20)
                .min(max_wave);
        }
        let inv = 1.0 / paths.max(1) as f32;
        for v in &mut vpls {
            for c in 0..3 {
                v.flux[c] *= inv;
            }
        }
        Ok(VplSet {
            buffer: ctx.storage_init("vpls", &vpls),
            vpls,
            paths,
        })
    }
}

/// What a VPL set was traced for, and which trace it is (`Renderer`'s count of traces: a light
/// change re-traces the same count, seed and bounces).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VplKey {
    pub count: u32,
    pub seed: u32,
    pub bounces: u32,
    pub trace: u32,
}

/// The resident VPLs (step 1) with what they were traced for and the GPU ms it took.
pub struct ResidentVpls {
    pub set: VplSet,
    pub key: VplKey,
    pub ms: f64,
}
