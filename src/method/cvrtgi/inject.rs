//! CVRTGI's CPU step between the clustering and the kernels (Cosin Ayerbe & Patow 2022, seed 003;
//! docs/cvrtgi.md): the exposed faces, and the VPLs' light pulled into their voxels and clusters
//! (§4.4's lit voxels and lit clusters). The kernels' CPU twin is `cpu::cvrtgi`.

use glam::Vec3;

use super::voxel::Voxels;
use crate::gi::vpl_trace::Vpl;

pub const INVALID: u32 = u32::MAX;

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
/// count, as f32 bits) with its box (two vec4), and per lit voxel one light (the same over its own
/// VPLs), sorted by cluster.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Lighting {
    pub clusters: Vec<[[f32; 4]; 5]>,
    pub lit: Vec<Vpl>,
    /// VPLs that fell in no voxel or in a voxel of no cluster (their light is lost, §4.2).
    pub dropped: u32,
    pub lit_clusters: u32,
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
/// so its voxel is lit and its flux is pulled into the voxel's cluster.
pub fn inject(v: &Voxels, num_clusters: usize, vpls: &[Vpl]) -> Lighting {
    let mut per_cluster: Vec<Vec<(u32, &Vpl)>> = vec![Vec::new(); num_clusters];
    let mut dropped = 0;
    for vpl in vpls {
        let p = Vec3::from_slice(&vpl.pos[..3]);
        let n = Vec3::from_slice(&vpl.nrm[..3]);
        match v.at_surface(p, -n) {
            Some(i) if v.voxels[i as usize].cluster != INVALID => {
                per_cluster[v.voxels[i as usize].cluster as usize].push((i, vpl));
            }
            _ => dropped += 1,
        }
    }
    let mut out = Lighting {
        dropped,
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
        out.clusters
            .push([light.pos, light.nrm, light.flux, [0.0; 4], [0.0; 4]]);
    }
    out
}

/// Sets the boxes of `l`'s clusters (vec4 3 and 4) from the voxel clustering.
pub fn set_boxes(l: &mut Lighting, clusters: &[super::voxel::Cluster]) {
    for (c, cl) in l.clusters.iter_mut().zip(clusters) {
        c[3] = cl.min.extend(0.0).into();
        c[4] = cl.max.extend(0.0).into();
    }
}
