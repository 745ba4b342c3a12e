//! `wang_cluster` (Wang, Wang, Zhou, Pan, Bao 2009, seed `001`, §3.2; docs/methods.md, "wang"): the
//! clustering of a frame's shading points, all of it on the GPU (`shaders-wgsl/wang_cluster.wgsl`,
//! its steps in `shaders-wgsl/wang/`), the G-buffer never read back. CPU twin: `super::twin::cluster`.
//!
//! 1. **Adaptive seeding**: a screen-space quadtree of the shading points (sums per node, built
//!    level by level from 2×2 leaves), each node's variation ε_q by Eq. (2) against its mean
//!    position and normal (every level at once, fixed-point sums reduced per 16×16 tile), then K
//!    seeds handed down from the root in proportion to the children's ε_q, one level a dispatch;
//!    a node with one seed draws it among its points (jittered sampling).
//! 2. **k-means with Eq. (2)**: every point to the centre of least error among its own cluster's
//!    (in the first assignment: the seed of its quadtree node) and those of the 27 cells of a
//!    uniform grid over the centres around it (the paper uses a kd-tree of the centres "to constrain
//!    the search within a small Euclidean distance"; the grid is the shared k-means grid over
//!    centres, `shaders-wgsl/common/grid.wgsl`, built on the GPU every iteration), so
//!    a border moves as far as the centres ask, up to a cell (1.5 cluster spacings) an iteration,
//!    whatever the pixels; centres the mean position and normal of their members, from 64-bit
//!    fixed-point sums that a point changing cluster updates with atomics.
//! 3. **Sample points**: per cluster the member of least error (an atomic minimum, then the lowest
//!    pixel with it).
//!
//! The iterations run on the grid image of `grid_step` (every other pixel along x and y when that
//! leaves enough points a cluster); with a step above 1 a last assignment labels the other pixels.
//! One submission seeds and
//! assigns, one per iteration, one labels every pixel, one picks the sample points; the number of
//! clusters with a sample point (4 bytes) is the only read-back.

use anyhow::Result;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::Image;
use crate::gi::dispatch::{Gpu, Kernel, RecordCopies, Run, WORKGROUP};
use crate::gi::kmeans::{GridBuffers, grid_steps, scan_groups};
use crate::gi::scene_gpu::{data_texture_layout, storage_layout, uniform_layout};
use crate::gpu::GpuContext;

pub const INVALID: u32 = u32::MAX;
/// At most this many grid cells an axis (`common/grid.wgsl`'s `MAX_DIM`).
pub use crate::gi::kmeans::MAX_DIM;
/// Words a cluster in `WangClustering::sums`: six 64-bit sums, the count, the sample point's error
/// bits and pixel, one spare.
pub const WORDS: u32 = 16;
/// The word of a cluster's sample pixel in `sums`.
pub const SAMPLE_WORD: u32 = 14;
/// Fixed point of the centre sums (positions in the scene's bounds, normals + 1) and of ε_q.
pub const POS_SCALE: f32 = 16_777_216.0;
pub const NRM_SCALE: f32 = 8_388_608.0;
pub const EPS_SCALE: f32 = 65_536.0;
pub const EPS_MAX: f32 = 8_388_607.0;
/// Rounds of `apportion` (wang/seed.wgsl's `APPORTION_ROUNDS`).
pub const APPORTION_ROUNDS: u32 = 8;
/// Grid points a cluster below which the iterations use every pixel (`grid_step`).
pub const MIN_GRID_POINTS_PER_CLUSTER: u32 = 16;

/// The grid step of the k-means iterations: 2 (a quarter of the pixels) when that leaves at least
/// `MIN_GRID_POINTS_PER_CLUSTER` grid points a cluster, else 1. Adaptation (docs/methods.md): the
/// paper's k-means runs on every shading point; here, as the paper's γ does, the iterations run on a
/// subset and the full image is labelled at the end.
pub fn grid_step(pixels: u32, k: u32) -> u32 {
    if pixels / 4 >= MIN_GRID_POINTS_PER_CLUSTER * k.max(1) {
        2
    } else {
        1
    }
}

/// Levels of the quadtree over a `gw` × `gh` grid image: its side is 2^levels (at least 2), the
/// levels 0 .. levels − 1 stored (level levels − 1 has 2×2 points a node).
pub fn quadtree_levels(gw: u32, gh: u32) -> u32 {
    gw.max(gh).max(2).next_power_of_two().trailing_zeros()
}

/// Nodes of the stored levels 0 .. levels − 1: (4^levels − 1) / 3.
pub fn stored_nodes(levels: u32) -> u64 {
    ((1u64 << (2 * levels)) - 1) / 3
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct ClusterParams {
    pub width: u32,
    pub height: u32,
    pub step: u32,
    pub gw: u32,
    pub gh: u32,
    pub levels: u32,
    pub k: u32,
    pub seed: u32,
    pub alpha: f32,
    pub pixels: u32,
    pub seeds_base: u32,
    pub _p: u32,
    /// The scene's bounds: lo, extent (at least 1e-30 an axis; w its length).
    pub lo: [f32; 4],
    pub ext: [f32; 4],
}

impl ClusterParams {
    /// The clustering of a `width` × `height` image into `k` clusters; `alpha` is α per unit of
    /// length; `bounds` (lo, hi) contains every shading point (the scene's bounds).
    pub fn new(
        width: u32,
        height: u32,
        k: u32,
        alpha: f32,
        seed: u32,
        bounds: (Vec3, Vec3),
    ) -> Self {
        let step = grid_step(width * height, k);
        let (gw, gh) = (width.div_ceil(step), height.div_ceil(step));
        let levels = quadtree_levels(gw, gh);
        let ext = (bounds.1 - bounds.0).max(Vec3::splat(1e-30));
        ClusterParams {
            width,
            height,
            step,
            gw,
            gh,
            levels,
            k,
            seed,
            alpha,
            pixels: width * height,
            seeds_base: (4 * stored_nodes(levels)) as u32,
            _p: 0,
            lo: bounds.0.extend(0.0).into(),
            ext: [ext.x, ext.y, ext.z, ext.length()],
        }
    }

    /// The image pixel of grid pixel i (row-major in the grid image).
    pub fn grid_pixel(&self, i: u32) -> u32 {
        (i / self.gw) * self.step * self.width + (i % self.gw) * self.step
    }
}

/// A frame's clustering, resident on the GPU.
pub struct WangClustering {
    pub params: ClusterParams,
    /// Per pixel its cluster (u32, `INVALID` for none), then per pixel its Eq. (2) error to its
    /// centre (f32 bits; where it has a cluster).
    pub labels: wgpu::Buffer,
    /// Two vec4 a cluster: the centre (position, w = 1 while it has members; normal).
    pub centres: wgpu::Buffer,
    /// `WORDS` a cluster: its fixed-point sums and count, its sample point (word `SAMPLE_WORD`).
    pub sums: wgpu::Buffer,
    /// The quadtree (4 words a stored node: ε_q lo, hi, seeds, first seed), then from
    /// `params.seeds_base` the seeds' pixels; word 2 is the number of seeds.
    pub tree: wgpu::Buffer,
    /// Two vec4 a cluster: its sample point (position, w = 1 when it has one; normal).
    pub samples: wgpu::Buffer,
    /// The sample points as shading points of albedo 1 (what the gather reads).
    pub sample_gbuffer: wgpu::Buffer,
    /// The clustering's counters (8 words; word 7: the clusters with a sample point), left on the
    /// GPU: read on request (`read_used`, the frame's pending counts).
    pub bounds: wgpu::Buffer,
    /// Assignment passes run.
    pub passes: u32,
}

impl WangClustering {
    pub fn k(&self) -> u32 {
        self.params.k
    }

    /// Clusters with a sample point (read back: a wait and 32 bytes; on request only).
    pub fn read_used(&self, ctx: &GpuContext) -> Result<u32> {
        used_of(&ctx.device, &ctx.queue, &self.bounds)
    }

    /// The labels (read back; tests and views).
    pub fn read_labels(&self, ctx: &GpuContext) -> Result<Vec<u32>> {
        ctx.read_buffer(&self.labels, self.params.pixels as usize)
    }

    /// The centres, two vec4 each (read back).
    pub fn read_centres(&self, ctx: &GpuContext) -> Result<Vec<[[f32; 4]; 2]>> {
        let raw: Vec<[f32; 4]> = ctx.read_buffer(&self.centres, 2 * self.k() as usize)?;
        Ok(raw.chunks(2).map(|c| [c[0], c[1]]).collect())
    }

    /// The seeds' pixels in seed order (read back).
    pub fn read_seeds(&self, ctx: &GpuContext) -> Result<Vec<u32>> {
        let base = self.params.seeds_base as usize;
        let words: Vec<u32> = ctx.read_buffer(&self.tree, base + self.k() as usize)?;
        let n = (words[2] as usize).min(self.k() as usize);
        Ok(words[base..base + n].to_vec())
    }

    /// Per cluster its sample point's pixel, `INVALID` for none (read back).
    pub fn read_sample_pixels(&self, ctx: &GpuContext) -> Result<Vec<u32>> {
        let w: Vec<u32> = ctx.read_buffer(&self.sums, (WORDS * self.k()) as usize)?;
        Ok(w.chunks(WORDS as usize)
            .map(|c| c[SAMPLE_WORD as usize])
            .collect())
    }
}

/// Clusters with a sample point: word 7 of a clustering's `bounds` (read back, waiting for it).
pub fn used_of(device: &wgpu::Device, queue: &wgpu::Queue, bounds: &wgpu::Buffer) -> Result<u32> {
    Ok(crate::gpu::read_buffer::<u32>(device, queue, bounds, 8)?[7])
}

const ENTRIES: &[&str] = &[
    "init_labels",
    "seed_leaves",
    "seed_up",
    "seed_next",
    "seed_eps",
    "seed_split",
    "seed_pixels",
    "seed_centres",
    "update",
    "grid_setup",
    "grid_count",
    "grid_scan_blocks",
    "grid_scan_ranges",
    "grid_scatter",
    "assign_first",
    "assign_grid",
    "assign_rest",
    "sample_clear",
    "sample_dist",
    "sample_pick",
    "sample_store",
];

/// The pipelines of `wang_cluster.wgsl` (its steps in `shaders-wgsl/wang/`).
pub struct WangCluster {
    kernel: Kernel,
    /// The search reads the grid through textures (`TEXTURE_SEARCH`: on a software adapter).
    texture_search: bool,
}

impl WangCluster {
    /// Its pipelines, the search reading the grid through textures on a software adapter.
    pub fn new(ctx: &GpuContext) -> Self {
        Self::with_texture_search(ctx, ctx.software)
    }

    /// Its pipelines with the search reading the grid through textures or not (the clusters do not
    /// depend on it; tested).
    pub fn with_texture_search(ctx: &GpuContext, texture_search: bool) -> Self {
        let mut entries = vec![uniform_layout(1), storage_layout(2, true)];
        entries.extend((3..=13).map(|b| storage_layout(b, false)));
        entries.push(data_texture_layout(14, wgpu::TextureSampleType::Uint));
        entries.push(data_texture_layout(15, wgpu::TextureSampleType::Uint));
        entries.push(storage_layout(16, false));
        let constants = [("TEXTURE_SEARCH", texture_search as u32 as f64)];
        WangCluster {
            kernel: Kernel::with_entries(ctx, None, "wang_cluster", ENTRIES, &entries, &constants),
            texture_search,
        }
    }

    /// §3.2: the clustering of `img`'s shading points (`p`: `ClusterParams::new` of its size) with
    /// `iterations` k-means iterations after the first assignment, every step timed as
    /// `wang_cluster` (`FVPL_PROFILE_STEPS`: each step under `wang_cluster.<step>`).
    pub fn run(
        &self,
        g: &mut Gpu,
        img: Image,
        p: &ClusterParams,
        iterations: u32,
    ) -> Result<WangClustering> {
        let ctx = g.ctx;
        let k = p.k.max(1) as u64;
        let nodes = stored_nodes(p.levels);
        let params = ctx.uniform("wang cluster params", p);
        let node_sums = ctx.storage("wang quadtree sums", nodes * 32);
        let tree = ctx.storage("wang quadtree", (4 * nodes + k) * 4);
        let bounds = ctx.storage("wang cluster bounds", 8 * 4);
        let centre_grid = GridBuffers::new(ctx, k, self.texture_search);
        let sums = ctx.storage("wang centre sums", k * WORDS as u64 * 4);
        let labels = ctx.storage("wang labels", 2 * p.pixels as u64 * 4);
        let centres = ctx.storage("wang centres", k * 32);
        let samples = ctx.storage("wang samples", k * 32);
        let sample_gbuffer = ctx.storage("wang sample gbuffer", k * 64);
        let bg = self.kernel.bind_group_with_textures(
            ctx,
            &[
                (1, &params),
                (2, img.gbuffer),
                (3, &node_sums),
                (4, &tree),
                (5, &bounds),
                (6, &centre_grid.cells),
                (7, &centre_grid.sorted),
                (8, &sums),
                (9, &labels),
                (10, &centres),
                (11, &samples),
                (12, &sample_gbuffer),
                (13, &centre_grid.ranges),
                (16, &centre_grid.grid),
            ],
            &[
                (14, &centre_grid.sorted_view),
                (15, &centre_grid.ranges_view),
            ],
        );
        // After each grid build the search's textures are refreshed (software adapters only).
        let copy = |enc: &mut wgpu::CommandEncoder| centre_grid.copy_to_textures(enc);
        let after = self
            .texture_search
            .then_some(("grid_scatter", &copy as &RecordCopies));
        let r = Run {
            label: super::CLUSTER.name(),
            group: &bg,
            seed: p.seed,
        };
        let kk = p.k;
        let grid_points = p.gw * p.gh;
        let grid = grid_steps(kk, scan_groups(kk));
        let nodes_at = |l: u32| 1u32 << (2 * l);
        let side = 1u32 << p.levels;
        let tiles = (side / 16).max(1).pow(2);
        // Seeding: the quadtree's sums bottom-up, ε_q, the seeds top-down; then the first grid and
        // assignment.
        let mut steps = vec![
            ("init_labels", p.pixels),
            ("seed_leaves", nodes_at(p.levels - 1)),
        ];
        for l in (0..p.levels - 1).rev() {
            steps.extend([("seed_up", nodes_at(l)), ("seed_next", 1)]);
        }
        steps.push(("seed_eps", WORKGROUP * tiles));
        for l in 0..p.levels {
            steps.extend([("seed_split", nodes_at(l)), ("seed_next", 1)]);
        }
        steps.extend([("seed_pixels", grid_points), ("seed_centres", kk)]);
        steps.extend(grid);
        steps.push(("assign_first", grid_points));
        self.kernel.run_entries(g, r, &steps, after);
        let mut passes = 1;
        let mut iterate = |rest: bool| {
            let mut steps = vec![("update", kk)];
            steps.extend(grid);
            steps.push(("assign_grid", grid_points));
            if rest {
                steps.push(("assign_rest", p.pixels));
            }
            self.kernel.run_entries(g, r, &steps, after);
            passes += 1;
        };
        for _ in 0..iterations {
            iterate(false);
        }
        if p.step > 1 {
            iterate(true);
        }
        self.kernel.run_entries(
            g,
            r,
            &[
                ("update", kk),
                ("sample_clear", kk),
                ("sample_dist", p.pixels),
                ("sample_pick", p.pixels),
                ("sample_store", kk),
            ],
            None,
        );
        Ok(WangClustering {
            params: *p,
            labels,
            centres,
            sums,
            tree,
            samples,
            sample_gbuffer,
            bounds,
            passes,
        })
    }
}
