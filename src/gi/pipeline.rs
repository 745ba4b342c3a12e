//! The frame graph: the one place that decides which passes run for a scene and its settings, in what
//! order, and collects their GPU times (the paper's Fig. 2).
//!
//! Resident (per scene / light change): BVH and scene buffers; VPLs (step 1) and their clusters
//! (step 2), rebuilt only when their inputs change.
//! Per frame: primary (step 3) → direct + emission → indirect, one of
//! - `reference`: every pixel × every VPL (Eq. 5), the paper's "no clustering";
//! - `gather`: every pixel × every light, the lights being VPL clusters ("VPLs only");
//! - `sp_cluster` (step 4) → `visibility` (step 5) → `shade` (step 6, Eq. 6 with Eq. 8 or 9), the lights
//!   being VPL clusters ("both") or the VPLs ("SPs only").

use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use anyhow::Result;

use super::direct::Direct;
use super::kmeans::{KMeans, KMeansSettings};
use super::primary::{CameraParams, Primary, SP_BYTES};
use super::reference::Reference;
use super::scene_gpu::SceneGpu;
use super::shade::{Shade, ShadeInputs, ShadeParams};
use super::visibility::Visibility;
use super::vpl_cluster::{self, LightList};
use super::vpl_trace::{VplSet, VplTrace};
use crate::bvh::SceneBvh;
use crate::gpu::{GpuContext, profiler::Profiler};
use crate::scene::{Camera, PunctualLight, Scene};

/// How a pixel's F SP clusters combine their visibility.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Weighting {
    /// F = 1: the nearest cluster only.
    Hard,
    /// Eq. (8): the mean over the F nearest clusters.
    Uniform,
    /// Eq. (9) with Eq. (10): inverse-distance weights.
    InverseDistance,
}

impl Weighting {
    pub fn name(self) -> &'static str {
        match self {
            Weighting::Hard => "hard",
            Weighting::Uniform => "uniform",
            Weighting::InverseDistance => "inverse-distance",
        }
    }
}

/// `on` / `off` (`--temporal`), as a bool.
pub fn parse_on_off(v: &str) -> Result<bool, String> {
    match v.trim() {
        "on" => Ok(true),
        "off" => Ok(false),
        t => Err(format!("'{t}': expected `on` or `off`")),
    }
}

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
    /// The most diffuse reflections a light path deposits VPLs at (the indirect bounce budget).
    pub bounces: u32,
    /// No clustering at all (Eq. 5 per pixel and VPL).
    pub reference: bool,
    /// K of the VPL clustering (0 or ≥ VPLs: off).
    pub vpl_clusters: u32,
    /// K of the SP clustering (0 or ≥ pixels: off).
    pub sp_clusters: u32,
    /// F: SP clusters per pixel (forced to 1 by `Weighting::Hard`).
    pub fuzziness: u32,
    /// γ: SP downsampling factor for the k-means iterations; `kmeans::AUTO_GAMMA` (the default) lets
    /// `kmeans::auto_gamma` choose it from the pixels and K.
    pub gamma: u32,
    /// n_t of Eq. (7), a cosine.
    pub normal_threshold: f32,
    pub iterations: u32,
    pub weighting: Weighting,
    /// Eq. (10) distances to the SP clusters' representatives instead of their centroids.
    pub weights_to_reps: bool,
    /// p of the fuzzy weights w'_f = dist^-p (Eq. 10: p = 1; Eq. 9 with a faster fall-off for p > 1).
    pub weight_exponent: f32,
    /// The plane gate of the SP clusters' F lists, in degrees (`None`: off, the paper; see
    /// `kmeans::plane_gate_sine`).
    pub plane_gate_deg: Option<f32>,
    /// G-term clamp: 1/d² uses d ≥ clamp × scene diagonal (scale-free; see docs/reference.md).
    pub clamp: f32,
    /// Temporal reuse: the SP clustering starts from the previous frame's centroids where the view
    /// still sees their surface, and the VPL clustering from its last centroids when the lights
    /// change (`kmeans::Warm`; docs/temporal.md). Off: every frame starts from the strata.
    pub temporal: bool,
    /// Print progress of long passes on stderr.
    pub progress: bool,
    /// Shared with another thread (the viewer): progress of the long gather passes and a cancel flag
    /// checked between their dispatches.
    pub control: Option<Arc<Control>>,
}

/// Progress of a frame's long pass (`reference` / `gather`) and a request to stop it, shared between
/// the rendering thread and another one. A cancelled frame returns the error `Cancelled`.
#[derive(Debug, Default)]
pub struct Control {
    pub cancel: AtomicBool,
    /// Dispatches of the long pass done and in all (0 / 0 until it starts).
    pub done: AtomicU64,
    pub total: AtomicU64,
}

impl Control {
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
    pub fn is_cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }
    /// Fraction of the long pass done, 0..1.
    pub fn fraction(&self) -> f32 {
        let all = self.total.load(Ordering::Relaxed);
        if all == 0 {
            0.0
        } else {
            self.done.load(Ordering::Relaxed) as f32 / all as f32
        }
    }
}

/// The error of a frame stopped through `Control::cancel`.
#[derive(Debug, thiserror::Error)]
#[error("frame cancelled")]
pub struct Cancelled;

impl Default for FrameSettings {
    fn default() -> Self {
        FrameSettings {
            width: 640,
            height: 480,
            seed: 1,
            direct_samples: 16,
            vpls: 8192,
            bounces: super::vpl_trace::MAX_DEPTH,
            reference: false,
            vpl_clusters: 1024,
            sp_clusters: 3072,
            fuzziness: 6,
            gamma: super::kmeans::AUTO_GAMMA,
            normal_threshold: 0.866,
            iterations: 10,
            weighting: Weighting::InverseDistance,
            weights_to_reps: false,
            weight_exponent: DEFAULT_WEIGHT_EXPONENT,
            plane_gate_deg: None,
            clamp: DEFAULT_CLAMP,
            temporal: false,
            progress: false,
            control: None,
        }
    }
}

impl FrameSettings {
    /// F in effect.
    pub fn f(&self) -> u32 {
        if self.weighting == Weighting::Hard {
            1
        } else {
            self.fuzziness.clamp(1, super::kmeans::MAX_F)
        }
    }
}

/// Default G-term clamp as a fraction of the scene diagonal.
/// p of the fuzzy weights (w'_f = dist^-p) by default: Eq. (10)'s 1.
pub const DEFAULT_WEIGHT_EXPONENT: f32 = 1.0;

/// Whether `p` is a usable weight exponent: finite, in [0, 64] (64 is already hard clustering).
pub fn valid_weight_exponent(p: f32) -> bool {
    (0.0..=64.0).contains(&p)
}

pub const DEFAULT_CLAMP: f32 = 0.02;

/// Bytes a pixel takes in a frame's largest per-pixel storage binding: the G-buffer (`SP_BYTES`);
/// the k-means' per-pixel assign and weight lists (F ≤ `MAX_F` words) are no larger. One binding
/// holds at most `max_storage_buffer_binding_size` bytes (lavapipe: 128 MiB, 2,097,152 pixels).
pub const PIXEL_BYTES: u64 = if SP_BYTES > super::kmeans::MAX_F as u64 * 4 {
    SP_BYTES
} else {
    super::kmeans::MAX_F as u64 * 4
};

/// The path tracer's: its accumulation buffer, 16 bytes a pixel.
pub const PATH_TRACE_PIXEL_BYTES: u64 = 16;

/// The most pixels a frame may have on `ctx` when each takes `bytes_per_pixel` in one binding.
pub fn max_pixels(ctx: &GpuContext, bytes_per_pixel: u64) -> u64 {
    ctx.max_binding() / bytes_per_pixel
}

/// A frame too large for one storage binding of this adapter (creating its bind groups would be a
/// wgpu panic).
#[derive(Debug, thiserror::Error)]
#[error(
    "a {width}x{height} frame has {} pixels; this adapter holds at most {most} ({bytes} bytes a pixel in one {binding}-byte storage binding)",
    *width as u64 * *height as u64
)]
pub struct TooLarge {
    pub width: u32,
    pub height: u32,
    pub most: u64,
    pub bytes: u64,
    pub binding: u64,
}

/// Refuses a frame whose per-pixel buffers do not fit in one storage binding of `ctx`.
pub fn check_frame_size(
    ctx: &GpuContext,
    width: u32,
    height: u32,
    bytes_per_pixel: u64,
) -> Result<(), TooLarge> {
    let most = max_pixels(ctx, bytes_per_pixel);
    if width as u64 * height as u64 > most {
        return Err(TooLarge {
            width,
            height,
            most,
            bytes: bytes_per_pixel,
            binding: ctx.max_binding(),
        });
    }
    Ok(())
}

/// Bytes of the visibility bit matrix a frame records (0 when it clusters no SPs): one row per SP
/// cluster, one bit per light, the lights being the VPL clusters or, unclustered, every VPL (an
/// upper bound: fewer may be traced or used). It is one storage binding.
pub fn visibility_bytes(plan: &Plan, s: &FrameSettings) -> u64 {
    if !plan.sp_clustering {
        return 0;
    }
    s.sp_clusters as u64 * visibility_lights(plan, s).div_ceil(32).max(1) as u64 * 4
}

fn visibility_lights(plan: &Plan, s: &FrameSettings) -> u32 {
    if plan.vpl_clustering {
        s.vpl_clusters
    } else {
        s.vpls
    }
}

/// Refuses a frame whose visibility bit matrix does not fit in one storage binding of `ctx` (K_sp ×
/// lights / 8 bytes: 200,000 SP clusters × 8192 VPLs is 205 MB, lavapipe binds 128 MiB): the message
/// names the options.
pub fn check_visibility_size(
    ctx: &GpuContext,
    plan: &Plan,
    s: &FrameSettings,
) -> Result<(), String> {
    let bytes = visibility_bytes(plan, s);
    let binding = ctx.max_binding();
    if bytes > binding {
        let lights = visibility_lights(plan, s);
        let what = if plan.vpl_clustering {
            "VPL clusters"
        } else {
            "VPLs"
        };
        return Err(format!(
            "--sp-clusters {} with {lights} {what}: the visibility bit matrix (a bit per SP cluster and light) takes {bytes} bytes, more than the {binding} bytes of one storage binding on this adapter; use fewer SP clusters or cluster the VPLs",
            s.sp_clusters
        ));
    }
    Ok(())
}

/// Which indirect path a frame takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Plan {
    pub indirect: bool,
    pub vpl_clustering: bool,
    pub sp_clustering: bool,
}

impl Plan {
    pub fn new(scene: &Scene, s: &FrameSettings) -> Plan {
        let indirect = s.vpls > 0 && scene.has_light();
        Plan {
            indirect,
            vpl_clustering: indirect
                && !s.reference
                && s.vpl_clusters > 0
                && s.vpl_clusters < s.vpls,
            sp_clustering: indirect
                && !s.reference
                && s.sp_clusters > 0
                && s.sp_clusters < s.width * s.height,
        }
    }

    pub fn passes(&self) -> Vec<&'static str> {
        let mut p = vec![];
        if self.indirect {
            p.push("vpl_trace");
        }
        if self.vpl_clustering {
            p.push("vpl_cluster");
        }
        p.extend(["primary", "direct"]);
        if self.indirect {
            if self.sp_clustering {
                p.extend(["sp_cluster", "visibility", "shade"]);
            } else if self.vpl_clustering {
                p.push("gather");
            } else {
                p.push("reference");
            }
        }
        p
    }
}

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
    /// GPU milliseconds per pass (summed over its dispatches); `frame` excludes resident VPL work.
    pub timings_ms: BTreeMap<String, f64>,
    pub shading_points: u32,
    pub shadow_rays: u64,
    pub sp_clusters_used: u32,
    pub vpl_clusters_used: u32,
    /// γ Alg. 1 sampled with (`kmeans::effective_gamma`); `None` when no SP clustering ran.
    pub gamma_used: Option<u32>,
    /// The shading point of each pixel: world position, w = 1 where the primary ray hit (0: sky).
    /// What the viewer reprojects a frame with.
    pub positions: Vec<[f32; 4]>,
    /// Alg. 1 iterations the SP clustering ran (0 when none ran).
    pub sp_iterations: u32,
    /// SP centroids a temporal warm start kept from the previous frame (`None`: a cold start).
    pub sp_warm_kept: Option<u32>,
    /// Rows of the visibility matrix copied from the previous frame instead of traced (kept
    /// representatives, same lights).
    pub visibility_rows_reused: u32,
}

/// What a light list was built for: (K, n_t bits, iterations, seed, VPLs, the VPL set's trace).
pub type LightKey = (u32, u32, u32, u32, u32, u32);
/// What a VPL set was traced for: (count, seed, bounces) and which trace it is (`Renderer`'s count of
/// traces: a light change re-traces the same count, seed and bounces).
pub type VplKey = (u32, u32, u32, u32);

/// Everything resident for one scene on one device.
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
    primary: Primary,
    direct: Direct,
    vpl_trace: VplTrace,
    reference: Reference,
    kmeans: KMeans,
    visibility: Visibility,
    shade: Shade,
    gbuffer: Option<(wgpu::Buffer, u32)>,
    /// Resident VPLs with what they were traced for and the GPU ms it took.
    pub vpl_set: Option<(VplSet, VplKey, f64)>,
    /// VPL traces so far (the last element of `VplKey`).
    vpl_traces: u32,
    /// Resident light list (VPL clusters or the VPLs), its key and the clustering's GPU ms.
    pub lights: Option<(LightList, LightKey, f64)>,
    /// The last frame's SP clustering (for views and tests).
    pub sp_clustering: Option<super::kmeans::Clustering>,
    /// The last frame's visibility matrix and the light list it was traced against.
    last_visibility: Option<(super::visibility::Previous, LightKey)>,
}

impl<'a> Renderer<'a> {
    pub fn new(ctx: &'a GpuContext, source: &'a Scene) -> Result<Self> {
        super::scene_gpu::check_fits(source, ctx.max_binding())?;
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
            visibility: Visibility::new(ctx, &gpu),
            shade: Shade::new(),
            profiler: Profiler::new(ctx),
            gbuffer: None,
            vpl_set: None,
            vpl_traces: 0,
            lights: None,
            sp_clustering: None,
            last_visibility: None,
            bvh,
            gpu,
        })
    }

    /// `camera` (in the caller's units) in the rendered scene's units: its eye scaled by
    /// `geometry_scale`.
    pub fn to_render_units(&self, camera: &Camera) -> Camera {
        let mut c = camera.clone();
        if self.geometry_scale != 1.0 {
            let eye = c.transform.w_axis.truncate().as_dvec3() * self.geometry_scale;
            c.transform.w_axis = eye.as_vec3().extend(1.0);
        }
        c
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
            self.visibility = Visibility::new(ctx, &gpu);
        }
        self.gpu = gpu;
        self.vpl_set = None;
    }

    /// The passes a frame with these settings runs, in order (also what `info` prints).
    pub fn passes_for(scene: &Scene, s: &FrameSettings) -> Vec<&'static str> {
        Plan::new(scene, s).passes()
    }

    /// Traces the VPLs unless the resident ones match (count, seed, bounces).
    pub fn ensure_vpls(&mut self, n: u32, seed: u32, bounces: u32) -> Result<&VplSet> {
        let traced = self.vpl_set.as_ref().map(|v| (v.1.0, v.1.1, v.1.2));
        if traced != Some((n, seed, bounces)) {
            self.vpl_traces += 1;
            let key = (n, seed, bounces, self.vpl_traces);
            let _ = self.profiler.collect(self.ctx)?;
            let set = self.vpl_trace.trace(
                self.ctx,
                &self.scene,
                &self.gpu,
                &mut self.profiler,
                n,
                seed,
                bounces,
            )?;
            let ms: f64 = self.profiler.collect(self.ctx)?.values().sum();
            self.vpl_set = Some((set, key, ms));
        }
        Ok(&self.vpl_set.as_ref().unwrap().0)
    }

    /// Builds the light list (VPL clusters, or the VPLs themselves) unless the resident one matches.
    fn ensure_lights(&mut self, s: &FrameSettings, plan: &Plan) -> Result<()> {
        self.ensure_vpls(s.vpls, s.seed, s.bounces)?;
        let k = if plan.vpl_clustering {
            s.vpl_clusters
        } else {
            0
        };
        let key = (
            k,
            s.normal_threshold.to_bits(),
            s.iterations,
            s.seed,
            s.vpls,
            self.vpl_set.as_ref().unwrap().1.3,
        );
        if self.lights.as_ref().map(|l| l.1) == Some(key) {
            return Ok(());
        }
        let vpls = &self.vpl_set.as_ref().unwrap().0;
        let _ = self.profiler.collect(self.ctx)?;
        let list = if plan.vpl_clustering {
            let ks = KMeansSettings {
                k,
                f: 1,
                gamma: 1,
                normal_threshold: s.normal_threshold,
                iterations: s.iterations,
                seed: s.seed,
                weights_to_reps: false,
                weight_exponent: 1.0,
                plane_gate_deg: None,
            };
            let previous = self.lights.take().filter(|_| s.temporal);
            let warm = previous
                .as_ref()
                .and_then(|(l, ..)| l.clustering.as_ref())
                .map(|c| super::kmeans::Warm {
                    centroids: &c.centroids,
                    rep_points: &c.rep_points,
                    k: c.k(),
                    view: None,
                });
            vpl_cluster::cluster(
                self.ctx,
                &self.gpu,
                &self.kmeans,
                &mut self.profiler,
                vpls,
                &ks,
                self.scene.bounds(),
                warm.as_ref(),
            )?
        } else {
            vpl_cluster::unclustered(self.ctx, vpls)
        };
        let ms: f64 = self.profiler.collect(self.ctx)?.values().sum();
        self.lights = Some((list, key, ms));
        Ok(())
    }

    /// The direct light (emission + direct, as `Frame::direct`) of the last frame's shading points
    /// again, with another seed: an independent estimate to average with it (the viewer accumulates
    /// these while the camera rests). Returns it with its GPU ms.
    pub fn direct_again(&mut self, s: &FrameSettings, seed: u32) -> Result<(Vec<[f32; 3]>, f64)> {
        let ctx = self.ctx;
        let Some((gbuffer, n)) = &self.gbuffer else {
            anyhow::bail!("no frame rendered yet");
        };
        let radiance = ctx.storage("radiance", *n as u64 * 16);
        let spp = if self.gpu.has_emitters {
            s.direct_samples.max(1)
        } else {
            0
        };
        let _ = self.profiler.collect(ctx)?;
        self.direct.record(
            ctx,
            &self.gpu,
            &mut self.profiler,
            gbuffer,
            &radiance,
            *n,
            spp,
            seed,
        );
        let ms: f64 = self.profiler.collect(ctx)?.values().sum();
        let px: Vec<[f32; 4]> = ctx.read_buffer(&radiance, *n as usize)?;
        let k = self.output_scale;
        Ok((
            px.iter()
                .map(|p| [0, 1, 2].map(|c| (p[c] * k).min(f32::MAX)))
                .collect(),
            ms,
        ))
    }

    /// The last clustered frame's visibility bit matrix and its words per row (for tests).
    pub fn last_visibility(&self) -> Option<(&wgpu::Buffer, u32)> {
        self.last_visibility
            .as_ref()
            .map(|(p, _)| (&p.bits, p.words))
    }

    /// The last frame's shading points, 4 × vec4 each (`common/gbuffer.wgsl`), for tests and views.
    pub fn last_gbuffer(&self) -> Result<Vec<[f32; 4]>> {
        match &self.gbuffer {
            Some((b, n)) => self.ctx.read_buffer(b, *n as usize * 4),
            None => anyhow::bail!("no frame rendered yet"),
        }
    }

    /// The diffuse path tracer (`--path-trace`, the check of the VPL reference's own bias) instead of
    /// the VPL frame: `spp` samples a pixel with the settings' bounce budget and seed, in the scene's
    /// own units (scaled back like `render`). Nothing of the VPL frame runs.
    pub fn path_trace(&mut self, camera: &Camera, s: &FrameSettings, spp: u32) -> Result<Frame> {
        let ctx = self.ctx;
        check_frame_size(ctx, s.width, s.height, PATH_TRACE_PIXEL_BYTES)?;
        let pt = super::pathtrace::PathTrace::new(ctx, &self.gpu);
        let cam = CameraParams::new(&self.to_render_units(camera), s.width, s.height);
        let _ = self.profiler.collect(ctx)?;
        // Samples an invocation traces per pass. lavapipe ends all loops of a SIMD batch after
        // 65,535 trips (docs/architecture.md): 16 samples of up to 9 vertices lost up to 2 of them on
        // 1% of the breakfast room's pixels (262k triangles; none on the built-in rooms), 4 lose none.
        let per_pass = if ctx.software && self.gpu.info.num_nodes > 1 << 16 {
            4
        } else {
            16
        };
        let img = pt.render(
            ctx,
            &self.gpu,
            &mut self.profiler,
            &cam,
            spp.max(1),
            per_pass,
            s.seed,
            s.bounces,
        )?;
        let mut timings_ms = self.profiler.collect(ctx)?;
        let ms: f64 = timings_ms.values().sum();
        timings_ms.insert("frame".into(), ms);
        let k = self.output_scale;
        let radiance: Vec<[f32; 3]> = img
            .iter()
            .map(|p| [0, 1, 2].map(|c| (p[c] * k).min(f32::MAX)))
            .collect();
        let n = radiance.len();
        Ok(Frame {
            width: s.width,
            height: s.height,
            // The path tracer does not separate direct from indirect light: all of it is here.
            direct: radiance.clone(),
            indirect: vec![[0.0; 3]; n],
            radiance,
            vpls: 0,
            passes: vec!["pathtrace"],
            timings_ms,
            shading_points: 0,
            shadow_rays: 0,
            sp_clusters_used: 0,
            vpl_clusters_used: 0,
            gamma_used: None,
            positions: Vec::new(),
            sp_iterations: 0,
            sp_warm_kept: None,
            visibility_rows_reused: 0,
        })
    }

    pub fn render(&mut self, camera: &Camera, s: &FrameSettings) -> Result<Frame> {
        let ctx = self.ctx;
        check_frame_size(ctx, s.width, s.height, PIXEL_BYTES)?;
        let n = s.width * s.height;
        let plan = Plan::new(&self.scene, s);
        check_visibility_size(ctx, &plan, s).map_err(anyhow::Error::msg)?;
        let passes = plan.passes();
        if plan.indirect {
            self.ensure_lights(s, &plan)?;
        }
        let gbuffer = ctx.storage("gbuffer", n as u64 * SP_BYTES);
        let radiance = ctx.storage("radiance", n as u64 * 16);
        let indirect = ctx.storage("indirect", n as u64 * 16);
        let cam = CameraParams::new(&self.to_render_units(camera), s.width, s.height);
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
        let d_min = s.clamp * self.scene.extent();
        let mut indirect_rays = 0u64;
        let mut sp_used = 0;
        let mut gamma_used = None;
        let mut num_lights = 0;
        let (mut sp_iterations, mut sp_warm_kept, mut rows_reused) = (0, None, 0);
        let previous = self.sp_clustering.take().filter(|_| s.temporal);
        if plan.indirect {
            let lights = &self.lights.as_ref().unwrap().0;
            num_lights = lights.lights.len() as u32;
            if plan.sp_clustering {
                let ks = KMeansSettings {
                    k: s.sp_clusters,
                    f: s.f(),
                    gamma: s.gamma,
                    normal_threshold: s.normal_threshold,
                    iterations: s.iterations,
                    seed: s.seed,
                    weights_to_reps: s.weights_to_reps,
                    weight_exponent: s.weight_exponent,
                    plane_gate_deg: s.plane_gate_deg,
                };
                let warm = previous.as_ref().map(|c| super::kmeans::Warm {
                    centroids: &c.centroids,
                    rep_points: &c.rep_points,
                    k: c.k(),
                    view: Some(cam),
                });
                let c = self.kmeans.run(
                    ctx,
                    &self.gpu,
                    &mut self.profiler,
                    "sp_cluster",
                    &gbuffer,
                    n,
                    4,
                    &ks,
                    self.scene.bounds(),
                    warm.as_ref(),
                )?;
                sp_iterations = c.iterations_run;
                sp_warm_kept = c.warm_kept;
                let light_key = self.lights.as_ref().unwrap().1;
                let previous = self
                    .last_visibility
                    .take()
                    .filter(|(_, key)| s.temporal && c.warm_kept.is_some() && *key == light_key);
                let (bits, words) = self.visibility.record(
                    ctx,
                    &self.gpu,
                    &mut self.profiler,
                    &c.rep_points,
                    &lights.buffer,
                    num_lights,
                    c.k(),
                    previous.as_ref().map(|p| &p.0),
                );
                self.shade.record(
                    ctx,
                    &self.gpu,
                    &mut self.profiler,
                    &ShadeInputs {
                        gbuffer: &gbuffer,
                        lights: &lights.buffer,
                        bits: &bits,
                        assign: &c.assign,
                        weights: &c.weights,
                        indirect: &indirect,
                        pixels: n,
                        params: ShadeParams {
                            num_lights,
                            words,
                            f: c.f(),
                            weighted: (s.weighting == Weighting::InverseDistance) as u32,
                            d_min2: d_min * d_min,
                            _pad: [0; 3],
                        },
                    },
                );
                let reps: Vec<u32> = ctx.read_buffer(&c.reps, c.k() as usize * 2)?;
                sp_used = reps.chunks(2).filter(|r| r[1] != u32::MAX).count() as u32;
                if let Some((p, _)) = &previous
                    && p.words == words
                {
                    // Rows copied, not traced: kept representatives below the previous row count.
                    let points: Vec<[f32; 4]> =
                        ctx.read_buffer(&c.rep_points, c.k() as usize * 2)?;
                    rows_reused = points
                        .chunks(2)
                        .take(p.rows as usize)
                        .filter(|r| r[0][3] > 0.0 && r[1][3] == 1.0)
                        .count() as u32;
                }
                indirect_rays = (sp_used - rows_reused) as u64 * num_lights as u64;
                self.last_visibility = Some((
                    super::visibility::Previous {
                        bits,
                        rows: c.k(),
                        words,
                    },
                    light_key,
                ));
                gamma_used = Some(c.params.gamma);
                self.sp_clustering = Some(c);
            } else {
                let label = if plan.vpl_clustering {
                    "gather"
                } else {
                    "reference"
                };
                let show = s.progress;
                let control = s.control.clone();
                let mut last = 0u64;
                self.reference.record(
                    ctx,
                    &self.gpu,
                    &mut self.profiler,
                    &gbuffer,
                    &lights.buffer,
                    num_lights,
                    &indirect,
                    n,
                    d_min,
                    label,
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
            }
        }
        let mut timings_ms = self.profiler.collect(ctx)?;
        let frame_ms: f64 = timings_ms.values().sum();
        timings_ms.insert("frame".into(), frame_ms);
        if plan.indirect {
            timings_ms.insert("vpl_trace".into(), self.vpl_set.as_ref().unwrap().2);
        }
        if plan.vpl_clustering {
            timings_ms.insert("vpl_cluster".into(), self.lights.as_ref().unwrap().2);
        }
        let px: Vec<[f32; 4]> = ctx.read_buffer(&radiance, n as usize)?;
        let ind: Vec<[f32; 4]> = ctx.read_buffer(&indirect, n as usize)?;
        let sps: Vec<[f32; 4]> = ctx.read_buffer(&gbuffer, n as usize * 4)?;
        let valid = sps.chunks(4).filter(|sp| sp[0][3] > 0.0).count() as u32;
        if plan.indirect && !plan.sp_clustering {
            indirect_rays = valid as u64 * num_lights as u64;
        }
        self.gbuffer = Some((gbuffer, n));
        // Scaled back to the scene's own units, saturating at the largest finite f32.
        let k = self.output_scale;
        let back = |p: &[f32; 4]| [0, 1, 2].map(|c| (p[c] * k).min(f32::MAX));
        let direct: Vec<[f32; 3]> = px.iter().map(back).collect();
        let indirect: Vec<[f32; 3]> = ind.iter().map(back).collect();
        let radiance = direct
            .iter()
            .zip(&indirect)
            .map(|(a, b)| [0, 1, 2].map(|c| (a[c] + b[c]).min(f32::MAX)))
            .collect();
        Ok(Frame {
            width: s.width,
            height: s.height,
            radiance,
            direct,
            indirect,
            vpls: self.vpl_set.as_ref().map_or(0, |v| v.0.vpls.len() as u32),
            passes,
            timings_ms,
            shading_points: valid,
            shadow_rays: valid as u64 * (spp as u64 + self.gpu.info.num_lights as u64)
                + indirect_rays,
            sp_clusters_used: sp_used,
            vpl_clusters_used: if plan.vpl_clustering { num_lights } else { 0 },
            gamma_used,
            // In the caller's units (the G-buffer holds the unit frame's, `geometry_scale`).
            positions: sps
                .chunks(4)
                .map(|sp| {
                    let p = sp[0];
                    let k = 1.0 / self.geometry_scale;
                    let q = glam::DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) * k;
                    [q.x as f32, q.y as f32, q.z as f32, p[3]]
                })
                .collect(),
            sp_iterations,
            sp_warm_kept,
            visibility_rows_reused: rows_reused,
        })
    }
}
