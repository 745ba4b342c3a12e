//! The frame graph: the one place that decides which passes run for a scene and its settings, in what
//! order, and collects their GPU times.
//!
//! Resident (per scene): BVH and scene buffers. Per frame: primary → direct (+ emission).

use std::collections::BTreeMap;

use anyhow::Result;

use super::direct::Direct;
use super::primary::{CameraParams, Primary, SP_BYTES};
use super::scene_gpu::SceneGpu;
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
}

impl Default for FrameSettings {
    fn default() -> Self {
        FrameSettings {
            width: 640,
            height: 480,
            seed: 1,
            direct_samples: 16,
        }
    }
}

/// A rendered frame: linear radiance per pixel, row-major from the top-left.
#[derive(Clone, Debug)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    pub radiance: Vec<[f32; 3]>,
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
    gbuffer: Option<(wgpu::Buffer, u32)>,
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
            gbuffer: None,
            profiler: Profiler::new(ctx),
            bvh,
            gpu,
        })
    }

    /// The passes a frame with these settings runs, in order (also what `info` prints).
    /// Direct light runs even without lights: it writes emission and clears the image, with the light
    /// paths compiled out by override constants.
    pub fn passes_for(_scene: &Scene, _settings: &FrameSettings) -> Vec<&'static str> {
        vec!["primary", "direct"]
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
        let mut timings_ms = self.profiler.collect(ctx)?;
        let frame_ms: f64 = timings_ms.values().sum();
        timings_ms.insert("frame".into(), frame_ms);
        let px: Vec<[f32; 4]> = ctx.read_buffer(&radiance, n as usize)?;
        let sps: Vec<[f32; 4]> = ctx.read_buffer(&gbuffer, n as usize * 4)?;
        let valid = sps.chunks(4).filter(|sp| sp[0][3] > 0.0).count() as u32;
        self.gbuffer = Some((gbuffer, n));
        Ok(Frame {
            width: s.width,
            height: s.height,
            radiance: px.iter().map(|p| [p[0], p[1], p[2]]).collect(),
            passes,
            timings_ms,
            shading_points: valid,
            shadow_rays: valid as u64 * (spp as u64 + self.gpu.info.num_lights as u64),
        })
    }
}
