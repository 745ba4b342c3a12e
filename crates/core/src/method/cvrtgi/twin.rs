//! CPU twin of `shaders-wgsl/cvrtgi.wgsl` (CVRTGI, Cosin Ayerbe & Patow 2022, seed 003;
//! docs/cvrtgi.md): one function per kernel step, same formulas. The CPU steps before the kernels
//! (voxels, SLIC, injection) are production code in `method::cvrtgi`, re-exported here.
//!
//! For tests only (`tests/cvrtgi.rs` checks the shader against it): no production code calls it.

use glam::{IVec3, Vec3};

pub use super::inject::*;

use super::settings::ClusterGather;
use super::voxel::{Voxels, face_axis};
use crate::bvh::SceneBvh;
use crate::gi::primary::ShadingPoint;
use crate::gi::rng::pcg_hash;
use crate::gi::vpl_trace::Vpl;

/// Van der Corput radical inverse in base 2.
fn radical_inverse(k: u32) -> f32 {
    (k.reverse_bits() >> 8) as f32 * (1.0 / 16777216.0)
}

/// Ray `k` of `rays` from face `f` (direction `dir`): a Hammersley point over the hemisphere about
/// the face's axis, uniform in solid angle (cos θ = (k + ½) / rays), turned about the axis by a
/// per-face angle (`pcg_hash(f)`) so neighbouring faces do not share directions (§4.3: the paper's
/// rays into the upper hemisphere).
pub fn face_ray(f: u32, dir: u32, k: u32, rays: u32) -> Vec3 {
    let cos_t = (k as f32 + 0.5) / rays as f32;
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let turn = (pcg_hash(f) >> 8) as f32 * (1.0 / 16777216.0);
    let phi = 2.0 * std::f32::consts::PI * (radical_inverse(k) + turn).fract();
    let a = (dir / 2) as usize;
    let mut t = Vec3::ZERO;
    t[(a + 1) % 3] = 1.0;
    let mut b = Vec3::ZERO;
    b[(a + 2) % 3] = 1.0;
    t * (sin_t * phi.cos()) + b * (sin_t * phi.sin()) + face_axis(dir) * cos_t
}

/// Where face `f`'s rays start: the face's centre, off it along its axis like `offset_origin`.
pub fn face_origin(v: &Voxels, voxel_dir: u32, eps: f32) -> Vec3 {
    let (i, dir) = (voxel_dir / 6, voxel_dir % 6);
    let c = v.grid.coord_of_key(v.voxels[i as usize].key);
    let p = v.grid.centre(c) + face_axis(dir) * (0.5 * v.grid.size);
    p + face_axis(dir) * (eps + 4e-6 * p.abs().max_element())
}

/// §4.3: the clusters face `f` sees, in the order its rays first meet them: each ray's first hit
/// (BVH traversal, not the paper's Bresenham walk through the voxels) gives the occupied voxel there
/// (`Voxels::at_surface`) and its cluster, kept once. Twin of the `visibility` entry point.
pub fn visible_clusters(
    bvh: &SceneBvh,
    v: &Voxels,
    faces: &Faces,
    f: u32,
    rays: u32,
    eps: f32,
) -> Vec<u32> {
    let vd = faces.voxel_dir[f as usize];
    let o = face_origin(v, vd, eps);
    let mut seen = Vec::new();
    for k in 0..rays {
        let d = face_ray(f, vd % 6, k, rays);
        let Some(hit) = bvh.closest(o.into(), d.into(), 0.0, f32::MAX) else {
            continue;
        };
        let h = o + d * hit.t;
        if let Some(i) = v.at_surface(h, d) {
            let c = v.voxels[i as usize].cluster;
            if c != INVALID && !seen.contains(&c) {
                seen.push(c);
            }
        }
    }
    seen
}

/// Ray `k` of `rays` from VPL `i` with normal `n`: cosine-distributed about n (the Hammersley
/// point ((k + ½)/R, radical inverse of k) through `cosine_hemisphere`), turned by a per-VPL angle.
/// Twin of `escape_ray`.
pub fn escape_ray(i: u32, n: Vec3, k: u32, rays: u32) -> Vec3 {
    let turn = (pcg_hash(i ^ 0x9e37_79b9) >> 8) as f32 * (1.0 / 16777216.0);
    let u1 = (k as f32 + 0.5) / rays as f32;
    let u2 = (radical_inverse(k) + turn).fract();
    let (t, b) = crate::cpu::shading::onb(n);
    let r = u1.sqrt();
    let phi = 2.0 * std::f32::consts::PI * u2;
    let local = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt());
    (t * local.x + b * local.y + n * local.z).normalize()
}

/// Where VPL `i`'s light goes (not in the paper): of `rays` cosine-distributed rays (`escape_ray`)
/// from the VPL (its origin offset as `offset_origin`), [the fraction that gets past `reach` or
/// meets nothing, the fraction that meets a surface beyond `reach`]. The first weighs the VPL's flux
/// at injection (light stopped closer, in a gap far thinner than a voxel, lights nothing the voxels
/// can tell from the VPL's own surface), the second is the share it sends into the scene
/// (`Lighting::sent`). Twin of `escape`.
pub fn escape_fractions(
    bvh: &SceneBvh,
    vpl: &Vpl,
    i: u32,
    rays: u32,
    reach: f32,
    eps: f32,
) -> [f32; 2] {
    let p = Vec3::from_slice(&vpl.pos[..3]);
    let n = Vec3::from_slice(&vpl.nrm[..3]);
    let o = p + n * (eps + 4e-6 * p.abs().max_element());
    let (mut kept, mut sent) = (0u32, 0u32);
    for k in 0..rays {
        let d = escape_ray(i, n, k, rays);
        match bvh.closest(o.into(), d.into(), 0.0, f32::MAX) {
            None => kept += 1,
            Some(h) if h.t >= reach => {
                kept += 1;
                sent += 1;
            }
            Some(_) => {}
        }
    }
    let r = rays.max(1) as f32;
    [kept as f32 / r, sent as f32 / r]
}

/// §4.4's differential-area form factor from a light to a receiving face: the irradiance at `x`
/// (face axis `n`) from `light` (flux Φ at a point with normal n_l), E = Φ/π cos θ cos θ_l / max(d²,
/// d_min²): seed 000's Eq. (5) term with ρ/π left out, so that ρ/π · E is Eq. (5)'s radiance and the
/// pixels compare with the reference in its units.
pub fn face_irradiance(x: Vec3, n: Vec3, light: &Vpl, d_min2: f32) -> Vec3 {
    crate::cpu::vpl::eq5_vpl_radiance(x, n, Vec3::splat(std::f32::consts::PI), light, d_min2)
}

fn bits(x: f32) -> u32 {
    x.to_bits()
}

/// The distance from `x` to the box of cluster light `c`.
fn box_distance(x: Vec3, c: &[[f32; 4]; 5]) -> f32 {
    let (lo, hi) = (Vec3::from_slice(&c[3][..3]), Vec3::from_slice(&c[4][..3]));
    (lo - x).max(x - hi).max(Vec3::ZERO).length()
}

/// The irradiance at face `f` from cluster `c` of its list, as the paper's gather takes it: the
/// cluster's light as a point or, when nearer than `near` (its box), each of its lit voxels' lights.
/// The receiving point is the voxel's mean surface position, the normal the face's axis. Zero for a
/// cluster without lit voxels.
pub fn cluster_irradiance(
    v: &Voxels,
    faces: &Faces,
    l: &Lighting,
    (f, c): (u32, u32),
    near: f32,
    d_min2: f32,
) -> Vec3 {
    let vd = faces.voxel_dir[f as usize];
    let x = v.voxels[(vd / 6) as usize].pos;
    let n = face_axis(vd % 6);
    let cl = &l.clusters[c as usize];
    let count = bits(cl[1][3]);
    if count == 0 {
        return Vec3::ZERO;
    }
    if box_distance(x, cl) < near {
        let first = bits(cl[0][3]);
        let mut e = Vec3::ZERO;
        for light in &l.lit[first as usize..(first + count) as usize] {
            e += face_irradiance(x, n, light, d_min2);
        }
        e
    } else {
        let light = Vpl {
            pos: cl[0],
            nrm: cl[1],
            flux: cl[2],
        };
        face_irradiance(x, n, &light, d_min2)
    }
}

/// The flux (luminance r + g + b) face `f` takes at irradiance `e`: e times the face's area
/// projected on its voxel's surface, s² |axis · n_voxel| (the faces of a staircase of voxels along a
/// slanted surface add up to the surface's area, not more). Not in the paper. Twin of `slot_flux`.
pub fn slot_flux(v: &Voxels, faces: &Faces, f: u32, e: Vec3) -> f32 {
    let vd = faces.voxel_dir[f as usize];
    let s = v.grid.size;
    s * s
        * v.voxels[(vd / 6) as usize]
            .normal
            .dot(face_axis(vd % 6))
            .abs()
        * (e.x + e.y + e.z)
}

/// §4.4's gathering at face `f`: every lit cluster it sees (`visible`, its cached list) adds its
/// `cluster_irradiance`, with `ClusterGather::Conserved` (not in the paper) times the cluster's
/// conservation scale (`flux.w`, `conservation_scales`). Twin of `gather`.
pub fn gather_face(
    v: &Voxels,
    faces: &Faces,
    l: &Lighting,
    (f, visible): (u32, &[u32]),
    mode: ClusterGather,
    near: f32,
    d_min2: f32,
) -> Vec3 {
    let mut e = Vec3::ZERO;
    for &c in visible {
        if c == INVALID {
            break;
        }
        let ec = cluster_irradiance(v, faces, l, (f, c), near, d_min2);
        e += match mode {
            ClusterGather::AnyHit => ec,
            ClusterGather::Conserved => ec * l.clusters[c as usize][2][3],
        };
    }
    e
}

/// One pass of §4.4's Gaussian filter at face `f`: the same-direction faces of the voxels within
/// `radius` (a (2r+1)³ kernel), weight exp(-|Δ|² / 2σ²) with σ = max(r, 1) / 2, weight 0 for an
/// empty neighbour, one whose face is not exposed, or an unlit one (zero irradiance) other than the
/// face itself; renormalised. Twin of `filter`.
pub fn filter_face(v: &Voxels, faces: &Faces, irr: &[Vec3], f: u32, radius: u32) -> Vec3 {
    let vd = faces.voxel_dir[f as usize];
    let (i, dir) = (vd / 6, vd % 6);
    let c = v.grid.coord_of_key(v.voxels[i as usize].key);
    let r = radius as i32;
    let sigma = (radius.max(1) as f32) * 0.5;
    let k = 1.0 / (2.0 * sigma * sigma);
    let (mut sum, mut wsum) = (Vec3::ZERO, 0.0f32);
    for dz in -r..=r {
        for dy in -r..=r {
            for dx in -r..=r {
                let d = IVec3::new(dx, dy, dz);
                let Some(u) = v.find(c + d) else { continue };
                let g = faces.of_voxel[(6 * u + dir) as usize];
                if g == INVALID {
                    continue;
                }
                let e = irr[g as usize];
                if g != f && e.max_element() <= 0.0 {
                    continue;
                }
                let w = (-(d.length_squared() as f32) * k).exp();
                sum += w * e;
                wsum += w;
            }
        }
    }
    if wsum > 0.0 {
        sum / wsum
    } else {
        irr[f as usize]
    }
}

/// §4.5: a pixel's indirect light, ρ/π times the irradiance of the face most similar to its normal,
/// interpolated trilinearly between the 8 voxel centres around it (weight 0 where that voxel is
/// empty or its face not exposed); where none has one, the exposed face of the pixel's own voxel
/// nearest its normal. Twin of `lookup`.
pub fn lookup_pixel(v: &Voxels, faces: &Faces, irr: &[Vec3], sp: &ShadingPoint) -> Vec3 {
    if !sp.valid {
        return Vec3::ZERO;
    }
    let g = v.grid;
    let dir = super::voxel::dominant_face(sp.normal);
    let q = (sp.pos - g.origin) / g.size - 0.5;
    let b = q.floor();
    let t = q - b;
    let base = b.as_ivec3();
    let (mut sum, mut wsum) = (Vec3::ZERO, 0.0f32);
    for corner in 0..8 {
        let o = IVec3::new(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        let w = [0, 1, 2]
            .map(|a| if o[a] == 1 { t[a] } else { 1.0 - t[a] })
            .iter()
            .product::<f32>();
        let Some(u) = v.find(base + o) else { continue };
        let f = faces.of_voxel[(6 * u + dir) as usize];
        if f != INVALID {
            sum += w * irr[f as usize];
            wsum += w;
        }
    }
    let e = if wsum > 0.0 {
        sum / wsum
    } else {
        nearest_face(v, faces, irr, sp.pos, sp.normal)
    };
    sp.albedo / std::f32::consts::PI * e
}

/// The fallback of `lookup_pixel`: the exposed face of the voxel at `p` whose axis is nearest `n`
/// (cos > 0), zero when there is none.
fn nearest_face(v: &Voxels, faces: &Faces, irr: &[Vec3], p: Vec3, n: Vec3) -> Vec3 {
    let Some(u) = v.at_surface(p, -n) else {
        return Vec3::ZERO;
    };
    let mut best = (0.0f32, INVALID);
    for dir in 0..6 {
        let f = faces.of_voxel[(6 * u + dir) as usize];
        let c = face_axis(dir).dot(n);
        if f != INVALID && c > best.0 {
            best = (c, f);
        }
    }
    if best.1 == INVALID {
        Vec3::ZERO
    } else {
        irr[best.1 as usize]
    }
}
