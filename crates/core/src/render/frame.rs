//! What a frame is: the `Frame` a render returns (read back), the `GpuFrame` whose images stay on
//! the GPU, and the per-pixel buffers (`FrameBuffers`) a renderer reuses by size (`FramePool`).

use std::collections::BTreeMap;

use crate::gi::pass::Pass;
use crate::gi::primary::SP_BYTES;
use crate::gpu::GpuContext;

/// A rendered frame: linear radiance per pixel, row-major from the top-left.
#[derive(Clone, Debug, Default)]
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
    pub passes: Vec<Pass>,
    /// GPU milliseconds per pass (summed over its dispatches); `frame` excludes resident VPL work.
    pub timings_ms: BTreeMap<String, f64>,
    pub shading_points: u32,
    pub shadow_rays: u64,
    pub sp_clusters_used: u32,
    pub vpl_clusters_used: u32,
    /// γ Alg. 1 sampled with (`kmeans::effective_gamma`), a setting as resolved (the stats'
    /// `settings.gamma_used`); `None` when no SP clustering ran.
    pub gamma_used: Option<u32>,
    /// The shading point of each pixel: world position, w = 1 where the primary ray hit (0: sky).
    /// What the viewer reprojects a frame with.
    pub positions: Vec<[f32; 4]>,
    /// The shading normal of each pixel's shading point (xyz; zero where the ray missed): with
    /// `positions`, what tells two frames' pixels show the same surface (`metrics::instability_world`).
    pub normals: Vec<[f32; 4]>,
    /// The method's own report and its name (`method::Tally::report` joined with what its
    /// pending counts read back: what its module counts, e.g. an SP clustering's iterations or a
    /// voxel grid's sizes): the stats' `counts.<method>`, the CSVs' report columns.
    pub report: Option<(crate::method::Method, serde_json::Value)>,
}

impl Frame {
    /// GPU milliseconds of `pass` (0 when it did not run).
    pub fn ms(&self, pass: Pass) -> f64 {
        self.timings_ms.get(pass.name()).copied().unwrap_or(0.0)
    }

    /// GPU milliseconds of the whole frame (`FRAME_KEY`: every pass but the resident VPL work).
    pub fn frame_ms(&self) -> f64 {
        self.timings_ms.get(FRAME_KEY).copied().unwrap_or(0.0)
    }

    pub fn ran(&self, pass: Pass) -> bool {
        self.passes.contains(&pass)
    }

    /// The report of `method` when this frame's method is that one and has one.
    pub fn report_of(&self, method: crate::method::Method) -> Option<&serde_json::Value> {
        self.report
            .as_ref()
            .filter(|(m, _)| *m == method)
            .map(|(_, v)| v)
    }
}

/// The timing key of the whole frame (docs/design.md, "Stats JSON").
pub const FRAME_KEY: &str = "frame";

/// A frame's per-pixel buffers. The renderer keeps them (`FramePool`) and hands the same ones to the
/// next frame of the same size once nothing else holds them, so a steady size allocates nothing.
pub struct FrameBuffers {
    /// The image's size.
    pub size: (u32, u32),
    /// The render-scale size the indirect passes run at (`Plan::low`); `None`: the image's.
    pub low: Option<(u32, u32)>,
    /// The indirect passes' G-buffer (4 vec4s a pixel, `common/gbuffer.wgsl`): the render scale's
    /// when `low` is set.
    pub gbuffer: wgpu::Buffer,
    /// Emission + direct light, a vec4 an image pixel, in render units (× `GpuFrame::output_scale`).
    pub radiance: wgpu::Buffer,
    /// The indirect passes' indirect light, a vec4 a pixel at their size.
    pub indirect: wgpu::Buffer,
    /// With `low`: the image's own G-buffer and its upsampled indirect light.
    pub image: Option<(wgpu::Buffer, wgpu::Buffer)>,
}

impl FrameBuffers {
    fn new(ctx: &GpuContext, size: (u32, u32), low: Option<(u32, u32)>) -> Self {
        let n = size.0 as u64 * size.1 as u64;
        let l = low.map_or(n, |(w, h)| w as u64 * h as u64);
        FrameBuffers {
            size,
            low,
            gbuffer: ctx.storage("gbuffer", l * SP_BYTES),
            radiance: ctx.storage("radiance", n * 16),
            indirect: ctx.storage("indirect", l * 16),
            image: low.map(|_| {
                (
                    ctx.storage("gbuffer (image)", n * SP_BYTES),
                    ctx.storage("indirect (image)", n * 16),
                )
            }),
        }
    }

    /// The image's G-buffer (4 vec4s an image pixel).
    pub fn image_gbuffer(&self) -> &wgpu::Buffer {
        self.image.as_ref().map_or(&self.gbuffer, |i| &i.0)
    }

    /// The image's indirect light (a vec4 an image pixel, render units).
    pub fn image_indirect(&self) -> &wgpu::Buffer {
        self.image.as_ref().map_or(&self.indirect, |i| &i.1)
    }
}

/// The frame buffers a renderer has made, reused by size: a set is free again once only the pool
/// holds it (the frame that used it, the accumulation history and the viewer's display have let it
/// go).
#[derive(Default)]
pub struct FramePool {
    sets: Vec<std::sync::Arc<FrameBuffers>>,
    /// Sets made so far (a steady size stops making them).
    pub made: u32,
}

/// The most sets of one size a pool keeps: the frame being rendered, the last one (history, the
/// displayed frame), and one the display may still read.
const POOL_SETS: usize = 4;

impl FramePool {
    /// A free set of this size, made when there is none. A set used before has its light buffers
    /// cleared on the GPU first: passes add to them (the reference over its light ranges) or leave
    /// the sky's pixels unwritten, as they find fresh, zeroed buffers.
    pub fn take(
        &mut self,
        ctx: &GpuContext,
        size: (u32, u32),
        low: Option<(u32, u32)>,
    ) -> std::sync::Arc<FrameBuffers> {
        let fits = |b: &FrameBuffers| b.size == size && b.low == low;
        if let Some(b) = self
            .sets
            .iter()
            .find(|b| fits(b) && std::sync::Arc::strong_count(b) == 1)
        {
            let mut enc = ctx.device.create_command_encoder(&Default::default());
            enc.clear_buffer(&b.radiance, 0, None);
            enc.clear_buffer(&b.indirect, 0, None);
            if let Some((_, indirect)) = &b.image {
                enc.clear_buffer(indirect, 0, None);
            }
            ctx.queue.submit([enc.finish()]);
            return b.clone();
        }
        // Sets of other sizes that nothing holds go; so do free sets beyond `POOL_SETS`.
        self.sets
            .retain(|b| std::sync::Arc::strong_count(b) > 1 || fits(b));
        while self.sets.iter().filter(|b| fits(b)).count() >= POOL_SETS {
            let Some(i) = self
                .sets
                .iter()
                .position(|b| fits(b) && std::sync::Arc::strong_count(b) == 1)
            else {
                break;
            };
            self.sets.remove(i);
        }
        let b = std::sync::Arc::new(FrameBuffers::new(ctx, size, low));
        self.made += 1;
        self.sets.push(b.clone());
        b
    }
}

/// A rendered frame whose images stay on the GPU (`Renderer::render_gpu`): the viewer displays them
/// where they are, and `read` copies them to the CPU only when asked (`Renderer::render` does).
pub struct GpuFrame {
    pub buffers: std::sync::Arc<FrameBuffers>,
    /// Everything known without reading anything back: size, passes, timings. Its images,
    /// positions and normals are empty, `shading_points` and `shadow_rays` are 0, and the counts
    /// the GPU keeps (`pending`: e.g. a clustering's SP clusters used, the method's report) are
    /// missing until `read` or `counts`.
    pub meta: Frame,
    /// The method's counts left on the GPU, read by `counts` and `read`.
    pub pending: Option<std::sync::Arc<dyn crate::method::PendingReport>>,
    /// The images' factor from render units to the scene's (`Renderer::output_scale`).
    pub output_scale: f32,
    /// The G-buffer's positions' factor from the scene's units to render units.
    pub geometry_scale: f64,
    /// Shadow rays a valid image pixel's direct light traces (area samples + punctual lights).
    pub direct_rays_per_point: u64,
    /// Shadow rays the indirect passes traced for each of their valid shading points, and the rays
    /// they counted themselves.
    pub rays_per_point: u64,
    pub indirect_rays: u64,
    /// The method whose indirect passes ran (`None`: none did), whose report `pending` adds to.
    pub method: Option<crate::method::Method>,
}

impl GpuFrame {
    /// The frame read back to the CPU: images in the scene's units, positions and normals, and the
    /// counts of valid shading points and shadow rays.
    pub fn read(&self, ctx: &GpuContext) -> anyhow::Result<Frame> {
        self.read_with(&ctx.device, &ctx.queue)
    }

    /// `meta` with the counts the GPU keeps read back (a few bytes; the images stay on the GPU),
    /// and the indirect passes' shadow rays with the ones those counts give.
    pub fn counts(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> anyhow::Result<(Frame, u64)> {
        let mut meta = self.meta.clone();
        let mut rays = self.indirect_rays;
        if let Some(p) = &self.pending {
            let c = p.read(device, queue)?;
            if let Some(used) = c.sp_used {
                meta.sp_clusters_used = used;
            }
            if let Some(m) = self.method {
                let before = meta.report.take().map(|(_, v)| v);
                meta.report = crate::method::join_reports(before, c.report).map(|v| (m, v));
            }
            rays += c.indirect_rays;
        }
        Ok((meta, rays))
    }

    /// `read` on the device's own handles (another thread's clones of the renderer's device).
    pub fn read_with(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> anyhow::Result<Frame> {
        let read = |b: &wgpu::Buffer, n: usize| -> anyhow::Result<Vec<[f32; 4]>> {
            crate::gpu::read_buffer(device, queue, b, n)
        };
        let (meta, indirect_rays) = self.counts(device, queue)?;
        let b = &self.buffers;
        let n = (b.size.0 * b.size.1) as usize;
        // The indirect passes traced from the render scale's shading points.
        let traced_points = match b.low {
            Some((w, h)) => {
                let low = read(&b.gbuffer, (w * h) as usize * 4)?;
                Some(low.chunks(4).filter(|sp| sp[0][3] > 0.0).count() as u64)
            }
            None => None,
        };
        let px = read(&b.radiance, n)?;
        let ind = read(b.image_indirect(), n)?;
        let sps = read(b.image_gbuffer(), n * 4)?;
        let valid = sps.chunks(4).filter(|sp| sp[0][3] > 0.0).count() as u32;
        let scene_units =
            |p: &[f32; 4]| [0, 1, 2].map(|c| (p[c] * self.output_scale).min(f32::MAX));
        let direct: Vec<[f32; 3]> = px.iter().map(scene_units).collect();
        let indirect: Vec<[f32; 3]> = ind.iter().map(scene_units).collect();
        let radiance = direct
            .iter()
            .zip(&indirect)
            .map(|(a, b)| [0, 1, 2].map(|c| (a[c] + b[c]).min(f32::MAX)))
            .collect();
        let k = 1.0 / self.geometry_scale;
        Ok(Frame {
            radiance,
            direct,
            indirect,
            shading_points: valid,
            shadow_rays: valid as u64 * self.direct_rays_per_point
                + indirect_rays
                + traced_points.unwrap_or(valid as u64) * self.rays_per_point,
            // In the caller's units (the G-buffer holds the unit frame's, `geometry_scale`).
            positions: sps
                .chunks(4)
                .map(|sp| {
                    let p = sp[0];
                    let q = glam::DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) * k;
                    [q.x as f32, q.y as f32, q.z as f32, p[3]]
                })
                .collect(),
            normals: sps
                .chunks(4)
                .map(|sp| {
                    let n = sp[1];
                    [n[0], n[1], n[2], 0.0]
                })
                .collect(),
            ..meta
        })
    }
}
