//! CVRTGI's CPU step between the clustering and the kernels (Cosin Ayerbe & Patow 2022, seed 003;
//! docs/cvrtgi.md): the exposed faces, and the VPLs' light pulled into their voxels and clusters
//! (§4.4's lit voxels and lit clusters). The kernels' CPU twin is `super::twin`.

use glam::Vec3;

use super::voxel::Voxels;
use crate::gi::vpl_trace::Vpl;

pub const INVALID: u32 = u32::MAX;

/// A cluster light as the gather reads it: pos | first lit, nrm | lit count, flux | lit area, box
/// min, box max.
pub type ClusterLight = [[f32; 4]; 5];

/// The exposed faces: `of_voxel[6 v + dir]` is face `dir`'s index or `INVALID`, `voxel_dir[f]` is
/// 6 v + dir of face f. Only exposed faces (the neighbour across is empty) get irradiance.
#[derive(Clone, Debug, PartialEq)]
pub struct Faces {
    pub of_voxel: Vec<u32>,
    pub voxel_dir: Vec<u32>,
}

pub fn faces(v: &Voxels) -> Faces {
    let mut of_voxel = vec![INVALID; 6 * v.voxels.len()];
    let mut voxel_dir = Vec::new();
    for (i, vx) in v.voxels.iter().enumerate() {
        for dir in 0..6 {
            if vx.exposed & (1 << dir) != 0 {
                of_voxel[6 * i + dir as usize] = voxel_dir.len() as u32;
                voxel_dir.push(6 * i as u32 + dir);
            }
        }
    }
    Faces {
        of_voxel,
        voxel_dir,
    }
}

/// The lights the faces gather from: per cluster one light (the flux of the VPLs in its voxels at
/// their flux-weighted mean position and normal; `pos.w` its first lit voxel in `lit`, `nrm.w` their
/// count, as f32 bits; `flux.w` its conservation scale, 1 until `set_scales`) with its box (two
/// vec4), and per lit voxel one light (the same over its own VPLs), sorted by cluster.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Lighting {
    pub clusters: Vec<ClusterLight>,
    pub lit: Vec<Vpl>,
    /// VPLs that fell in no voxel or in a voxel of no cluster (their light is lost, §4.2).
    pub dropped: u32,
    pub lit_clusters: u32,
    /// Per cluster, the luminance (r + g + b) of the flux its VPLs send into the scene: each VPL's
    /// flux times the fraction of its escape rays that met a surface beyond the reach (`escape`;
    /// the whole flux without escape rays). `conservation_scales` reads it.
    pub sent: Vec<f32>,
}

fn lum(c: [f32; 4]) -> f32 {
    (c[0] + c[1] + c[2]).max(0.0)
}

/// Sums VPLs into one light: flux, and flux-weighted position and normal.
fn merge(vpls: &[&Vpl]) -> Vpl {
    let (mut p, mut n, mut f, mut w) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, 0.0f32);
    for v in vpls {
        let l = lum(v.flux).max(1e-30);
        p += Vec3::from_slice(&v.pos[..3]) * l;
        n += Vec3::from_slice(&v.nrm[..3]) * l;
        f += Vec3::from_slice(&v.flux[..3]);
        w += l;
    }
    let p = p / w.max(1e-30);
    let n = n.normalize_or_zero();
    Vpl {
        pos: [p.x, p.y, p.z, 0.0],
        nrm: [n.x, n.y, n.z, 0.0],
        flux: [f.x, f.y, f.z, 0.0],
    }
}

/// §4.4's injection with VPLs as the lit surface: each VPL lies on a surface its light path reached
/// (the path's rays were the emitter visibility test the paper does with a distance shadow map),
/// so its voxel is lit and its flux is pulled into the voxel's cluster. `escape` (empty: [1, 1]
/// each; not in the paper) gives per VPL the fraction of its light that leaves its surface, which
/// weighs its flux (a VPL of weight 0 is left out), and the fraction it sends into the scene, which
/// `Lighting::sent` sums.
pub fn inject(v: &Voxels, num_clusters: usize, vpls: &[Vpl], escape: &[[f32; 2]]) -> Lighting {
    let mut sent = vec![0.0f32; num_clusters];
    let weighted: Vec<Vpl> = vpls
        .iter()
        .enumerate()
        .map(|(i, vpl)| {
            let [w, into_scene] = escape.get(i).copied().unwrap_or([1.0, 1.0]);
            let p = Vec3::from_slice(&vpl.pos[..3]);
            let n = Vec3::from_slice(&vpl.nrm[..3]);
            if let Some(c) = v
                .at_surface(p, -n)
                .map(|i| v.voxels[i as usize].cluster)
                .filter(|&c| c != INVALID)
            {
                sent[c as usize] += lum(vpl.flux) * into_scene;
            }
            let mut out = *vpl;
            for c in &mut out.flux[..3] {
                *c *= w;
            }
            out
        })
        .collect();
    let mut per_cluster: Vec<Vec<(u32, &Vpl)>> = vec![Vec::new(); num_clusters];
    let mut dropped = 0;
    for vpl in &weighted {
        let p = Vec3::from_slice(&vpl.pos[..3]);
        let n = Vec3::from_slice(&vpl.nrm[..3]);
        if lum(vpl.flux) <= 0.0 {
            continue;
        }
        match v.at_surface(p, -n) {
            Some(i) if v.voxels[i as usize].cluster != INVALID => {
                per_cluster[v.voxels[i as usize].cluster as usize].push((i, vpl));
            }
            _ => dropped += 1,
        }
    }
    let mut out = Lighting {
        dropped,
        sent,
        ..Default::default()
    };
    for list in per_cluster.iter_mut() {
        list.sort_by_key(|(i, _)| *i);
        let first = out.lit.len() as u32;
        let mut k = 0;
        while k < list.len() {
            let mut e = k;
            while e < list.len() && list[e].0 == list[k].0 {
                e += 1;
            }
            let group: Vec<&Vpl> = list[k..e].iter().map(|x| x.1).collect();
            out.lit.push(merge(&group));
            k = e;
        }
        let count = out.lit.len() as u32 - first;
        let all: Vec<&Vpl> = list.iter().map(|x| x.1).collect();
        let mut light = if all.is_empty() {
            bytemuck::Zeroable::zeroed()
        } else {
            merge(&all)
        };
        light.pos[3] = f32::from_bits(first);
        light.nrm[3] = f32::from_bits(count);
        out.lit_clusters += (count > 0) as u32;
        light.flux[3] = 1.0;
        out.clusters
            .push([light.pos, light.nrm, light.flux, [0.0; 4], [0.0; 4]]);
    }
    out
}

/// Each cluster's conservation scale (not in the paper): the flux its VPLs send into the scene
/// (`Lighting::sent`) over the flux the paper's gather hands to the faces whose rays met it, so
/// that those faces receive, in all, what the cluster sends, however many of them found it and
/// however much of it each saw. `ids` and `flux` are the faces' cached lists and, beside them, the
/// flux each listed cluster sends to the face before the scale (`gather`'s `vis_w`: s² × the
/// luminance of its irradiance); `rays` slots a face, a list ending at `INVALID`. A cluster that
/// sends something no face takes keeps scale 1 (nothing to scale).
pub fn conservation_scales(l: &Lighting, ids: &[u32], flux: &[f32], rays: usize) -> Vec<f32> {
    let mut taken = vec![0.0f64; l.clusters.len()];
    for (face, fl) in ids.chunks(rays.max(1)).zip(flux.chunks(rays.max(1))) {
        for (&c, &x) in face.iter().zip(fl) {
            if c == INVALID {
                break;
            }
            let cl = &l.clusters[c as usize];
            if cl[1][3].to_bits() > 0 {
                taken[c as usize] += x as f64;
            }
        }
    }
    l.sent
        .iter()
        .zip(taken)
        .map(|(&sent, taken)| {
            if taken > 0.0 {
                (sent as f64 / taken) as f32
            } else {
                1.0
            }
        })
        .collect()
}

/// Writes `scales` into the cluster lights' `flux.w` (what `gather` multiplies by).
pub fn set_scales(l: &mut Lighting, scales: &[f32]) {
    for (c, &k) in l.clusters.iter_mut().zip(scales) {
        c[2][3] = k;
    }
}

/// Sets the boxes of `l`'s clusters (vec4 3 and 4) from the voxel clustering.
pub fn set_boxes(l: &mut Lighting, clusters: &[super::voxel::Cluster]) {
    for (c, cl) in l.clusters.iter_mut().zip(clusters) {
        c[3] = cl.min.extend(0.0).into();
        c[4] = cl.max.extend(0.0).into();
    }
}

#[cfg(test)]
mod tests {
    use glam::IVec3;

    use super::*;
    use crate::method::cvrtgi::voxel::tests::unit_voxels;

    fn vpl(p: [f32; 3], n: Vec3, flux: f32) -> Vpl {
        Vpl {
            pos: [p[0], p[1], p[2], 0.0],
            nrm: n.extend(0.0).into(),
            flux: [flux, flux, flux, 0.0],
        }
    }

    fn near(a: [f32; 4], b: Vec3) -> bool {
        (Vec3::from_slice(&a[..3]) - b).abs().max_element() < 1e-5
    }

    /// §4.4's injection worked by hand on a unit grid of 4³ with four occupied voxels (sorted by
    /// key x + 4 (y + 4 z)): A (1, 0, 1) and B (2, 1, 1) of cluster 0, C (1, 2, 1) of cluster 1, D
    /// (3, 0, 3) of no cluster; cluster 2 has no VPL. The VPLs (flux f per channel, luminance 3 f;
    /// `escape` [weight, into the scene]):
    /// - v1 in A at (1.3, 0.9, 1.5), +y, f 1; v2 in A at (1.7, 0.5, 1.5), +x, f 1/3, into 0.5.
    /// - v3 in the empty voxel (1, 1, 1) at (1.8, 1.8, 1.5), normal (-1, 1, 0)/√2: half a voxel
    ///   into its surface (along -n) is B, half a voxel out of it is C. It lies on B.
    /// - v4 in D and v5 at (3.5, 3.5, 0.5), in no voxel: dropped, 2.
    /// - v6 in C of weight 0: left out, sends nothing. v7 in C at (1.5, 2.2, 1.5), f 2, escape
    ///   [0.5, 0.25]: flux 1, sends 6 × 0.25.
    ///
    /// So cluster 0 sends 3 + 1 × 0.5 + 3 = 6.5 and cluster 1 1.5; lit voxels A (v1 + v2: flux
    /// 4/3, position (3 v1 + v2)/4 = (1.4, 0.8, 1.5), normal (x + 3 y)/√10), B (v3) and C (v7);
    /// cluster 0's light is v1 + v2 + v3 (flux 7/3, position (3 v1 + v2 + 3 v3)/7, first lit 0,
    /// count 2), cluster 1's v7 (first 2, count 1), cluster 2's zero (first 3, count 0).
    /// (cargo-mutants: the normal's weight as `/ l`, the lookup's `-n` as `n` (twice), the cluster
    /// guard as `true` and the dropped count as `-=`, `*=` or absent survived.)
    #[test]
    fn injection_by_hand() {
        let cells = [[1, 0, 1], [2, 1, 1], [1, 2, 1], [3, 0, 3]]
            .map(|c| (IVec3::from(c), Vec3::Y, Vec3::ONE, 1.0));
        let mut v = unit_voxels([4; 3], &cells);
        let keys: Vec<u32> = v.voxels.iter().map(|x| x.key).collect();
        assert_eq!(keys, [17, 22, 25, 51]);
        for (x, c) in v.voxels.iter_mut().zip([0, 0, 1, INVALID]) {
            x.cluster = c;
        }
        let corner = Vec3::new(-1.0, 1.0, 0.0).normalize();
        let vpls = [
            vpl([1.3, 0.9, 1.5], Vec3::Y, 1.0),
            vpl([1.7, 0.5, 1.5], Vec3::X, 1.0 / 3.0),
            vpl([1.8, 1.8, 1.5], corner, 1.0),
            vpl([3.5, 0.5, 3.5], Vec3::Y, 1.0),
            vpl([3.5, 3.5, 0.5], Vec3::Y, 1.0),
            vpl([1.5, 2.5, 1.5], Vec3::Y, 1.0),
            vpl([1.5, 2.2, 1.5], Vec3::Y, 2.0),
        ];
        let escape = [
            [1.0, 1.0],
            [1.0, 0.5],
            [1.0, 1.0],
            [1.0, 1.0],
            [1.0, 1.0],
            [0.0, 0.0],
            [0.5, 0.25],
        ];
        let l = inject(&v, 3, &vpls, &escape);
        assert_eq!(l.dropped, 2);
        assert_eq!(l.lit_clusters, 2);
        assert_eq!(l.sent.len(), 3);
        for (got, want) in l.sent.iter().zip([6.5, 1.5, 0.0]) {
            assert!((got - want).abs() < 1e-5, "sent {:?}", l.sent);
        }
        // The lit voxels: A, B, C.
        assert_eq!(l.lit.len(), 3, "{:?}", l.lit);
        let a = &l.lit[0];
        assert!(near(a.flux, Vec3::splat(4.0 / 3.0)), "{a:?}");
        assert!(near(a.pos, Vec3::new(1.4, 0.8, 1.5)), "{a:?}");
        assert!(
            near(a.nrm, Vec3::new(1.0, 3.0, 0.0) / 10f32.sqrt()),
            "{a:?}"
        );
        let b = &l.lit[1];
        let v3 = Vec3::new(1.8, 1.8, 1.5);
        assert!(
            near(b.pos, v3) && near(b.nrm, corner) && near(b.flux, Vec3::ONE),
            "{b:?}"
        );
        assert!(near(l.lit[2].flux, Vec3::ONE) && near(l.lit[2].pos, Vec3::new(1.5, 2.2, 1.5)));
        // The cluster lights.
        assert_eq!(l.clusters.len(), 3);
        let [pos, nrm, flux, _, _] = l.clusters[0];
        let want = (3.0 * Vec3::new(1.3, 0.9, 1.5)
            + Vec3::new(1.7, 0.5, 1.5)
            + 3.0 * Vec3::new(1.8, 1.8, 1.5))
            / 7.0;
        assert!(near(pos, want), "{pos:?}");
        let n = (3.0 * Vec3::Y + Vec3::X + 3.0 * corner).normalize();
        assert!(near(nrm, n), "{nrm:?}");
        assert!(near(flux, Vec3::splat(7.0 / 3.0)), "{flux:?}");
        let first_count = |c: &ClusterLight| (c[0][3].to_bits(), c[1][3].to_bits(), c[2][3]);
        assert_eq!(first_count(&l.clusters[0]), (0, 2, 1.0));
        assert_eq!(first_count(&l.clusters[1]), (2, 1, 1.0));
        assert_eq!(first_count(&l.clusters[2]), (3, 0, 1.0));
        assert!(near(l.clusters[2][2], Vec3::ZERO));
    }
}
