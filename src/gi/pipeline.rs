//! The frame graph: the one place that decides which passes run for a scene and its settings, in what
//! order, and collects their GPU times.
//!
//! Resident (per scene): BVH and scene buffers; VPLs (per VPL count and seed).
//! Per frame: primary → direct (+ emission) → indirect (`reference`: Eq. 5 over every VPL).

use std::collections::BTreeMap;

use anyhow::Result;

use super::direct::Direct;
use super::primary::{CameraParams, Primary, SP_BYTES};
use super::reference::Reference;
use super::scene_gpu::SceneGpu;
use super::vpl_trace::{VplSet, VplTrace};
use crate::bvh::SceneBvh;
use crate::gpu::{GpuContext, profiler::Profiler};
use crate::scene::{Camera, Scene};

/// What a frame is rendered with.
#[derive(Clone, Debug)]
pub struct FrameSettings {
    pub width: u32,
    pub height: u32,
    pub seed: u32,
    /// Area-light samples per pixel for direct light.
    pub direct_samples: u32,
    /// VPLs to trace (resident; 0 = no indirect light).
    pub vpls: u32,
    /// Indirect light by the unclustered reference (Eq. 5, every pixel × every VPL).
    pub reference: bool,
    /// G-term clamp: 1/d² uses d ≥ clamp × scene diagonal (scale-free; see docs/reference.md).
    pub clamp: f32,
    /// Print progress of long passes on stderr.
    pub progress: bool,
}

impl Default for FrameSettings {
    fn default() -> Self {
        FrameSettings {
            width: 640,
            height: 480,
            seed: 1,
            direct_samples: 16,
            vpls: 8192,
            reference: false,
            clamp: DEFAULT_CLAMP,
            progress: false,
        }
    }
}

/// Default G-term clamp as a fraction of the scene diagonal.
pub const DEFAULT_CLAMP: f32 = 0.02;

/// A rendered frame: linear radiance per pixel, row-major from the top-left.
#[derive(Clone, Debug)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// emission + direct + indirect.
    pub radiance: Vec<[f32; 3]>,
    /// emission + direct.
    pub direct: Vec<[f32; 3]>,
    /// Indirect light from the VPLs (zero when none ran).
    pub indirect: Vec<[f32; 3]>,
    pub vpls: u32,
    /// Passes that ran, in order.
    pub passes: Vec<&'static str>,
    /// GPU milliseconds per pass (summed over its dispatches).
    pub timings_ms: BTreeMap<String, f64>,
    pub shading_points: u32,
    pub shadow_rays: u64,
}

/// Everything resident for one scene on one device.
pub struct Renderer<'a> {
    pub ctx: &'a GpuContext,
    pub scene: &'a Scene,
    pub bvh: SceneBvh,
    pub gpu: SceneGpu,
    pub profiler: Profiler,
    primary: Primary,
    direct: Direct,
    vpl_trace: VplTrace,
    reference: Reference,
    gbuffer: Option<(wgpu::Buffer, u32)>,
    /// Resident VPLs with the (count, seed) they were traced for and the GPU ms it took.
    pub vpl_set: Option<(VplSet, (u32, u32), f64)>,
}

impl<'a> Renderer<'a> {
    pub fn new(ctx: &'a GpuContext, scene: &'a Scene) -> Result<Self> {
        let bvh = SceneBvh::build(scene)?;
        let gpu = SceneGpu::upload(ctx, scene, &bvh);
        Ok(Renderer {
            ctx,
            scene,
            primary: Primary::new(ctx, &gpu),
            direct: Direct::new(ctx, &gpu),
            vpl_trace: VplTrace::new(ctx, &gpu),
            reference: Reference::new(ctx, &gpu),
            gbuffer: None,
            vpl_set: None,
            profiler: Profiler::new(ctx),
            bvh,
            gpu,
        })
    }

    /// The passes a frame with these settings runs, in order (also what `info` prints).
    /// Direct light runs even without lights: it writes emission and clears the image, with the light
    /// paths compiled out by override constants.
    pub fn passes_for(scene: &Scene, s: &FrameSettings) -> Vec<&'static str> {
        let mut p = vec![];
        let indirect = s.reference && s.vpls > 0 && scene.has_light();
        if indirect {
            p.push("vpl_trace");
        }
        p.extend(["primary", "direct"]);
        if indirect {
            p.push("reference");
        }
        p
    }

    /// Traces the VPLs unless the resident ones match (count, seed).
    pub fn ensure_vpls(&mut self, n: u32, seed: u32) -> Result<&VplSet> {
        let key = (n, seed);
        if self.vpl_set.as_ref().map(|v| v.1) != Some(key) {
            let _ = self.profiler.collect(self.ctx)?;
            let set = self.vpl_trace.trace(
                self.ctx,
                self.scene,
                &self.gpu,
                &mut self.profiler,
                n,
                seed,
            )?;
            let ms: f64 = self.profiler.collect(self.ctx)?.values().sum();
            self.vpl_set = Some((set, key, ms));
        }
        Ok(&self.vpl_set.as_ref().unwrap().0)
    }

    /// The last frame's shading points, 4 × vec4 each (`common/gbuffer.wgsl`), for tests and views.
    pub fn last_gbuffer(&self) -> Result<Vec<[f32; 4]>> {
        match &self.gbuffer {
            Some((b, n)) => self.ctx.read_buffer(b, *n as usize * 4),
            None => anyhow::bail!("no frame rendered yet"),
        }
    }

    pub fn render(&mut self, camera: &Camera, s: &FrameSettings) -> Result<Frame> {
        let ctx = self.ctx;
        let n = s.width * s.height;
        let gbuffer = ctx.storage("gbuffer", n as u64 * SP_BYTES);
        let radiance = ctx.storage("radiance", n as u64 * 16);
        let cam = CameraParams::new(camera, s.width, s.height);
        let passes = Self::passes_for(self.scene, s);
        if passes.contains(&"vpl_trace") {
            self.ensure_vpls(s.vpls, s.seed)?;
        }
        self.primary
            .record(ctx, &self.gpu, &mut self.profiler, &cam, &gbuffer);
        // With no light at all the direct pass still runs to write emission (zero) and clear the image.
        let spp = if self.gpu.has_emitters {
            s.direct_samples.max(1)
        } else {
            0
        };
        self.direct.record(
            ctx,
            &self.gpu,
            &mut self.profiler,
            &gbuffer,
            &radiance,
            n,
            spp,
            s.seed,
        );
        let indirect = ctx.storage("indirect", n as u64 * 16);
        let mut reference_rays = 0u64;
        let mut num_vpls = 0;
        if passes.contains(&"reference") {
            let (set, _, _) = self.vpl_set.as_ref().unwrap();
            num_vpls = set.vpls.len() as u32;
            let d_min = s.clamp * self.scene.extent();
            let show = s.progress;
            let mut last = 0u64;
            self.reference.record(
                ctx,
                &self.gpu,
                &mut self.profiler,
                &gbuffer,
                &set.buffer,
                num_vpls,
                &indirect,
                n,
                d_min,
                &mut |done, all| {
                    let pct = done * 100 / all.max(1);
                    if show && (pct >= last + 5 || done == all) {
                        last = pct;
                        eprint!("\rreference: {pct:3}% ({done}/{all} dispatches)");
                        if done == all {
                            eprintln!();
                        }
                    }
                },
            );
            reference_rays = n as u64 * num_vpls as u64;
        }
        let mut timings_ms = self.profiler.collect(ctx)?;
        let frame_ms: f64 = timings_ms.values().sum();
        timings_ms.insert("frame".into(), frame_ms);
        if let Some((_, _, ms)) = &self.vpl_set
            && passes.contains(&"vpl_trace")
        {
            timings_ms.insert("vpl_trace".into(), *ms);
        }
        let px: Vec<[f32; 4]> = ctx.read_buffer(&radiance, n as usize)?;
        let ind: Vec<[f32; 4]> = ctx.read_buffer(&indirect, n as usize)?;
        let sps: Vec<[f32; 4]> = ctx.read_buffer(&gbuffer, n as usize * 4)?;
        let valid = sps.chunks(4).filter(|sp| sp[0][3] > 0.0).count() as u32;
        self.gbuffer = Some((gbuffer, n));
        let direct: Vec<[f32; 3]> = px.iter().map(|p| [p[0], p[1], p[2]]).collect();
        let indirect: Vec<[f32; 3]> = ind.iter().map(|p| [p[0], p[1], p[2]]).collect();
        let radiance = direct
            .iter()
            .zip(&indirect)
            .map(|(a, b)| [a[0] + b[0], a[1] + b[1], a[2] + b[2]])
            .collect();
        Ok(Frame {
            width: s.width,
            height: s.height,
            radiance,
            direct,
            indirect,
            vpls: num_vpls,
            passes,
            timings_ms,
            shading_points: valid,
            shadow_rays: valid as u64 * (spp as u64 + self.gpu.info.num_lights as u64)
                + reference_rays,
        })
    }
}
