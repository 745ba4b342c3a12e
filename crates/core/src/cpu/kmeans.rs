//! CPU twin of `shaders-wgsl/kmeans.wgsl` (Alg. 1 and 2): the same sampling, initial centroids, grid,
//! metric (Eq. 7), fixed-point sums, fallbacks and tie-breaking, in plain sequential Rust.

use glam::Vec3;

use super::grid::CentreGrid;
use crate::gi::kmeans::KmParams;
use crate::settings::Adaptations;

const POS_SCALE: f32 = 16777216.0;
const NRM_SCALE: f32 = 8388608.0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    pub pos: Vec3,
    pub valid: bool,
    pub nrm: Vec3,
}

impl Point {
    /// Reads point `m` of a GPU array with `stride` vec4s per point.
    pub fn from_vec4s(data: &[[f32; 4]], m: usize, stride: usize) -> Point {
        let p = data[m * stride];
        let n = data[m * stride + 1];
        Point {
            pos: Vec3::new(p[0], p[1], p[2]),
            valid: p[3] > 0.0,
            nrm: Vec3::new(n[0], n[1], n[2]),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Centroid {
    pub pos: Vec3,
    pub valid: bool,
    pub nrm: Vec3,
}

#[derive(Clone, Debug)]
pub struct CpuClustering {
    pub centroids: Vec<Centroid>,
    pub sample_assign: Vec<u32>,
    /// M × F.
    pub assign: Vec<u32>,
    pub weights: Vec<f32>,
    /// Per cluster: representative member index (u32::MAX when unused).
    pub reps: Vec<u32>,
    /// Per cluster: the representative as a point (`rep_points`).
    pub rep_points: Vec<RepPoint>,
    /// Iterations run (fewer than asked when one changed no assignment).
    pub iterations_run: u32,
}

pub fn sample_index(p: &KmParams, s: u32) -> u32 {
    let g = p.gamma.max(1);
    let h = (s
        .wrapping_mul(747796405)
        .wrapping_add(p.seed.wrapping_mul(2891336453)))
        ^ (s >> 7);
    (s * g + (h >> 8) % g).min(p.num_points - 1)
}

/// The cluster sampled point `s` proposes itself to for re-seeding in iteration `iteration` (1 in
/// the first; the grid builds so far): twin of `reseed_target` in kmeans.wgsl.
pub fn reseed_target(p: &KmParams, s: u32, iteration: u32) -> u32 {
    reseed_mix(p, s.wrapping_mul(747796405), iteration) % p.k.max(1)
}

/// The sampled point an empty cluster `k` is re-seeded at in an iteration without orphans (the
/// cluster stays empty when it is invalid): twin of `reseed_draw` in kmeans.wgsl.
pub fn reseed_draw(p: &KmParams, k: u32, iteration: u32) -> u32 {
    let x = k.wrapping_mul(2654435761).wrapping_add(1013904223);
    reseed_mix(p, x, iteration) % p.num_sampled.max(1)
}

fn reseed_mix(p: &KmParams, x: u32, iteration: u32) -> u32 {
    let mut h = x
        .wrapping_add(iteration.wrapping_mul(2891336453))
        .wrapping_add(p.seed.wrapping_mul(1442695041));
    h = ((h >> ((h >> 28) + 4)) ^ h).wrapping_mul(277803737);
    (h >> 22) ^ h
}

/// Eq. (7): |p − c| when n_p · n_c > n_t, else ∞ (`f32::MAX`). Twin of `eq7_dist` in
/// common/kmeans.wgsl.
pub fn eq7_dist(p: &Point, c: &Centroid, n_t: f32) -> f32 {
    if p.nrm.dot(c.nrm) > n_t {
        (p.pos - c.pos).length()
    } else {
        f32::MAX
    }
}

/// Alg. 1 line 5: the grid over the valid centroids (`cpu::grid`; kmeans/grid.wgsl builds it
/// without the guard for centres along a line, `along_line`).
fn grid(p: &KmParams, cs: &[Centroid]) -> CentreGrid {
    let valid = cs.iter().enumerate().filter(|(_, c)| c.valid);
    let centres = valid.map(|(k, c)| (k as u32, c.pos));
    CentreGrid::build(centres, p.k, p.lo, p.ext, false)
}

/// Cells of the grid Alg. 1 line 5 builds over these centroids (the GPU's grid has the same; tests use
/// it to know how many blocks its prefix sum spans).
pub fn grid_cells(p: &KmParams, cs: &[Centroid]) -> u32 {
    grid(p, cs).cells() as u32
}

/// The adaptations `p` was made with (`KmParams::adapt`; kmeans.wgsl's overrides `RESEED`, ...).
pub fn adapt(p: &KmParams) -> Adaptations {
    Adaptations::from_bits(p.adapt)
}

fn before(r: f32, k: u32, rd: f32, rk: u32) -> bool {
    r < rd || (r == rd && k < rk)
}

/// Rings searched while iterating (`ITER_RINGS` in kmeans.wgsl): a sampled point with no centroid
/// passing n_t within them stays out of the iteration's update.
pub const ITER_RINGS: i32 = 3;
/// Rings searched with Eq. (7) in the final assignment before the fallback by position alone
/// (`FINAL_RINGS` in kmeans.wgsl).
pub const FINAL_RINGS: i32 = 4;

/// The F nearest centroids by Eq. (7) in the 27 cells around the point, with the shader's fallbacks
/// (`bounded`: the iterations' search, `ITER_RINGS` rings and no fallback).
fn nearest(
    g: &CentreGrid,
    cs: &[Centroid],
    pt: &Point,
    n_t: f32,
    f: usize,
    bounded: bool,
    adapt: Adaptations,
) -> Vec<(u32, f32)> {
    let mut best: Vec<(u32, f32)> = Vec::new();
    let c = g.coord(pt.pos);
    let scan = |best: &mut Vec<(u32, f32)>, ring: i32, f: usize, normals: bool| {
        for k in g.ring(c, ring) {
            let r = if normals {
                eq7_dist(pt, &cs[k as usize], n_t)
            } else {
                (pt.pos - cs[k as usize].pos).length()
            };
            if r < f32::MAX {
                if best.len() == f {
                    let (lk, lr) = best[f - 1];
                    if !before(r, k, lr, lk) {
                        continue;
                    }
                    best.pop();
                }
                let at = best
                    .iter()
                    .position(|&(bk, br)| before(r, k, br, bk))
                    .unwrap_or(best.len());
                best.insert(at, (k, r));
            }
        }
    };
    scan(&mut best, 1, f, true);
    if bounded {
        // While iterating: ITER_RINGS rings with the metric, no further fallback.
        let mut ring = 2;
        while adapt.ring_fallback && best.is_empty() && ring <= ITER_RINGS {
            scan(&mut best, ring, f, true);
            ring += 1;
        }
        return best;
    }
    let maxr = g.max_ring();
    let mut ring = 2;
    while adapt.ring_fallback && best.is_empty() && ring <= FINAL_RINGS.min(maxr) {
        scan(&mut best, ring, f, true);
        ring += 1;
    }
    let mut ring = 1;
    while adapt.position_fallback && best.is_empty() && ring <= maxr {
        scan(&mut best, ring, 1, false);
        ring += 1;
    }
    best
}

/// Alg. 1 line 2 for cluster `kk`: the first valid sampled point of stratum `kk` (twin of
/// `stratum_centroid` in kmeans.wgsl); an invalid centroid when the stratum has none.
pub fn stratum_centroid(points: &[Point], p: &KmParams, kk: u32) -> Centroid {
    let s_n = p.num_sampled;
    let s0 = (kk as f32 * (s_n as f32 / p.k as f32)).floor() as u32;
    let s1 = (((kk + 1) as f32 * (s_n as f32 / p.k as f32)).floor() as u32).max(s0 + 1);
    (s0..s1.min(s_n))
        .map(|s| points[sample_index(p, s) as usize])
        .find(|pt| pt.valid)
        .map_or(
            Centroid {
                pos: Vec3::ZERO,
                valid: false,
                nrm: Vec3::Z,
            },
            |pt| Centroid {
                pos: pt.pos,
                valid: true,
                nrm: pt.nrm,
            },
        )
}

/// A cluster's representative as a point (kmeans.wgsl `rep_points`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RepPoint {
    pub pos: Vec3,
    /// The cluster has a representative.
    pub valid: bool,
    pub nrm: Vec3,
    /// It is the previous frame's, kept by a warm start.
    pub previous: bool,
}

impl RepPoint {
    pub const NONE: RepPoint = RepPoint {
        pos: Vec3::ZERO,
        valid: false,
        nrm: Vec3::Z,
        previous: false,
    };

    /// Reads K of them from the GPU layout (2 vec4s each).
    pub fn from_vec4s(raw: &[[f32; 4]]) -> Vec<RepPoint> {
        raw.chunks(2)
            .map(|r| RepPoint {
                pos: Vec3::new(r[0][0], r[0][1], r[0][2]),
                valid: r[0][3] > 0.0,
                nrm: Vec3::new(r[1][0], r[1][1], r[1][2]),
                previous: r[1][3] == 1.0,
            })
            .collect()
    }
}

/// Twin of `warm_keeps` in kmeans.wgsl: whether surface point `q` (normal `nq`) of the previous
/// frame is still seen by the view in `p.warm`.
pub fn warm_keeps(points: &[Point], p: &KmParams, q: Vec3, nq: Vec3) -> bool {
    let v = &p.warm;
    let (w, h) = (v.size[0], v.size[1]);
    let eye = v.eye_point();
    let Some((x, y, _)) = v.project(q - eye, 0.0) else {
        return false;
    };
    if !(x >= 0.0 && y >= 0.0 && x < w as f32 && y < h as f32) {
        return false;
    }
    let m = (y as u32).min(h - 1) * w + (x as u32).min(w - 1);
    let Some(pt) = points.get(m as usize).filter(|_| m < p.num_points) else {
        return false;
    };
    if !pt.valid || pt.nrm.dot(nq) <= p.normal_threshold {
        return false;
    }
    let tol = v.eye[3] * (pt.pos - eye).length();
    pt.nrm.dot(q - pt.pos).abs() <= tol
}

/// Twin of `warm_centroids`: a previous cluster is kept where the view still sees its representative
/// (every valid one without a view), the others start from their strata. Returns the initial
/// centroids, the representatives that may be kept (`rep_store`), and how many clusters were kept.
pub fn warm_centroids(
    points: &[Point],
    p: &KmParams,
    previous: &[Centroid],
    previous_reps: &[RepPoint],
) -> (Vec<Centroid>, Vec<Option<RepPoint>>, u32) {
    let mut kept = 0;
    let mut candidates = vec![None; p.k as usize];
    let cs = (0..p.k)
        .map(|kk| {
            let i = kk as usize;
            if kk < p.warm.size[2] {
                let (c, r) = (previous[i], previous_reps[i]);
                let seen = p.warm.size[0] == 0 || (r.valid && warm_keeps(points, p, r.pos, r.nrm));
                if c.valid && seen {
                    kept += 1;
                    candidates[i] = Some(r);
                    return c;
                }
            }
            stratum_centroid(points, p, kk)
        })
        .collect();
    (cs, candidates, kept)
}

/// Alg. 1 + Alg. 2 on the CPU, mirroring the shader step by step.
pub fn kmeans(points: &[Point], p: &KmParams, iterations: u32) -> CpuClustering {
    let cs = (0..p.k).map(|kk| stratum_centroid(points, p, kk)).collect();
    kmeans_from(points, p, iterations, cs, vec![None; p.k as usize])
}

/// `kmeans` warm-started from the previous clustering's centroids and representative points (`p`
/// made by `KmParams::with_warm`), with the iterations `gi::kmeans::warm_iterations` gives, as
/// `KMeans::run` does with a `Warm`. Also returns how many clusters were kept.
pub fn kmeans_warm(
    points: &[Point],
    p: &KmParams,
    iterations: u32,
    previous: &[Centroid],
    previous_reps: &[RepPoint],
) -> (CpuClustering, u32) {
    let (cs, candidates, kept) = warm_centroids(points, p, previous, previous_reps);
    let n = crate::gi::kmeans::warm_iterations(iterations, kept, p.k);
    (kmeans_from(points, p, n, cs, candidates), kept)
}

/// Alg. 1 from the initial centroids `cs`, then Alg. 2; `candidates`: the representatives a warm
/// start may keep (twin of `rep_store`).
fn kmeans_from(
    points: &[Point],
    p: &KmParams,
    iterations: u32,
    cs: Vec<Centroid>,
    candidates: Vec<Option<RepPoint>>,
) -> CpuClustering {
    let k = p.k as usize;
    let mut alg1 = Alg1 {
        points,
        p,
        sample_assign: vec![u32::MAX; p.num_sampled as usize],
        proposals: vec![u32::MAX; k],
        last_empty: cs.iter().rposition(|c| !c.valid),
        cs,
    };
    let mut iterations_run = 0;
    for it in 0..iterations {
        iterations_run += 1;
        let (mut changed, orphans) = alg1.assign_samples(it);
        changed += alg1.update(it, orphans);
        // Converged: the next iterations would repeat this one (as the GPU stops).
        if it >= 1 && changed == 0 {
            break;
        }
    }
    let Alg1 {
        cs, sample_assign, ..
    } = alg1;
    let (assign, weights) = fuzzy_assign(points, p, &cs);
    let (reps, rep_d) = representatives(points, p, &cs, &assign);
    let rep_points = rep_points(points, p, &cs, &reps, &rep_d, &candidates);
    CpuClustering {
        iterations_run,
        rep_points,
        centroids: cs,
        sample_assign,
        assign,
        weights,
        reps,
    }
}

/// Alg. 1's state between its iterations (twin of the buffers iterate.wgsl works on).
struct Alg1<'a> {
    points: &'a [Point],
    p: &'a KmParams,
    cs: Vec<Centroid>,
    /// Per sampled point: its cluster (u32::MAX: none).
    sample_assign: Vec<u32>,
    /// Per cluster: the lowest sampled point an orphan proposed for its re-seeding (u32::MAX: none).
    proposals: Vec<u32>,
    /// The highest-index cluster the last update (at first: the initial centroids) left empty; every
    /// orphan also proposes itself to it.
    last_empty: Option<usize>,
}

impl Alg1<'_> {
    /// Alg. 1 line 5 and lines 6-11 of iteration `it`: the grid over the centroids, then each sampled
    /// point to its nearest centroid by Eq. (7); an orphan proposes itself for re-seeding. Returns how
    /// many assignments changed and whether there was an orphan.
    fn assign_samples(&mut self, it: u32) -> (u32, bool) {
        let p = self.p;
        let g = grid(p, &self.cs);
        let mut changed = 0u32;
        let mut orphans = false;
        for s in 0..p.num_sampled {
            let pt = self.points[sample_index(p, s) as usize];
            let k = if pt.valid {
                nearest(&g, &self.cs, &pt, p.normal_threshold, 1, true, adapt(p))
                    .first()
                    .map_or(u32::MAX, |b| b.0)
            } else {
                u32::MAX
            };
            changed += (k != self.sample_assign[s as usize]) as u32;
            self.sample_assign[s as usize] = k;
            // An orphan (no centroid passing n_t near it) proposes itself for re-seeding; a
            // cluster keeps the lowest index proposed to it.
            if adapt(p).reseed && pt.valid && k == u32::MAX {
                orphans = true;
                let t = reseed_target(p, s, it + 1) as usize;
                self.proposals[t] = self.proposals[t].min(s);
                if let Some(e) = self.last_empty {
                    self.proposals[e] = self.proposals[e].min(s);
                }
            }
        }
        (changed, orphans)
    }

    /// Alg. 1 lines 12-16: the fixed-point sums of the members' positions (relative to the bounds)
    /// and normals per cluster, and the member counts.
    fn sums(&self) -> (Vec<[u64; 6]>, Vec<u32>) {
        let p = self.p;
        let lo = Vec3::from_slice(&p.lo[..3]);
        let ext = Vec3::from_slice(&p.ext[..3]);
        let mut sums = vec![[0u64; 6]; p.k as usize];
        let mut counts = vec![0u32; p.k as usize];
        for s in 0..p.num_sampled {
            let kk = self.sample_assign[s as usize];
            if kk == u32::MAX {
                continue;
            }
            let pt = self.points[sample_index(p, s) as usize];
            let rel = ((pt.pos - lo) / ext).clamp(Vec3::ZERO, Vec3::ONE);
            let nq = (pt.nrm + 1.0).clamp(Vec3::ZERO, Vec3::splat(2.0)) * NRM_SCALE;
            for a in 0..3 {
                sums[kk as usize][a] += (rel[a] * POS_SCALE) as u32 as u64;
                sums[kk as usize][3 + a] += nq[a] as u32 as u64;
            }
            counts[kk as usize] += 1;
        }
        (sums, counts)
    }

    /// Alg. 1 lines 12-18 of iteration `it`: the centroids become their members' mean position and
    /// normalised mean normal; an empty cluster is re-seeded (`reseed_at`) or left out of the grid.
    /// Returns how many clusters were re-seeded (each counts as a change).
    fn update(&mut self, it: u32, orphans: bool) -> u32 {
        let p = self.p;
        let lo = Vec3::from_slice(&p.lo[..3]);
        let ext = Vec3::from_slice(&p.ext[..3]);
        let (sums, counts) = self.sums();
        let mut changed = 0u32;
        self.last_empty = None;
        for kk in 0..p.k as usize {
            let count = counts[kk];
            let proposal = std::mem::replace(&mut self.proposals[kk], u32::MAX);
            if count == 0 && !adapt(p).reseed {
                self.cs[kk].valid = false;
                continue;
            }
            if count == 0 {
                match self.reseed_at(kk, it, proposal, orphans, &counts) {
                    None => {
                        self.cs[kk].valid = false;
                        self.last_empty = Some(kk);
                    }
                    Some(pt) => {
                        changed += 1;
                        self.cs[kk] = Centroid {
                            pos: pt.pos,
                            valid: true,
                            nrm: pt.nrm,
                        };
                    }
                }
                continue;
            }
            let mean =
                |v: u64| ((v >> 32) as u32 as f32 * 4294967296.0 + v as u32 as f32) / count as f32;
            let sm = sums[kk];
            let rel = Vec3::new(mean(sm[0]), mean(sm[1]), mean(sm[2])) / POS_SCALE;
            let nrm = Vec3::new(mean(sm[3]), mean(sm[4]), mean(sm[5])) / NRM_SCALE - 1.0;
            let c = &mut self.cs[kk];
            c.pos = lo + rel * ext;
            c.valid = true;
            let l = nrm.length();
            if !adapt(p).normalised_normal {
                c.nrm = nrm;
            } else if l > 1e-6 {
                c.nrm = nrm / l;
            }
        }
        changed
    }

    /// Where empty cluster `kk` is re-seeded in iteration `it`: at the orphan proposed to it
    /// (`proposal`), or (no orphan this iteration) at a drawn sampled point of a cluster with two or
    /// more members (`counts`); `None`: it stays empty, out of the grid.
    fn reseed_at(
        &self,
        kk: usize,
        it: u32,
        proposal: u32,
        orphans: bool,
        counts: &[u32],
    ) -> Option<Point> {
        let p = self.p;
        match proposal {
            u32::MAX if orphans => None,
            u32::MAX => {
                // Only a draw that splits a cluster (not an invalid point, not a cluster's only
                // member).
                let s = reseed_draw(p, kk as u32, it + 1);
                match self.sample_assign[s as usize] {
                    u32::MAX => None,
                    owner if counts[owner as usize] <= 1 => None,
                    _ => Some(self.points[sample_index(p, s) as usize]),
                }
            }
            s => Some(self.points[sample_index(p, s) as usize]),
        }
    }
}

/// Alg. 2: every point to its F nearest centroids with the weights of Eq. (10), after the plane
/// gate. Returns the M × F assignments and weights.
fn fuzzy_assign(points: &[Point], p: &KmParams, cs: &[Centroid]) -> (Vec<u32>, Vec<f32>) {
    let f = p.f as usize;
    let g = grid(p, cs);
    let m = p.num_points as usize;
    let mut assign = vec![u32::MAX; m * f];
    let mut weights = vec![0f32; m * f];
    for (i, pt) in points.iter().enumerate().take(m) {
        let b = if pt.valid {
            nearest(&g, cs, pt, p.normal_threshold, f, false, adapt(p))
        } else {
            Vec::new()
        };
        // The plane gate (slots 2..F): a dropped slot has distance -1 (weight 0) and no cluster.
        let kept: Vec<bool> = b
            .iter()
            .enumerate()
            .map(|(j, &(kk, _))| j == 0 || plane_gate_keeps(pt, &cs[kk as usize], p.plane_gate))
            .collect();
        let d: Vec<f32> = b
            .iter()
            .zip(&kept)
            .map(|(x, &keep)| if keep { x.1 } else { -1.0 })
            .collect();
        let w = eq10_weights(&d, p.weight_exponent);
        for (j, &(kk, _)) in b.iter().enumerate() {
            if kept[j] {
                assign[i * f + j] = kk;
            }
            weights[i * f + j] = w[j];
        }
    }
    (assign, weights)
}

/// Representatives: the member (in any of its F slots of `assign`) nearest to its centroid, lowest
/// index on ties (reps.wgsl). Returns them per cluster (u32::MAX: none) and that nearest distance
/// (its `f32` bits).
fn representatives(
    points: &[Point],
    p: &KmParams,
    cs: &[Centroid],
    assign: &[u32],
) -> (Vec<u32>, Vec<u32>) {
    let (k, f, m) = (p.k as usize, p.f as usize, p.num_points as usize);
    let member_dist = |i: usize, kk: u32| (points[i].pos - cs[kk as usize].pos).length().to_bits();
    let mut rep_d = vec![u32::MAX; k];
    for i in 0..m {
        for &kk in &assign[i * f..i * f + f] {
            if kk != u32::MAX {
                rep_d[kk as usize] = rep_d[kk as usize].min(member_dist(i, kk));
            }
        }
    }
    let mut reps = vec![u32::MAX; k];
    for i in 0..m {
        for &kk in &assign[i * f..i * f + f] {
            if kk != u32::MAX && member_dist(i, kk) == rep_d[kk as usize] {
                reps[kk as usize] = reps[kk as usize].min(i as u32);
            }
        }
    }
    (reps, rep_d)
}

/// Representatives as points: a kept one (`candidates`) while it is still one of its cluster (its
/// normal agrees with the centroid's, within twice the nearest member distance `rep_d` of it), else
/// the member `reps` names.
fn rep_points(
    points: &[Point],
    p: &KmParams,
    cs: &[Centroid],
    reps: &[u32],
    rep_d: &[u32],
    candidates: &[Option<RepPoint>],
) -> Vec<RepPoint> {
    (0..p.k as usize)
        .map(|kk| {
            if reps[kk] == u32::MAX {
                return RepPoint::NONE;
            }
            let c = &cs[kk];
            if let Some(r) = candidates[kk].filter(|r| r.valid) {
                let nearest = f32::from_bits(rep_d[kk]);
                if r.nrm.dot(c.nrm) > p.normal_threshold
                    && (r.pos - c.pos).length() <= 2.0 * nearest
                {
                    return RepPoint {
                        previous: true,
                        ..r
                    };
                }
            }
            let pt = points[reps[kk] as usize];
            RepPoint {
                pos: pt.pos,
                valid: true,
                nrm: pt.nrm,
                previous: false,
            }
        })
        .collect()
}

/// Twin of `plane_gate_keeps` in kmeans.wgsl: the centroid lies within the gate's angle of the
/// point's tangent plane (`sine`: `gi::kmeans::plane_gate_sine`).
pub fn plane_gate_keeps(pt: &Point, c: &Centroid, sine: f32) -> bool {
    let d = c.pos - pt.pos;
    pt.nrm.dot(d).abs() <= sine * d.length()
}

/// The exact nearest valid centroid by Eq. (7) over all centroids (no grid), or u32::MAX.
pub fn exact_nearest(pt: &Point, cs: &[Centroid], n_t: f32) -> u32 {
    let mut best = (u32::MAX, f32::MAX);
    for (k, c) in cs.iter().enumerate() {
        if !c.valid {
            continue;
        }
        let r = eq7_dist(pt, c, n_t);
        if r < f32::MAX && before(r, k as u32, best.1, best.0) {
            best = (k as u32, r);
        }
    }
    best.0
}

/// The k-means objective: mean squared distance of sampled points to their assigned centroid.
pub fn objective(points: &[Point], p: &KmParams, sample_assign: &[u32], cs: &[Centroid]) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (s, &k) in sample_assign.iter().enumerate() {
        if k != u32::MAX {
            let pt = points[sample_index(p, s as u32) as usize];
            sum += (pt.pos - cs[k as usize].pos).length_squared() as f64;
            n += 1;
        }
    }
    sum / n.max(1) as f64
}

/// A distance at or below this counts as 0 (`ZERO_DIST` in kmeans.wgsl).
pub const ZERO_DIST: f32 = 1e-30;

/// Eq. (10) generalised to w'_f = d_f^-p (twin of `eq10_weights` in kmeans/assign.wgsl): computed
/// as (d_min / d_f)^p normalised, so no distance or p overflows; exact for p = 1 and 0. Negative
/// distances mark unused slots (weight 0); the first distance of 0 (≤ `ZERO_DIST`) takes the whole
/// weight.
pub fn eq10_weights(d: &[f32], p: f32) -> Vec<f32> {
    let zero = d.iter().position(|&x| (0.0..=ZERO_DIST).contains(&x));
    let d_min = d
        .iter()
        .copied()
        .filter(|&x| x >= 0.0)
        .fold(f32::MAX, f32::min);
    let mut w: Vec<f32> = d
        .iter()
        .enumerate()
        .map(|(j, &x)| match zero {
            _ if x < 0.0 => 0.0,
            Some(z) => (j == z) as u32 as f32,
            None => {
                let r = d_min / x;
                match p {
                    1.0 => r,
                    0.0 => 1.0,
                    _ => (p * r.log2()).exp2(),
                }
            }
        })
        .collect();
    let sum: f32 = w.iter().sum();
    if zero.is_none() && sum > 0.0 {
        for x in &mut w {
            *x /= sum;
        }
    }
    w
}

/// Twin of `rep_weights`: Eq. (10) (exponent `p`) with Eq. (7)'s distances to the representatives:
/// one whose normal fails `n_t` is at distance ∞ (weight 0). A point whose representatives all fail
/// keeps its weights to the centroids (`centroid_weights`, Alg. 2's).
pub fn rep_weights(
    points: &[Point],
    f: usize,
    assign: &[u32],
    reps: &[u32],
    centroid_weights: &[f32],
    p: f32,
    n_t: f32,
) -> Vec<f32> {
    let mut out = centroid_weights.to_vec();
    for (m, pt) in points.iter().enumerate() {
        let row = &assign[m * f..m * f + f];
        let d: Vec<f32> = row
            .iter()
            .map(|&k| match k {
                u32::MAX => -1.0,
                k if reps[k as usize] == u32::MAX => -1.0,
                k => {
                    let r = points[reps[k as usize] as usize];
                    if pt.nrm.dot(r.nrm) > n_t {
                        (pt.pos - r.pos).length()
                    } else {
                        -1.0
                    }
                }
            })
            .collect();
        if d.iter().all(|&x| x < 0.0) {
            continue;
        }
        let w = eq10_weights(&d, p);
        out[m * f..m * f + f].copy_from_slice(&w);
    }
    out
}
