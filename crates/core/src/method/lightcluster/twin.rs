//! CPU twin of `shaders-wgsl/lightcluster.wgsl` (seed 002, docs/methods.md "lightcluster"): §3.2's
//! cluster-shadowed shading, with the paper's disc (`disc_points`, `disc_visibility`) or member
//! targets (`target_visible`; not in the paper), `shade`. The clustering (§3.1) and the member
//! groups are production code, `method::lightcluster::cluster`, re-exported here.
//!
//! For tests only (`tests/methods.rs` checks the shader against it): no production code calls it.

use glam::Vec3;

pub use super::cluster::*;

use super::settings::LcVisibility;
use crate::cpu::shading::{CpuScene, onb};
use crate::cpu::vpl::eq5_vpl_radiance;
use crate::gi::primary::ShadingPoint;
use crate::gi::rng::pcg_hash;
use crate::gi::vpl_trace::Vpl;

/// The `DISC_SAMPLES` points of a disc the visibility rays aim at: a Vogel (golden-angle) spiral,
/// r = R √((i + ½) / N), θ = 2.39996 i, in the disc's plane (Duff et al.'s basis of its normal).
pub fn disc_points(d: &Disc) -> Vec<Vec3> {
    let (t, bt) = onb(d.normal);
    (0..DISC_SAMPLES)
        .map(|i| {
            let r = d.radius * ((i as f32 + 0.5) / DISC_SAMPLES as f32).sqrt();
            let th = 2.399_963 * i as f32;
            d.center + (t * th.cos() + bt * th.sin()) * r
        })
        .collect()
}

/// (1/A_c) ∫ V over a cluster's disc from (p, n): the fraction of `disc_points` visible, each ray
/// offset as Eq. (5)'s (`CpuScene::vpl_visible`, the point offset along the disc's normal).
pub fn disc_visibility(cpu: &CpuScene, p: Vec3, n: Vec3, d: &Disc) -> f32 {
    let seen = disc_points(d)
        .iter()
        .filter(|q| {
            let v = Vpl {
                pos: q.extend(0.0).to_array(),
                nrm: d.normal.extend(0.0).to_array(),
                flux: [0.0; 4],
            };
            cpu.vpl_visible(p, n, &v)
        })
        .count();
    seen as f32 / DISC_SAMPLES as f32
}

/// The uniform number of pixel `i` and sorted VPL `j` in [0, 1) that decides the draw. Twin of
/// `member_u`.
pub fn member_u(i: u32, j: u32) -> f32 {
    (pcg_hash(pcg_hash(i) ^ j) >> 8) as f32 * (1.0 / 16777216.0)
}

/// A weighted reservoir of one: after `w` joined a total that is now `total`, whether the member
/// drawn becomes the new one (probability w / total). Not in the paper. Twin of `member_draw`.
pub fn member_draw(u: f32, w: f32, total: f32) -> bool {
    u * total < w
}

/// A group's light at (p, n): its summed `terms` when the member drawn is visible (Eq. (5)'s shadow
/// ray, `CpuScene::vpl_visible`), else nothing. Not in the paper. Twin of `members_flush`.
pub fn members_flush(cpu: &CpuScene, p: Vec3, n: Vec3, drawn: &Vpl, terms: Vec3) -> Vec3 {
    if cpu.vpl_visible(p, n, drawn) {
        terms
    } else {
        Vec3::ZERO
    }
}

/// §3.2.1 at pixel `pixel`, with the shadow rays traced: Σ over the sorted VPLs of its Eq. (5) term
/// times its cluster's visibility. `LcVisibility::Disc`: the disc's, computed once a cluster
/// (`DISC_SAMPLES` rays) where a term of it is positive. `Members` (not in the paper): per member
/// group, in the sorted order, the terms summed and one member drawn in proportion to its term
/// (`member_draw`), the sum counting when that member is visible (`members_flush`, one ray a group
/// with a positive term).
pub fn shade_counted(
    cpu: &CpuScene,
    (pixel, sp): (u32, &ShadingPoint),
    c: &LightClusters,
    d_min2: f32,
    mode: LcVisibility,
) -> (Vec3, u32) {
    if !sp.valid {
        return (Vec3::ZERO, 0);
    }
    let (p, n) = (sp.pos, sp.normal);
    let mut vis: Vec<Option<f32>> = vec![None; c.discs.len()];
    let mut sum = Vec3::ZERO;
    let mut rays = 0;
    // Members: the current group (cluster × 8 + group), its total weight, terms and drawn member.
    let mut cur: Option<u32> = None;
    let (mut total, mut terms, mut drawn) = (0.0f32, Vec3::ZERO, 0usize);
    let packed = c.packed_groups();
    for (j, (v, &k)) in c.sorted.iter().zip(&c.cluster_of).enumerate() {
        let t = eq5_vpl_radiance(p, n, sp.albedo, v, d_min2);
        if t.max_element() <= 0.0 {
            continue;
        }
        match mode {
            LcVisibility::Disc => {
                let f = *vis[k as usize].get_or_insert_with(|| {
                    rays += DISC_SAMPLES;
                    disc_visibility(cpu, p, n, &c.discs[k as usize])
                });
                sum += t * f;
            }
            LcVisibility::Members => {
                if cur != Some(packed[j]) {
                    if cur.is_some() {
                        sum += members_flush(cpu, p, n, &c.sorted[drawn], terms);
                        rays += 1;
                    }
                    cur = Some(packed[j]);
                    total = 0.0;
                    terms = Vec3::ZERO;
                }
                let w = t.x + t.y + t.z;
                total += w;
                terms += t;
                if member_draw(member_u(pixel, j as u32), w, total) {
                    drawn = j;
                }
            }
        }
    }
    if cur.is_some() {
        sum += members_flush(cpu, p, n, &c.sorted[drawn], terms);
        rays += 1;
    }
    (sum, rays)
}

/// `shade_counted`'s light alone.
pub fn shade(
    cpu: &CpuScene,
    pixel: (u32, &ShadingPoint),
    c: &LightClusters,
    d_min2: f32,
    mode: LcVisibility,
) -> Vec3 {
    shade_counted(cpu, pixel, c, d_min2, mode).0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vpl(x: f32, y: f32, power: f32) -> Vpl {
        Vpl {
            pos: [x, y, 0.0, 0.0],
            nrm: [0.0, 0.0, 1.0, 0.0],
            flux: [power; 4],
        }
    }

    #[test]
    fn d_min_by_hand() {
        // d_init 2 at a third of z_far: 2 (1 − 1/3) = 4/3.
        assert!((d_min(2.0, 1.0, 3.0) - 4.0 / 3.0).abs() < 1e-6);
        assert_eq!(d_min(2.0, 0.0, 3.0), 2.0);
        assert_eq!(d_min(2.0, 3.0, 3.0), 0.0);
        assert_eq!(d_min(2.0, 5.0, 3.0), 0.0);
    }

    #[test]
    fn leader_algorithm_on_five_vpls() {
        // The camera far away (z_far 1000, |C| ≈ 100: d_min ≈ 0.9 d_init = 0.9 for d_init 1).
        // Powers 5, 4, 3, 2, 1 at x = 0, 0.5, 3, 3.4, 10: VPL 0 is a centre; 1 is within 0.9 of it;
        // 2 is far: a centre; 3 is within 0.9 of 2; 4 is far: a centre.
        let v = [
            vpl(0.0, 0.0, 5.0),
            vpl(0.5, 0.0, 4.0),
            vpl(3.0, 0.0, 3.0),
            vpl(3.4, 0.0, 2.0),
            vpl(10.0, 0.0, 1.0),
        ];
        let eye = Vec3::new(0.0, 0.0, 100.0);
        let c = leader_centers(&v, eye, 1000.0, 1.0);
        assert_eq!(c, vec![0, 2, 4]);
        assert_eq!(assign_nearest(&v, &c), vec![0, 0, 1, 1, 2]);
        // The same lights in another order: the powers decide, not the order.
        let w = [v[4], v[3], v[2], v[1], v[0]];
        assert_eq!(leader_centers(&w, eye, 1000.0, 1.0), vec![4, 2, 0]);
        // d_init tiny: every VPL its own cluster; huge: one cluster.
        assert_eq!(leader_centers(&v, eye, 1000.0, 1e-3).len(), 5);
        assert_eq!(leader_centers(&v, eye, 1000.0, 100.0), vec![0]);
        let lc = cluster(&v, eye, 1000.0, 1.0);
        assert_eq!(lc.cluster_of, vec![0, 0, 1, 1, 2]);
        assert_eq!(lc.discs.len(), 3);
        assert!(
            (lc.discs[1].radius - d_min(1.0, Vec3::new(3.0, 0.0, 0.0).distance(eye), 1000.0)).abs()
                < 1e-6
        );
    }

    #[test]
    fn member_draw_by_hand_and_in_proportion() {
        // u = 0.5 over the weights 1, 1: the first is drawn (0.5 · 1 < 1), the second not
        // (0.5 · 2 = 1, not < 1); over 1, 3: the second (0.5 · 4 < 3).
        assert!(member_draw(0.5, 1.0, 1.0) && !member_draw(0.5, 1.0, 2.0));
        assert!(member_draw(0.5, 3.0, 4.0));
        // The first positive weight is always drawn (u < 1).
        assert!(member_draw(0.999_999, 1e-30, 1e-30));
        // Over many pixels a reservoir of weights 1, 2, 3, 4 ends on each in proportion w / 10
        // (the closed form of a weighted reservoir of one), within 4 standard deviations.
        let w = [1.0f32, 2.0, 3.0, 4.0];
        let n = 40_000u32;
        let mut count = [0u32; 4];
        for pixel in 0..n {
            let (mut total, mut drawn) = (0.0f32, 0);
            for (j, &wj) in w.iter().enumerate() {
                total += wj;
                if member_draw(member_u(pixel, j as u32), wj, total) {
                    drawn = j;
                }
            }
            count[drawn] += 1;
        }
        for (j, &c) in count.iter().enumerate() {
            let p = w[j] as f64 / 10.0;
            let sd = (n as f64 * p * (1.0 - p)).sqrt();
            assert!(
                (c as f64 - n as f64 * p).abs() < 4.0 * sd,
                "{j}: {c} of {n}"
            );
        }
    }

    #[test]
    fn member_groups_by_hand() {
        // At most MEMBER_TARGETS members: each its own group.
        let v: Vec<Vpl> = (0..5).map(|i| vpl(i as f32, 0.0, 1.0)).collect();
        assert_eq!(split_members(&v, &[3, 0, 1, 2, 4]), vec![0, 1, 2, 3, 4]);
        // Eight tight pairs along x (x = 10 g and 10 g + 0.1): every pair one group, none shared,
        // the centre's pair group 0.
        let mut v = Vec::new();
        for g in 0..8 {
            v.push(vpl(10.0 * g as f32, 0.0, 1.0));
            v.push(vpl(10.0 * g as f32 + 0.1, 0.0, 1.0));
        }
        let members: Vec<u32> = (0..16).collect();
        let groups = split_members(&v, &members);
        for g in 0..8 {
            assert_eq!(groups[2 * g], groups[2 * g + 1], "pair {g}");
        }
        let mut seen = groups.clone();
        seen.sort();
        seen.dedup();
        assert_eq!(seen.len(), 8);
        assert_eq!(groups[0], 0);
        // Facing apart parts VPLs at one place: 8 VPLs facing +z and 8 at the same points facing
        // -z (two sides of a thin wall) never share a group.
        let mut v = Vec::new();
        for i in 0..8 {
            v.push(vpl(0.01 * i as f32, 0.0, 1.0));
        }
        for i in 0..8 {
            let mut back = vpl(0.01 * i as f32, 0.0, 1.0);
            back.nrm = [0.0, 0.0, -1.0, 0.0];
            v.push(back);
        }
        let groups = split_members(&v, &members);
        for a in 0..8 {
            for b in 8..16 {
                assert_ne!(groups[a], groups[b], "{a} and {b} face apart");
            }
        }
        // The clustering sorts by cluster, then group, and packs them as the shader reads them.
        let c = cluster(&v, Vec3::new(0.0, 0.0, 100.0), 1000.0, 100.0);
        assert_eq!(c.discs.len(), 1);
        assert!(c.group_of.windows(2).all(|w| w[0] <= w[1]));
        assert_eq!(c.packed_groups(), c.group_of);
    }

    #[test]
    fn disc_points_lie_on_the_disc() {
        let d = Disc {
            center: Vec3::new(1.0, 2.0, 3.0),
            normal: Vec3::new(0.0, 0.6, 0.8),
            radius: 0.5,
        };
        let p = disc_points(&d);
        assert_eq!(p.len(), DISC_SAMPLES as usize);
        for q in &p {
            let r = *q - d.center;
            assert!(r.dot(d.normal).abs() < 1e-5, "in the plane");
            assert!(r.length() <= 0.5 + 1e-5 && r.length() > 0.0);
        }
    }
}
