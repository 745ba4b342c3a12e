//! What tests and views read of the renderer: the last frame's G-buffer and SP-cluster labels, and
//! the upsampling and accumulation kernels run on given data (the GPU against their CPU twins).

use anyhow::Result;

use super::renderer::{Renderer, gpu};

impl Renderer<'_> {
    /// Each pixel's nearest SP cluster in the last frame (`frame`, the first of its F slots),
    /// `metrics::NO_LABEL` where its primary ray missed: the label image of the cluster-border
    /// measure (`metrics::border_error`) and the viewer's SP-cluster view. `None` when that frame
    /// clustered no shading points.
    pub fn sp_labels(&self, frame: &super::frame::Frame) -> Result<Option<Vec<u32>>> {
        let Some(c) = self.sp_clustering() else {
            return Ok(None);
        };
        let n = (frame.width * frame.height) as usize;
        if frame.positions.len() != n {
            return Ok(None);
        }
        let f = c.f().max(1) as usize;
        // A render-scale clustering labels each image pixel with its low-res pixel's cluster.
        let image = (frame.width, frame.height);
        let low = self.upsample.last_low.unwrap_or(image);
        let all: Vec<u32> = self
            .ctx
            .read_buffer(&c.assign, (low.0 * low.1) as usize * f)?;
        Ok(Some(
            (0..n as u32)
                .zip(&frame.positions)
                .map(|(i, p)| {
                    if p[3] > 0.0 {
                        all[crate::gi::upsample::low_pixel(i, image, low) as usize * f]
                    } else {
                        crate::metrics::NO_LABEL
                    }
                })
                .collect(),
        ))
    }

    /// The last frame's shading points, 4 × vec4 each (`common/gbuffer.wgsl`), for tests and views.
    pub fn last_gbuffer(&self) -> Result<Vec<[f32; 4]>> {
        match &self.gbuffer {
            Some(b) => self
                .ctx
                .read_buffer(b.image_gbuffer(), (b.size.0 * b.size.1) as usize * 4),
            None => anyhow::bail!("no frame rendered yet"),
        }
    }

    /// Both kernels on given data (tests: the GPU against `cpu::upsample`): the render-scale
    /// G-buffer `downsample` makes of `image_gbuffer` (4 vec4s a pixel), and the image's indirect
    /// light upsampled from `low_indirect` (a vec4 a low-res pixel) on that G-buffer.
    pub fn upsample_buffers(
        &mut self,
        p: &crate::gi::upsample::UpsampleParams,
        image_gbuffer: &[[f32; 4]],
        low_indirect: &[[f32; 4]],
    ) -> anyhow::Result<(Vec<Vec4>, Vec<Vec4>)> {
        let ctx = self.ctx;
        let image = ctx.storage_init("gbuffer (image)", image_gbuffer);
        let low = ctx.storage(
            "gbuffer",
            p.low_pixels() as u64 * crate::gi::primary::SP_BYTES,
        );
        let low_ind = ctx.storage_init("indirect", low_indirect);
        let out = ctx.storage("indirect (image)", p.image_pixels() as u64 * 16);
        let k = self.upsample.get(ctx);
        let mut g = gpu!(self);
        k.downsample(&mut g, p, &image, &low);
        k.upsample(&mut g, p, (&image, &low), &low_ind, &out);
        let _ = self.profiler.collect(ctx)?;
        Ok((
            ctx.read_buffer(&low, p.low_pixels() as usize * 4)?,
            ctx.read_buffer(&out, p.image_pixels() as usize)?,
        ))
    }

    /// The accumulation kernel on given data (tests: the GPU against `cpu::accumulate`): this
    /// frame's G-buffer (4 vec4s a pixel) and indirect light, the previous frame's G-buffer and
    /// accumulated light (`None`: no history). Returns the accumulated light.
    pub fn accumulate_buffers(
        &mut self,
        p: &crate::gi::accumulate::AccumulateParams,
        gbuffer: &[Vec4],
        indirect: &[Vec4],
        history: Option<(&[Vec4], &[Vec4])>,
    ) -> anyhow::Result<Vec<Vec4>> {
        let ctx = self.ctx;
        let g = ctx.storage_init("gbuffer", gbuffer);
        let ind = ctx.storage_init("indirect", indirect);
        let prev = history.map(|(g, h)| {
            (
                ctx.storage_init("gbuffer (previous)", g),
                ctx.storage_init("indirect (previous)", h),
            )
        });
        let kernel = self
            .accumulator
            .get_or_init(|| crate::gi::accumulate::Accumulate::new(ctx));
        let prev = prev.as_ref().map(|(g, h)| (g, h));
        kernel.record(&mut gpu!(self), p, &g, prev, &ind);
        let _ = self.profiler.collect(ctx)?;
        ctx.read_buffer(&ind, p.pixels() as usize)
    }
}

/// One vec4 of a read-back buffer.
type Vec4 = [f32; 4];
