//! LightCluster (Wiesenhütter, Klein et al.; seed `002`, "LightCluster – Clustering Lights to
//! Accelerate Shadow Computation") adapted to VPLs and ray-traced visibility (docs/methods.md,
//! "lightcluster"): the clustering itself, which runs on the CPU as the paper's does (§4). The CPU twin
//! of `shaders-wgsl/lightcluster.wgsl` is `cpu::lightcluster`.
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
