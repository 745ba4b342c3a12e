//! CPU twin of `common/vpl.wgsl` and `reference.wgsl`: Eq. (5) for one shading point.

use glam::Vec3;

use super::shading::CpuScene;
use crate::gi::primary::ShadingPoint;
use crate::gi::vpl_trace::Vpl;

/// One term of Eq. (5) without visibility: I_j(p) ρ(p) G(p, p_j), 1/d² clamped at d_min².
pub fn eq5_vpl_radiance(p: Vec3, n: Vec3, albedo: Vec3, v: &Vpl, d_min2: f32) -> Vec3 {
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
    let g = cp * cv / d2.max(d_min2);
    let pi = std::f32::consts::PI;
    Vec3::new(v.flux[0], v.flux[1], v.flux[2]) / pi * (albedo / pi) * g
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

    /// Eq. (5): indirect light at `sp` from every VPL.
    pub fn reference_indirect(&self, sp: &ShadingPoint, vpls: &[Vpl], d_min2: f32) -> Vec3 {
        if !sp.valid {
            return Vec3::ZERO;
        }
        vpls.iter()
            .map(|v| {
                let c = eq5_vpl_radiance(sp.pos, sp.normal, sp.albedo, v, d_min2);
                if c.max_element() > 0.0 && self.vpl_visible(sp.pos, sp.normal, v) {
                    c
                } else {
                    Vec3::ZERO
                }
            })
            .sum()
    }
}
