//! CPU twin of `common/vpl.wgsl` and `reference.wgsl`: Eq. (5) for one shading point.

use glam::Vec3;

use super::shading::CpuScene;
use crate::gi::primary::ShadingPoint;
use crate::gi::vpl_trace::Vpl;
use crate::settings::ClusterLight;

/// One term of Eq. (5) without visibility: I_j(p) ρ(p) G(p, p_j), 1/d² clamped at d_min².
pub fn eq5_vpl_radiance(p: Vec3, n: Vec3, albedo: Vec3, v: &Vpl, d_min2: f32) -> Vec3 {
    eq5_term(p, n, albedo, v, d_min2, false)
}

/// Not in the paper: Eq. (5)'s term of a VPL-cluster light, the representative's own share of the
/// flux (1 − `flux[3]`) as its VPL's term and the other members' share (`flux[3]`) with d clamped
/// at max(d_min, r), r² = `nrm[3]` their mean squared distance from it: one G-term times
/// `cluster_spread`. A VPL (`flux[3]` = 0) gives `eq5_vpl_radiance`. Twin of
/// `eq5_cluster_radiance` in `common/vpl.wgsl`.
pub fn eq5_cluster_radiance(p: Vec3, n: Vec3, albedo: Vec3, v: &Vpl, d_min2: f32) -> Vec3 {
    eq5_term(p, n, albedo, v, d_min2, true)
}

/// Not in the paper: the spread's factor on a cluster light's G-term, (1 − s) + s d′² / d″² with
/// s = `flux[3]`, d′² = max(d², d_min²) and d″² = max(d², d_min², r²) (twin of `cluster_spread`
/// in `common/vpl.wgsl`).
pub fn cluster_spread(d2: f32, d_min2: f32, v: &Vpl) -> f32 {
    let s = v.flux[3];
    (1.0 - s) + s * (d2.max(d_min2) / d2.max(d_min2.max(v.nrm[3])))
}

/// Eq. (5)'s term; with `spread`, the G-term times `cluster_spread` for a light with other members
/// (twin of `eq5_term` in `common/vpl.wgsl`).
fn eq5_term(p: Vec3, n: Vec3, albedo: Vec3, v: &Vpl, d_min2: f32, spread: bool) -> Vec3 {
    let d = Vec3::new(v.pos[0], v.pos[1], v.pos[2]) - p;
    let d2 = d.dot(d);
    if d2 <= 0.0 || !d2.is_finite() {
        return Vec3::ZERO;
    }
    let wi = d / d2.sqrt();
    let vn = Vec3::new(v.nrm[0], v.nrm[1], v.nrm[2]);
    let (cp, cv) = (n.dot(wi), vn.dot(-wi));
    if cp <= 0.0 || cv <= 0.0 {
        return Vec3::ZERO;
    }
    let mut g = cp * cv / d2.max(d_min2);
    if spread && v.flux[3] > 0.0 {
        g *= cluster_spread(d2, d_min2, v);
    }
    let pi = std::f32::consts::PI;
    Vec3::new(v.flux[0], v.flux[1], v.flux[2]) / pi * (albedo / pi) * g
}

/// Eq. (5)'s term of a VPL-cluster light as `light` says (`--cluster-light`): `Point`, the paper's
/// point light (`eq5_vpl_radiance` of the representative with the summed flux); `Spread`,
/// `eq5_cluster_radiance`. Twin of `eq5_cluster_radiance` in `common/vpl.wgsl` with its
/// `CLUSTER_SPREAD`.
pub fn eq5_cluster_light(
    p: Vec3,
    n: Vec3,
    albedo: Vec3,
    v: &Vpl,
    d_min2: f32,
    light: ClusterLight,
) -> Vec3 {
    match light {
        ClusterLight::Point => eq5_vpl_radiance(p, n, albedo, v, d_min2),
        ClusterLight::Spread => eq5_cluster_radiance(p, n, albedo, v, d_min2),
    }
}

impl CpuScene<'_> {
    /// V(p, q) of Eq. (5), with the shader's offsets.
    pub fn vpl_visible(&self, p: Vec3, n: Vec3, v: &Vpl) -> bool {
        let q = Vec3::new(v.pos[0], v.pos[1], v.pos[2]);
        let qn = Vec3::new(v.nrm[0], v.nrm[1], v.nrm[2]);
        let off = |x: Vec3, m: Vec3| x + m * (self.info.eps + 4e-6 * x.abs().max_element());
        let (o, t) = (off(p, n), off(q, qn));
        let d = t - o;
        let dist = d.length();
        if dist <= 0.0 {
            return false;
        }
        !self
            .bvh
            .occluded(o.into(), (d / dist).into(), 0.0, dist * (1.0 - 1e-4))
    }

    /// Eq. (5): indirect light at `sp` from every VPL (or VPL-cluster light, `eq5_cluster_radiance`).
    pub fn reference_indirect(&self, sp: &ShadingPoint, vpls: &[Vpl], d_min2: f32) -> Vec3 {
        if !sp.valid {
            return Vec3::ZERO;
        }
        vpls.iter()
            .map(|v| {
                let c = eq5_cluster_radiance(sp.pos, sp.normal, sp.albedo, v, d_min2);
                if c.max_element() > 0.0 && self.vpl_visible(sp.pos, sp.normal, v) {
                    c
                } else {
                    Vec3::ZERO
                }
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A light at the origin facing up, the point 1 above it facing down (both cosines 1, d² = 1),
    /// albedo π (ρ = 1) and flux π (I = 1, so I ρ G = 1/d² clamped): the VPL's term 1. As a cluster light
    /// with the other members' share 0.75 spread over r² = 4 (d_min² = 0.25): 0.25·1 + 0.75·(1/4)
    /// = 0.4375. At d = 3 (beyond r) both are 1/9: the far field is the VPL's.
    #[test]
    fn cluster_term_by_hand() {
        let pi = std::f32::consts::PI;
        let mut v = Vpl {
            pos: [0.0, 0.0, 0.0, 1.0],
            nrm: [0.0, 1.0, 0.0, 0.0],
            flux: [pi, pi, pi, 0.0],
        };
        let (n, a) = (Vec3::NEG_Y, Vec3::splat(pi));
        let near = Vec3::new(0.0, 1.0, 0.0);
        let far = Vec3::new(0.0, 3.0, 0.0);
        let vpl_near = eq5_vpl_radiance(near, n, a, &v, 0.25);
        assert!(
            (vpl_near - Vec3::ONE).abs().max_element() < 1e-6,
            "{vpl_near}"
        );
        assert_eq!(eq5_cluster_radiance(near, n, a, &v, 0.25), vpl_near);
        v.flux[3] = 0.75;
        v.nrm[3] = 4.0;
        let c = eq5_cluster_radiance(near, n, a, &v, 0.25);
        assert!((c - Vec3::splat(0.4375)).abs().max_element() < 1e-6, "{c}");
        let c = eq5_cluster_radiance(far, n, a, &v, 0.25);
        assert!(
            (c - Vec3::splat(1.0 / 9.0)).abs().max_element() < 1e-6,
            "{c}"
        );
        // The clamp at d_min when it is the larger: r² = 0.01 < d_min² = 0.25 changes nothing at d = 0.3.
        v.nrm[3] = 0.01;
        let p = Vec3::new(0.0, 0.3, 0.0);
        assert_eq!(
            eq5_cluster_radiance(p, n, a, &v, 0.25),
            eq5_vpl_radiance(p, n, a, &v, 0.25)
        );
    }
}
