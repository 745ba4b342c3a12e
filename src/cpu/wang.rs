//! CPU twins of `shaders-wgsl/wang.wgsl` (seed 001, docs/methods.md "wang"): §3.4's R_j and the
//! interpolation E(x) = Σ w(s_j) E(s_j) / Σ w(s_j) (`harmonic_radius`, `interpolate`). The method's
//! production CPU stages and shared math are `method::wang::cluster`, re-exported here.

use glam::Vec3;

pub use crate::method::wang::cluster::*;

use super::shading::{CpuScene, onb};
use crate::gi::primary::ShadingPoint;
use crate::gi::rng::{rng_next, rng_seed};

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
