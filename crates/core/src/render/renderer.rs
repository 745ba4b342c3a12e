//! The `Renderer` and its lifetime: what it holds for one scene on one device (the role of Bevy
//! Solari's `prepare.rs` with its plugin), how it is made, how its lights move, and how the past that
//! temporal reuse starts from is put aside or forgotten. What it records each frame is `record.rs`;
//! its resident caches (VPLs, their clustering) `resident.rs`.

use std::collections::BTreeMap;

use anyhow::Result;

use crate::bvh::SceneBvh;
use crate::gi::direct::Direct;
use crate::gi::kmeans::{Clustering, KMeans};
use crate::gi::primary::Primary;
use crate::gi::reference::Reference;
use crate::gi::scene_gpu::SceneGpu;
use crate::gi::vpl_cluster::ResidentLights;
use crate::gi::vpl_trace::{ResidentVpls, VplTrace};
use crate::gpu::{GpuContext, profiler::Profiler};
use crate::method::{IndirectMethod, Method};
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
    pub(super) vpl_trace: VplTrace,
    pub(super) reference: Reference,
    pub(super) kmeans: KMeans,
    /// The other methods' state (`method::REGISTRY`), each built the first time a frame uses it.
    pub(super) methods: BTreeMap<Method, Box<dyn IndirectMethod>>,
    /// The method whose passes computed the last frame's indirect light (`None`: the shared
    /// gather, or no indirect light).
    pub(super) last_method: Option<Method>,
    /// The indirect light at the render scale (`gi::upsample`).
    pub(super) upsample: crate::gi::upsample::Upsampler,
    /// Temporal accumulation (`gi::accumulate`): its kernel, built on first use, and the last
    /// frame's history (`None` after a frame without accumulation).
    pub(super) accumulator: std::cell::OnceCell<crate::gi::accumulate::Accumulate>,
    pub(super) history: Option<crate::render::History>,
    /// The last frame's buffers (`direct_again`, `last_gbuffer`: its image G-buffer).
    pub(super) gbuffer: Option<std::sync::Arc<crate::render::FrameBuffers>>,
    /// The frames' buffers, reused by size.
    pub(super) frames: crate::render::FramePool,
    /// The pass that writes a frame into a caller's texture (`render_to_texture`), built on first use.
    pub(super) compose: std::cell::OnceCell<crate::gi::compose::Compose>,
    /// The viewer's refinement at rest on the GPU (`refine_direct`): its kernel and the buffers of
    /// one estimate (radiance, jittered G-buffer), kept between calls.
    pub(super) refine: std::cell::OnceCell<crate::gi::refine::Refine>,
    pub(super) estimate: Option<(wgpu::Buffer, wgpu::Buffer, u32)>,
    /// Lit pixels counted on the GPU (`count_lit`: `gi::sum` over the G-buffer's `pos.w`), built on
    /// first use.
    pub(super) lit: Option<crate::gi::sum::WordSum>,
    /// The last frame's camera (render units), for `direct_again`'s jittered primary rays.
    pub(super) last_camera: Option<crate::gi::primary::CameraParams>,
    pub vpl_set: Option<ResidentVpls>,
    /// VPL traces so far (`VplKey::trace`).
    pub(super) vpl_traces: u32,
    pub lights: Option<ResidentLights>,
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
pub(super) use gpu;

impl<'a> Renderer<'a> {
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
            last_method: None,
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
            // The methods' pipelines are built again; their past (a last SP clustering and
            // visibility) carries over.
            let pasts: Vec<_> = (self.methods.iter_mut())
                .map(|(&m, state)| (m, state.take_past()))
                .collect();
            self.methods = pasts
                .into_iter()
                .map(|(m, past)| {
                    let mut state = crate::method::build(m)(ctx, &gpu);
                    state.put_past(past);
                    (m, state)
                })
                .collect();
        }
        self.gpu = gpu;
        self.vpl_set = None;
        // The indirect light of the old lights is no history for the new ones.
        self.history = None;
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

    /// Sets of frame buffers made so far (`FramePool`): frames of a steady size make none.
    pub fn frame_sets_made(&self) -> u32 {
        self.frames.made
    }

    /// A method's state (`method::REGISTRY`) as its module's type `T`, once a frame has used it (tests
    /// and views read a method's last clustering from it).
    pub fn method_state<T: 'static>(&self, method: Method) -> Option<&T> {
        let state: &dyn std::any::Any = self.methods.get(&method)?.as_ref();
        state.downcast_ref()
    }

    /// `method_state`, mutable, the state built if no frame has used it yet.
    pub fn method_state_mut<T: 'static>(&mut self, method: Method) -> Option<&mut T> {
        let state: &mut dyn std::any::Any = self.method(method).as_mut();
        state.downcast_mut()
    }

    /// A method's state, built if no frame has used it yet.
    pub(super) fn method(&mut self, method: Method) -> &mut Box<dyn IndirectMethod> {
        let (ctx, gpu) = (self.ctx, &self.gpu);
        self.methods
            .entry(method)
            .or_insert_with(|| crate::method::build(method)(ctx, gpu))
    }

    /// The SP clustering of the last frame's method, where it keeps one
    /// (`IndirectMethod::sp_clustering`): `None` after a frame that clustered no shading points.
    pub fn sp_clustering(&self) -> Option<&Clustering> {
        self.methods.get(&self.last_method?)?.sp_clustering()
    }

    /// Forgets every method's past (the last SP clustering and visibility) and the accumulated
    /// indirect light: the next frame starts cold (a camera path run).
    pub fn forget_past(&mut self) {
        for m in self.methods.values_mut() {
            drop(m.take_past());
        }
        self.history = None;
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
}
