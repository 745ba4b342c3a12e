//! LightCluster (Wiesenhütter, Klein et al.; seed `002`, "LightCluster – Clustering Lights to
//! Accelerate Shadow Computation") adapted to VPLs and ray-traced visibility (docs/methods.md,
//! "lightcluster"): the clustering itself, which runs on the CPU as the paper's does (§4). The CPU twin
//! of `shaders-wgsl/lightcluster.wgsl` is `super::twin`.
//!
//! - §3.1.2: the lights sorted by decreasing power (the paper: attenuation range); the first is a
//!   cluster centre, and every next light farther than d_min from every centre becomes one, with
//!   d_min = d_init (1 − |C_pos| / z_far) for the centre C it is tested against (`d_min`,
//!   `leader_centers`).
//! - §3.1.3: every other light to its nearest centre (`assign_nearest`).
//! - §3.2.1: L(p) ≈ Σ_i L_d(p, l_i) · (1/A_c) ∫_{A_c} V(p, l) dl: each light's own unshadowed term
//!   times the visibility of its cluster's disc (§3.2.2: a disc of radius d_min at the centre),
//!   estimated with `DISC_SAMPLES` shadow rays to fixed points of the disc (the paper filters a
//!   cube shadow map with PCSS) (`disc_points`, `shade`); `--lightcluster-visibility disc`.
//! - Not in the paper, the default (`--lightcluster-visibility members`): the rays aim at member
//!   VPLs instead of free points of the disc. Each cluster's members are split into at most
//!   `MEMBER_TARGETS` groups of nearby VPLs facing alike (`split_members`); per pixel, each group
//!   with a positive term traces one ray, to a member drawn in proportion to its term, and the
//!   group's summed terms count when that member is visible: still at most `MEMBER_TARGETS` rays
//!   a cluster and pixel, no ray ending inside a wall or past an occluder where no member is, and
//!   the group's light unbiased (docs/methods.md, "lightcluster").

use glam::Vec3;

use crate::gi::vpl_trace::Vpl;

/// Shadow rays over a cluster's disc (the paper's Poisson disk has eight samples).
pub const DISC_SAMPLES: u32 = 8;

/// The most member groups (and so rays) a cluster has with `members` visibility: as many as the
/// disc's samples, so a cluster costs a pixel at most the rays the paper's disc does.
pub const MEMBER_TARGETS: usize = 8;

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

/// The clustering of a frame: the discs, and the VPLs reordered by cluster with each one's cluster
/// and member group.
#[derive(Clone, Debug, PartialEq)]
pub struct LightClusters {
    pub discs: Vec<Disc>,
    /// The VPLs sorted by cluster, then member group (stable: in their own order within one).
    pub sorted: Vec<Vpl>,
    /// The cluster of each sorted VPL.
    pub cluster_of: Vec<u32>,
    /// The member group of each sorted VPL (0..`MEMBER_TARGETS`, `split_members`).
    pub group_of: Vec<u32>,
}

impl LightClusters {
    /// Per sorted VPL, its cluster and group as the shader reads them: cluster × 8 + group.
    pub fn packed_groups(&self) -> Vec<u32> {
        self.cluster_of
            .iter()
            .zip(&self.group_of)
            .map(|(&c, &g)| c * MEMBER_TARGETS as u32 + g)
            .collect()
    }
}

/// The distance `split_members` groups by: between positions, plus `scale` (1 − n_a · n_b), so that
/// VPLs facing apart (two sides of a thin wall, a floor and a wall) part before near ones do.
fn member_distance(a: &Vpl, b: &Vpl, scale: f32) -> f32 {
    let n = |v: &Vpl| Vec3::new(v.nrm[0], v.nrm[1], v.nrm[2]);
    pos(a).distance(pos(b)) + scale * (1.0 - n(a).dot(n(b)))
}

/// Not in the paper: splits a cluster's `members` (VPL indices, the first its centre) into at most
/// `MEMBER_TARGETS` groups of nearby VPLs facing alike (`--lightcluster-visibility members`). With
/// at most `MEMBER_TARGETS` members each is its own group (the shading is then exact). Otherwise
/// farthest-point seeds from the centre (`member_distance`, scaled by the cluster's radius, ties to
/// the earlier member), then two rounds of: every member to its nearest seed, each seed moved to
/// the member nearest its group's flux-weighted mean position. Returns each member's group.
pub fn split_members(vpls: &[Vpl], members: &[u32]) -> Vec<u32> {
    let k = MEMBER_TARGETS;
    if members.len() <= k {
        return (0..members.len() as u32).collect();
    }
    let v = |i: u32| &vpls[i as usize];
    let c0 = pos(v(members[0]));
    let scale = members
        .iter()
        .map(|&i| pos(v(i)).distance(c0))
        .fold(0.0f32, f32::max);
    let mut seeds = vec![members[0]];
    let mut near: Vec<f32> = members
        .iter()
        .map(|&i| member_distance(v(i), v(members[0]), scale))
        .collect();
    while seeds.len() < k {
        let (best, _) = near
            .iter()
            .enumerate()
            .fold((0, -1.0f32), |b, (j, &d)| if d > b.1 { (j, d) } else { b });
        let s = members[best];
        seeds.push(s);
        for (d, &i) in near.iter_mut().zip(members) {
            *d = d.min(member_distance(v(i), v(s), scale));
        }
    }
    let nearest = |seeds: &[u32]| -> Vec<u32> {
        members
            .iter()
            .map(|&i| {
                let mut best = (f32::INFINITY, 0u32);
                for (g, &s) in seeds.iter().enumerate() {
                    let d = member_distance(v(i), v(s), scale);
                    if d < best.0 {
                        best = (d, g as u32);
                    }
                }
                best.1
            })
            .collect()
    };
    let mut group = nearest(&seeds);
    for _ in 0..2 {
        for (g, seed) in seeds.iter_mut().enumerate() {
            let (mut sum, mut w) = (Vec3::ZERO, 0.0f32);
            for (&i, &gi) in members.iter().zip(&group) {
                if gi == g as u32 {
                    let p = power(v(i)).max(1e-30);
                    sum += pos(v(i)) * p;
                    w += p;
                }
            }
            if w > 0.0 {
                let mean = sum / w;
                let mut best = (f32::INFINITY, *seed);
                for (&i, &gi) in members.iter().zip(&group) {
                    let d = pos(v(i)).distance_squared(mean);
                    if gi == g as u32 && d < best.0 {
                        best = (d, i);
                    }
                }
                *seed = best.1;
            }
        }
        group = nearest(&seeds);
    }
    group
}

/// The whole §3.1 clustering: centres, assignment, discs (radius d_min of each centre), the VPLs
/// sorted by cluster, and each cluster's member groups (`split_members`).
pub fn cluster(vpls: &[Vpl], eye: Vec3, z_far: f32, d_init: f32) -> LightClusters {
    let centers = leader_centers(vpls, eye, z_far, d_init);
    let assign = assign_nearest(vpls, &centers);
    // Each cluster's members, its centre first (a centre at another's very position belongs to
    // the first).
    let mut members: Vec<Vec<u32>> = centers
        .iter()
        .enumerate()
        .map(|(k, &c)| {
            if assign[c as usize] == k as u32 {
                vec![c]
            } else {
                vec![]
            }
        })
        .collect();
    for (i, &c) in assign.iter().enumerate() {
        if i as u32 != centers[c as usize] {
            members[c as usize].push(i as u32);
        }
    }
    let mut group = vec![0u32; vpls.len()];
    for m in &members {
        for (&i, g) in m.iter().zip(split_members(vpls, m)) {
            group[i as usize] = g;
        }
    }
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
    order.sort_by_key(|&i| (assign[i as usize], group[i as usize]));
    LightClusters {
        discs,
        sorted: order.iter().map(|&i| vpls[i as usize]).collect(),
        cluster_of: order.iter().map(|&i| assign[i as usize]).collect(),
        group_of: order.iter().map(|&i| group[i as usize]).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `member_distance` by hand: positions 3-4-5 apart, normals equal (no term), opposite (2 × scale)
    /// and perpendicular (1 × scale) (cargo-mutants: `scale * (1 − n·n)` as `scale + …` survived).
    #[test]
    fn member_distance_by_hand() {
        let v = |p: [f32; 3], n: [f32; 3]| Vpl {
            pos: [p[0], p[1], p[2], 1.0],
            nrm: [n[0], n[1], n[2], 0.0],
            flux: [1.0; 4],
        };
        let a = v([0.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let near = |b: &Vpl, s: f32, want: f32| {
            let d = member_distance(&a, b, s);
            assert!((d - want).abs() < 1e-6, "{d} against {want}");
        };
        near(&v([3.0, 4.0, 0.0], [0.0, 1.0, 0.0]), 10.0, 5.0);
        near(&v([3.0, 4.0, 0.0], [0.0, -1.0, 0.0]), 10.0, 25.0);
        near(&v([3.0, 4.0, 0.0], [1.0, 0.0, 0.0]), 0.5, 5.5);
    }

    /// `power` by hand: Rec. 709 luminance, one channel at a time and a mix (2, 4, 8) → 0.4252 +
    /// 2.8608 + 0.5776, no channel 1 so that a `/` shows (cargo-mutants: each `+` and `*` swapped
    /// survived, as every sort test had grey flux).
    #[test]
    fn power_is_the_luminance_of_the_flux() {
        let v = |f: [f32; 3]| Vpl {
            pos: [0.0; 4],
            nrm: [0.0, 1.0, 0.0, 0.0],
            flux: [f[0], f[1], f[2], 0.0],
        };
        for (f, want) in [
            ([1.0, 0.0, 0.0], 0.2126),
            ([0.0, 1.0, 0.0], 0.7152),
            ([0.0, 0.0, 1.0], 0.0722),
            ([2.0, 4.0, 8.0], 3.8636),
        ] {
            let got = power(&v(f));
            assert!((got - want).abs() < 1e-6, "{f:?}: {got} against {want}");
        }
    }

    fn at(p: [f32; 3], flux: f32) -> Vpl {
        Vpl {
            pos: [p[0], p[1], p[2], 1.0],
            nrm: [0.0, 1.0, 0.0, 0.0],
            flux: [flux, flux, flux, 0.0],
        }
    }

    /// §3.1.2's "farther than d_min": with the eye on the brightest light, d_min = d_init = 1, and a
    /// light exactly 1 away joins it while one 1 + 2⁻²⁰ away starts its own cluster (cargo-mutants:
    /// `>` as `>=` survived).
    #[test]
    fn a_light_at_exactly_d_min_is_not_a_centre() {
        let far = 1.0 + 2f32.powi(-20);
        let vpls = [
            at([0.0; 3], 2.0),
            at([1.0, 0.0, 0.0], 1.0),
            at([0.0, 0.0, far], 0.5),
        ];
        assert_eq!(d_min(1.0, 0.0, 10.0), 1.0);
        assert_eq!(leader_centers(&vpls, Vec3::ZERO, 10.0, 1.0), vec![0, 2]);
    }

    /// §3.1.3 on a tie: a light halfway between two centres goes to the first (cargo-mutants: `<` as
    /// `<=`, the last, survived).
    #[test]
    fn a_light_halfway_between_centres_joins_the_first() {
        let vpls = [
            at([-1.0, 0.0, 0.0], 1.0),
            at([1.0, 0.0, 0.0], 1.0),
            at([0.0; 3], 1.0),
        ];
        assert_eq!(assign_nearest(&vpls, &[0, 1]), vec![0, 1, 0]);
        assert_eq!(assign_nearest(&vpls, &[1, 0]), vec![1, 0, 0]);
    }

    /// `split_members` worked by hand on 11 lights in the plane z = 0, all facing +z (so
    /// `member_distance` is the distance), member 0 the centre:
    ///
    /// ```text
    /// member  0     1     2     3     4     5     6     7     8     9     10
    /// x, y    4,0   1,2   5,0   6,0   1,0   1,1   0,0   3,1   4,3   0,3   2,1
    /// flux    4     1     8     2     2     4     8     4     4     2     4
    /// ```
    ///
    /// Farthest-point seeds from 0: 9 (5 away), 4 (3; before 6 and 8 on the tie), 8, 3, 1 (√2;
    /// before 7 and 10), 7, 2 (1; before 5, 6, 10): groups 0..8 seeded by 0 9 4 8 3 1 7 2. The
    /// nearest seed: 5 is 1 from 4 and from 1, so group 2 (the first); 6 → 2, 10 → 6. Round one:
    /// group 2 = {4, 5, 6} of flux 2, 4, 8 has its flux-weighted mean at (3/7, 2/7), nearest to 6
    /// (the plain mean (2/3, 1/3) is nearest to 4, which would stay), so its seed moves to 6; 5 is
    /// then √2 from 6 and 1 from 1: group 5. Round two: group 5 = {1, 5} of flux 1, 4, mean (1, 1.2),
    /// seed → 5. Last: 4 is 1 from 6 and from 5 (group 2, the first), 10 is 1 from 5 and from 7
    /// (group 5). (cargo-mutants: 17 mutants of the seeds' ties, the mean, its weights and the move
    /// survived, as no test had more than `MEMBER_TARGETS` members with the groups checked.)
    #[test]
    fn split_members_by_hand() {
        let xy = [
            (4, 0),
            (1, 2),
            (5, 0),
            (6, 0),
            (1, 0),
            (1, 1),
            (0, 0),
            (3, 1),
            (4, 3),
            (0, 3),
            (2, 1),
        ];
        let flux = [4.0, 1.0, 8.0, 2.0, 2.0, 4.0, 8.0, 4.0, 4.0, 2.0, 4.0];
        let vpls: Vec<Vpl> = xy
            .iter()
            .zip(flux)
            .map(|(&(x, y), f)| Vpl {
                pos: [x as f32, y as f32, 0.0, 1.0],
                nrm: [0.0, 0.0, 1.0, 0.0],
                flux: [f, f, f, 0.0],
            })
            .collect();
        let members: Vec<u32> = (0..11).collect();
        assert_eq!(
            split_members(&vpls, &members),
            vec![0, 5, 7, 4, 2, 5, 2, 6, 3, 1, 5]
        );
        // At most `MEMBER_TARGETS` members: each its own group.
        assert_eq!(
            split_members(&vpls, &members[..8]),
            (0..8).collect::<Vec<u32>>()
        );
    }
}
