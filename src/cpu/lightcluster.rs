//! CPU twin of `shaders-wgsl/lightcluster.wgsl` (seed 002, docs/methods.md "lightcluster"): §3.2's
//! cluster-shadowed shading, with the paper's disc (`disc_points`, `disc_visibility`) or member
//! targets (`target_visible`; not in the paper), `shade`. The clustering (§3.1) and the member
//! groups are production code, `method::lightcluster::cluster`, re-exported here.

use glam::Vec3;

pub use crate::method::lightcluster::cluster::*;

use super::shading::{CpuScene, onb};
use super::vpl::eq5_vpl_radiance;
use crate::gi::primary::ShadingPoint;
use crate::gi::rng::pcg_hash;
use crate::gi::vpl_trace::Vpl;
use crate::method::lightcluster::settings::LcVisibility;

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
