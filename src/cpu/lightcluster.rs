//! LightCluster (Wiesenhütter, Klein et al.; seed `002`, "LightCluster – Clustering Lights to
//! Accelerate Shadow Computation") adapted to VPLs and ray-traced visibility (docs/methods.md,
//! "lightcluster"): the clustering itself (the paper runs it on the CPU as well, §4) and the CPU twin
//! of `shaders-wgsl/lightcluster.wgsl`.
//!
//! - §3.1.2: the lights sorted by decreasing power (the paper: attenuation range); the first is a
//!   cluster centre, and every next light farther than d_min from every centre becomes one, with
//!   d_min = d_init (1 − |C_pos| / z_far) for the centre C it is tested against (`d_min`,
//!   `leader_centers`).
//! - §3.1.3: every other light to its nearest centre (`assign_nearest`).
//! - §3.2.1: L(p) ≈ Σ_i L_d(p, l_i) · (1/A_c) ∫_{A_c} V(p, l) dl: each light's own unshadowed term
//!   times the visibility of its cluster's disc (§3.2.2: a disc of radius d_min at the centre),
//!   estimated with `DISC_SAMPLES` shadow rays to fixed points of the disc (the paper filters a
//!   cube shadow map with PCSS) (`disc_points`, `shade`).

use glam::Vec3;

use super::shading::{CpuScene, ShadingPoint, onb};
use super::vpl::eq5_vpl_radiance;
use crate::gi::vpl_trace::Vpl;

/// Shadow rays over a cluster's disc (the paper's Poisson disk has eight samples).
pub const DISC_SAMPLES: u32 = 8;

/// §3.1.2: d_min = d_init (1 − |C_pos| / z_far), |C_pos| the centre's distance from the camera,
/// z_far the largest view distance; at least 0.
pub fn d_min(d_init: f32, c_dist: f32, z_far: f32) -> f32 {
    (d_init * (1.0 - c_dist / z_far.max(f32::MIN_POSITIVE))).max(0.0)
}

/// A light's power for the sort: the Rec. 709 luminance of its flux.
pub fn power(v: &Vpl) -> f32 {
    0.2126 * v.flux[0] + 0.7152 * v.flux[1] + 0.0722 * v.flux[2]
}

fn pos(v: &Vpl) -> Vec3 {
    Vec3::new(v.pos[0], v.pos[1], v.pos[2])
}

/// §3.1.2: the cluster centres (VPL indices, in the order found): the VPLs by decreasing power
/// (the lowest index first on a tie), each promoted when it is farther than its d_min from every
/// centre so far. `d_init` and `z_far` in the scene's units.
pub fn leader_centers(vpls: &[Vpl], eye: Vec3, z_far: f32, d_init: f32) -> Vec<u32> {
    let mut order: Vec<u32> = (0..vpls.len() as u32).collect();
    order.sort_by(|&a, &b| {
        power(&vpls[b as usize])
            .total_cmp(&power(&vpls[a as usize]))
            .then(a.cmp(&b))
    });
    let mut centers: Vec<u32> = Vec::new();
    let mut radius: Vec<f32> = Vec::new();
    for i in order {
        let p = pos(&vpls[i as usize]);
        let far = centers
            .iter()
            .zip(&radius)
            .all(|(&c, &r)| p.distance(pos(&vpls[c as usize])) > r);
        if far {
            centers.push(i);
            radius.push(d_min(d_init, p.distance(eye), z_far));
        }
    }
    centers
}

/// §3.1.3: each VPL's cluster (index into `centers`): the nearest centre (the first on a tie); a
/// centre is its own.
pub fn assign_nearest(vpls: &[Vpl], centers: &[u32]) -> Vec<u32> {
    vpls.iter()
        .map(|v| {
            let p = pos(v);
            let mut best = (f32::INFINITY, 0u32);
            for (k, &c) in centers.iter().enumerate() {
                let d = p.distance_squared(pos(&vpls[c as usize]));
                if d < best.0 {
                    best = (d, k as u32);
                }
            }
            best.1
        })
        .collect()
}

/// A cluster as the shader reads it: the centre VPL's position with the disc radius in w, its
/// normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disc {
    pub center: Vec3,
    pub normal: Vec3,
    pub radius: f32,
}

impl Disc {
    pub fn to_gpu(&self) -> [[f32; 4]; 2] {
        [
            self.center.extend(self.radius).to_array(),
            self.normal.extend(0.0).to_array(),
        ]
    }
}

/// The clustering of a frame: the discs, and the VPLs reordered by cluster with each one's cluster.
#[derive(Clone, Debug, PartialEq)]
pub struct LightClusters {
    pub discs: Vec<Disc>,
    /// The VPLs sorted by cluster (stable: in their own order within one).
    pub sorted: Vec<Vpl>,
    /// The cluster of each sorted VPL.
    pub cluster_of: Vec<u32>,
}

/// The whole §3.1 clustering: centres, assignment, discs (radius d_min of each centre), the VPLs
/// sorted by cluster.
pub fn cluster(vpls: &[Vpl], eye: Vec3, z_far: f32, d_init: f32) -> LightClusters {
    let centers = leader_centers(vpls, eye, z_far, d_init);
    let assign = assign_nearest(vpls, &centers);
    let discs = centers
        .iter()
        .map(|&c| {
            let v = &vpls[c as usize];
            Disc {
                center: pos(v),
                normal: Vec3::new(v.nrm[0], v.nrm[1], v.nrm[2]),
                radius: d_min(d_init, pos(v).distance(eye), z_far),
            }
        })
        .collect();
    let mut order: Vec<u32> = (0..vpls.len() as u32).collect();
    order.sort_by_key(|&i| assign[i as usize]);
    LightClusters {
        discs,
        sorted: order.iter().map(|&i| vpls[i as usize]).collect(),
        cluster_of: order.iter().map(|&i| assign[i as usize]).collect(),
    }
}

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

/// §3.2.1 at one shading point: Σ over the sorted VPLs of its Eq. (5) term times its cluster's disc
/// visibility (computed once a cluster, only where a term is positive).
pub fn shade(cpu: &CpuScene, sp: &ShadingPoint, c: &LightClusters, d_min2: f32) -> Vec3 {
    if !sp.valid {
        return Vec3::ZERO;
    }
    let mut vis: Vec<Option<f32>> = vec![None; c.discs.len()];
    let mut sum = Vec3::ZERO;
    for (v, &k) in c.sorted.iter().zip(&c.cluster_of) {
        let t = eq5_vpl_radiance(sp.pos, sp.normal, sp.albedo, v, d_min2);
        if t.max_element() > 0.0 {
            let f = *vis[k as usize].get_or_insert_with(|| {
                disc_visibility(cpu, sp.pos, sp.normal, &c.discs[k as usize])
            });
            sum += t * f;
        }
    }
    sum
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
