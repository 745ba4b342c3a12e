//! A frame's recording: `Plan::passes` run in order (the shared passes of `gi`, then the method's
//! through `method::IndirectMethod`, then the shared ones again), its timings collected and what the
//! next frame reuses kept; nothing of its images read back (`GpuFrame`).

use std::sync::Arc;
use std::sync::atomic::Ordering;

use anyhow::Result;

use super::frame::{FRAME_KEY, Frame, FrameBuffers, GpuFrame};
use super::history::{History, HistoryKey};
use super::limits::{PIXEL_BYTES, check_frame_size, check_method_limits};
use super::plan::Plan;
use super::renderer::{Renderer, gpu};
use super::settings::{Cancelled, RenderSettings};
use crate::gi::accumulate::Accumulate;
use crate::gi::pass::Pass;
use crate::gi::primary::CameraParams;
use crate::method::{FrameInputs, Method, Tally};
use crate::scene::{Camera, Scene};

/// A frame's buffers and what its passes hand on to the next ones (the other methods' passes read
/// it as `method::FrameInputs`).
pub(super) struct FrameResources {
    /// The size, camera, G-buffer and indirect light the indirect passes work on: the render
    /// scale's when `image` is set, else the image's.
    pub pixels: u32,
    pub cam: CameraParams,
    /// The frame's buffers (`FramePool`).
    pub buffers: Arc<FrameBuffers>,
    /// The image's camera and the upsampling's uniform when the indirect light is at the render
    /// scale (`Plan::low`, `gi::upsample`).
    image: Option<(CameraParams, crate::gi::upsample::UpsampleParams)>,
    /// Area-light samples a pixel the direct pass took.
    direct_samples: u32,
    /// Shadow rays of the passes that trace per pixel, for each valid shading point (`GpuFrame::read`
    /// counts the pixels).
    pub rays_per_point: u64,
    /// The indirect passes' shadow rays in all, SP clusters and VPL clusters used, CPU steps.
    pub counts: Tally,
}

impl FrameResources {
    fn gbuffer(&self) -> &wgpu::Buffer {
        &self.buffers.gbuffer
    }
    fn indirect(&self) -> &wgpu::Buffer {
        &self.buffers.indirect
    }
}

impl Renderer<'_> {
    /// The passes a frame with these settings runs, in order (also what `info` prints).
    pub fn passes_for(scene: &Scene, s: &RenderSettings) -> Vec<Pass> {
        Plan::new(scene, s).passes()
    }

    /// A frame read back to the CPU (`render_gpu`, then `GpuFrame::read`).
    pub fn render(&mut self, camera: &Camera, s: &RenderSettings) -> Result<Frame> {
        self.render_gpu(camera, s)?.read(self.ctx)
    }

    /// A frame whose images stay on the GPU: its passes recorded and submitted, its timings
    /// collected, nothing of its images read back. The buffers are the renderer's (`FramePool`),
    /// reused once the returned frame and what else holds them are dropped.
    pub fn render_gpu(&mut self, camera: &Camera, s: &RenderSettings) -> Result<GpuFrame> {
        let ctx = self.ctx;
        let (width, height) = (s.frame.width, s.frame.height);
        check_frame_size(ctx, width, height, PIXEL_BYTES)?;
        let n = width * height;
        let plan = Plan::new(&self.scene, s);
        check_method_limits(ctx, &plan, s).map_err(anyhow::Error::msg)?;
        let passes = plan.passes();
        let camera = self.to_render_units(camera);
        let (lw, lh) = plan.low.unwrap_or((width, height));
        let low = lw * lh;
        let mut r = FrameResources {
            pixels: low,
            cam: CameraParams::new(&camera, lw, lh),
            buffers: self.frames.take(ctx, (width, height), plan.low),
            image: plan.low.map(|l| {
                let cam = CameraParams::new(&camera, width, height);
                (cam, crate::gi::upsample::UpsampleParams::new(&cam, l))
            }),
            direct_samples: 0,
            rays_per_point: 0,
            counts: Tally::default(),
        };
        for &pass in &passes {
            match pass {
                Pass::VplTrace => {
                    let f = &s.frame;
                    self.ensure_vpls(f.vpls, f.seed, f.bounces)?;
                    if !plan.vpl_clustering {
                        self.ensure_lights(s, &plan)?;
                    }
                }
                Pass::VplCluster => self.ensure_lights(s, &plan)?,
                Pass::Primary => match &r.image {
                    Some((cam, params)) => {
                        let image = r.buffers.image_gbuffer();
                        self.primary.record(&mut gpu!(self), cam, image);
                        let k = self.upsample.get(ctx);
                        k.downsample(&mut gpu!(self), params, image, r.gbuffer());
                    }
                    None => self.primary.record(&mut gpu!(self), &r.cam, r.gbuffer()),
                },
                Pass::Direct => {
                    r.direct_samples = self.direct_samples(s);
                    self.direct.record(
                        &mut gpu!(self),
                        r.buffers.image_gbuffer(),
                        &r.buffers.radiance,
                        n,
                        r.direct_samples,
                        s.frame.seed,
                    );
                }
                Pass::Gather | Pass::Reference => self.gather(pass, s, &mut r)?,
                Pass::Upsample => {
                    let (_, params) = r.image.as_ref().expect("planned");
                    let k = self.upsample.get(ctx);
                    let b = &r.buffers;
                    let gbuffers = (b.image_gbuffer(), &b.gbuffer);
                    k.upsample(
                        &mut gpu!(self),
                        params,
                        gbuffers,
                        &b.indirect,
                        b.image_indirect(),
                    );
                }
                Pass::Accumulate => self.accumulate(s, &r),
                Pass::PathTrace => unreachable!("the path tracer is `path_trace`"),
                _ => {
                    let method = plan.method.expect("a method's pass");
                    self.method_pass(method, pass, s, &mut r)?
                }
            }
        }
        self.finish(s, &plan, passes, r)
    }

    /// A frame's final radiance (linear, in the scene's units, alpha 1) written into `texture`, a
    /// texture of the caller's device (`GpuContext::from_device`): `Rgba32Float`, the frame's size,
    /// with `STORAGE_BINDING` usage (a compute pass writes it from the frame's buffers) or
    /// `COPY_DST` (the pass writes a texture of the renderer's, copied over on the GPU): nothing
    /// goes through the CPU. The frame returned holds the timings and counts (`GpuFrame::meta`) and
    /// its buffers; `GpuFrame::read` reads its images back when the caller wants them.
    pub fn render_to_texture(
        &mut self,
        camera: &Camera,
        s: &RenderSettings,
        texture: &wgpu::Texture,
    ) -> Result<GpuFrame> {
        let (w, h) = (s.frame.width, s.frame.height);
        let size = texture.size();
        if texture.format() != wgpu::TextureFormat::Rgba32Float
            || (size.width, size.height, size.depth_or_array_layers) != (w, h, 1)
            || !texture
                .usage()
                .intersects(wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_DST)
        {
            anyhow::bail!(
                "render_to_texture: the texture must be Rgba32Float, {w}×{h}, with STORAGE_BINDING or COPY_DST usage; it is {:?}, {}×{}×{}, {:?}",
                texture.format(),
                size.width,
                size.height,
                size.depth_or_array_layers,
                texture.usage()
            );
        }
        let frame = self.render_gpu(camera, s)?;
        let compose = self
            .compose
            .get_or_init(|| crate::gi::compose::Compose::new(self.ctx));
        let light = crate::gi::compose::FrameLight {
            direct: &frame.buffers.radiance,
            indirect: frame.buffers.image_indirect(),
            size: frame.buffers.size,
            output_scale: frame.output_scale,
        };
        compose.record(self.ctx, &light, texture);
        Ok(frame)
    }

    /// Blends the frame's indirect light (at the image's size) with the last frame's history where
    /// it was rendered with the same settings (`gi::accumulate`).
    fn accumulate(&mut self, s: &RenderSettings, r: &FrameResources) {
        let b = &r.buffers;
        let (gbuffer, indirect) = (b.image_gbuffer(), b.image_indirect());
        let cam = r.image.as_ref().map_or(&r.cam, |i| &i.0);
        let (p, history) = History::params(self.history.as_ref(), s, cam);
        let kernel = self.accumulator.get_or_init(|| Accumulate::new(self.ctx));
        let prev = history.map(|h| (h.buffers.image_gbuffer(), h.buffers.image_indirect()));
        kernel.record(&mut gpu!(self), &p, gbuffer, prev, indirect);
    }

    /// Every pixel × every light with its own shadow ray: the VPL clusters (`gather`) or the VPLs
    /// (`reference`, Eq. 5), reporting progress and stopping on `Control::cancel`.
    fn gather(&mut self, pass: Pass, s: &RenderSettings, r: &mut FrameResources) -> Result<()> {
        let ctx = self.ctx;
        let lights = &self.lights.as_ref().unwrap().list;
        r.rays_per_point = lights.lights.len() as u64;
        let label = pass.name();
        let show = s.progress;
        let control = s.control.clone();
        let mut last = 0u64;
        self.reference.record(
            &mut gpu!(self),
            &crate::gi::reference::GatherInputs {
                gbuffer: r.gbuffer(),
                lights: &lights.buffer,
                num_lights: lights.lights.len() as u32,
                indirect: r.indirect(),
                pixels: r.pixels,
                d_min: s.frame.d_min(self.scene.extent()),
                label,
                light: s.cluster.cluster_light,
            },
            &mut |done, all| {
                let pct = done * 100 / all.max(1);
                if show && all > 1 && (pct >= last + 5 || done == all) {
                    last = pct;
                    eprint!("\r{label}: {pct:3}% ({done}/{all} dispatches)");
                    if done == all {
                        eprintln!();
                    }
                }
                match &control {
                    Some(c) => {
                        c.done.store(done, Ordering::Relaxed);
                        c.total.store(all, Ordering::Relaxed);
                        !c.is_cancelled()
                    }
                    None => true,
                }
            },
        );
        if s.control.as_ref().is_some_and(|c| c.is_cancelled()) {
            let _ = self.profiler.collect(ctx)?;
            return Err(Cancelled.into());
        }
        Ok(())
    }

    /// One of the pass list of `method`'s entry (`method::REGISTRY`), its state built the first time.
    fn method_pass(
        &mut self,
        method: Method,
        pass: Pass,
        s: &RenderSettings,
        r: &mut FrameResources,
    ) -> Result<()> {
        self.method(method);
        let state = self.methods.get_mut(&method).expect("built above");
        let inputs = FrameInputs {
            scene: &self.scene,
            frame: &s.frame,
            cluster: &s.cluster,
            method: &s.method,
            vpls: self.vpl_set.as_ref().expect("vpl_trace ran"),
            lights: self.lights.as_ref(),
            reference: &self.reference,
            gbuffer: &r.buffers.gbuffer,
            size: r.buffers.low.unwrap_or(r.buffers.size),
            d_min: s.frame.d_min(self.scene.extent()),
            cam: r.cam,
            indirect: &r.buffers.indirect,
        };
        debug_assert_eq!(
            inputs.pixels(),
            r.pixels,
            "the frame's pixels are its size's"
        );
        let mut gpu = gpu!(self);
        state.record(pass, &mut gpu, &inputs, &mut r.counts)
    }

    /// Keeps what the next frame reuses and collects the timings; reads nothing of the images.
    fn finish(
        &mut self,
        s: &RenderSettings,
        plan: &Plan,
        passes: Vec<Pass>,
        r: FrameResources,
    ) -> Result<GpuFrame> {
        let ctx = self.ctx;
        self.upsample.last_low = plan.low;
        let mut timings_ms = self.profiler.collect(ctx)?;
        // A pass's CPU steps count as its time (docs/methods.md).
        for &(pass, ms) in &r.counts.cpu_ms {
            *timings_ms.entry(pass.name().into()).or_insert(0.0) += ms;
        }
        // A method's resident stages are not the frame's (as the VPLs and their clustering).
        let resident = match plan.method.and_then(|m| self.methods.get_mut(&m)) {
            Some(m) if plan.indirect => m.take_resident_timings(&mut timings_ms),
            _ => Default::default(),
        };
        let frame_ms: f64 = timings_ms.values().sum();
        timings_ms.insert(FRAME_KEY.into(), frame_ms);
        timings_ms.extend(resident);
        if plan.indirect {
            timings_ms.insert(
                Pass::VplTrace.name().into(),
                self.vpl_set.as_ref().unwrap().ms,
            );
        }
        if plan.vpl_clustering {
            timings_ms.insert(
                Pass::VplCluster.name().into(),
                self.lights.as_ref().unwrap().ms,
            );
        }
        let num_lights = self
            .lights
            .as_ref()
            .filter(|_| plan.indirect)
            .map_or(0, |l| l.list.lights.len() as u32);
        // Every method's state: this frame's becomes the last one (or, where it did not run, none).
        for m in self.methods.values_mut() {
            m.end_frame();
        }
        self.last_method = plan.method.filter(|_| plan.indirect);
        let c = &r.counts;
        let image_cam = r.image.as_ref().map_or(r.cam, |i| i.0);
        self.history = plan.accumulate.then(|| History {
            buffers: r.buffers.clone(),
            cam: image_cam,
            key: HistoryKey::of(s),
        });
        self.gbuffer = Some(r.buffers.clone());
        self.last_camera = Some(image_cam);
        let (width, height) = (s.frame.width, s.frame.height);
        Ok(GpuFrame {
            output_scale: self.output_scale,
            geometry_scale: self.geometry_scale,
            direct_rays_per_point: r.direct_samples as u64 + self.gpu.info.num_lights as u64,
            rays_per_point: r.rays_per_point,
            indirect_rays: c.indirect_rays,
            pending: c.pending.clone(),
            method: self.last_method,
            meta: Frame {
                width,
                height,
                vpls: self.vpl_set.as_ref().map_or(0, |v| v.set.vpls.len() as u32),
                passes,
                timings_ms,
                sp_clusters_used: c.sp_used,
                vpl_clusters_used: if plan.vpl_clustering {
                    num_lights
                } else {
                    c.vpl_clusters_used
                },
                gamma_used: c.gamma_used,
                report: self.last_method.zip(c.report.clone()),
                ..Default::default()
            },
            buffers: r.buffers,
        })
    }
}
