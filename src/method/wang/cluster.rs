//! wang's CPU stages (Wang, Wang, Zhou, Pan, Bao 2009, "An efficient GPU-based approach for
//! interactive global illumination", seed `001`; docs/methods.md, "wang"): the steps of §3.2 that run
//! on the CPU between the GPU's assignment passes (the quadtree seeding, the centre updates and the
//! choice of each cluster's sample point: O(pixels) or O(K) work), and the math they share with
//! `shaders-wgsl/wang.wgsl`. The CPU twins of the kernels are `cpu::wang`.
//!
//! - §3.2, Eq. (2): ε = α‖x_i − x_k‖ + √(2 − 2 n_i·n_k), positions in scene diagonals
//!   (`eq2_error`; the caller passes α / diagonal).
//! - §3.2, "Adaptive Seeding of Sample Points": a screen-space quadtree of the shading points, each
//!   node's geometric variation ε_q by Eq. (2) against its mean position and normal, K seeds
//!   distributed from the root to the four children in proportion to their ε_q, a seed jittered in
//!   a node that gets one (`quadtree_seeds`, `apportion`).
//! - §3.2, "K-Means Clustering": every shading point to its closest centre by Eq. (2), centres the
//!   mean position and normal of their members, and finally "the shading point with the smallest
//!   error" as the cluster's irradiance sample point (`assign_pass`, `update_centers`,
//!   `sample_points`, `cluster`).
//! - §3.4's weight w(s_j) = 1 / (‖x − s_j‖ / R_j + √(2 − 2 n(x)·n(s_j))) (`interpolation_weight`)
//!   and R_j from its rays (`radius_from_sum`).

use glam::Vec3;

use crate::gi::primary::ShadingPoint;
use crate::gi::rng::{rng_next, rng_seed};

pub const INVALID: u32 = u32::MAX;

/// Rays a sample point traces for its harmonic mean distance R_j (§3.4), two dispatches of 16.
pub const RADIUS_RAYS: u32 = 32;
/// Rays one invocation traces per dispatch (lavapipe's loop budget, docs/architecture.md).
pub const RADIUS_RAYS_PER_DISPATCH: u32 = 16;
/// R_j is at least this fraction of the scene diagonal (a sample in a corner whose rays all hit at
/// once would otherwise weigh nothing but itself) and at most the diagonal (every ray missed).
pub const RADIUS_MIN: f32 = 1e-3;

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

/// Splits `k` seeds among a node's four children in proportion to `weight` (their ε_q), each at most
/// `cap` (its valid shading points): floors first, then the largest remainders (lowest index on a
/// tie), repeated over the children with room until every seed is placed (or every child is full).
/// With no weight anywhere, equal shares.
pub fn apportion(k: u32, weight: [f64; 4], cap: [u32; 4]) -> [u32; 4] {
    let mut a = [0u32; 4];
    let mut left = k.min(cap.iter().sum());
    while left > 0 {
        let open: Vec<usize> = (0..4).filter(|&i| a[i] < cap[i]).collect();
        let wsum: f64 = open.iter().map(|&i| weight[i].max(0.0)).sum();
        let share = |i: usize| {
            if wsum > 0.0 {
                weight[i].max(0.0) / wsum
            } else {
                1.0 / open.len() as f64
            }
        };
        let mut rest = Vec::new();
        let mut given = 0;
        for &i in &open {
            let ideal = left as f64 * share(i);
            let f = (ideal.floor() as u32).min(cap[i] - a[i]);
            a[i] += f;
            given += f;
            rest.push((ideal - ideal.floor(), i));
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

/// One quadtree node: the square [x0, x0 + size) × [y0, y0 + size) of the padded image.
#[derive(Clone, Copy, Debug)]
struct Node {
    x0: u32,
    y0: u32,
    size: u32,
}

/// The valid shading points of a node's square, in row-major order.
fn node_points(n: Node, width: u32, height: u32, sps: &[ShadingPoint]) -> Vec<u32> {
    let mut out = Vec::new();
    for y in n.y0..(n.y0 + n.size).min(height) {
        for x in n.x0..(n.x0 + n.size).min(width) {
            let m = y * width + x;
            if sps[m as usize].valid {
                out.push(m);
            }
        }
    }
    out
}

/// ε_q of §3.2 for a node: Eq. (2) summed over its shading points against their mean position and
/// (normalised) mean normal, "treating all shading points belonging to quadtree node q as a
/// cluster". The sum (not the mean) so that a node's share grows with its size as well as with its
/// variation.
pub fn node_variation(alpha: f32, points: &[u32], sps: &[ShadingPoint]) -> f64 {
    if points.is_empty() {
        return 0.0;
    }
    let (mut p, mut n) = (Vec3::ZERO, Vec3::ZERO);
    for &m in points {
        p += sps[m as usize].pos;
        n += sps[m as usize].normal;
    }
    let p = p / points.len() as f32;
    let n = n.normalize_or_zero();
    points
        .iter()
        .map(|&m| {
            let s = &sps[m as usize];
            eq2_error(alpha, s.pos, s.normal, p, n) as f64
        })
        .sum()
}

/// §3.2's adaptive seeding: K seed pixels (distinct, valid; fewer only when there are fewer valid
/// shading points), distributed down a screen-space quadtree of the image (padded to a power of two)
/// in proportion to each child's ε_q (`node_variation`), jittered within a node that gets one seed
/// (a uniformly drawn valid shading point of its square). A node with as many seeds as shading
/// points takes every one of them.
pub fn quadtree_seeds(
    width: u32,
    height: u32,
    sps: &[ShadingPoint],
    k: u32,
    alpha: f32,
    seed: u32,
) -> Vec<u32> {
    let side = width.max(height).max(1).next_power_of_two();
    let mut out = Vec::new();
    // Breadth first, one level at a time (the paper processes each level in parallel).
    let root = Node {
        x0: 0,
        y0: 0,
        size: side,
    };
    let root_points = node_points(root, width, height, sps);
    let mut level: Vec<(Node, u32, Vec<u32>)> = vec![(root, k, root_points)];
    let mut node_id = 0u32;
    while !level.is_empty() {
        let mut next = Vec::new();
        for (node, kn, points) in level {
            node_id += 1;
            if kn == 0 || points.is_empty() {
                continue;
            }
            if kn as usize >= points.len() {
                out.extend_from_slice(&points);
                continue;
            }
            if kn == 1 {
                // Jittered sampling within the quad.
                let mut st = rng_seed(seed, node_id, 0x5eed);
                let u = rng_next(&mut st);
                let i = ((u * points.len() as f32) as usize).min(points.len() - 1);
                out.push(points[i]);
                continue;
            }
            let h = node.size / 2;
            let kids = [(0, 0), (h, 0), (0, h), (h, h)].map(|(dx, dy)| Node {
                x0: node.x0 + dx,
                y0: node.y0 + dy,
                size: h,
            });
            let kid_points = kids.map(|c| node_points(c, width, height, sps));
            let weight = [0, 1, 2, 3].map(|i| node_variation(alpha, &kid_points[i], sps));
            let cap = [0, 1, 2, 3].map(|i| kid_points[i].len() as u32);
            let share = apportion(kn, weight, cap);
            for (i, pts) in kid_points.into_iter().enumerate() {
                next.push((kids[i], share[i], pts));
            }
        }
        level = next;
    }
    out
}

/// A cluster centre: mean position and normalised mean normal of its members (`count` 0: empty).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Center {
    pub pos: Vec3,
    pub nrm: Vec3,
    pub count: u32,
}

impl Center {
    /// As the GPU reads it: two vec4 (position with w = 1 when the cluster has members, normal).
    pub fn to_gpu(&self) -> [[f32; 4]; 2] {
        [
            self.pos.extend((self.count > 0) as u32 as f32).to_array(),
            self.nrm.extend(0.0).to_array(),
        ]
    }
}

/// The centres of the seed pixels (each its own shading point).
pub fn seed_centers(seeds: &[u32], sps: &[ShadingPoint]) -> Vec<Center> {
    seeds
        .iter()
        .map(|&m| {
            let s = &sps[m as usize];
            Center {
                pos: s.pos,
                nrm: s.normal,
                count: 1,
            }
        })
        .collect()
}

/// The labels of the seeds alone (every other pixel `INVALID`), where the first assignment pass
/// starts.
pub fn seed_labels(n: usize, seeds: &[u32]) -> Vec<u32> {
    let mut l = vec![INVALID; n];
    for (j, &m) in seeds.iter().enumerate() {
        l[m as usize] = j as u32;
    }
    l
}

/// A frame's shading points: `width` × `height`, row-major.
#[derive(Clone, Copy)]
pub struct Image<'a> {
    pub width: u32,
    pub height: u32,
    pub sps: &'a [ShadingPoint],
}

/// One run of assignment passes with the same centres: the labels the first pass starts from, the
/// strides in order, the grid step and α per unit of length.
#[derive(Clone, Copy)]
pub struct AssignRun<'a> {
    pub labels: &'a [u32],
    pub centers: &'a [Center],
    pub strides: &'a [u32],
    pub step: u32,
    pub alpha: f32,
}

/// One assignment pass (twin of `wang.wgsl`'s `assign`) over the pixels of the grid of `step`
/// (x and y multiples of it; the others keep their labels): each valid pixel takes, among the labels of
/// the pixels at offsets {−s, 0, s}² (`stride` s, inside the image), the cluster whose centre is
/// closest by Eq. (2) (the first on a tie, in the order dy, dx = −1, 0, 1); `INVALID` where no
/// candidate has a centre. Adaptation: the paper searches the centres near x_i in a kd-tree; here the
/// candidates are those of the screen neighbourhood, and passes of halving strides (a jump flood,
/// `cluster`) carry the seeds' labels across the image.
pub fn assign_pass(img: Image, run: &AssignRun, labels: &[u32], stride: u32) -> Vec<u32> {
    let Image { width, height, sps } = img;
    let (centers, alpha) = (run.centers, run.alpha);
    let s = stride as i64;
    let g = run.step.max(1);
    (0..width * height)
        .map(|m| {
            let sp = &sps[m as usize];
            if !(m % width).is_multiple_of(g) || !(m / width).is_multiple_of(g) {
                return labels[m as usize];
            }
            if !sp.valid {
                return INVALID;
            }
            let (x, y) = ((m % width) as i64, (m / width) as i64);
            let mut best = INVALID;
            let mut best_d = f32::INFINITY;
            for dy in -1..=1i64 {
                for dx in -1..=1i64 {
                    let (qx, qy) = (x + dx * s, y + dy * s);
                    if qx < 0 || qy < 0 || qx >= width as i64 || qy >= height as i64 {
                        continue;
                    }
                    let l = labels[(qy * width as i64 + qx) as usize];
                    if l == INVALID || centers[l as usize].count == 0 {
                        continue;
                    }
                    let c = &centers[l as usize];
                    let d = eq2_error(alpha, sp.pos, sp.normal, c.pos, c.nrm);
                    if d < best_d {
                        best_d = d;
                        best = l;
                    }
                }
            }
            best
        })
        .collect()
}

/// `assign_pass` once per stride of `run`, in order.
pub fn assign_passes(img: Image, run: &AssignRun) -> Vec<u32> {
    let mut l = run.labels.to_vec();
    for &s in run.strides {
        l = assign_pass(img, run, &l, s);
    }
    l
}

/// The grid step of the k-means iterations: 2 (a quarter of the pixels) when that leaves at least
/// `MIN_GRID_POINTS_PER_CLUSTER` grid points a cluster, else 1. Adaptation (docs/methods.md): the
/// paper's k-means runs on every shading point; here, as Colom's γ does, the iterations run on a
/// subset and the full image is labelled at the end.
pub fn grid_step(pixels: u32, k: u32) -> u32 {
    if pixels / 4 >= MIN_GRID_POINTS_PER_CLUSTER * k.max(1) {
        2
    } else {
        1
    }
}

pub const MIN_GRID_POINTS_PER_CLUSTER: u32 = 16;

/// The halving strides from `start` down to 1.
pub(crate) fn halving(start: u32) -> Vec<u32> {
    std::iter::successors(Some(start.max(1)), |&s| (s > 1).then_some(s / 2)).collect()
}

/// The centres of `labels` (K of them): mean position and normalised mean normal of the members,
/// in f64 (exact and independent of order); an empty cluster keeps count 0.
pub fn update_centers(sps: &[ShadingPoint], labels: &[u32], k: usize) -> Vec<Center> {
    let mut sum = vec![([0f64; 3], [0f64; 3], 0u32); k];
    for (sp, &l) in sps.iter().zip(labels) {
        if l == INVALID || !sp.valid {
            continue;
        }
        let e = &mut sum[l as usize];
        for c in 0..3 {
            e.0[c] += sp.pos[c] as f64;
            e.1[c] += sp.normal[c] as f64;
        }
        e.2 += 1;
    }
    sum.iter()
        .map(|(p, n, count)| {
            let c = (*count).max(1) as f64;
            let pos = Vec3::new((p[0] / c) as f32, (p[1] / c) as f32, (p[2] / c) as f32);
            let nrm = Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32).normalize_or_zero();
            Center {
                pos,
                nrm,
                count: *count,
            }
        })
        .collect()
}

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

/// The stride of the first flood pass: the largest power of two at most half the longer side.
pub fn flood_start(width: u32, height: u32) -> u32 {
    let half = (width.max(height) / 2).max(1);
    1 << (31 - half.leading_zeros())
}

/// The strides of the assignment passes of one k-means iteration after the flood: boundaries move
/// up to 3 pixels an iteration.
pub const ITERATION_STRIDES: [u32; 2] = [2, 1];

/// A run of assignment passes → the labels after the last.
pub type AssignPasses<'a> = dyn FnMut(&AssignRun) -> anyhow::Result<Vec<u32>> + 'a;

/// Wang's clustering (§3.2), done.
#[derive(Clone, Debug, PartialEq)]
pub struct WangClusters {
    /// Per pixel its cluster (`INVALID`: not a valid shading point).
    pub labels: Vec<u32>,
    pub centers: Vec<Center>,
    /// Per cluster its sample point's pixel (`INVALID`: empty).
    pub samples: Vec<u32>,
    /// Assignment passes run.
    pub passes: u32,
}

/// The whole §3.2 clustering with `assign` doing a run of assignment passes with the same centres,
/// one per stride in order, over the grid of a step (`assign_passes` on the CPU, or the GPU's):
/// the quadtree seeds among the grid's shading points (`grid_step`), a jump flood of the seeds'
/// labels over the grid (strides from `flood_start` down to the step), then `iterations` rounds of
/// centre update and `ITERATION_STRIDES` passes (times the step), a centre update and, with a step
/// above 1, the passes that label every pixel (strides step/2 … 1, then 1 again); a last centre update
/// and the sample points.
pub fn cluster(
    img: Image,
    k: u32,
    alpha: f32,
    iterations: u32,
    seed: u32,
    assign: &mut AssignPasses,
) -> anyhow::Result<WangClusters> {
    let Image { width, height, sps } = img;
    let g = grid_step(width * height, k);
    let (wg, hg) = (width.div_ceil(g), height.div_ceil(g));
    let grid: Vec<ShadingPoint> = (0..wg * hg)
        .map(|i| sps[((i / wg) * g * width + (i % wg) * g) as usize])
        .collect();
    let seeds: Vec<u32> = quadtree_seeds(wg, hg, &grid, k, alpha, seed)
        .into_iter()
        .map(|i| (i / wg) * g * width + (i % wg) * g)
        .collect();
    let mut centers = seed_centers(&seeds, sps);
    let mut labels = seed_labels(sps.len(), &seeds);
    let mut passes = 0;
    if seeds.is_empty() {
        return Ok(WangClusters {
            labels,
            centers,
            samples: vec![],
            passes,
        });
    }
    let mut run = |labels: &[u32], centers: &[Center], strides: &[u32], step: u32| {
        passes += strides.len() as u32;
        assign(&AssignRun {
            labels,
            centers,
            strides,
            step,
            alpha,
        })
    };
    let flood: Vec<u32> = halving(flood_start(wg, hg)).iter().map(|s| s * g).collect();
    labels = run(&labels, &centers, &flood, g)?;
    for _ in 0..iterations {
        centers = update_centers(sps, &labels, seeds.len());
        labels = run(&labels, &centers, &ITERATION_STRIDES.map(|s| s * g), g)?;
    }
    if g > 1 {
        centers = update_centers(sps, &labels, seeds.len());
        let mut strides = halving(g / 2);
        strides.push(1);
        labels = run(&labels, &centers, &strides, 1)?;
    }
    centers = update_centers(sps, &labels, seeds.len());
    let samples = sample_points(sps, &labels, &centers, alpha);
    Ok(WangClusters {
        labels,
        centers,
        samples,
        passes,
    })
}

/// The stride of the interpolation's neighbourhood: about the spacing of K clusters over the pixels.
pub fn interp_stride(pixels: u32, k: u32) -> u32 {
    ((pixels as f32 / k.max(1) as f32).sqrt().round() as u32).max(1)
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

/// The sample points as shading points with albedo 1 (what the gather at the sample points reads:
/// their irradiance times 1/π, `reference.wgsl` with ρ = 1/π); an empty cluster's all zero.
pub fn sample_gbuffer(sps: &[ShadingPoint], samples: &[u32]) -> Vec<[[f32; 4]; 4]> {
    sample_to_gpu(sps, samples)
        .into_iter()
        .map(|[p, n]| {
            let albedo = if p[3] > 0.0 {
                [1.0, 1.0, 1.0, 0.0]
            } else {
                [0.0; 4]
            };
            [p, n, albedo, [0.0; 4]]
        })
        .collect()
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
