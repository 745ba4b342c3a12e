// VPLs and their contribution to a shading point (Eq. 5); mirrored by src/cpu/vpl.rs.
#import common/scene.wgsl

// A VPL: position, normal (the side it lights), flux reflected at its hit (RGB). As a Lambertian
// reflector it has radiant intensity I = flux / pi * cos(theta) about its normal.
struct Vpl {
    pos: vec4<f32>,
    nrm: vec4<f32>,
    flux: vec4<f32>,
}

// One term of Eq. (5) without visibility: I_j(p) rho(p) G(p, p_j), with rho = albedo / pi and the
// G-term's 1/d^2 clamped at d_min^2 (scale-free: d_min is a fraction of the scene diagonal).
// Returns zero when either cosine is not positive.
fn eq5_vpl_radiance(p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, v: Vpl, d_min2: f32) -> vec3<f32> {
    let d = v.pos.xyz - p;
    let d2 = dot(d, d);
    if !(d2 > 0.0) {
        return vec3<f32>(0.0);
    }
    let wi = d * inverseSqrt(d2);
    let cos_p = dot(n, wi);
    let cos_v = dot(v.nrm.xyz, -wi);
    if cos_p <= 0.0 || cos_v <= 0.0 {
        return vec3<f32>(0.0);
    }
    let g = cos_p * cos_v / max(d2, d_min2);
    return (v.flux.xyz / PI) * (albedo / PI) * g;
}
