//! The viewer's refinement at rest: the last frame's direct light estimated again with other seeds
//! and sub-pixel offsets (`direct_again`, or `refine_direct` on the GPU), and the lit pixels counted
//! on the GPU (`count_lit`, by `gi::sum`).

use anyhow::Result;

use super::renderer::{Renderer, gpu};
use crate::gi::sum::{Each, PendingSum, WordSum, Words};
use crate::render::settings::RenderSettings;

/// Frames whose lit counts `Renderer::count_lit`'s ring holds: the viewer reads them together,
/// when the stats are written.
pub const LIT_SLOTS: u32 = 4096;

impl Renderer<'_> {
    /// The direct light (emission + direct, as `Frame::direct`) of the last frame's shading points
    /// again, with another seed: an independent estimate to average with it (the viewer accumulates
    /// these while the camera rests). With `jitter` the shading points are traced again first, each
    /// primary ray through that sub-pixel offset of its pixel centre (`CameraParams::with_jitter`):
    /// averaged over offsets, edges are anti-aliased. Returns it with its GPU ms.
    pub fn direct_again(
        &mut self,
        s: &RenderSettings,
        seed: u32,
        jitter: Option<[f32; 2]>,
    ) -> Result<(Vec<[f32; 3]>, f64)> {
        let ctx = self.ctx;
        let Some(last) = self.gbuffer.clone() else {
            anyhow::bail!("no frame rendered yet");
        };
        let (gbuffer, n) = (last.image_gbuffer().clone(), last.size.0 * last.size.1);
        let radiance = ctx.storage("radiance", n as u64 * 16);
        let spp = self.direct_samples(s);
        let _ = self.profiler.collect(ctx)?;
        let gbuffer = match jitter {
            Some(j) => self.trace_jittered(j)?,
            None => gbuffer,
        };
        self.direct
            .record(&mut gpu!(self), &gbuffer, &radiance, n, spp, seed);
        let ms: f64 = self.profiler.collect(ctx)?.values().sum();
        let px: Vec<[f32; 4]> = ctx.read_buffer(&radiance, n as usize)?;
        Ok((px.iter().map(|p| self.to_scene_units(p)).collect(), ms))
    }

    /// `direct_again` on the GPU: another estimate of the last frame's direct light (seed `seed`,
    /// primary rays through sub-pixel offset `jitter`), blended into `into`'s emission + direct light
    /// as the running mean of `n` estimates (`gi::refine`). Nothing is read back and, at a steady
    /// size, nothing allocated but the passes' uniforms. Returns its GPU ms.
    pub fn refine_direct(
        &mut self,
        s: &RenderSettings,
        seed: u32,
        jitter: Option<[f32; 2]>,
        into: &super::frame::FrameBuffers,
        n: u32,
    ) -> Result<f64> {
        let ctx = self.ctx;
        let Some(last) = self.gbuffer.clone() else {
            anyhow::bail!("no frame rendered yet");
        };
        let pixels = last.size.0 * last.size.1;
        anyhow::ensure!(into.size == last.size, "the frame changed size");
        if self.estimate.as_ref().is_none_or(|e| e.2 != pixels) {
            self.estimate = Some((
                ctx.storage("radiance (estimate)", pixels as u64 * 16),
                ctx.storage(
                    "gbuffer (jittered)",
                    pixels as u64 * crate::gi::primary::SP_BYTES,
                ),
                pixels,
            ));
        }
        let (radiance, jittered, _) = self.estimate.clone().expect("made above");
        let spp = self.direct_samples(s);
        let _ = self.profiler.collect(ctx)?;
        let gbuffer = match (jitter, self.last_camera) {
            (Some(j), Some(cam)) => {
                self.primary
                    .record(&mut gpu!(self), &cam.with_jitter(j), &jittered);
                &jittered
            }
            _ => last.image_gbuffer(),
        };
        self.direct
            .record(&mut gpu!(self), gbuffer, &radiance, pixels, spp, seed);
        let k = self
            .refine
            .get_or_init(|| crate::gi::refine::Refine::new(ctx));
        k.record(&mut gpu!(self), &radiance, &into.radiance, n, pixels);
        Ok(self.profiler.collect(ctx)?.values().sum())
    }

    /// Counts `frame`'s pixels with a surface hit (the G-buffer's `pos.w > 0`) on the GPU into the
    /// next slot of a ring of `LIT_SLOTS` totals (`gi::sum`, `Each::Positive`); returns the pending
    /// count, read only on request.
    pub fn count_lit(&mut self, frame: &super::frame::FrameBuffers) -> PendingSum {
        let ctx = self.ctx;
        let mut lit = self
            .lit
            .take()
            .unwrap_or_else(|| WordSum::with_slots(ctx, LIT_SLOTS));
        let words = Words {
            items: frame.size.0 * frame.size.1,
            // A shading point's words (`common/gbuffer.wgsl`); `pos.w` is its fourth.
            stride: (crate::gi::primary::SP_BYTES / 4) as u32,
            word: 3,
            each: Each::Positive,
        };
        let pending = lit.record(&mut gpu!(self), "count_lit", frame.image_gbuffer(), words);
        let _ = self.profiler.collect(ctx);
        self.lit = Some(lit);
        pending
    }

    /// The last frame's shading points traced again, each primary ray through sub-pixel offset
    /// `jitter` of its pixel centre (a new G-buffer).
    fn trace_jittered(&mut self, jitter: [f32; 2]) -> Result<wgpu::Buffer> {
        let (Some(last), Some(cam)) = (&self.gbuffer, self.last_camera) else {
            anyhow::bail!("no frame rendered yet");
        };
        let n = last.size.0 as u64 * last.size.1 as u64;
        let buffer = self
            .ctx
            .storage("gbuffer (jittered)", n * crate::gi::primary::SP_BYTES);
        self.primary
            .record(&mut gpu!(self), &cam.with_jitter(jitter), &buffer);
        Ok(buffer)
    }

    /// `trace_jittered` read back (4 vec4s a pixel, as `last_gbuffer`): what the twins compare.
    pub fn jittered_gbuffer(&mut self, jitter: [f32; 2]) -> Result<Vec<[f32; 4]>> {
        let n = self.gbuffer.as_ref().map_or(0, |g| g.size.0 * g.size.1) as usize;
        let b = self.trace_jittered(jitter)?;
        let _ = self.profiler.collect(self.ctx)?;
        self.ctx.read_buffer(&b, n * 4)
    }
}
