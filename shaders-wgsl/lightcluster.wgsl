// LightCluster (seed 002) adapted to VPLs (docs/methods.md, "lightcluster"); CPU twin:
// src/cpu/lightcluster.rs. §3.2.1: L(p) = sum_i L_d(p, l_i) (1/A_c) int_{A_c} V(p, l) dl: every VPL's
// own Eq. (5) term times the visibility of its cluster's disc (radius d_min, §3.2.2), estimated with
// DISC_SAMPLES shadow rays to fixed points of the disc (the paper filters a cube shadow map with
// PCSS). The VPLs come sorted by cluster; a dispatch walks the range [sub_offset, + sub_count) of
// them and traces a cluster's rays once per pixel, where a term of it is positive: the cluster
// whose disc was traced last and its visibility carry from one range to the next in `state`, so a
// cluster spanning several ranges is not traced again in each.
#import common/bvh.wgsl
#import common/chunk.wgsl
#import common/gbuffer.wgsl
#import common/sampling.wgsl
#import common/vpl.wgsl

struct LcParams {
    d_min2: f32,
    num_vpls: u32,
    _a: u32,
    _b: u32,
}

@group(1) @binding(1) var<uniform> params: LcParams;
@group(1) @binding(2) var<storage, read> gbuffer: array<ShadingPoint>;
// The VPLs sorted by cluster.
@group(1) @binding(3) var<storage, read> vpls: array<Vpl>;
// The cluster of each sorted VPL.
@group(1) @binding(4) var<storage, read> cluster_of: array<u32>;
// Two vec4 a cluster: the centre VPL's position with the disc radius in w, its normal.
@group(1) @binding(5) var<storage, read> discs: array<vec4<f32>>;
@group(1) @binding(6) var<storage, read_write> indirect: array<vec4<f32>>;
// Per pixel, across the ranges: the cluster traced last, its visibility (f32 bits), and the discs
// traced so far (`shadow_rays` = their sum × DISC_SAMPLES).
@group(1) @binding(7) var<storage, read_write> state: array<vec4<u32>>;

const DISC_SAMPLES: u32 = 8u;

// The fraction of the disc's DISC_SAMPLES points (a golden-angle spiral) visible from (p, n).
fn disc_visibility(p: vec3<f32>, n: vec3<f32>, c: u32) -> f32 {
    let a = discs[2u * c];
    let dn = discs[2u * c + 1u].xyz;
    let b = onb(dn);
    var seen = 0u;
    for (var i = 0u; i < DISC_SAMPLES; i++) {
        let r = a.w * sqrt((f32(i) + 0.5) / f32(DISC_SAMPLES));
        let th = 2.399963 * f32(i);
        let q = a.xyz + (b[0] * cos(th) + b[1] * sin(th)) * r;
        if vpl_visible(p, n, q, dn) {
            seen += 1u;
        }
    }
    return f32(seen) / f32(DISC_SAMPLES);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    if i == INVALID {
        return;
    }
    let sp = gbuffer[i];
    if sp.pos.w <= 0.0 {
        return;
    }
    var sum = vec3<f32>(0.0);
    var cur = INVALID;
    var vis = 0.0;
    var traced = 0u;
    if chunk.sub_offset != 0u {
        let s = state[i];
        cur = s.x;
        vis = bitcast<f32>(s.y);
        traced = s.z;
    }
    for (var j = chunk.sub_offset; j < min(chunk.sub_offset + chunk.sub_count, params.num_vpls); j++) {
        let t = eq5_vpl_radiance(sp.pos.xyz, sp.nrm.xyz, sp.albedo.xyz, vpls[j], params.d_min2);
        if any(t > vec3<f32>(0.0)) {
            let c = cluster_of[j];
            if c != cur {
                cur = c;
                vis = disc_visibility(sp.pos.xyz, sp.nrm.xyz, c);
                traced += 1u;
            }
            sum += t * vis;
        }
    }
    indirect[i] += vec4<f32>(sum, 0.0);
    state[i] = vec4<u32>(cur, bitcast<u32>(vis), traced, 0u);
}
