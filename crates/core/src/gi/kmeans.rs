//! Steps 2 and 4: the paper's GPU k-means (Alg. 1) and final fuzzy assignment (Alg. 2) of surface
//! points, one implementation for shading points and VPLs (`shaders-wgsl/kmeans.wgsl`). CPU twin:
//! `cpu::kmeans`.
//!
//! Centroid sums are 64-bit fixed point built from 32-bit atomics (`add64`): positions in the scene's
//! bounds frame with 2^-24 of the extent per step, normals (n + 1) with 2^-23. A cluster can take up to
//! 2^32 − 1 points (the u32 count) before overflow; the 64-bit sums would take 2^40. Sums are exact
//! integers, so the result does not depend on the order of the atomic adds.

use std::cell::OnceCell;

use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::dispatch::{Gpu, Run};
use super::dispatch::{Kernel, RecordCopies, WORKGROUP, copy_to_texture, data_texture};
use super::primary::CameraParams;
use super::scene_gpu::{data_texture_layout, storage_layout, uniform_layout};
use crate::gpu::GpuContext;
use crate::settings::{
    Adaptations, ClusterSettings, Gamma, MAX_F, MAX_NORMAL_THRESHOLD, plane_gate_sine,
};

pub const MAX_DIM: u32 = 64;
/// The sets of adaptations a pipeline is built for (`Adaptations::bits`).
const ADAPT_SETS: usize = Adaptations::ALL as usize + 1;
const WORDS: u64 = 13;
const MAX_CELLS: u64 = (MAX_DIM as u64).pow(3);
/// The most blocks of the grid's prefix sum (1024 cells each, kmeans.wgsl `SCAN_BLOCK`).
const SCAN_BLOCKS: u64 = MAX_CELLS / 1024;

/// Workgroups for the grid's prefix sum: one per block of cells. Only the GPU knows the cell count
/// (grid_setup), so this bounds it from K. With cell edge c ≥ 1.5 s, s² = A / K (A: the surface of the
/// centroids' bounding box) and at most 64 cells an axis (c ≥ e_max / 64), the cells Π ceil(e_a / c)
/// are at most V / c³ + (A / 2) / c² + Σ e_a / c + 1 ≤ K^1.5 / (3.375 · 6^1.5) + K / 4.5 + 193 (a
/// cube has the most volume for its surface). Conference K 1000 / 8000 / 30000: 720 / 14,144 /
/// 94,080 cells in 1 / 14 / 92 blocks, bounds 2 / 17 / 110 (an idle workgroup costs lavapipe
/// ~15 µs). The scan stays right with fewer workgroups (each takes every n-th block; tested).
pub fn scan_groups(k: u32) -> u32 {
    let k = k as f64;
    let cells = k.powf(1.5) / (3.375 * 6f64.powf(1.5)) + k / 4.5 + 193.0;
    ((cells / 1024.0).ceil() as u64).clamp(1, SCAN_BLOCKS) as u32
}

/// The points a clustering reads: `count` points of `stride` vec4s each in `data` (position with
/// w > 0 when valid, then normal).
#[derive(Clone, Copy)]
pub struct Points<'a> {
    pub data: &'a wgpu::Buffer,
    pub count: u32,
    pub stride: u32,
}

/// Alg. 1 parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KMeansSettings {
    /// K: clusters.
    pub k: u32,
    /// F: clusters per point in the final assignment (1 = hard).
    pub f: u32,
    /// γ: downsampling factor (one sampled point per γ data points).
    pub gamma: Gamma,
    /// n_t of Eq. (7), a cosine.
    pub normal_threshold: f32,
    pub iterations: u32,
    pub seed: u32,
    /// Eq. (10) distances to the clusters' representatives (the paper's text) instead of their
    /// centroids (Alg. 2's W).
    pub weights_to_reps: bool,
    /// p of the fuzzy weights w'_f = dist^-p (Eq. 10: p = 1).
    pub weight_exponent: f32,
    /// The plane gate of the final assignment, in degrees (`None`: off, the paper): slots 2..F keep
    /// only clusters whose centroid lies within this angle of the point's tangent plane, seen from
    /// the point (`settings::plane_gate_sine`).
    pub plane_gate_deg: Option<f32>,
    /// The departures from Alg. 1 and 2 in use (all by default; `--paper`: none).
    pub adapt: Adaptations,
}

impl KMeansSettings {
    /// The shading-point clustering of a frame (step 4): the user's K_SP, F, γ, n_t, iterations, p
    /// and plane gate.
    pub fn shading_points(c: &ClusterSettings, seed: u32) -> Self {
        KMeansSettings {
            k: c.sp_clusters,
            f: c.f(),
            gamma: c.gamma,
            normal_threshold: c.normal_threshold,
            iterations: c.iterations,
            seed,
            weights_to_reps: c.weights_to_reps,
            weight_exponent: c.weight_exponent,
            plane_gate_deg: c.plane_gate,
            adapt: c.adaptations(),
        }
    }

    /// The VPL clustering (step 2): K_VPL, hard, every VPL sampled (γ 1), the same n_t and
    /// iterations.
    pub fn vpls(c: &ClusterSettings, seed: u32) -> Self {
        KMeansSettings {
            k: c.vpl_clusters,
            f: 1,
            gamma: Gamma::Fixed(1),
            normal_threshold: c.normal_threshold,
            iterations: c.iterations,
            seed,
            weights_to_reps: false,
            weight_exponent: 1.0,
            plane_gate_deg: None,
            adapt: c.adaptations(),
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct KmParams {
    pub num_points: u32,
    pub stride: u32,
    pub gamma: u32,
    pub num_sampled: u32,
    pub k: u32,
    pub f: u32,
    pub normal_threshold: f32,
    pub seed: u32,
    pub lo: [f32; 4],
    pub ext: [f32; 4],
    pub weight_exponent: f32,
    /// `plane_gate_sine` of the settings.
    pub plane_gate: f32,
    /// `Adaptations::bits` of the settings: the CPU twin follows them; the shaders take them as
    /// pipeline constants (`KMeans::kernel`), so they do not read this word.
    pub adapt: u32,
    pub _pad: u32,
    /// The temporal warm start's view (kmeans.wgsl `warm_keeps`): the new frame's camera, with
    /// `warm.eye[3]` the same-surface tolerance; `warm.size` = (width, height, previous K, 0), width 0
    /// when the points are no view's pixels. All zero for a cold start.
    pub warm: CameraParams,
}

impl KmParams {
    /// `frame`: bounds (lo, hi) containing every point (the scene's bounds).
    pub fn new(num_points: u32, stride: u32, s: &KMeansSettings, frame: (Vec3, Vec3)) -> Self {
        let k = s.k.max(1);
        let gamma = s.gamma.effective(num_points, k);
        let ext = (frame.1 - frame.0).max(Vec3::splat(1e-30));
        KmParams {
            num_points,
            stride,
            gamma,
            num_sampled: num_points.div_ceil(gamma),
            k,
            f: s.f.clamp(1, MAX_F),
            normal_threshold: s.normal_threshold.min(MAX_NORMAL_THRESHOLD),
            seed: s.seed,
            lo: frame.0.extend(0.0).into(),
            ext: [ext.x, ext.y, ext.z, ext.length()],
            weight_exponent: s.weight_exponent,
            plane_gate: plane_gate_sine(s.plane_gate_deg),
            adapt: s.adapt.bits(),
            _pad: 0,
            warm: CameraParams::zeroed(),
        }
    }

    /// These parameters warm-started from `previous_k` centroids, tested against `view` (the new
    /// frame's camera when the points are its pixels).
    pub fn with_warm(mut self, previous_k: u32, view: Option<&CameraParams>) -> Self {
        self.warm = match view {
            Some(v) => {
                let mut w = *v;
                w.eye[3] = WARM_SURFACE_TOLERANCE;
                w
            }
            None => CameraParams::zeroed(),
        };
        self.warm.size[2] = previous_k.min(self.k);
        self
    }
}

/// How far a previous centroid may lie off the tangent plane of the shading point it projects to,
/// as a fraction of that point's distance from the eye, and still count as the same surface
/// (`warm_keeps`). 2%: a centroid is a mean over a curved patch, so it lies a little inside a curved
/// surface; geometry that hides it lies farther off.
pub const WARM_SURFACE_TOLERANCE: f32 = 0.02;

/// Alg. 1 iterations after a warm start that kept `kept` of `k` centroids: the share of re-seeded
/// centroids of the cold start's `iterations`, rounded up, at least 1 (a still camera keeps every
/// centroid and runs one iteration; a view with half its clusters new runs half of them).
pub fn warm_iterations(iterations: u32, kept: u32, k: u32) -> u32 {
    if iterations == 0 {
        return 0;
    }
    let new = k.saturating_sub(kept) as u64;
    let n = (iterations as u64 * new).div_ceil(k.max(1) as u64) as u32;
    n.clamp(1, iterations)
}

/// A warm start: the previous clustering of the same kind of points.
pub struct Warm<'a> {
    /// Its centroids and representative points (`Clustering::centroids`, `rep_points`).
    pub centroids: &'a wgpu::Buffer,
    pub rep_points: &'a wgpu::Buffer,
    /// Its K.
    pub k: u32,
    /// The new frame's camera when the points are that frame's pixels (SP clustering); `None` for
    /// VPLs (every valid previous centroid is kept).
    pub view: Option<CameraParams>,
}

/// The result of one clustering, resident on the GPU.
pub struct Clustering {
    pub params: KmParams,
    /// Whether it started from a previous clustering (`Warm`).
    pub warm: bool,
    /// kmeans.wgsl's `bounds`: the loop's state and the counts `counters` reads.
    pub bounds: wgpu::Buffer,
    /// K centroids (pos xyz + valid w, normal).
    pub centroids: wgpu::Buffer,
    /// M × F cluster indices (u32::MAX where fewer than F were found).
    pub assign: wgpu::Buffer,
    /// M × F normalised inverse-distance weights (Eq. 10).
    pub weights: wgpu::Buffer,
    /// Per cluster: (smallest member distance bits, member index); index u32::MAX when unused.
    pub reps: wgpu::Buffer,
    /// Per cluster its representative as a point, 2 vec4s: position (w = 1: the cluster has one),
    /// normal (w = 1: the previous frame's, kept by a warm start). The visibility pass traces from it.
    pub rep_points: wgpu::Buffer,
    /// The sampled points' assignment of the last iteration (for tests).
    pub sample_assign: wgpu::Buffer,
    /// The set these buffers belong to, held (not reused by the next clustering) while this lives.
    _set: std::sync::Arc<Buffers>,
}

/// A clustering's counts, kept on the GPU and read back only when asked (`Clustering::counters`):
/// the host never waits on them while it records a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KmCounters {
    /// Iterations of Alg. 1 run: the requested count, or fewer when one changed no assignment or
    /// after a warm start (`warm_iterations`).
    pub iterations_run: u32,
    /// Centroids a warm start kept from the previous clustering (`None`: a cold start).
    pub warm_kept: Option<u32>,
    /// Clusters with a representative.
    pub reps_used: u32,
    /// Clusters below the previous K whose representative is the previous frame's.
    pub reps_kept: u32,
}

/// Words of kmeans.wgsl's `bounds` (`BOUND_WORDS`).
const BOUND_WORDS: usize = 17;

impl KmCounters {
    /// The counts in kmeans.wgsl's `bounds` words of a clustering that started warm or not. The grid
    /// builds (word 7) are the iterations run and the final one.
    pub fn from_words(words: &[u32], warm: bool) -> KmCounters {
        KmCounters {
            iterations_run: words[7].saturating_sub(1),
            warm_kept: warm.then_some(words[11]),
            reps_used: words[15],
            reps_kept: words[16],
        }
    }

    /// Reads a clustering's `bounds` back (a small read that waits for the clustering: on request
    /// only) and decodes them (`from_words`).
    pub fn read(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        bounds: &wgpu::Buffer,
        warm: bool,
    ) -> Result<KmCounters> {
        let words: Vec<u32> = crate::gpu::read_buffer(device, queue, bounds, BOUND_WORDS)?;
        Ok(KmCounters::from_words(&words, warm))
    }
}

impl Clustering {
    /// The grid of its final assignment (Alg. 2), read back (tests).
    pub fn read_grid(&self, ctx: &GpuContext) -> Result<GridSnapshot> {
        self._set.grid.read(ctx)
    }

    /// Its counts, read back from the GPU (a small read that waits for the clustering: on request
    /// only, for the stats and tests).
    pub fn counters(&self, ctx: &GpuContext) -> Result<KmCounters> {
        KmCounters::read(&ctx.device, &ctx.queue, &self.bounds, self.warm)
    }

    pub fn k(&self) -> u32 {
        self.params.k
    }
    pub fn f(&self) -> u32 {
        self.params.f
    }
}

const ENTRIES: &[&str] = &[
    "init_centroids",
    "warm_centroids",
    "grid_setup",
    "grid_count",
    "grid_scan_blocks",
    "grid_scan_ranges",
    "grid_scatter",
    "init_sampled",
    "assign_sampled",
    "update",
    "final_assign",
    "rep_clear",
    "rep_pick",
    "rep_store",
    "rep_weights",
    "converge",
    "loop_end",
    "rep_count",
];

/// How the k-means runs on an adapter; the clusters do not depend on it (tested). `None` picks the
/// default.
#[derive(Clone, Copy, Debug, Default)]
pub struct KMeansTuning {
    /// Workgroups of the grid's prefix sum (default `scan_groups(K)`; clamped to 1..=256).
    pub scan_groups: Option<u32>,
    /// The search reads the grid through textures (kmeans.wgsl `TEXTURE_SEARCH`; default on a
    /// software adapter) instead of storage buffers.
    pub texture_search: Option<bool>,
}

#[derive(Default)]
pub struct KMeans {
    /// One pipeline set per F (the shader's `override F`), plane gate off / on (`override
    /// PLANE_GATE`) and set of adaptations (`Adaptations::bits`, the overrides `RESEED`, ...),
    /// built the first time that combination is clustered.
    kernels: [[[OnceCell<Kernel>; ADAPT_SETS]; 2]; MAX_F as usize],
    tuning: KMeansTuning,
    /// The buffer sets of its clusterings, by size (`SetKey`): a clustering holds its set while a
    /// warm start may read it, so steady frames alternate between two and make none.
    sets: crate::gpu::persistent::Pool<SetKey, Buffers>,
}

/// What sizes a clustering's buffers: K, the points, F, the sampled points, the texture search.
type SetKey = (u32, u32, u32, u32, bool);

impl KMeans {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn with_tuning(tuning: KMeansTuning) -> Self {
        KMeans {
            tuning,
            ..Self::default()
        }
    }

    fn texture_search(&self, ctx: &GpuContext) -> bool {
        self.tuning.texture_search.unwrap_or(ctx.software)
    }

    fn kernel(&self, ctx: &GpuContext, f: u32, gate: bool, adapt: u32) -> &Kernel {
        let f = f.clamp(1, MAX_F);
        let adapt = adapt & Adaptations::ALL;
        self.kernels[f as usize - 1][gate as usize][adapt as usize].get_or_init(|| {
            let mut entries = vec![uniform_layout(1), storage_layout(2, true)];
            entries.extend((3..=14).map(|b| storage_layout(b, false)));
            entries.push(data_texture_layout(15, wgpu::TextureSampleType::Uint));
            entries.push(data_texture_layout(16, wgpu::TextureSampleType::Uint));
            entries.push(storage_layout(17, false));
            let texture = self.texture_search(ctx) as u32 as f64;
            Kernel::with_entries(
                ctx,
                None,
                "kmeans",
                ENTRIES,
                &entries,
                &[
                    [
                        ("F", f as f64),
                        ("TEXTURE_SEARCH", texture),
                        ("PLANE_GATE", gate as u32 as f64),
                    ]
                    .as_slice(),
                    Adaptations::from_bits(adapt).constants().as_slice(),
                ]
                .concat(),
            )
        })
    }

    /// Clusters `points`, timing every step under `label`; from `warm`'s centroids where given
    /// (`warm_centroids`), else from strata (Alg. 1 line 2). `frame`: bounds (lo, hi) containing every
    /// point (the scene's bounds).
    pub fn run(
        &self,
        gpu: &mut Gpu,
        label: &str,
        points: &Points,
        settings: &KMeansSettings,
        frame: (Vec3, Vec3),
        warm: Option<&Warm>,
    ) -> Result<Clustering> {
        let ctx = gpu.ctx;
        let Points {
            data,
            count: num_points,
            stride,
        } = *points;
        let mut p = KmParams::new(num_points, stride, settings, frame);
        if let Some(w) = warm {
            p = p.with_warm(w.k, w.view.as_ref());
        }
        let texture_search = self.texture_search(ctx);
        let key = (p.k, p.num_points, p.f, p.num_sampled, texture_search);
        let (b, reused) = self
            .sets
            .take(&key, || Buffers::new(ctx, &p, texture_search));
        b.reset(ctx, &p, settings.iterations, warm.is_some(), reused);
        let kernel = self.kernel(ctx, p.f, p.f > 1 && p.plane_gate <= 1.0, p.adapt);
        let bg = b.bind_group(ctx, kernel, data);
        // After each grid build the search's textures are refreshed (software adapters only).
        let copy = |enc: &mut wgpu::CommandEncoder| b.grid.copy_to_textures(enc);
        let after = texture_search.then_some(("grid_scatter", &copy as &RecordCopies));
        let kk = p.k;
        let grid = self.grid_steps(kk);
        // Small steps share a submission: one per iteration, then the final assignment and the
        // representatives (each bounded by the point count).
        let r = Run {
            label,
            group: &bg,
            seed: settings.seed,
        };
        let mut run = |steps: &[(&str, u32)]| kernel.run_entries(gpu, r, steps, after);
        init_centroids(ctx, &p, &b, warm, &mut run);
        iterate(&p, &grid, settings.iterations, &mut run);
        // Alg. 2 on the last grid, then the representatives and their counts.
        let mut steps = vec![("loop_end", 1)];
        steps.extend(grid);
        steps.extend([("rep_clear", kk), ("final_assign", num_points)]);
        run(&steps);
        run(&[
            ("rep_pick", num_points),
            ("rep_store", kk),
            ("rep_count", kk),
        ]);
        if settings.weights_to_reps && p.f > 1 {
            run(&[("rep_weights", num_points)]);
        }
        let c = Clustering {
            warm: warm.is_some(),
            bounds: b.bounds.clone(),
            params: p,
            centroids: b.centroids.clone(),
            assign: b.assign.clone(),
            weights: b.weights.clone(),
            reps: b.reps.clone(),
            rep_points: b.rep_points.clone(),
            sample_assign: b.sample_assign.clone(),
            _set: b.clone(),
        };
        if std::env::var_os("FVPL_PROFILE_STEPS").is_some() {
            print_grid(ctx, label, &c, &b.grid.grid)?;
        }
        Ok(c)
    }

    /// Alg. 1 line 5: the grid's steps (the centroids' bounds come from init_centroids and update).
    /// Every step's count is of invocations of `WORKGROUP` (the scan's workgroups are 256 wide, one
    /// each).
    fn grid_steps(&self, kk: u32) -> [(&'static str, u32); 5] {
        let groups = self
            .tuning
            .scan_groups
            .map_or_else(|| scan_groups(kk), |g| g.clamp(1, SCAN_BLOCKS as u32));
        grid_steps(kk, groups)
    }
}

/// The steps that build the grid over `k` centres (`shaders-wgsl/common/grid.wgsl`, the paper's
/// k-means (Alg. 1) and a method module's own), the prefix sum in `groups` workgroups: every count is of
/// invocations of `WORKGROUP` (the scan's workgroups are 256 wide, one each).
pub fn grid_steps(k: u32, groups: u32) -> [(&'static str, u32); 5] {
    let scan = WORKGROUP * groups;
    [
        ("grid_setup", 1),
        ("grid_count", k),
        ("grid_scan_blocks", scan),
        ("grid_scan_ranges", scan),
        ("grid_scatter", k),
    ]
}

/// The resources of the grid over cluster centres (`shaders-wgsl/common/grid.wgsl`), the paper's
/// k-means' (Alg. 1) and a method module's own: the grid, the cell counts and scan words, the centres sorted
/// by cell (2 texels each) and per cell the sorted offsets of it and its row neighbours (one texel
/// gives a row run of three cells). On a software adapter (`texture_search`) the search reads copies
/// of the last two in textures, refreshed after each grid build (lavapipe fetches texels with vector
/// code, storage reads per lane with scalar loops); otherwise the textures are bound but never read:
/// one texel each.
pub struct GridBuffers {
    pub grid: wgpu::Buffer,
    pub cells: wgpu::Buffer,
    pub sorted: wgpu::Buffer,
    pub ranges: wgpu::Buffer,
    sorted_tex: wgpu::Texture,
    ranges_tex: wgpu::Texture,
    pub sorted_view: wgpu::TextureView,
    pub ranges_view: wgpu::TextureView,
    /// Bytes of `sorted` (2 vec4 a centre).
    sorted_bytes: u64,
}

impl GridBuffers {
    /// Allocates them for `k` centres.
    pub fn new(ctx: &GpuContext, k: u64, texture_search: bool) -> GridBuffers {
        let grid = ctx.storage("grid", 32);
        let cells = ctx.storage("grid cells", (2 * MAX_CELLS + SCAN_BLOCKS) * 4);
        let sorted = ctx.storage("sorted centres", k * 32);
        let ranges = ctx.storage("cell ranges", MAX_CELLS * 16);
        let texels = |n: u64| if texture_search { n } else { 1 };
        let uint = wgpu::TextureFormat::Rgba32Uint;
        let sorted_tex = data_texture(ctx, "sorted centres", uint, texels(2 * k));
        let ranges_tex = data_texture(ctx, "cell ranges", uint, texels(MAX_CELLS));
        GridBuffers {
            sorted_view: sorted_tex.create_view(&Default::default()),
            ranges_view: ranges_tex.create_view(&Default::default()),
            grid,
            cells,
            sorted,
            ranges,
            sorted_tex,
            ranges_tex,
            sorted_bytes: k * 32,
        }
    }

    /// The search's textures refreshed from the last grid build (after `grid_scatter`).
    pub fn copy_to_textures(&self, enc: &mut wgpu::CommandEncoder) {
        copy_to_texture(enc, &self.sorted, &self.sorted_tex, self.sorted_bytes);
        copy_to_texture(enc, &self.ranges, &self.ranges_tex, MAX_CELLS * 16);
    }

    /// The buffers, to clear a reused set.
    pub fn buffers(&self) -> [&wgpu::Buffer; 4] {
        [&self.grid, &self.cells, &self.sorted, &self.ranges]
    }

    /// The grid as its last build left it (read back; tests).
    pub fn read(&self, ctx: &GpuContext) -> Result<GridSnapshot> {
        let g: Vec<u32> = ctx.read_buffer(&self.grid, 8)?;
        let f = |i: usize| f32::from_bits(g[i]);
        let n = g[7] as usize;
        let ranges: Vec<[u32; 4]> = ctx.read_buffer(&self.ranges, n)?;
        let total = ranges.iter().map(|r| r[2]).max().unwrap_or(0) as usize;
        let sorted: Vec<[u32; 4]> = ctx.read_buffer(&self.sorted, 2 * total)?;
        let cells = ranges
            .iter()
            .map(|r| (r[1]..r[2]).map(|s| sorted[2 * s as usize][3]).collect())
            .collect();
        Ok(GridSnapshot {
            origin: Vec3::new(f(0), f(1), f(2)),
            cell: f(3),
            dims: [g[4], g[5], g[6]],
            cells,
        })
    }
}

/// A grid over centres as the GPU built it (`GridBuffers::read`): origin, cell side, cells an axis
/// and each cell's centres (in the scatter's order, which varies).
#[derive(Clone, Debug, PartialEq)]
pub struct GridSnapshot {
    pub origin: Vec3,
    pub cell: f32,
    pub dims: [u32; 3],
    pub cells: Vec<Vec<u32>>,
}

/// Runs k-means steps in one submission (`Kernel::run_entries` with the clustering's bind group).
type RunSteps<'a> = dyn FnMut(&[(&str, u32)]) + 'a;

/// The buffers of one clustering (kmeans.wgsl's bindings) and the textures of its search.
struct Buffers {
    params: wgpu::Buffer,
    centroids: wgpu::Buffer,
    sums: wgpu::Buffer,
    bounds: wgpu::Buffer,
    grid: GridBuffers,
    sample_assign: wgpu::Buffer,
    assign: wgpu::Buffer,
    weights: wgpu::Buffer,
    reps: wgpu::Buffer,
    rep_points: wgpu::Buffer,
    member_dists: wgpu::Buffer,
}

impl Buffers {
    /// Allocates them for `p` (`texture_search`: `KMeans::texture_search`), for a loop of
    /// `iterations` from a warm start or not (`converge`).
    fn new(ctx: &GpuContext, p: &KmParams, texture_search: bool) -> Buffers {
        let k = p.k as u64;
        let m = p.num_points as u64;
        let f = p.f as u64;
        let params = ctx.uniform("kmeans params", p);
        let centroids = ctx.storage("centroids", k * 32);
        let sums = ctx.storage("centroid sums", k * WORDS * 4);
        let bounds = ctx.storage("centroid bounds", BOUND_WORDS as u64 * 4);
        let sample_assign = ctx.storage("sample assign", p.num_sampled as u64 * 4);
        let assign = ctx.storage("assign", m * f * 4);
        let weights = ctx.storage("weights", m * f * 4);
        let reps = ctx.storage("representatives", k * 8);
        let rep_points = ctx.storage("representative points", k * 32);
        let member_dists = ctx.storage("member distances", m * f * 4);
        let grid = GridBuffers::new(ctx, k, texture_search);
        Buffers {
            params,
            centroids,
            sums,
            bounds,
            grid,
            sample_assign,
            assign,
            weights,
            reps,
            rep_points,
            member_dists,
        }
    }

    /// Ready for a clustering with `p`: its parameters and `bounds`' first words (the loop's
    /// `iterations`, started `warm` or not) written; a `reused` set also cleared, so that it starts
    /// as a new one (zeroed) does.
    fn reset(&self, ctx: &GpuContext, p: &KmParams, iterations: u32, warm: bool, reused: bool) {
        let mut words = [0u32; BOUND_WORDS];
        words[..3].fill(u32::MAX);
        words[13] = iterations;
        words[14] = warm as u32;
        ctx.write_buffer(&self.bounds, 0, bytemuck::cast_slice(&words));
        if !reused {
            return;
        }
        ctx.write_buffer(&self.params, 0, bytemuck::bytes_of(p));
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        for b in [
            &self.centroids,
            &self.sums,
            &self.sample_assign,
            &self.assign,
            &self.weights,
            &self.reps,
            &self.rep_points,
            &self.member_dists,
        ]
        .into_iter()
        .chain(self.grid.buffers())
        {
            enc.clear_buffer(b, 0, None);
        }
        ctx.queue.submit([enc.finish()]);
    }

    /// Their bind group for `kernel`, with the points' `data`.
    fn bind_group(
        &self,
        ctx: &GpuContext,
        kernel: &Kernel,
        data: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        kernel.bind_group_with_textures(
            ctx,
            &[
                (1, &self.params),
                (2, data),
                (3, &self.centroids),
                (4, &self.sums),
                (5, &self.bounds),
                (6, &self.grid.grid),
                (7, &self.grid.cells),
                (8, &self.member_dists),
                (9, &self.sample_assign),
                (10, &self.assign),
                (11, &self.weights),
                (12, &self.reps),
                (13, &self.grid.sorted),
                (14, &self.grid.ranges),
                (17, &self.rep_points),
            ],
            &[(15, &self.grid.sorted_view), (16, &self.grid.ranges_view)],
        )
    }
}

/// Alg. 1 line 2: the initial centroids, from `warm`'s (copied in with its representatives) where
/// the view still sees them (`warm_centroids`, which counts the kept ones: `converge` shortens the
/// loop by them), else from strata (`init_centroids`); then the sampled points.
fn init_centroids(
    ctx: &GpuContext,
    p: &KmParams,
    b: &Buffers,
    warm: Option<&Warm>,
    run: &mut RunSteps,
) {
    let kk = p.k;
    match warm {
        Some(w) => {
            let n = p.warm.size[2] as u64 * 32;
            if n > 0 {
                let mut enc = ctx.device.create_command_encoder(&Default::default());
                enc.copy_buffer_to_buffer(w.centroids, 0, &b.centroids, 0, n);
                enc.copy_buffer_to_buffer(w.rep_points, 0, &b.rep_points, 0, n);
                ctx.queue.submit([enc.finish()]);
            }
            run(&[("warm_centroids", kk), ("init_sampled", p.num_sampled)]);
        }
        None => run(&[("init_centroids", kk), ("init_sampled", p.num_sampled)]),
    }
}

/// Alg. 1 lines 5-18, `iterations` times: the grid (`grid`), the sampled points' assignment, the
/// centroids' update and `converge`, one submission an iteration. The GPU ends the loop early
/// (`converge`: an iteration that changed nothing, or a warm start's shorter count); the iterations
/// after the end are recorded but do nothing, so the host never waits to read a flag back.
fn iterate(p: &KmParams, grid: &[(&str, u32)], iterations: u32, run: &mut RunSteps) {
    for _ in 0..iterations {
        let mut steps = grid.to_vec();
        steps.extend([
            ("assign_sampled", p.num_sampled),
            ("update", p.k),
            ("converge", 1),
        ]);
        run(&steps);
    }
}

/// Diagnosis (`FVPL_PROFILE_STEPS`): the last grid (origin xyz, cell, dims xyz, cells) and the
/// centroids per cell.
fn print_grid(ctx: &GpuContext, label: &str, c: &Clustering, grid: &wgpu::Buffer) -> Result<()> {
    let p = &c.params;
    let iterations_run = c.counters(ctx)?.iterations_run;
    let g: Vec<u32> = ctx.read_buffer(grid, 8)?;
    let cell = f32::from_bits(g[3]);
    let cells = g[7].max(1);
    eprintln!(
        "{label}: {iterations_run} iteration(s), K {}, grid {}x{}x{} = {} cells of {cell:.4}, {:.1} centroids a cell",
        p.k,
        g[4],
        g[5],
        g[6],
        g[7],
        p.k as f32 / cells as f32
    );
    Ok(())
}
