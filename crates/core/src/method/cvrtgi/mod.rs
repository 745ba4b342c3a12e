//! The CVRTGI method (Cosin Ayerbe & Patow 2022, "Clustered voxel real-time global illumination",
//! seed 003; docs/cvrtgi.md) as one pass that writes a frame's indirect light in the form of the
//! default method's shade pass (`shade.wgsl`: ρ/π × irradiance, vec4 a pixel, render units), so
//! the direct light, exposure, metrics and the reference are shared.
//!
//! Stages and what each is keyed on (the paper's Fig. 5: the costly part is not redone for a camera
//! move while the lights stay):
//! 1. geometry (scene + voxel/cluster/ray settings), resident: the voxelisation (§4.1) and the SLIC
//!    clustering (§4.2, Eq. 1, Alg. 1) on the CPU (`voxel`), then the per-face cluster visibility
//!    cache (§4.3) on the GPU (`visibility`, BVH rays);
//! 2. light (+ the VPL set, near distance, filter, clamp, gather mode, escape rays), resident:
//!    where each VPL's light goes (`escape`, GPU, not in the paper), the VPLs pulled into their
//!    voxels and clusters on the CPU (`inject`), the per-face gathering (§4.4, `gather`; with
//!    `--cluster-gather conserved`, not in the paper, run twice: the second time with each
//!    cluster's conservation scale, `inject::conservation_scales`) and the Gaussian filter passes
//!    (`filter`) on the GPU;
//! 3. per frame: each pixel reads its face's filtered irradiance (§4.5, `lookup`).
//!
//! Shader: `shaders-wgsl/cvrtgi.wgsl`; CPU twin of every kernel: `twin`. The pass is
//! `PASS` (`ENTRY`).

pub mod inject;
pub mod settings;
/// The CPU twin of this module's shader, for tests only: no production code calls it.
pub mod twin;
pub mod voxel;

mod bindings;
use bindings::{Bindings, entries, light_words, run_faces};
use std::cell::OnceCell;
use std::time::Instant;

use anyhow::{Result, bail};
use glam::Vec3;

use self::inject::{Faces, Lighting};
use self::settings::{ClusterGather, CvrtgiSettings};
use self::voxel::{Cluster, SlicSettings, Voxels};
use super::Method;
use super::{FrameInputs, IndirectMethod, MethodEntry, Tally};
use crate::gi::dispatch::{Gpu, Kernel, Run};
use crate::gi::pass::Pass;
use crate::gi::scene_gpu::{SceneGpu, TooBig};
use crate::gi::vpl_trace::{VplKey, VplSet};

pub use settings::{CvrtgiLists as Lists, CvrtgiSettings as Settings};

/// cvrtgi's one pass: voxels, clusters and the per-face visibility cache (resident while the scene
/// and its knobs stay), the lit clusters' per-face irradiance, filtered (resident while the VPLs
/// stay), and every pixel's lookup (GPU times under `cvrtgi.*`, the CPU stages under `cvrtgi`).
pub const PASS: Pass = Pass::Method("cvrtgi");
use crate::gpu::GpuContext;
use crate::scene::Scene;

/// How far (in voxels) a VPL's ray must get for its light to count as leaving its surface
/// (`escape`).
pub const ESCAPE_REACH: f32 = 0.1;

/// The profiler labels of the kernels (what the GPU timings are keyed by).
pub const LABELS: [&str; 5] = [
    "cvrtgi.visibility",
    "cvrtgi.gather",
    "cvrtgi.filter",
    "cvrtgi.lookup",
    "cvrtgi.escape",
];

crate::gpu::shader::gpu_struct! {
    /// `cvrtgi.wgsl`'s parameters.
    pub(crate) struct CvParams {
        /// xyz: the grid's min corner; w: the voxel size s.
        origin: [f32; 4],
        /// xyz: voxels per axis; w: occupied voxels V.
        dims: [u32; 4],
        num_faces: u32,
        rays: u32,
        num_clusters: u32,
        /// The filter's radius r ((2r+1)³ kernel).
        radius: u32,
        d_min2: f32,
        /// Clusters nearer than this (to their box) give their lit voxels one by one.
        near: f32,
        inv_two_sigma2: f32,
        _pad: u32,
        /// 0: the paper's gather; 1: each cluster's light times its conservation scale (flux.w),
        /// and each slot's `slot_flux` before the scale to `vis_w`.
        gather_mode: u32,
        /// Rays per VPL of `escape`, and how far one must get to escape.
        escape_rays: u32,
        escape_reach: f32,
        num_vpls: u32,
    }
}

/// What one frame's CVRTGI pass reads and writes. The caller (the frame graph) provides the scene as
/// rendered (`Renderer::scene`, in render units: the G-buffer's and the VPLs' units), the resident
/// VPLs with their key, the frame's G-buffer (`common/gbuffer.wgsl`, from the primary pass) and the
/// `indirect` image to write (vec4 a pixel, overwritten), like `ShadeInputs`.
pub struct CvrtgiInputs<'a> {
    pub scene: &'a Scene,
    pub vpls: &'a VplSet,
    pub vpl_key: VplKey,
    pub gbuffer: &'a wgpu::Buffer,
    pub pixels: u32,
    pub indirect: &'a wgpu::Buffer,
    /// The G-term clamp distance in render units (`FrameSettings::clamp` × scene diagonal), as the
    /// reference's.
    pub d_min: f32,
}

/// What a `record` did: sizes, and which resident stages it (re)built. The stats' `counts.cvrtgi`
/// (docs/design.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct CvrtgiReport {
    pub voxels: u32,
    pub clusters: u32,
    pub unassigned_voxels: u32,
    pub faces: u32,
    pub lit_clusters: u32,
    pub lit_voxels: u32,
    pub dropped_vpls: u32,
    /// Rays traced for the visibility cache this call (0 when it was resident).
    pub visibility_rays: u64,
    /// Rays traced for the VPLs' escape weights this call (0 when the light stage was resident).
    pub escape_rays: u64,
    pub geometry_built: bool,
    pub light_built: bool,
    /// CPU milliseconds of the stages rebuilt this call (voxelisation, clustering, injection); not
    /// among the counts (the stats' `timings_ms.cvrtgi` is the last build's).
    #[serde(skip)]
    pub cpu_ms: f64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct GeometryKey {
    voxel_res: u32,
    step: u32,
    iterations: u32,
    angle: u32,
    rays: u32,
    triangles: usize,
    bounds: [u32; 6],
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct LightKey {
    geometry: GeometryKey,
    vpls: VplKey,
    near: u32,
    radius: u32,
    passes: u32,
    d_min: u32,
    gather: ClusterGather,
    escape_rays: u32,
}

/// The resident geometry stage: voxels, clusters, faces and the visibility cache.
pub struct CvrtgiGeometry {
    pub voxels: Voxels,
    pub clusters: Vec<Cluster>,
    pub faces: Faces,
    pub rays: u32,
    voxel_buf: wgpu::Buffer,
    faces_buf: wgpu::Buffer,
    /// Per face `rays` cluster ids (`visibility`).
    pub vis: wgpu::Buffer,
}

/// The resident light stage: the lights and the per-face irradiance before and after filtering.
pub struct CvrtgiLight {
    pub lighting: Lighting,
    /// Per VPL the fractions of its light that leave its surface and that it sends into the scene
    /// (`escape`; empty when `--escape-rays` is 0).
    pub escape: Vec<[f32; 2]>,
    /// Beside the visibility cache, the flux each listed cluster sends to the face before its
    /// conservation scale (`gather` with `--cluster-gather conserved`; 4 bytes otherwise).
    pub slot_flux: wgpu::Buffer,
    lights_buf: wgpu::Buffer,
    /// vec4 a face: `gather`'s output.
    pub gathered: wgpu::Buffer,
    /// vec4 a face: after the filter passes (the buffer `lookup` reads).
    pub filtered: wgpu::Buffer,
}

/// The kernels, one per entry point of `cvrtgi.wgsl` (each with its own chunk uniform).
struct Kernels {
    visibility: Kernel,
    gather: Kernel,
    filter: Kernel,
    lookup: Kernel,
    escape: Kernel,
    overrides: Vec<(&'static str, f64)>,
}

/// The CVRTGI pass: its pipelines (built on first use) and its resident stages.
#[derive(Default)]
pub struct Cvrtgi {
    kernels: OnceCell<Kernels>,
    geometry: Option<(GeometryKey, CvrtgiGeometry)>,
    light: Option<(LightKey, CvrtgiLight)>,
    /// The times of the resident stages when they were last built (`RESIDENT_KEYS`).
    last_build: std::collections::BTreeMap<String, f64>,
}

/// The timing keys of cvrtgi's resident stages: its CPU stages (`PASS`'s key:
/// voxelisation, SLIC, injection) and the kernels that run only when their stage is rebuilt. Like
/// `vpl_trace` and `vpl_cluster` they are not in `frame` (a frame with the same scene and VPLs runs
/// only `cvrtgi.lookup`); the stats report their last build's times.
pub const RESIDENT_KEYS: [&str; 5] = ["cvrtgi", LABELS[0], LABELS[1], LABELS[2], LABELS[4]];

fn f32_bits(v: Vec3) -> [u32; 3] {
    [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()]
}

impl Cvrtgi {
    /// Takes the resident stages' times out of a frame's `timings` (they are not the frame's),
    /// keeps those this frame built as the last build's, and returns the last build's times.
    pub fn take_build_times(
        &mut self,
        timings: &mut std::collections::BTreeMap<String, f64>,
    ) -> std::collections::BTreeMap<String, f64> {
        for k in RESIDENT_KEYS {
            if let Some(ms) = timings.remove(k).filter(|&ms| ms > 0.0) {
                self.last_build.insert(k.to_string(), ms);
            }
        }
        self.last_build.clone()
    }

    pub fn new() -> Self {
        Self::default()
    }

    fn kernels(&mut self, ctx: &GpuContext, scene: &SceneGpu) -> &Kernels {
        if self
            .kernels
            .get()
            .is_some_and(|k| k.overrides != scene.overrides())
        {
            self.kernels = OnceCell::new();
        }
        self.kernels.get_or_init(|| {
            let k =
                |entry| Kernel::with_entries(ctx, Some(scene), "cvrtgi", &[entry], &entries(), &[]);
            Kernels {
                visibility: k("visibility"),
                gather: k("gather"),
                filter: k("filter_faces"),
                lookup: k("lookup"),
                escape: k("escape"),
                overrides: scene.overrides(),
            }
        })
    }

    /// The resident geometry stage, if built.
    pub fn geometry(&self) -> Option<&CvrtgiGeometry> {
        self.geometry.as_ref().map(|g| &g.1)
    }

    /// The resident light stage, if built.
    pub fn light(&self) -> Option<&CvrtgiLight> {
        self.light.as_ref().map(|l| &l.1)
    }

    fn params(&self, s: &CvrtgiSettings, d_min: f32) -> CvParams {
        let geo = &self.geometry.as_ref().unwrap().1;
        let g = geo.voxels.grid;
        let sigma = s.filter_radius.max(1) as f32 * 0.5;
        CvParams {
            origin: g.origin.extend(g.size).into(),
            dims: [
                g.dims[0],
                g.dims[1],
                g.dims[2],
                geo.voxels.voxels.len() as u32,
            ],
            num_faces: geo.faces.voxel_dir.len() as u32,
            rays: geo.rays,
            num_clusters: geo.clusters.len() as u32,
            radius: s.filter_radius,
            d_min2: d_min * d_min,
            near: s.near_voxels * g.size,
            inv_two_sigma2: 1.0 / (2.0 * sigma * sigma),
            _pad: 0,
            gather_mode: match s.cluster_gather {
                ClusterGather::AnyHit => 0,
                ClusterGather::Conserved => 1,
            },
            escape_rays: s.escape_rays,
            escape_reach: ESCAPE_REACH * g.size,
            num_vpls: 0,
        }
    }

    /// Writes the frame's indirect light into `i.indirect`: rebuilds the geometry stage when the
    /// scene or its settings changed, the light stage when the VPLs or its settings changed, and
    /// always runs the per-pixel lookup. Errors when the visibility cache would not fit one storage
    /// binding of this adapter.
    pub fn record(
        &mut self,
        g: &mut Gpu,
        i: &CvrtgiInputs,
        s: &CvrtgiSettings,
    ) -> Result<CvrtgiReport> {
        let ctx = g.ctx;
        let mut report = CvrtgiReport::default();
        let (lo, hi) = i.scene.bounds();
        let (l, h) = (f32_bits(lo), f32_bits(hi));
        let gkey = GeometryKey {
            voxel_res: s.voxel_res,
            step: s.cluster_step,
            iterations: s.cluster_iterations,
            angle: s.cluster_angle.to_bits(),
            rays: s.face_rays,
            triangles: i.scene.triangles.len(),
            bounds: [l[0], l[1], l[2], h[0], h[1], h[2]],
        };
        self.kernels(ctx, g.scene);
        if self.geometry.as_ref().map(|x| x.0) != Some(gkey) {
            self.light = None;
            self.geometry = None;
            let t = Instant::now();
            let mut voxels = voxel::voxelise(i.scene, s.voxel_res.max(1));
            let slic = SlicSettings {
                step: s.cluster_step,
                iterations: s.cluster_iterations,
                angle: s.cluster_angle,
            };
            let clusters = voxel::slic(&mut voxels, &slic);
            let faces = inject::faces(&voxels);
            report.cpu_ms += t.elapsed().as_secs_f64() * 1e3;
            let rays = s.face_rays.max(1);
            let vis_bytes = faces.voxel_dir.len() as u64 * rays as u64 * 4;
            if vis_bytes > ctx.max_binding() {
                return Err(TooBig(format!(
                    "cvrtgi: the visibility cache ({} faces × {rays} rays, {vis_bytes} bytes) exceeds this adapter's storage binding ({} bytes); lower --voxel-res or --face-rays",
                    faces.voxel_dir.len(),
                    ctx.max_binding()
                ))
                .into());
            }
            let packed: Vec<[f32; 4]> = voxels
                .voxels
                .iter()
                .flat_map(|v| {
                    [
                        v.pos.extend(f32::from_bits(v.cluster)).into(),
                        v.normal.extend(f32::from_bits(v.key)).into(),
                    ]
                })
                .collect();
            let mut face_words = faces.of_voxel.clone();
            face_words.extend_from_slice(&faces.voxel_dir);
            // Empty scenes still bind something.
            face_words.push(inject::INVALID);
            let mut packed = packed;
            if packed.is_empty() {
                packed.push([0.0; 4]);
            }
            let geo = CvrtgiGeometry {
                voxel_buf: ctx.storage_init("cvrtgi voxels", &packed),
                faces_buf: ctx.storage_init("cvrtgi faces", &face_words),
                vis: ctx.storage("cvrtgi visibility", vis_bytes.max(4)),
                voxels,
                clusters,
                faces,
                rays,
            };
            self.geometry = Some((gkey, geo));
            report.visibility_rays = self.run_visibility(g, s, i.d_min);
            report.geometry_built = true;
        }
        let lkey = LightKey {
            geometry: gkey,
            vpls: i.vpl_key,
            near: s.near_voxels.to_bits(),
            radius: s.filter_radius,
            passes: s.filter_passes,
            d_min: i.d_min.to_bits(),
            gather: s.cluster_gather,
            escape_rays: s.escape_rays,
        };
        if self.light.as_ref().map(|x| x.0) != Some(lkey) {
            let escape = self.run_escape(g, s, i.d_min, &i.vpls.vpls)?;
            report.escape_rays = i.vpls.vpls.len() as u64 * s.escape_rays as u64;
            let t = Instant::now();
            let geo = &self.geometry.as_ref().unwrap().1;
            let mut lighting =
                inject::inject(&geo.voxels, geo.clusters.len(), &i.vpls.vpls, &escape);
            inject::set_boxes(&mut lighting, &geo.clusters);
            report.cpu_ms += t.elapsed().as_secs_f64() * 1e3;
            let (light, ms) = self.run_light(g, s, i.d_min, lighting, escape)?;
            report.cpu_ms += ms;
            self.light = Some((lkey, light));
            report.light_built = true;
        }
        self.run_lookup(g, s, i);
        let geo = &self.geometry.as_ref().unwrap().1;
        let light = &self.light.as_ref().unwrap().1;
        report.voxels = geo.voxels.voxels.len() as u32;
        report.clusters = geo.clusters.len() as u32;
        report.unassigned_voxels = geo
            .voxels
            .voxels
            .iter()
            .filter(|v| v.cluster == inject::INVALID)
            .count() as u32;
        report.faces = geo.faces.voxel_dir.len() as u32;
        report.lit_clusters = light.lighting.lit_clusters;
        report.lit_voxels = light.lighting.lit.len() as u32;
        report.dropped_vpls = light.lighting.dropped;
        Ok(report)
    }

    /// §4.3 on the GPU: fills the visibility cache; returns the rays traced.
    fn run_visibility(&self, g: &mut Gpu, s: &CvrtgiSettings, d_min: f32) -> u64 {
        let ctx = g.ctx;
        let geo = &self.geometry.as_ref().unwrap().1;
        let k = &self.kernels.get().unwrap().visibility;
        let params = ctx.uniform("cvrtgi params", &self.params(s, d_min));
        let bg = Bindings {
            params: &params,
            voxels: &geo.voxel_buf,
            faces: &geo.faces_buf,
            lights: None,
            vis: Some(&geo.vis),
            irr_in: None,
            out: None,
            gbuffer: None,
            vis_w: None,
        }
        .group(ctx, k);
        let faces = geo.faces.voxel_dir.len() as u32;
        // About 2^18 rays a submission.
        let per = ((1u32 << 18) / geo.rays).max(64);
        let run = Run {
            label: LABELS[0],
            group: &bg,
            seed: 0,
        };
        if faces > 0 {
            k.run(g, run, faces, per, &mut |_, _| {});
        }
        faces as u64 * geo.rays as u64
    }

    /// Where the VPLs' light goes, on the GPU (`escape`): per VPL, of `--escape-rays`
    /// cosine-distributed rays, the fraction that gets past `ESCAPE_REACH` voxels and the fraction
    /// that meets a surface beyond it; empty when the knob is 0.
    fn run_escape(
        &self,
        g: &mut Gpu,
        s: &CvrtgiSettings,
        d_min: f32,
        vpls: &[crate::gi::vpl_trace::Vpl],
    ) -> Result<Vec<[f32; 2]>> {
        if s.escape_rays == 0 || vpls.is_empty() {
            return Ok(Vec::new());
        }
        let ctx = g.ctx;
        let geo = &self.geometry.as_ref().unwrap().1;
        let k = &self.kernels.get().unwrap().escape;
        let n = vpls.len() as u32;
        let params = CvParams {
            num_vpls: n,
            ..self.params(s, d_min)
        };
        let params = ctx.uniform("cvrtgi params", &params);
        let input = ctx.storage_init("cvrtgi escape vpls", vpls);
        let out = ctx.storage("cvrtgi escape", n as u64 * 16);
        let bg = Bindings {
            params: &params,
            voxels: &geo.voxel_buf,
            faces: &geo.faces_buf,
            lights: Some(&input),
            vis: None,
            irr_in: None,
            out: Some(&out),
            gbuffer: None,
            vis_w: None,
        }
        .group(ctx, k);
        let run = Run {
            label: LABELS[4],
            group: &bg,
            seed: 0,
        };
        // About 2^18 rays a submission.
        let per = ((1u32 << 18) / s.escape_rays).max(64);
        k.run(g, run, n, per, &mut |_, _| {});
        let raw: Vec<[f32; 4]> = ctx.read_buffer(&out, n as usize)?;
        Ok(raw.iter().map(|w| [w[0], w[1]]).collect())
    }

    /// §4.4 on the GPU: the gathering (twice for the conserved gathering: at scale 1, then with
    /// each cluster's scale), then the filter passes.
    fn run_light(
        &self,
        g: &mut Gpu,
        s: &CvrtgiSettings,
        d_min: f32,
        mut lighting: Lighting,
        escape: Vec<[f32; 2]>,
    ) -> Result<(CvrtgiLight, f64)> {
        let ctx = g.ctx;
        let geo = &self.geometry.as_ref().unwrap().1;
        let ks = self.kernels.get().unwrap();
        let params = ctx.uniform("cvrtgi params", &self.params(s, d_min));
        let lights_buf = ctx.storage_init("cvrtgi lights", &light_words(&lighting));
        let faces = geo.faces.voxel_dir.len() as u32;
        let bytes = faces.max(1) as u64 * 16;
        let conserved = s.cluster_gather == ClusterGather::Conserved;
        let slot_bytes = if conserved {
            faces.max(1) as u64 * geo.rays as u64 * 4
        } else {
            4
        };
        let slot_flux = ctx.storage("cvrtgi slot flux", slot_bytes);
        let gathered = ctx.storage("cvrtgi gathered", bytes);
        let base = Bindings {
            params: &params,
            voxels: &geo.voxel_buf,
            faces: &geo.faces_buf,
            lights: Some(&lights_buf),
            vis: Some(&geo.vis),
            irr_in: None,
            out: Some(&gathered),
            gbuffer: None,
            vis_w: Some(&slot_flux),
        };
        let bg = base.group(ctx, &ks.gather);
        run_faces(&ks.gather, g, LABELS[1], &bg, faces);
        let mut cpu_ms = 0.0;
        if conserved && faces > 0 {
            // The flux each cluster hands the faces at scale 1, then again with each cluster's
            // conservation scale.
            let n = faces as usize * geo.rays as usize;
            let ids: Vec<u32> = ctx.read_buffer(&geo.vis, n)?;
            let flux: Vec<f32> = ctx.read_buffer(&slot_flux, n)?;
            let t = Instant::now();
            let scales = inject::conservation_scales(&lighting, &ids, &flux, geo.rays as usize);
            inject::set_scales(&mut lighting, &scales);
            cpu_ms += t.elapsed().as_secs_f64() * 1e3;
            ctx.write_buffer(
                &lights_buf,
                0,
                bytemuck::cast_slice(&light_words(&lighting)),
            );
            run_faces(&ks.gather, g, LABELS[1], &bg, faces);
        }
        let filtered = self.run_filter(g, s, &base, faces, bytes);
        let light = CvrtgiLight {
            lighting,
            escape,
            slot_flux,
            lights_buf,
            gathered,
            filtered,
        };
        Ok((light, cpu_ms))
    }

    /// §4.4's filter passes over `base.out` (the gathered irradiance), ping-pong between two
    /// buffers; the last one written, or with no pass a copy of the gathered irradiance.
    fn run_filter(
        &self,
        g: &mut Gpu,
        s: &CvrtgiSettings,
        base: &Bindings,
        faces: u32,
        bytes: u64,
    ) -> wgpu::Buffer {
        let ctx = g.ctx;
        let filter = &self.kernels.get().unwrap().filter;
        let gathered = base.out.expect("the gathered irradiance");
        let ping = [
            ctx.storage("cvrtgi filtered a", bytes),
            ctx.storage("cvrtgi filtered b", bytes),
        ];
        let mut src = gathered;
        for p in 0..s.filter_passes as usize {
            let dst = &ping[p % 2];
            let bg = Bindings {
                lights: None,
                vis: None,
                irr_in: Some(src),
                out: Some(dst),
                vis_w: None,
                ..*base
            }
            .group(ctx, filter);
            run_faces(filter, g, LABELS[2], &bg, faces);
            src = dst;
        }
        if s.filter_passes == 0 {
            let copy = ctx.storage("cvrtgi filtered", bytes);
            let mut enc = ctx.device.create_command_encoder(&Default::default());
            enc.copy_buffer_to_buffer(gathered, 0, &copy, 0, bytes);
            ctx.queue.submit([enc.finish()]);
            copy
        } else {
            let [a, b] = ping;
            if s.filter_passes % 2 == 1 { a } else { b }
        }
    }

    /// §4.5 on the GPU: every pixel's indirect light from its face's filtered irradiance.
    fn run_lookup(&self, g: &mut Gpu, s: &CvrtgiSettings, i: &CvrtgiInputs) {
        let ctx = g.ctx;
        let geo = &self.geometry.as_ref().unwrap().1;
        let light = &self.light.as_ref().unwrap().1;
        let k = &self.kernels.get().unwrap().lookup;
        let params = ctx.uniform("cvrtgi params", &self.params(s, i.d_min));
        let bg = Bindings {
            params: &params,
            voxels: &geo.voxel_buf,
            faces: &geo.faces_buf,
            lights: Some(&light.lights_buf),
            vis: None,
            irr_in: Some(&light.filtered),
            out: Some(i.indirect),
            gbuffer: Some(i.gbuffer),
            vis_w: None,
        }
        .group(ctx, k);
        let run = Run {
            label: LABELS[3],
            group: &bg,
            seed: 0,
        };
        if i.pixels > 0 {
            k.run(g, run, i.pixels, 1 << 17, &mut |_, _| {});
        }
    }

    /// Reads a vec4-a-face buffer of the light stage back as RGB (tests, views).
    pub fn read_faces(&self, ctx: &GpuContext, buf: &wgpu::Buffer) -> Result<Vec<Vec3>> {
        let n = self
            .geometry()
            .map_or(0, |g| g.faces.voxel_dir.len())
            .max(1);
        let raw: Vec<[f32; 4]> = ctx.read_buffer(buf, n)?;
        Ok(raw.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect())
    }

    /// Reads the visibility cache back: `rays` cluster ids a face.
    pub fn read_visibility(&self, ctx: &GpuContext) -> Result<Vec<u32>> {
        let Some(geo) = self.geometry() else {
            bail!("cvrtgi: no geometry stage yet");
        };
        let n = (geo.faces.voxel_dir.len() * geo.rays as usize).max(1);
        ctx.read_buffer(&geo.vis, n)
    }

    /// Reads the light stage's per-slot flux back (beside the visibility cache; `--cluster-gather
    /// conserved` only).
    pub fn read_slot_flux(&self, ctx: &GpuContext) -> Result<Vec<f32>> {
        let (Some(geo), Some(light)) = (self.geometry(), self.light()) else {
            bail!("cvrtgi: no light stage yet");
        };
        let n = (geo.faces.voxel_dir.len() * geo.rays as usize).max(1);
        ctx.read_buffer(&light.slot_flux, n)
    }
}

/// cvrtgi in the registry.
pub const ENTRY: MethodEntry = MethodEntry {
    method: Method::Cvrtgi,
    doc: "CVRTGI (Cosin Ayerbe & Patow 2022): the scene voxelised, voxels clustered by \
          SLIC with the 35° normal rule (Eq. 1, Alg. 1), per-voxel-face irradiance from the lit \
          clusters a face's rays find, filtered, read by every pixel; cached while the lights stay",
    passes: &[PASS],
    build: |_, _| Box::new(Cvrtgi::new()),
    clusters_sps: false,
    vpl_clusters: |_| false,
    limits: super::no_limits,
    own_settings: true,
    colour: [188, 189, 34],
    about: "CVRTGI: voxel clusters (SLIC, 35° rule) light every voxel face; pixels read their \
            face's filtered irradiance, cached while the lights stay (docs/methods.md)",
    label: |m| {
        let v = &m.cvrtgi;
        let mut l = format!("v{} s{}", v.voxel_res, v.cluster_step);
        if v.cluster_gather == ClusterGather::AnyHit {
            l += " any-hit";
        }
        if v.escape_rays != settings::CvrtgiSettings::default().escape_rays {
            l += &format!(" e{}", v.escape_rays);
        }
        l
    },
    series: |m| format!("{}³ step {}", m.cvrtgi.voxel_res, m.cvrtgi.cluster_step),
    short: |m| {
        let v = &m.cvrtgi;
        format!("v{}-s{}-r{}", v.voxel_res, v.cluster_step, v.face_rays)
    },
    report_columns: &[],
};

impl IndirectMethod for Cvrtgi {
    /// `PASS`: the frame's indirect light by CVRTGI, from the resident VPLs (no VPL
    /// clustering: a VPL is injected into the cluster of its voxel). Its CPU stages (voxelisation,
    /// SLIC, injection) count as the pass's time when they run.
    fn record(&mut self, pass: Pass, g: &mut Gpu, f: &FrameInputs, n: &mut Tally) -> Result<()> {
        debug_assert_eq!(pass, PASS);
        let inputs = CvrtgiInputs {
            scene: f.scene,
            vpls: &f.vpls.set,
            vpl_key: f.vpls.key,
            gbuffer: f.gbuffer,
            pixels: f.pixels(),
            indirect: f.indirect,
            d_min: f.d_min,
        };
        let report = Cvrtgi::record(self, g, &inputs, &f.method.cvrtgi)?;
        n.cpu_ms.push((PASS, report.cpu_ms));
        n.vpl_clusters_used = report.lit_clusters;
        n.report = Some(serde_json::to_value(report).expect("a plain struct"));
        Ok(())
    }

    /// The voxel, cluster and visibility-cache stages and the light stage are resident (`Cvrtgi`).
    fn take_resident_timings(
        &mut self,
        timings: &mut std::collections::BTreeMap<String, f64>,
    ) -> std::collections::BTreeMap<String, f64> {
        self.take_build_times(timings)
    }
}
