// VPLs and their contribution to a shading point (Eq. 5); mirrored by crates/core/src/cpu/vpl.rs.
#import common/scene.wgsl

// A VPL: position, normal (the side it lights), flux reflected at its hit (RGB). As a Lambertian
// reflector it has radiant intensity I = flux / pi * cos(theta) about its normal. As a VPL-cluster
// light (gi::vpl_cluster): the representative VPL with the members' summed flux, flux.w the share
// of that flux from the other members and nrm.w their flux-weighted mean squared distance from the
// representative (both 0 for a VPL; eq5_cluster_radiance).
struct Vpl {
    pos: vec4<f32>,
    nrm: vec4<f32>,
    flux: vec4<f32>,
}

// One term of Eq. (5) without visibility: I_j(p) rho(p) G(p, p_j), with rho = albedo / pi and the
// G-term's 1/d^2 clamped at d_min^2 (scale-free: d_min is a fraction of the scene diagonal).
// Returns zero when either cosine is not positive.
fn eq5_vpl_radiance(p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, v: Vpl, d_min2: f32) -> vec3<f32> {
    return eq5_term(p, n, albedo, v, d_min2, false);
}

// How a VPL-cluster light reaches a point (--cluster-light): true, the spread below (the default);
// false, the paper's point light, eq5_vpl_radiance of the representative with the summed flux. Set
// by the pipelines that shade with cluster lights (crates/core/src/method/colom/shade.rs, crates/core/src/gi/reference.rs), each built
// per value, so the point light costs no test of the spread.
override CLUSTER_SPREAD: bool = true;

// Not in the paper (docs/clustering.md, "VPL clusters as lights"): Eq. (5)'s term of a VPL-cluster
// light, with CLUSTER_SPREAD (else the representative as a point light). The representative's own
// share of the flux (1 - flux.w) is its VPL's term; the other members' share (flux.w), which lies
// around it at a root-mean-square distance r (r^2 = nrm.w), is evaluated with the G-term's d
// clamped at max(d_min, r): a cluster spread over r is no point closer than r. The same cosines for
// both, so the two shares are one G-term times cluster_spread. A VPL (flux.w = 0) gives
// eq5_vpl_radiance's value bit for bit. CPU twin: cpu::vpl::eq5_cluster_radiance.
fn eq5_cluster_radiance(p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, v: Vpl, d_min2: f32) -> vec3<f32> {
    return eq5_term(p, n, albedo, v, d_min2, CLUSTER_SPREAD);
}

// Not in the paper: the spread's factor on a cluster light's G-term, (1 - s) + s d'^2 / d''^2 with
// s = flux.w, d'^2 = max(d^2, d_min^2) (the own share's clamp) and d''^2 = max(d^2, d_min^2, r^2)
// (the other members'). CPU twin: cpu::vpl::cluster_spread.
fn cluster_spread(d2: f32, d_min2: f32, v: Vpl) -> f32 {
    return (1.0 - v.flux.w) + v.flux.w * (max(d2, d_min2) / max(d2, max(d_min2, v.nrm.w)));
}

// Eq. (5)'s term (eq5_vpl_radiance), with `spread` the G-term times cluster_spread for a light
// with other members (flux.w > 0). CPU twin: cpu::vpl::eq5_term.
fn eq5_term(p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, v: Vpl, d_min2: f32, spread: bool) -> vec3<f32> {
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
    var g = cos_p * cos_v / max(d2, d_min2);
    if spread && v.flux.w > 0.0 {
        g *= cluster_spread(d2, d_min2, v);
    }
    return (v.flux.xyz / PI) * (albedo / PI) * g;
}
