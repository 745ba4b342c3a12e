//! CPU twins of wang's shaders (seed 001, docs/methods.md "wang"): the whole §3.2 clustering of
//! `shaders-wgsl/wang_cluster.wgsl` (`cluster`: the quadtree seeding of `wang/seed.wgsl`, the
//! k-means with Eq. (2) over the shared grid of the centres (`common/grid.wgsl` in `wang/grid.wgsl`,
//! `wang/assign.wgsl`; `cpu::grid`), the centre updates of `wang/centres.wgsl` and the sample points
//! of `wang/sample.wgsl`, in the same f32 arithmetic and fixed-point sums as the GPU) and §3.4's R_j and interpolation of `shaders-wgsl/wang.wgsl`
//! (`harmonic_radius`, `interpolate`).
//!
//! - §3.2, Eq. (2): ε = α‖x_i − x_k‖ + √(2 − 2 n_i·n_k), positions in scene diagonals
//!   (`eq2_error`; the caller passes α / diagonal).
//! - §3.2, "Adaptive Seeding of Sample Points": a screen-space quadtree of the shading points, each
//!   node's geometric variation ε_q by Eq. (2) against its mean position and normal, K seeds
//!   distributed from the root to the four children in proportion to their ε_q, a seed jittered in
//!   a node that gets one (`Quadtree`, `apportion`, `quadtree_seeds`).
//! - §3.2, "K-Means Clustering": every shading point to its closest centre by Eq. (2) among those
//!   near it (`CentreGrid`), centres the mean position and normal of their members, and finally
//!   "the shading point with the smallest error" as the cluster's irradiance sample point
//!   (`update_centers`, `sample_points`, `cluster`).
//! - §3.4's weight w(s_j) = 1 / (‖x − s_j‖ / R_j + √(2 − 2 n(x)·n(s_j))) (`interpolation_weight`)
//!   and R_j from its rays (`radius_from_sum`).
//!
//! For tests only (`tests/methods.rs` checks the shaders against it): no production code calls it.

use glam::Vec3;

pub use super::cluster::{
    APPORTION_ROUNDS, ClusterParams, EPS_MAX, EPS_SCALE, INVALID, MIN_GRID_POINTS_PER_CLUSTER,
    NRM_SCALE, POS_SCALE, grid_step, quadtree_levels, stored_nodes,
};
pub use super::{RADIUS_MIN, RADIUS_RAYS, RADIUS_RAYS_PER_DISPATCH, interp_stride};
pub use crate::cpu::grid::CentreGrid;
use crate::cpu::shading::{CpuScene, onb};
use crate::gi::primary::ShadingPoint;
use crate::gi::rng::{rng_next, rng_seed};

// --- wang/common.wgsl (Eq. 2) and wang.wgsl (§3.4's weight and R_j).

/// Eq. (2) of §3.2: the geometric error of shading point (x_i, n_i) against centre (x_k, n_k);
/// `alpha` is α per unit of length (the paper's α over the scene diagonal: "after the scene geometry
/// scale is normalized").
pub fn eq2_error(alpha: f32, xi: Vec3, ni: Vec3, xk: Vec3, nk: Vec3) -> f32 {
    alpha * (xi - xk).length() + (2.0 - 2.0 * ni.dot(nk)).max(0.0).sqrt()
}

/// The §3.4 interpolation weight w(s_j) = 1 / (‖x − s_j‖ / R_j + √(2 − 2 n(x)·n(s_j))) (infinite
/// where x is s_j with its normal).
pub fn interpolation_weight(x: Vec3, n: Vec3, s: Vec3, ns: Vec3, r: f32) -> f32 {
    1.0 / ((x - s).length() / r + (2.0 - 2.0 * n.dot(ns)).max(0.0).sqrt())
}

/// R_j from the summed inverse hit distances of `RADIUS_RAYS` rays (misses add 0): the harmonic
/// mean N / Σ 1/t, clamped to [RADIUS_MIN × diagonal, diagonal] (every ray missed: the diagonal).
pub fn radius_from_sum(sum_inv: f32, diagonal: f32) -> f32 {
    let r = if sum_inv > 0.0 {
        RADIUS_RAYS as f32 / sum_inv
    } else {
        diagonal
    };
    r.clamp(RADIUS_MIN * diagonal, diagonal)
}

// --- wang/seed.wgsl: the quadtree seeding.

/// Splits `k` seeds among a node's four children in proportion to `weight` (their ε_q), each at most
/// `cap` (its valid shading points): floors first, then the largest remainders (lowest index on a
/// tie), repeated over the children with room until every seed is placed (at most
/// `APPORTION_ROUNDS` rounds). With no weight anywhere, equal shares. In f32, as `wang/seed.wgsl`.
pub fn apportion(k: u32, weight: [f32; 4], cap: [u32; 4]) -> [u32; 4] {
    let mut a = [0u32; 4];
    let mut left = k.min(cap.iter().sum());
    for _ in 0..APPORTION_ROUNDS {
        if left == 0 {
            break;
        }
        let mut wsum = 0.0f32;
        let mut open = 0u32;
        for i in 0..4 {
            if a[i] < cap[i] {
                wsum += weight[i].max(0.0);
                open += 1;
            }
        }
        let mut rest = Vec::new();
        let mut given = 0;
        for i in 0..4 {
            if a[i] < cap[i] {
                let share = if wsum > 0.0 {
                    weight[i].max(0.0) / wsum
                } else {
                    1.0 / open as f32
                };
                let ideal = left as f32 * share;
                let fl = ideal.floor();
                let f = (fl as u32).min(cap[i] - a[i]);
                a[i] += f;
                given += f;
                rest.push((ideal - fl, i));
            }
        }
        left -= given;
        rest.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
        for (_, i) in rest {
            if left == 0 {
                break;
            }
            if a[i] < cap[i] {
                a[i] += 1;
                left -= 1;
            }
        }
    }
    a
}

/// The grid image of `p` (every `step`-th pixel along x and y) over the frame's shading points.
#[derive(Clone, Copy)]
pub struct GridImage<'a> {
    pub p: &'a ClusterParams,
    pub sps: &'a [ShadingPoint],
}

impl GridImage<'_> {
    /// Grid pixel (x, y)'s image pixel when it has a shading point.
    pub fn valid(&self, x: u32, y: u32) -> Option<u32> {
        let p = self.p;
        if x >= p.gw || y >= p.gh {
            return None;
        }
        let m = y * p.step * p.width + x * p.step;
        self.sps[m as usize].valid.then_some(m)
    }
}

fn level_base(l: u32) -> usize {
    (((1u64 << (2 * l)) - 1) / 3) as usize
}

fn node_index(l: u32, x: u32, y: u32) -> usize {
    level_base(l) + ((y as usize) << l) + x as usize
}

/// The seeding's screen-space quadtree (§3.2): per stored node (levels 0 .. levels − 1, level l
/// from (4^l − 1) / 3, row-major) the sums of its valid points' positions and normals, their count,
/// ε_q as the GPU's fixed-point sum, and (after `quadtree_seeds`) the seeds it got and its first.
pub struct Quadtree {
    pub levels: u32,
    pub pos: Vec<Vec3>,
    pub nrm: Vec<Vec3>,
    pub count: Vec<f32>,
    pub eps: Vec<u64>,
    pub seeds: Vec<(u32, u32)>,
}

impl Quadtree {
    /// Builds it as `wang/seed.wgsl` does: 2×2 leaves in the order (0,0), (1,0), (0,1), (1,1),
    /// each level up the sum of its children in that order; then ε_q, Eq. (2) of each point against
    /// the node's mean (`mean`), `EPS_SCALE` fixed point, summed exactly.
    pub fn build(img: GridImage, alpha: f32) -> Quadtree {
        let levels = img.p.levels;
        let nodes = stored_nodes(levels) as usize;
        let mut t = Quadtree {
            levels,
            pos: vec![Vec3::ZERO; nodes],
            nrm: vec![Vec3::ZERO; nodes],
            count: vec![0.0; nodes],
            eps: vec![0; nodes],
            seeds: vec![(0, 0); nodes],
        };
        let last = levels - 1;
        for y in 0..1u32 << last {
            for x in 0..1u32 << last {
                let n = node_index(last, x, y);
                for q in 0..4 {
                    if let Some(m) = img.valid(2 * x + (q & 1), 2 * y + (q >> 1)) {
                        t.pos[n] += img.sps[m as usize].pos;
                        t.nrm[n] += img.sps[m as usize].normal;
                        t.count[n] += 1.0;
                    }
                }
            }
        }
        for l in (0..last).rev() {
            for y in 0..1u32 << l {
                for x in 0..1u32 << l {
                    let n = node_index(l, x, y);
                    for q in 0..4 {
                        let c = node_index(l + 1, 2 * x + (q & 1), 2 * y + (q >> 1));
                        let (cp, cn, cc) = (t.pos[c], t.nrm[c], t.count[c]);
                        t.pos[n] += cp;
                        t.nrm[n] += cn;
                        t.count[n] += cc;
                    }
                }
            }
        }
        let side = 1u32 << levels;
        for y in 0..side {
            for x in 0..side {
                let Some(m) = img.valid(x, y) else { continue };
                let sp = &img.sps[m as usize];
                for l in 0..levels {
                    let shift = levels - l;
                    let n = node_index(l, x >> shift, y >> shift);
                    let (mp, mn) = t.mean(n);
                    let e = eq2_error(alpha, sp.pos, sp.normal, mp, mn);
                    t.eps[n] += (e * EPS_SCALE).min(EPS_MAX) as u32 as u64;
                }
            }
        }
        t
    }

    /// Node n's mean position and normalised mean normal (zero when the normals cancel).
    pub fn mean(&self, n: usize) -> (Vec3, Vec3) {
        let l = self.nrm[n].length();
        let nrm = if l > 0.0 { self.nrm[n] / l } else { Vec3::ZERO };
        (self.pos[n] / self.count[n], nrm)
    }

    fn count_of(&self, n: usize) -> u32 {
        self.count[n] as u32
    }

    /// ε_q as the weight `apportion` takes (the 64-bit sum as the GPU converts it).
    pub fn weight(&self, n: usize) -> f32 {
        let v = self.eps[n];
        (v >> 32) as u32 as f32 * 4_294_967_296.0 + v as u32 as f32
    }

    /// The valid points of node (x, y) of level l in Z order (children (0,0), (1,0), (0,1), (1,1)
    /// at every level).
    fn points_z(&self, img: GridImage, l: u32, x: u32, y: u32, out: &mut Vec<u32>) {
        for q in 0..4 {
            let (cx, cy) = (2 * x + (q & 1), 2 * y + (q >> 1));
            if l + 1 == self.levels {
                out.extend(img.valid(cx, cy));
            } else {
                self.points_z(img, l + 1, cx, cy, out);
            }
        }
    }

    /// Hands node (x, y) of level l its `kn` seeds from `first` on (`quadtree_seeds`).
    #[allow(clippy::too_many_arguments)]
    fn descend(
        &mut self,
        img: GridImage,
        l: u32,
        x: u32,
        y: u32,
        kn: u32,
        first: u32,
        seeds: &mut [u32],
    ) {
        let n = node_index(l, x, y);
        let count = self.count_of(n);
        self.seeds[n] = (kn, first);
        if kn == 0 {
            return;
        }
        let put = |seeds: &mut [u32], pts: &[u32]| {
            for (r, &m) in pts.iter().enumerate() {
                seeds[(first as usize) + r] = m;
            }
        };
        if kn >= count || kn == 1 || l + 1 == self.levels {
            let mut pts = Vec::new();
            self.points_z(img, l, x, y, &mut pts);
            if kn >= count {
                put(seeds, &pts);
            } else if kn == 1 {
                // Jittered sampling within the quad.
                let mut st = rng_seed(img.p.seed, n as u32, 0x5eed);
                let u = rng_next(&mut st);
                let r = ((u * count as f32) as u32).min(count - 1);
                put(seeds, &pts[r as usize..r as usize + 1]);
            } else {
                // The last stored level: its points weigh nothing (each is its own mean), so the
                // first kn in Z order.
                put(seeds, &pts[..kn as usize]);
            }
            return;
        }
        let kids = [0, 1, 2, 3].map(|q| (2 * x + (q & 1), 2 * y + (q >> 1)));
        let ids = kids.map(|(cx, cy)| node_index(l + 1, cx, cy));
        let a = apportion(
            kn,
            ids.map(|c| self.weight(c)),
            ids.map(|c| self.count_of(c)),
        );
        let mut off = first;
        for q in 0..4 {
            self.descend(img, l + 1, kids[q].0, kids[q].1, a[q], off, seeds);
            off += a[q];
        }
    }
}

/// §3.2's adaptive seeding over the grid image (twin of `wang/seed.wgsl`'s `seed_*` steps):
/// min(K, valid points) seed pixels (image pixels, distinct, valid), in the order of a depth-first
/// walk of the quadtree in Z order; a node with as many seeds as points takes them all, one with a
/// single seed draws it uniformly among its points (stream `rng_seed(seed, node, 0x5eed)`), a node
/// of the last stored level with fewer seeds than points its first ones, any other splits them among
/// its children by `apportion` of their ε_q. Records each node's seeds in `tree.seeds`.
pub fn quadtree_seeds(img: GridImage, tree: &mut Quadtree) -> Vec<u32> {
    let kn = img.p.k.min(tree.count_of(0));
    let mut seeds = vec![INVALID; kn as usize];
    tree.descend(img, 0, 0, 0, kn, 0, &mut seeds);
    seeds
}

/// The first assignment's hint of grid pixel (x, y) (`nearest`): the first seed of the
/// deepest node on its way down from the root that got any (after `quadtree_seeds`).
pub fn seed_hint(tree: &Quadtree, x: u32, y: u32) -> u32 {
    let levels = tree.levels;
    let mut hint = 0;
    for l in 0..levels {
        let shift = levels - l;
        let n = node_index(l, x >> shift, y >> shift);
        let (kn, first) = tree.seeds[n];
        if kn == 0 {
            break;
        }
        hint = first;
        if kn >= tree.count_of(n) || kn == 1 || l + 1 == levels {
            break;
        }
    }
    hint
}

// --- wang/centres.wgsl: the centres and their update.

/// A cluster centre: mean position and normalised mean normal of its members (`count` 0: empty, out
/// of the grid).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Center {
    pub pos: Vec3,
    pub nrm: Vec3,
    pub count: u32,
}

impl Center {
    /// From the GPU's two vec4 (position with w = 1 while the cluster has members, normal); the
    /// count is 1 for a valid one.
    pub fn from_gpu(c: &[[f32; 4]; 2]) -> Center {
        Center {
            pos: Vec3::new(c[0][0], c[0][1], c[0][2]),
            nrm: Vec3::new(c[1][0], c[1][1], c[1][2]),
            count: (c[0][3] > 0.0) as u32,
        }
    }
}

/// The centres of `labels` (K of them, `prev` the centres before): mean position and normalised
/// mean normal of the members from the GPU's 64-bit fixed-point sums (positions in the scene's
/// bounds scaled by `POS_SCALE`, normals + 1 by `NRM_SCALE`: exact, independent of order); a
/// normal that cancels keeps `prev`'s; an empty cluster keeps `prev`'s place with count 0.
pub fn update_centers(
    p: &ClusterParams,
    sps: &[ShadingPoint],
    labels: &[u32],
    prev: &[Center],
) -> Vec<Center> {
    let lo = Vec3::from_slice(&p.lo[..3]);
    let ext = Vec3::from_slice(&p.ext[..3]);
    let mut sums = vec![([0u64; 6], 0u32); prev.len()];
    for (sp, &l) in sps.iter().zip(labels) {
        if l == INVALID || !sp.valid {
            continue;
        }
        let rel = ((sp.pos - lo) / ext).clamp(Vec3::ZERO, Vec3::ONE) * POS_SCALE;
        let nq = (sp.normal + 1.0).clamp(Vec3::ZERO, Vec3::splat(2.0)) * NRM_SCALE;
        let e = &mut sums[l as usize];
        for a in 0..3 {
            e.0[a] += rel[a] as u32 as u64;
            e.0[3 + a] += nq[a] as u32 as u64;
        }
        e.1 += 1;
    }
    sums.iter()
        .zip(prev)
        .map(|((s, count), prev)| {
            if *count == 0 {
                return Center { count: 0, ..*prev };
            }
            let mean = |v: u64| {
                ((v >> 32) as u32 as f32 * 4_294_967_296.0 + v as u32 as f32) / *count as f32
            };
            let rel = Vec3::new(mean(s[0]), mean(s[1]), mean(s[2])) / POS_SCALE;
            let nrm = Vec3::new(mean(s[3]), mean(s[4]), mean(s[5])) / NRM_SCALE - 1.0;
            let l = nrm.length();
            Center {
                pos: lo + rel * ext,
                nrm: if l > 1e-6 { nrm / l } else { prev.nrm },
                count: *count,
            }
        })
        .collect()
}

// --- wang/grid.wgsl and wang/assign.wgsl: the grid over the centres (`cpu::grid`) and the
// assignment with Eq. (2).

/// The grid over the valid centres that the assignment searches (twin of wang/grid.wgsl: the
/// shared `cpu::grid` with the guard for centres along a line).
pub fn centre_grid(p: &ClusterParams, cs: &[Center]) -> CentreGrid {
    let valid = cs.iter().enumerate().filter(|(_, c)| c.count > 0);
    let centres = valid.map(|(k, c)| (k as u32, c.pos));
    CentreGrid::build(centres, p.k, p.lo, p.ext, true)
}

/// The centre of least Eq. (2) error (the lower index on a tie) among `hint` (when it is a cluster
/// with members) and the centres of the 27 cells of `grid` around `pos`; without either, the first
/// ring of cells further out that holds a centre; `INVALID` without any valid centre (twin of
/// wang/assign.wgsl's `nearest`).
pub fn nearest(
    grid: &CentreGrid,
    cs: &[Center],
    alpha: f32,
    (pos, nrm): (Vec3, Vec3),
    hint: u32,
) -> u32 {
    let c = grid.coord(pos);
    let (mut best_e, mut best) = match cs.get(hint as usize) {
        Some(h) if h.count > 0 => (eq2_error(alpha, pos, nrm, h.pos, h.nrm), hint),
        _ => (f32::MAX, INVALID),
    };
    for ring in 1..=grid.max_ring() {
        for k in grid.ring(c, ring) {
            let ck = &cs[k as usize];
            let e = eq2_error(alpha, pos, nrm, ck.pos, ck.nrm);
            if e < best_e || (e == best_e && k < best) {
                (best_e, best) = (e, k);
            }
        }
        if best != INVALID {
            break;
        }
    }
    best
}

/// Every valid pixel m of `pixels` to its nearest centre (`nearest` on the grid over `cs`)
/// with the hint `hint(m, labels)`.
fn assign(
    p: &ClusterParams,
    sps: &[ShadingPoint],
    cs: &[Center],
    pixels: &[u32],
    labels: &mut [u32],
    hint: impl Fn(u32, &[u32]) -> u32,
) {
    let grid = centre_grid(p, cs);
    for &m in pixels {
        let sp = &sps[m as usize];
        if sp.valid {
            let h = hint(m, labels);
            labels[m as usize] = nearest(&grid, cs, p.alpha, (sp.pos, sp.normal), h);
        }
    }
}

// --- wang/sample.wgsl: the sample points.

/// Each cluster's irradiance sample point (§3.2: "in each cluster, we pick the shading point with
/// the smallest error"): the member pixel closest to its centre by Eq. (2), the lowest index on a
/// tie; `INVALID` for an empty cluster.
pub fn sample_points(
    sps: &[ShadingPoint],
    labels: &[u32],
    centers: &[Center],
    alpha: f32,
) -> Vec<u32> {
    let mut best = vec![(f32::INFINITY, INVALID); centers.len()];
    for (m, (sp, &l)) in sps.iter().zip(labels).enumerate() {
        if l == INVALID || !sp.valid {
            continue;
        }
        let c = &centers[l as usize];
        let d = eq2_error(alpha, sp.pos, sp.normal, c.pos, c.nrm);
        if d < best[l as usize].0 {
            best[l as usize] = (d, m as u32);
        }
    }
    best.into_iter().map(|b| b.1).collect()
}

// --- The whole clustering (wang_cluster.wgsl's steps in order).

/// Wang's clustering (§3.2), done.
#[derive(Clone, Debug, PartialEq)]
pub struct WangClusters {
    /// The seeds' pixels, in seed order.
    pub seeds: Vec<u32>,
    /// Per pixel its cluster (`INVALID`: not a valid shading point).
    pub labels: Vec<u32>,
    /// K centres (those past the seeds empty).
    pub centers: Vec<Center>,
    /// Per cluster its sample point's pixel (`INVALID`: empty).
    pub samples: Vec<u32>,
    /// Assignment passes run.
    pub passes: u32,
}

/// The whole §3.2 clustering of `sps` (twin of `method::wang::cluster::WangCluster::run` with the
/// same `p`): the quadtree seeds over the grid image, the first assignment of its pixels (hinted
/// with `seed_hint`), then `iterations` rounds of centre update and assignment (each pixel hinted
/// with its cluster); with a step above 1 a centre update, the assignment of the grid pixels and
/// then of the others (without a hint); a last centre update and the sample points.
pub fn cluster(p: &ClusterParams, sps: &[ShadingPoint], iterations: u32) -> WangClusters {
    let img = GridImage { p, sps };
    let mut tree = Quadtree::build(img, p.alpha);
    let seeds = quadtree_seeds(img, &mut tree);
    let mut centers: Vec<Center> = (0..p.k as usize)
        .map(|j| match seeds.get(j) {
            Some(&m) => Center {
                pos: sps[m as usize].pos,
                nrm: sps[m as usize].normal,
                count: 1,
            },
            None => Center {
                pos: Vec3::ZERO,
                nrm: Vec3::ZERO,
                count: 0,
            },
        })
        .collect();
    let mut labels = vec![INVALID; sps.len()];
    let grid: Vec<u32> = (0..p.gw * p.gh).map(|i| p.grid_pixel(i)).collect();
    let (w, g) = (p.width, p.step);
    let first_hint = |m: u32, _: &[u32]| seed_hint(&tree, (m % w) / g, (m / w) / g);
    assign(p, sps, &centers, &grid, &mut labels, first_hint);
    let own = |m: u32, l: &[u32]| l[m as usize];
    let mut passes = 1;
    for _ in 0..iterations {
        centers = update_centers(p, sps, &labels, &centers);
        assign(p, sps, &centers, &grid, &mut labels, own);
        passes += 1;
    }
    if g > 1 {
        centers = update_centers(p, sps, &labels, &centers);
        assign(p, sps, &centers, &grid, &mut labels, own);
        let rest: Vec<u32> = (0..p.pixels)
            .filter(|m| m % w % g != 0 || m / w % g != 0)
            .collect();
        assign(p, sps, &centers, &rest, &mut labels, |_, _| INVALID);
        passes += 1;
    }
    centers = update_centers(p, sps, &labels, &centers);
    let samples = sample_points(sps, &labels, &centers, p.alpha);
    WangClusters {
        seeds,
        labels,
        centers,
        samples,
        passes,
    }
}

/// A sample point as `wang.wgsl` reads it: two vec4 (position with w = 1 when valid, normal).
pub fn sample_to_gpu(sps: &[ShadingPoint], samples: &[u32]) -> Vec<[[f32; 4]; 2]> {
    samples
        .iter()
        .map(|&m| {
            if m == INVALID {
                [[0.0; 4]; 2]
            } else {
                let s = &sps[m as usize];
                [
                    s.pos.extend(1.0).to_array(),
                    s.normal.extend(0.0).to_array(),
                ]
            }
        })
        .collect()
}

/// §3.4's R_j at sample point (p, n), twin of `wang.wgsl`'s `radius`: Σ 1/t over `RADIUS_RAYS`
/// cosine-distributed rays (stream `rng_seed(seed, j, ray)`), turned into R_j by `radius_from_sum`.
/// Adaptation: the paper keeps the distances of its 250–500 final-gather rays; VPL lighting has no
/// final gather, so 32 rays are traced for R_j alone.
pub fn harmonic_radius(cpu: &CpuScene, p: Vec3, n: Vec3, j: u32, seed: u32) -> f32 {
    let mut sum = 0.0f32;
    let off = p + n * (cpu.info.eps + 4e-6 * p.abs().max_element());
    for ray in 0..RADIUS_RAYS {
        let mut st = rng_seed(seed, j, ray);
        let (u1, u2) = (rng_next(&mut st), rng_next(&mut st));
        let d = cosine_hemisphere(n, u1, u2);
        if let Some(h) = cpu.bvh.closest(off.into(), d.into(), 0.0, f32::MAX) {
            sum += 1.0 / h.t.max(1e-30);
        }
    }
    radius_from_sum(sum, cpu.scene.extent())
}

/// Twin of `common/sampling.wgsl`'s `cosine_hemisphere` (Duff et al.'s basis).
pub fn cosine_hemisphere(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let (t, bt) = onb(n);
    let r = u1.sqrt();
    let phi = 2.0 * std::f32::consts::PI * u2;
    let l = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt());
    (t * l.x + bt * l.y + n * l.z).normalize()
}

/// What §3.4's interpolation reads: each pixel's cluster, each cluster's sample point (position,
/// normal, valid), its R_j and its irradiance, and the stride of a pixel's neighbourhood.
#[derive(Clone, Copy)]
pub struct Samples<'a> {
    pub labels: &'a [u32],
    pub points: &'a [(Vec3, Vec3, bool)],
    pub radius: &'a [f32],
    pub irradiance: &'a [Vec3],
    pub stride: u32,
}

/// §3.4's interpolation at one pixel (twin of `wang.wgsl`'s `interp`): its candidates are the
/// clusters of the pixels at offsets {−s, 0, s}² (`stride` s; its own cluster among them), each
/// once; a candidate whose sample faces away (n·n_j ≤ 0) is skipped unless it is the pixel's own;
/// E = Σ w E_j / Σ w with the §3.4 weight, or E_j alone where the weight is infinite (the pixel is
/// the sample point). Returns albedo × E (E being the gathered irradiance times 1/π).
pub fn interpolate(width: u32, height: u32, m: u32, sp: &ShadingPoint, s: &Samples) -> Vec3 {
    let Samples {
        labels,
        points: samples,
        radius,
        irradiance,
        stride,
    } = *s;
    let own = labels[m as usize];
    if !sp.valid || own == INVALID || !samples[own as usize].2 {
        return Vec3::ZERO;
    }
    let (x, y) = ((m % width) as i64, (m / width) as i64);
    let s = stride as i64;
    let mut seen = [INVALID; 9];
    let mut ns = 0;
    let (mut sum, mut wsum) = (Vec3::ZERO, 0.0f32);
    for dy in -1..=1i64 {
        for dx in -1..=1i64 {
            let (qx, qy) = (x + dx * s, y + dy * s);
            if qx < 0 || qy < 0 || qx >= width as i64 || qy >= height as i64 {
                continue;
            }
            let j = labels[(qy * width as i64 + qx) as usize];
            if j == INVALID || seen[..ns].contains(&j) {
                continue;
            }
            seen[ns] = j;
            ns += 1;
            let (sp_j, n_j, valid) = samples[j as usize];
            if !valid || (j != own && sp.normal.dot(n_j) <= 0.0) {
                continue;
            }
            let den = (sp.pos - sp_j).length() / radius[j as usize]
                + (2.0 - 2.0 * sp.normal.dot(n_j)).max(0.0).sqrt();
            if den <= 1e-6 {
                return sp.albedo * irradiance[j as usize];
            }
            let w = 1.0 / den;
            sum += irradiance[j as usize] * w;
            wsum += w;
        }
    }
    if wsum > 0.0 {
        sp.albedo * sum / wsum
    } else {
        Vec3::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sp(pos: Vec3, normal: Vec3) -> ShadingPoint {
        ShadingPoint {
            valid: true,
            pos,
            normal,
            material: 0,
            albedo: Vec3::ONE,
            emission: Vec3::ZERO,
        }
    }

    #[test]
    fn eq2_by_hand() {
        // Same normal: α‖Δx‖ alone; 3-4-5 triangle.
        let z = Vec3::Z;
        let e = eq2_error(0.5, Vec3::ZERO, z, Vec3::new(3.0, 4.0, 0.0), z);
        assert!((e - 2.5).abs() < 1e-6, "{e}");
        // Perpendicular normals at one point: √2; opposite: 2.
        assert!((eq2_error(0.5, Vec3::ZERO, z, Vec3::ZERO, Vec3::X) - 2f32.sqrt()).abs() < 1e-6);
        assert!((eq2_error(0.5, Vec3::ZERO, z, Vec3::ZERO, -z) - 2.0).abs() < 1e-6);
    }

    #[test]
    fn section_3_4_weight_by_hand() {
        // x at the origin facing +z; s_j one unit along x, R_j = 2.
        let (x, n) = (Vec3::ZERO, Vec3::Z);
        let s = Vec3::X;
        // Same normal: 1 / (1/2 + 0) = 2.
        assert!((interpolation_weight(x, n, s, Vec3::Z, 2.0) - 2.0).abs() < 1e-6);
        // Perpendicular normal: 1 / (0.5 + √2) = 0.522407...
        let w = interpolation_weight(x, n, s, Vec3::X, 2.0);
        assert!((w - 1.0 / (0.5 + 2f32.sqrt())).abs() < 1e-6 && (w - 0.522_407).abs() < 1e-5);
        // On the sample itself: infinite.
        assert!(interpolation_weight(s, n, s, n, 1.0).is_infinite());
    }

    fn params(w: u32, h: u32, k: u32, alpha: f32, seed: u32) -> ClusterParams {
        ClusterParams::new(
            w,
            h,
            k,
            alpha,
            seed,
            (Vec3::splat(-10.0), Vec3::splat(10.0)),
        )
    }

    /// The quadtree by hand: a 2×2 image (one stored level, the root) with α = 0.5, points at x = 1,
    /// 2 (top row), 6 and 3 (bottom row), the last facing +x, the others +z. The root's mean is
    /// x = 3 with normal (1, 0, 3)/√10, so ε_q = 0.5 (2 + 1 + 3 + 0) + 3 √(2 − 6/√10) + √(2 − 2/√10)
    /// = 3 + 3 · 0.320364 + 1.169421 = 5.130514, in fixed point 5.130514 · 2^16 = 336,237 less at
    /// most one for each point's floor (cargo-mutants: the mean as the sum % count survived).
    #[test]
    fn quadtree_by_hand() {
        let sps = [
            sp(Vec3::X, Vec3::Z),
            sp(2.0 * Vec3::X, Vec3::Z),
            sp(6.0 * Vec3::X, Vec3::Z),
            sp(3.0 * Vec3::X, Vec3::X),
        ];
        let p = params(2, 2, 1, 0.5, 1);
        assert_eq!((p.levels, p.step, p.gw, p.gh), (1, 1, 2, 2));
        let mut t = Quadtree::build(GridImage { p: &p, sps: &sps }, 0.5);
        assert_eq!(t.count, [4.0]);
        let (mp, mn) = t.mean(0);
        assert_eq!(mp, 3.0 * Vec3::X);
        assert!((mn - Vec3::new(1.0, 0.0, 3.0) / 10f32.sqrt()).length() < 1e-6);
        let want = 5.130_514 * EPS_SCALE as f64;
        assert!(
            (t.eps[0] as f64 - want).abs() < 4.0,
            "{} vs {want}",
            t.eps[0]
        );
        assert_eq!(t.weight(0), t.eps[0] as f32);
        // One seed: drawn among the four points; four: every point, in Z order (0, 1, 2, 3).
        let one = quadtree_seeds(GridImage { p: &p, sps: &sps }, &mut t);
        assert!(one.len() == 1 && one[0] < 4);
        let p4 = params(2, 2, 4, 0.5, 1);
        assert_eq!(
            quadtree_seeds(GridImage { p: &p4, sps: &sps }, &mut t),
            [0, 1, 2, 3]
        );
    }

    /// Seeds in Z order by hand: a 4×4 image, the left half one point facing +z (ε_q 0), the right
    /// half facing alternately +z and +x (ε_q > 0), K 6. The root (4×4) splits 6
    /// by ε_q between its right children (quadrants (1,0) and (1,1): 3 each), each a leaf node of
    /// four points with fewer seeds than points that takes its first three in Z order: pixels 2, 3, 6
    /// of the top-right quadrant, then 10, 11, 14 of the bottom-right.
    #[test]
    fn seeds_in_z_order_by_hand() {
        let (w, h) = (4u32, 4u32);
        let sps: Vec<ShadingPoint> = (0..w * h)
            .map(|m| {
                let (x, y) = (m % w, m / w);
                let n = if x < 2 || (x + y) % 2 == 0 {
                    Vec3::Z
                } else {
                    Vec3::X
                };
                let pos = if x < 2 {
                    Vec3::ZERO
                } else {
                    Vec3::new(x as f32, y as f32, 0.0)
                };
                sp(pos * 1e-3, n)
            })
            .collect();
        let p = params(w, h, 6, 0.3, 1);
        assert_eq!((p.levels, p.step), (2, 1));
        let img = GridImage { p: &p, sps: &sps };
        let mut t = Quadtree::build(img, 0.3);
        assert_eq!(quadtree_seeds(img, &mut t), [2, 3, 6, 10, 11, 14]);
        // The first assignment's hints: the left half's quadrants got no seed, so their pixels take
        // the root's first (0); the right's take their quadrant's first (0 and 3).
        assert_eq!(seed_hint(&t, 0, 3), 0);
        assert_eq!(seed_hint(&t, 3, 0), 0);
        assert_eq!(seed_hint(&t, 2, 2), 3);
    }

    /// A cluster's sample point is its valid member nearest its centre by Eq. (2); a pixel without
    /// a surface or without a label is never one, and an empty cluster has none (cargo-mutants: the
    /// skip as `l == INVALID && !sp.valid` survived).
    #[test]
    fn sample_points_skip_pixels_without_a_surface_or_a_label() {
        let centre = |count| Center {
            pos: Vec3::ZERO,
            nrm: Vec3::Z,
            count,
        };
        let mut sky = sp(Vec3::ZERO, Vec3::Z);
        sky.valid = false;
        let sps = [
            sp(Vec3::X, Vec3::Z),
            sky,
            sp(0.5 * Vec3::X, Vec3::Z),
            sp(Vec3::ZERO, Vec3::Z),
        ];
        let labels = [0, 0, 0, INVALID];
        let s = sample_points(&sps, &labels, &[centre(3), centre(0)], 1.0);
        assert_eq!(s, [2, INVALID]);
    }

    #[test]
    fn apportion_by_hand() {
        assert_eq!(apportion(4, [1.0, 1.0, 2.0, 0.0], [10; 4]), [1, 1, 2, 0]);
        // 2 seeds by 3.8 : 1 (ideals 1.58, 0.42): floors 1, 0, then the larger remainder.
        assert_eq!(
            apportion(2, [1024.0, 272.0, 0.0, 0.0], [64, 33, 0, 0]),
            [2, 0, 0, 0]
        );
        // Equal weights, 3 seeds: remainders 0.75 each, the lowest indices win.
        assert_eq!(apportion(3, [1.0; 4], [10; 4]), [1, 1, 1, 0]);
        // A child full at its cap: the rest go to the others (here with no weight: equal shares).
        assert_eq!(
            apportion(5, [0.0, 0.0, 1.0, 0.0], [1, 1, 2, 1]),
            [1, 1, 2, 1]
        );
        // More seeds than points: every point.
        assert_eq!(apportion(9, [1.0; 4], [1, 0, 2, 1]), [1, 0, 2, 1]);
        // 10 seeds over weights 1:2:3:4.
        assert_eq!(apportion(10, [1.0, 2.0, 3.0, 4.0], [10; 4]), [1, 2, 3, 4]);
    }

    #[test]
    fn seeds_follow_the_geometric_variation() {
        // 8×8 image: the left half a flat floor, the right half a box corner (normals alternate), so
        // the right half varies more and gets more seeds.
        let (w, h) = (8u32, 8u32);
        let sps: Vec<ShadingPoint> = (0..w * h)
            .map(|m| {
                let (x, y) = ((m % w) as f32, (m / w) as f32);
                let n = if x < 4.0 || (m % 2 == 0) {
                    Vec3::Y
                } else {
                    Vec3::X
                };
                sp(Vec3::new(x * 0.01, 0.0, y * 0.01), n)
            })
            .collect();
        let p = params(w, h, 8, 0.3, 1);
        let img = GridImage { p: &p, sps: &sps };
        let seeds = quadtree_seeds(img, &mut Quadtree::build(img, 0.3));
        assert_eq!(seeds.len(), 8);
        let mut d = seeds.clone();
        d.sort();
        d.dedup();
        assert_eq!(d.len(), 8, "distinct");
        let right = seeds.iter().filter(|&&m| m % w >= 4).count();
        assert!(
            right >= 6,
            "{right} of 8 seeds on the varied half: {seeds:?}"
        );
        // As many seeds as points: all of them; invalid pixels are never seeds.
        let mut holes = sps.clone();
        for s in holes.iter_mut().step_by(3) {
            s.valid = false;
        }
        let p = params(w, h, 64, 0.3, 1);
        let img = GridImage { p: &p, sps: &holes };
        let all = quadtree_seeds(img, &mut Quadtree::build(img, 0.3));
        assert_eq!(all.len(), holes.iter().filter(|s| s.valid).count());
        assert!(all.iter().all(|&m| holes[m as usize].valid));
    }

    #[test]
    fn clustering_splits_two_walls() {
        // A 16×8 image: the left half a wall facing +x, the right half one facing +z, 2 clusters:
        // one per wall, every sample point on its own wall.
        let (w, h) = (16u32, 8u32);
        let sps: Vec<ShadingPoint> = (0..w * h)
            .map(|m| {
                let (x, y) = ((m % w) as f32, (m / w) as f32);
                let n = if x < 8.0 { Vec3::X } else { Vec3::Z };
                sp(Vec3::new(x * 0.01, y * 0.01, 0.0), n)
            })
            .collect();
        let c = cluster(&params(w, h, 2, 0.3, 7), &sps, 3);
        let left = c.labels[0];
        for m in 0..(w * h) as usize {
            let on_left = (m as u32 % w) < 8;
            assert_eq!(c.labels[m] == left, on_left, "pixel {m}");
        }
        for (j, &s) in c.samples.iter().enumerate() {
            assert_eq!(c.labels[s as usize], j as u32);
        }
        assert_eq!(c.centers.iter().map(|c| c.count).sum::<u32>(), w * h);
    }

    #[test]
    fn interpolation_reproduces_a_constant_and_the_sample_itself() {
        let (w, h) = (4u32, 1u32);
        let sps: Vec<ShadingPoint> = (0..4)
            .map(|x| sp(Vec3::new(x as f32, 0.0, 0.0), Vec3::Z))
            .collect();
        let labels = [0, 0, 1, 1];
        let samples = [(sps[0].pos, Vec3::Z, true), (sps[3].pos, Vec3::Z, true)];
        let radius = [1.0, 1.0];
        // Equal irradiance everywhere: any convex weights give it back.
        let e = [Vec3::splat(0.5), Vec3::splat(0.5)];
        let mut s = Samples {
            labels: &labels,
            points: &samples,
            radius: &radius,
            irradiance: &e,
            stride: 2,
        };
        for m in 0..4 {
            let v = interpolate(w, h, m, &sps[m as usize], &s);
            assert!(
                (v - Vec3::splat(0.5)).abs().max_element() < 1e-6,
                "{m}: {v}"
            );
        }
        // Pixel 1 between sample 0 (distance 1) and sample 1 (distance 2): weights 1 and 1/2.
        let e = [Vec3::splat(1.0), Vec3::splat(4.0)];
        s.irradiance = &e;
        let v = interpolate(w, h, 1, &sps[1], &s);
        let want = (1.0 * 1.0 + 0.5 * 4.0) / 1.5;
        assert!((v.x - want).abs() < 1e-5, "{v} vs {want}");
        // Pixel 0 is sample 0: its irradiance exactly.
        let v = interpolate(w, h, 0, &sps[0], &s);
        assert_eq!(v, Vec3::splat(1.0));
    }

    #[test]
    fn radius_is_the_clamped_harmonic_mean() {
        // 32 rays at distance 2: R = 2.
        assert!((radius_from_sum(32.0 / 2.0, 10.0) - 2.0).abs() < 1e-6);
        assert_eq!(radius_from_sum(0.0, 10.0), 10.0);
        assert_eq!(radius_from_sum(1e9, 10.0), 10.0 * RADIUS_MIN);
        assert_eq!(interp_stride(640 * 480, 3072), 10);
        assert_eq!(grid_step(640 * 480, 3072), 2);
        assert_eq!(grid_step(640 * 480, 8000), 1);
        // 320 × 240 grid pixels: a 512 side; 1 + 4 + … + 4^8 stored nodes.
        assert_eq!(quadtree_levels(320, 240), 9);
        assert_eq!(quadtree_levels(1, 1), 1);
        assert_eq!(stored_nodes(9), 87_381);
    }
}
