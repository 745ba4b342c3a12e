//! The frame graph: the one place that decides which passes run for a scene and its settings, in what
//! order (the paper's Fig. 2), and runs them.
//!
//! Resident (per scene / light change, `resident.rs`): BVH and scene buffers; VPLs (step 1) and their
//! clusters (step 2), rebuilt only when their inputs change.
//! Per frame: primary (step 3) → direct + emission → indirect, one of
//! - `reference`: every pixel × every VPL (Eq. 5), the paper's "no clustering";
//! - `gather`: every pixel × every light, the lights being VPL clusters ("VPLs only");
//! - `sp_cluster` (step 4) → `visibility` (step 5) → `shade` (step 6, Eq. 6 with Eq. 8 or 9), the lights
//!   being VPL clusters ("both") or the VPLs ("SPs only").
//!
//! The other methods (`method::Method`, docs/methods.md) reuse the VPLs, the primary rays, the
//! direct light and the reference, and replace the clustered indirect passes with their own:
//! each method's room (`method::ROOMS`) lists its passes and records them through
//! `method::IndirectMethod`.
//!
//! `Plan::new` lists the passes; `Renderer::render` runs exactly that list, in order.

use std::sync::Arc;
use std::sync::atomic::Ordering;

use anyhow::Result;

pub use super::frame::{
    FRAME_KEY, Frame, FrameBuffers, GpuFrame, PATH_TRACE_PIXEL_BYTES, PIXEL_BYTES, TooLarge,
    check_frame_size, check_visibility_size, max_pixels, visibility_bytes,
};
pub use super::resident::Renderer;
use crate::gi::accumulate::Accumulate;
pub use crate::gi::pass::Pass;
use crate::gi::primary::CameraParams;
pub use crate::gi::vpl_cluster::LightKey;
pub use crate::gi::vpl_trace::VplKey;
use crate::method::Method;
use crate::method::{Counts, FrameInputs};
use crate::render::history::{History, HistoryKey};
pub use crate::render::settings::{Cancelled, Control, RenderSettings};
use crate::scene::{Camera, Scene};
use crate::settings::FrameSettings;

/// Which passes a frame runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Plan {
    pub indirect: bool,
    /// Step 2 (the resident VPL clustering: colom's lights, and a room's with `vpl_clusters`).
    pub vpl_clustering: bool,
    /// Colom's SP clustering (steps 4–6).
    pub sp_clustering: bool,
    /// The method whose own passes compute the indirect light: the one asked, or `Colom` (whose
    /// unclustered passes `gather` and `reference` then run) for the reference and where the
    /// method asked does not apply (one that clusters SPs without 0 < K_SP < pixels).
    pub method: Method,
    /// The render-scale size the indirect light is computed at when it is upsampled to the image
    /// (`--indirect-scale` below 1, not for the reference); `None`: at the image's size.
    pub low: Option<(u32, u32)>,
    /// Temporal accumulation of the indirect light (`--temporal on` with α below 1, clustered
    /// frames: `gi::accumulate`).
    pub accumulate: bool,
}

impl Plan {
    pub fn new(scene: &Scene, s: &RenderSettings) -> Plan {
        let (f, c) = (&s.frame, &s.cluster);
        let indirect = f.vpls > 0 && scene.has_light();
        let clustered = indirect && !s.reference;
        let low = Some(crate::gi::upsample::indirect_size(
            f.width,
            f.height,
            f.indirect_scale,
        ))
        .filter(|&l| clustered && l != (f.width, f.height));
        let pixels = low.map_or(f.width * f.height, |(w, h)| w * h);
        let sp = clustered && c.sp_clusters > 0 && c.sp_clusters < pixels;
        // A method's room runs where it applies (one clustering SPs needs 0 < K_SP < pixels);
        // elsewhere colom's unclustered passes do.
        let room = s
            .method
            .room()
            .filter(|r| clustered && (sp || !r.clusters_sps));
        let method = room.map_or(Method::Colom, |r| r.method);
        Plan {
            indirect,
            vpl_clustering: clustered
                && room.is_none_or(|r| r.vpl_clusters)
                && c.vpl_clusters > 0
                && c.vpl_clusters < f.vpls,
            sp_clustering: sp && method == Method::Colom,
            method,
            low,
            accumulate: clustered && c.temporal && c.temporal_alpha < 1.0,
        }
    }

    /// The passes, in the order they run.
    pub fn passes(&self) -> Vec<Pass> {
        let mut p = vec![];
        if self.indirect {
            p.push(Pass::VplTrace);
        }
        if self.vpl_clustering {
            p.push(Pass::VplCluster);
        }
        p.extend([Pass::Primary, Pass::Direct]);
        if self.indirect {
            p.extend_from_slice(match self.method {
                Method::Colom if self.sp_clustering => {
                    &[Pass::SpCluster, Pass::Visibility, Pass::Shade][..]
                }
                Method::Colom if self.vpl_clustering => &[Pass::Gather],
                Method::Colom => &[Pass::Reference],
                m => crate::method::room(m).expect("a method's room").passes,
            });
        }
        if self.low.is_some() {
            p.push(Pass::Upsample);
        }
        if self.accumulate {
            p.push(Pass::Accumulate);
        }
        p
    }
}

/// The `dispatch::Gpu` of a `Renderer` (a macro, so that the passes stay borrowable beside it).
macro_rules! gpu {
    ($r:ident) => {
        crate::gi::dispatch::Gpu {
            ctx: $r.ctx,
            scene: &$r.gpu,
            profiler: &mut $r.profiler,
        }
    };
}
pub(crate) use gpu;

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
    pub counts: Counts,
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
        check_visibility_size(ctx, &plan, s).map_err(anyhow::Error::msg)?;
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
            counts: Counts::default(),
        };
        // The indirect passes see the render scale's frame.
        let at_scale = plan.low.map(|(width, height)| RenderSettings {
            frame: FrameSettings {
                width,
                height,
                ..s.frame
            },
            ..s.clone()
        });
        let si = at_scale.as_ref().unwrap_or(s);
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
                Pass::SpCluster | Pass::Visibility | Pass::Shade => {
                    self.method_pass(Method::Colom, pass, si, &mut r)?
                }
                Pass::Gather | Pass::Reference => self.gather(pass, si, &mut r)?,
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
                _ => self.method_pass(plan.method, pass, si, &mut r)?,
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
        compose.record(self.ctx, &frame, texture);
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
                d_min: s.frame.clamp * self.scene.extent(),
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

    /// One of the pass list of `method`'s room (`method::ROOMS`), its state built the first time.
    fn method_pass(
        &mut self,
        method: Method,
        pass: Pass,
        s: &RenderSettings,
        r: &mut FrameResources,
    ) -> Result<()> {
        let ctx = self.ctx;
        let state = self
            .methods
            .entry(method)
            .or_insert_with(|| crate::method::build(method)(ctx, &self.gpu));
        let inputs = FrameInputs {
            scene: &self.scene,
            frame: &s.frame,
            cluster: &s.cluster,
            method: &s.method,
            vpls: self.vpl_set.as_ref().expect("vpl_trace ran"),
            lights: self.lights.as_ref(),
            reference: &self.reference,
            gbuffer: &r.buffers.gbuffer,
            pixels: r.pixels,
            cam: r.cam,
            indirect: &r.buffers.indirect,
        };
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
        let resident = match self.methods.get_mut(&plan.method) {
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
                sp_iterations: c.sp_iterations,
                sp_warm_kept: c.sp_warm_kept,
                visibility_rows_reused: c.rows_reused,
                cvrtgi: c.cvrtgi,
                ..Default::default()
            },
            buffers: r.buffers,
        })
    }

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
