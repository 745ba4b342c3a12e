//! Wang, Wang, Zhou, Pan, Bao 2009, "An efficient GPU-based approach for interactive global
//! illumination" (seed `001`), adapted to VPL lighting and ray-traced visibility (docs/methods.md,
//! "wang"): the math of `shaders-wgsl/wang.wgsl` on the CPU, and the steps of the method that run on
//! the CPU in the frame as well (the quadtree seeding, the centre updates and the choice of each
//! cluster's sample point: O(pixels) or O(K) work between the GPU's assignment passes).
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
//! - §3.4, "Interpolation": E(x) = Σ w(s_j) E(s_j) / Σ w(s_j), w(s_j) = 1 / (‖x − s_j‖ / R_j +
//!   √(2 − 2 n(x)·n(s_j))), R_j the harmonic mean distance to the surfaces seen from s_j
//!   (`interpolation_weight`, `harmonic_radius`, `interpolate`).

use glam::Vec3;

use super::rng::{rng_next, rng_seed};
use super::shading::{CpuScene, ShadingPoint, onb};

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
fn halving(start: u32) -> Vec<u32> {
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

    /// ε_q by hand: α = 0.5, points at x = 1, 2, 6 facing +z and x = 3 facing +x. The mean is x = 3
    /// with normal (1, 0, 3)/√10, so ε_q = 0.5 (2 + 1 + 3 + 0) + 3 √(2 − 6/√10) + √(2 − 2/√10) =
    /// 3 + 3 · 0.320364 + 1.169421 = 5.130514 (cargo-mutants: the mean as the sum % count survived).
    #[test]
    fn node_variation_by_hand() {
        let sps = [
            sp(Vec3::X, Vec3::Z),
            sp(2.0 * Vec3::X, Vec3::Z),
            sp(6.0 * Vec3::X, Vec3::Z),
            sp(3.0 * Vec3::X, Vec3::X),
        ];
        let e = node_variation(0.5, &[0, 1, 2, 3], &sps);
        assert!((e - 5.130_514).abs() < 1e-5, "{e}");
        assert_eq!(node_variation(0.5, &[], &sps), 0.0);
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
        let seeds = quadtree_seeds(w, h, &sps, 8, 0.3, 1);
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
        let all = quadtree_seeds(w, h, &holes, 64, 0.3, 1);
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
        let img = Image {
            width: w,
            height: h,
            sps: &sps,
        };
        let c = cluster(img, 2, 0.3, 3, 7, &mut |run| Ok(assign_passes(img, run))).unwrap();
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
        assert_eq!(flood_start(640, 480), 256);
        assert_eq!(flood_start(3, 1), 1);
        assert_eq!(interp_stride(640 * 480, 3072), 10);
        assert_eq!(grid_step(640 * 480, 3072), 2);
        assert_eq!(grid_step(640 * 480, 8000), 1);
        assert_eq!(halving(8), vec![8, 4, 2, 1]);
    }
}
