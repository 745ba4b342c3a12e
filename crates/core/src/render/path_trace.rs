//! The diffuse path tracer (`--path-trace`): the check of the VPL reference's own bias, a frame of
//! its own (nothing of the VPL frame runs).

use anyhow::Result;

use super::frame::{FRAME_KEY, Frame};
use super::limits::{PATH_TRACE_PIXEL_BYTES, check_frame_size};
use super::renderer::{Renderer, gpu};
use super::settings::RenderSettings;
use crate::gi::pass::Pass;
use crate::gi::primary::CameraParams;
use crate::scene::Camera;

impl Renderer<'_> {
    /// The diffuse path tracer (`--path-trace`, the check of the VPL reference's own bias) instead of
    /// the VPL frame: `spp` samples a pixel with the settings' bounce budget and seed, in the scene's
    /// own units (scaled back like `render`). Nothing of the VPL frame runs.
    pub fn path_trace(&mut self, camera: &Camera, s: &RenderSettings, spp: u32) -> Result<Frame> {
        let ctx = self.ctx;
        let f = &s.frame;
        check_frame_size(ctx, f.width, f.height, PATH_TRACE_PIXEL_BYTES)?;
        let pt = crate::gi::pathtrace::PathTrace::new(ctx, &self.gpu);
        let cam = CameraParams::new(&self.to_render_units(camera), f.width, f.height);
        let _ = self.profiler.collect(ctx)?;
        // Samples an invocation traces per pass. lavapipe ends all loops of a SIMD batch after
        // 65,535 trips (docs/architecture.md): 16 samples of up to 9 vertices lost up to 2 of them on
        // 1% of the breakfast room's pixels (262k triangles; none on the built-in rooms), 4 lose none.
        let per_pass = if ctx.software && self.gpu.info.num_nodes > 1 << 16 {
            4
        } else {
            16
        };
        let samples = crate::gi::pathtrace::PtSamples {
            spp: spp.max(1),
            per_pass,
        };
        let img = pt.render(&mut gpu!(self), &cam, samples, f.seed, f.bounces)?;
        let mut timings_ms = self.profiler.collect(ctx)?;
        let ms: f64 = timings_ms.values().sum();
        timings_ms.insert(FRAME_KEY.into(), ms);
        let radiance: Vec<[f32; 3]> = img
            .iter()
            .map(|p| self.to_scene_units(&[p[0], p[1], p[2], 0.0]))
            .collect();
        let n = radiance.len();
        Ok(Frame {
            width: f.width,
            height: f.height,
            // The path tracer does not separate direct from indirect light: all of it is here.
            direct: radiance.clone(),
            indirect: vec![[0.0; 3]; n],
            radiance,
            passes: vec![Pass::PathTrace],
            timings_ms,
            ..Default::default()
        })
    }
}
