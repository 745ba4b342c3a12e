//! What stays on the device for one scene between frames (the role of Bevy Solari's `prepare.rs`):
//! the scene's buffers and BVH, the passes' pipelines, the VPLs (step 1) and their light list (step
//! 2), rebuilt only when their inputs change, and the last frame's clustering and visibility that
//! temporal reuse starts from. `pipeline.rs` records the frame passes on top of it.

use anyhow::Result;

use std::collections::BTreeMap;

use super::pipeline::{Plan, gpu};
use crate::bvh::SceneBvh;
use crate::gi::direct::Direct;
use crate::gi::kmeans::{Clustering, KMeans, KMeansSettings};
use crate::gi::primary::Primary;
use crate::gi::reference::Reference;
use crate::gi::scene_gpu::SceneGpu;
use crate::gi::vpl_cluster::{self, LightKey, ResidentLights};
use crate::gi::vpl_trace::{ResidentVpls, VplKey, VplSet, VplTrace};
use crate::gpu::{GpuContext, profiler::Profiler};
use crate::method::IndirectMethod;
use crate::method::Method;
use crate::method::colom::Colom;
use crate::render::settings::RenderSettings;
use crate::scene::{Camera, PunctualLight, Scene};

/// fuzzy-vpl's renderer: everything resident for one scene on one device, and the frame.
///
/// `Renderer::new` uploads the scene and builds its BVH; `render` (or `render_to_texture`, into a
/// texture of the caller's device) renders a frame for a camera and `RenderSettings`, keeping what
/// the next frame may reuse (VPLs and their clustering while their settings stay; with temporal
/// reuse, the last SP clustering and visibility). `set_lights` moves the lights; `path_trace` renders
/// the diffuse path-traced check instead. Cameras are in the scene's units; the images are linear
/// radiance in the scene's units, row-major from the top-left.
pub struct Renderer<'a> {
    pub ctx: &'a GpuContext,
    /// The scene as rendered: borrowed, or a copy with its geometry scaled by a power of two into a
    /// unit frame (`Scene::normalize_geometry`, `geometry_scale`) and/or its emitters scaled into
    /// range (`Scene::normalize_emission`, `output_scale` scales the images back).
    pub scene: std::borrow::Cow<'a, Scene>,
    /// The scene as given (`set_lights` scales its emitters from these).
    source: &'a Scene,
    pub output_scale: f32,
    /// The factor from the caller's units to the rendered scene's (a power of two; 1 for scenes of
    /// 2^-10..2^10 across): cameras given to `render` and `path_trace` are scaled by it.
    pub geometry_scale: f64,
    pub bvh: SceneBvh,
    pub gpu: SceneGpu,
    pub profiler: Profiler,
    pub(super) primary: Primary,
    pub(super) direct: Direct,
    vpl_trace: VplTrace,
    pub(super) reference: Reference,
    pub(super) kmeans: KMeans,
    /// The other methods' state (`method::ROOMS`), each built the first time a frame uses it.
    pub(super) methods: BTreeMap<Method, Box<dyn IndirectMethod>>,
    /// The indirect light at the render scale (`gi::upsample`).
    pub(super) upsample: crate::gi::upsample::Upsampler,
    /// Temporal accumulation (`gi::accumulate`): its kernel, built on first use, and the last
    /// frame's history (`None` after a frame without accumulation).
    pub(super) accumulator: std::cell::OnceCell<crate::gi::accumulate::Accumulate>,
    pub(super) history: Option<super::history::History>,
    /// The last frame's buffers (`direct_again`, `last_gbuffer`: its image G-buffer).
    pub(super) gbuffer: Option<std::sync::Arc<super::frame::FrameBuffers>>,
    /// The frames' buffers, reused by size.
    pub(super) frames: super::frame::FramePool,
    /// The pass that writes a frame into a caller's texture (`render_to_texture`), built on first use.
    pub(super) compose: std::cell::OnceCell<crate::gi::compose::Compose>,
    /// The viewer's refinement at rest on the GPU (`refine_direct`): its kernel and the buffers of
    /// one estimate (radiance, jittered G-buffer), kept between calls.
    refine: std::cell::OnceCell<crate::gi::refine::Refine>,
    estimate: Option<(wgpu::Buffer, wgpu::Buffer, u32)>,
    /// Lit pixels counted on the GPU (`count_lit`), built on first use.
    lit: Option<crate::gi::count_lit::CountLit>,
    /// The last frame's camera (render units), for `direct_again`'s jittered primary rays.
    pub(super) last_camera: Option<crate::gi::primary::CameraParams>,
    pub vpl_set: Option<ResidentVpls>,
    /// VPL traces so far (`VplKey::trace`).
    vpl_traces: u32,
    pub lights: Option<ResidentLights>,
}

impl<'a> Renderer<'a> {
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

    /// Sets of frame buffers made so far (`FramePool`): frames of a steady size make none.
    pub fn frame_sets_made(&self) -> u32 {
        self.frames.made
    }

    /// A method's state (`method::ROOMS`) as its room's type `T`, once a frame has used it (tests
    /// and views read a method's last clustering from it).
    pub fn method_state<T: 'static>(&self, method: Method) -> Option<&T> {
        let state: &dyn std::any::Any = self.methods.get(&method)?.as_ref();
        state.downcast_ref()
    }

    /// The last frame's SP clustering (colom's steps 4–6): `None` after a frame that clustered
    /// no shading points.
    pub fn sp_clustering(&self) -> Option<&Clustering> {
        self.method_state::<Colom>(Method::Colom)?
            .clustering
            .as_ref()
    }

    /// Forgets the last frame's SP clustering, every other method's past (`take_past`, dropped)
    /// and the accumulated indirect light: the next frame starts cold (a camera path run).
    pub fn forget_past(&mut self) {
        self.colom().clustering = None;
        for (_, state) in self
            .methods
            .iter_mut()
            .filter(|(m, _)| **m != Method::Colom)
        {
            drop(state.take_past());
        }
        self.history = None;
    }

    /// colom's state, built if no frame has used it yet.
    fn colom(&mut self) -> &mut Colom {
        let (ctx, gpu) = (self.ctx, &self.gpu);
        let state = self
            .methods
            .entry(Method::Colom)
            .or_insert_with(|| crate::method::colom::build(ctx, gpu));
        let any: &mut dyn std::any::Any = state.as_mut();
        any.downcast_mut().expect("colom's state")
    }

    /// The shade pass's `PATTERNS` (`gi::shade::patterns`, 0..8): its pipelines are built again.
    /// The image does not depend on it.
    pub fn set_shade_patterns(&mut self, patterns: u32) {
        self.colom().set_shade_patterns(patterns);
    }

    /// Before timing `s` at `camera`: on a hardware adapter one untimed render (its pipelines built,
    /// its buffers sized: work a first timed run would otherwise leave the GPU idle for; the temporal
    /// state it found is put back), then `ms` of GPU work (`GpuContext::warm_up`, `--warmup-ms`).
    /// 0 does nothing. Returns the ms of the busy kernel.
    pub fn warm_up(
        &mut self,
        camera: &crate::scene::Camera,
        s: &RenderSettings,
        ms: f64,
    ) -> Result<f64> {
        if ms <= 0.0 {
            return Ok(0.0);
        }
        if !self.ctx.software {
            // The untimed frame leaves no past: the timed ones start as they would without it.
            let pasts: Vec<_> = (self.methods.iter_mut())
                .map(|(&m, state)| (m, state.take_past()))
                .collect();
            let history = self.history.take();
            self.render(camera, s)?;
            self.history = history;
            let mut pasts: BTreeMap<Method, _> = pasts.into_iter().collect();
            for (m, state) in self.methods.iter_mut() {
                match pasts.remove(m) {
                    Some(past) => state.put_past(past),
                    // Built by the untimed frame: it leaves nothing either.
                    None => drop(state.take_past()),
                }
            }
        }
        self.ctx.warm_up(ms)
    }

    pub fn new(ctx: &'a GpuContext, source: &'a Scene) -> Result<Self> {
        crate::gi::scene_gpu::check_fits(source, ctx.max_binding())?;
        let mut scene = std::borrow::Cow::Borrowed(source);
        let geometry_scale = scene.geometry_scale();
        if geometry_scale != 1.0 {
            scene.to_mut().scale_geometry(geometry_scale);
        }
        let output_scale = if scene.emission_out_of_range() {
            scene.to_mut().normalize_emission()
        } else {
            1.0
        };
        let bvh = SceneBvh::build(&scene)?;
        let gpu = SceneGpu::upload(ctx, &scene, &bvh);
        Ok(Renderer {
            ctx,
            scene,
            source,
            output_scale,
            geometry_scale,
            primary: Primary::new(ctx, &gpu),
            direct: Direct::new(ctx, &gpu),
            vpl_trace: VplTrace::new(ctx, &gpu),
            reference: Reference::new(ctx, &gpu),
            kmeans: KMeans::new(),
            methods: BTreeMap::new(),
            upsample: Default::default(),
            accumulator: Default::default(),
            history: None,
            profiler: Profiler::new(ctx),
            gbuffer: None,
            frames: Default::default(),
            compose: Default::default(),
            refine: Default::default(),
            estimate: None,
            lit: None,
            last_camera: None,
            vpl_set: None,
            vpl_traces: 0,
            lights: None,
            bvh,
            gpu,
        })
    }

    /// `camera` (in the caller's units) in the rendered scene's units: its eye scaled by
    /// `geometry_scale`.
    pub fn to_render_units(&self, camera: &Camera) -> Camera {
        camera.with_eye_scaled(self.geometry_scale)
    }

    /// Lights that move: replaces the scene's punctual lights with `lights` (in the caller's units,
    /// like cameras) and scales its emissive materials by `emitter_scale` (from the scene as given).
    /// The geometry and its BVH stay; the scene's GPU buffers are uploaded again, and the passes
    /// rebuilt only when the shader paths a scene needs change (punctual lights or emitters appear or
    /// go). The next frame traces the VPLs again and clusters them (from the last clustering, with
    /// temporal reuse on).
    pub fn set_lights(&mut self, lights: &[PunctualLight], emitter_scale: f32) {
        let ctx = self.ctx;
        let scene = self.scene.to_mut();
        scene.lights = lights.to_vec();
        // Lights come in the caller's units: into the unit frame the geometry was scaled to.
        scene.scale_lights(self.geometry_scale);
        for (m, base) in scene.materials.iter_mut().zip(&self.source.materials) {
            m.emissive = base.emissive * emitter_scale;
        }
        self.output_scale = if scene.emission_out_of_range() {
            scene.normalize_emission()
        } else {
            1.0
        };
        let gpu = SceneGpu::upload(ctx, scene, &self.bvh);
        if gpu.overrides() != self.gpu.overrides() {
            self.primary = Primary::new(ctx, &gpu);
            self.direct = Direct::new(ctx, &gpu);
            self.vpl_trace = VplTrace::new(ctx, &gpu);
            self.reference = Reference::new(ctx, &gpu);
            // The methods' pipelines are built again; colom's past (the last SP clustering and
            // visibility) carries over.
            let past = self.methods.get_mut(&Method::Colom).map(|m| m.take_past());
            self.methods.clear();
            if let Some(p) = past {
                let mut colom = crate::method::colom::build(ctx, &gpu);
                colom.put_past(p);
                self.methods.insert(Method::Colom, colom);
            }
        }
        self.gpu = gpu;
        self.vpl_set = None;
        // The indirect light of the old lights is no history for the new ones.
        self.history = None;
    }

    /// Step 1: traces the VPLs unless the resident ones match (count, seed, bounces).
    pub fn ensure_vpls(&mut self, n: u32, seed: u32, bounces: u32) -> Result<&VplSet> {
        let traced = self
            .vpl_set
            .as_ref()
            .map(|v| (v.key.count, v.key.seed, v.key.bounces));
        if traced != Some((n, seed, bounces)) {
            self.vpl_traces += 1;
            let key = VplKey {
                count: n,
                seed,
                bounces,
                trace: self.vpl_traces,
            };
            let _ = self.profiler.collect(self.ctx)?;
            let set = self
                .vpl_trace
                .trace(&mut gpu!(self), &self.scene, n, seed, bounces)?;
            let ms: f64 = self.profiler.collect(self.ctx)?.values().sum();
            self.vpl_set = Some(ResidentVpls { set, key, ms });
        }
        Ok(&self.vpl_set.as_ref().unwrap().set)
    }

    /// Step 2: builds the light list (VPL clusters, or the VPLs themselves) unless the resident one
    /// matches.
    pub(super) fn ensure_lights(&mut self, s: &RenderSettings, plan: &Plan) -> Result<()> {
        let f = &s.frame;
        let c = &s.cluster;
        self.ensure_vpls(f.vpls, f.seed, f.bounces)?;
        let key = LightKey {
            k: if plan.vpl_clustering {
                c.vpl_clusters
            } else {
                0
            },
            normal_threshold_bits: c.normal_threshold.to_bits(),
            iterations: c.iterations,
            adapt: c.adaptations().bits(),
            seed: f.seed,
            vpls: self.vpl_set.as_ref().unwrap().key,
        };
        if self.lights.as_ref().map(|l| l.key) == Some(key) {
            return Ok(());
        }
        let vpls = &self.vpl_set.as_ref().unwrap().set;
        let _ = self.profiler.collect(self.ctx)?;
        let list = if plan.vpl_clustering {
            let previous = self.lights.take().filter(|_| c.temporal);
            let warm = previous
                .as_ref()
                .and_then(|l| l.list.clustering.as_ref())
                .map(|c| crate::gi::kmeans::Warm {
                    centroids: &c.centroids,
                    rep_points: &c.rep_points,
                    k: c.k(),
                    view: None,
                });
            vpl_cluster::cluster(
                &mut gpu!(self),
                &self.kmeans,
                vpls,
                &KMeansSettings::vpls(c, f.seed),
                self.scene.bounds(),
                warm.as_ref(),
            )?
        } else {
            vpl_cluster::unclustered(self.ctx, vpls)
        };
        let ms: f64 = self.profiler.collect(self.ctx)?.values().sum();
        self.lights = Some(ResidentLights { list, key, ms });
        Ok(())
    }

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

    /// Counts `frame`'s pixels with a surface hit on the GPU into the next slot of the ring of
    /// counters (`gi::count_lit`); returns the ring and the slot.
    pub fn count_lit(&mut self, frame: &super::frame::FrameBuffers) -> (wgpu::Buffer, u32) {
        let ctx = self.ctx;
        let mut lit = self
            .lit
            .take()
            .unwrap_or_else(|| crate::gi::count_lit::CountLit::new(ctx));
        let pixels = frame.size.0 * frame.size.1;
        let slot = lit.record(&mut gpu!(self), frame.image_gbuffer(), pixels);
        let _ = self.profiler.collect(ctx);
        let ring = lit.ring.clone();
        self.lit = Some(lit);
        (ring, slot)
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

    /// Area-light samples a pixel: the settings', or 0 in a scene without emitters (the direct pass
    /// then only writes emission, zero, and clears the image).
    pub(super) fn direct_samples(&self, s: &RenderSettings) -> u32 {
        if self.gpu.has_emitters {
            s.frame.direct_samples.max(1)
        } else {
            0
        }
    }

    /// A pixel of the rendered scene scaled back to the scene's own units, saturating at the largest
    /// finite f32.
    pub(super) fn to_scene_units(&self, p: &[f32; 4]) -> [f32; 3] {
        [0, 1, 2].map(|c| (p[c] * self.output_scale).min(f32::MAX))
    }

    /// The last clustered frame's visibility bit matrix and its words per row (for tests).
    pub fn last_visibility(&self) -> Option<(&wgpu::Buffer, u32)> {
        let v = self
            .method_state::<Colom>(Method::Colom)?
            .last_visibility
            .as_ref()?;
        Some((&v.matrix.bits, v.matrix.words))
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
}

impl Renderer<'_> {
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
}

impl Renderer<'_> {
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
