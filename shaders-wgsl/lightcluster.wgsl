// LightCluster (seed 002) adapted to VPLs (docs/methods.md, "lightcluster"); CPU twin:
// crates/core/src/method/lightcluster/twin.rs. §3.2.1: L(p) = sum_i L_d(p, l_i) (1/A_c) int_{A_c} V(p, l) dl: every VPL's
// own Eq. (5) term times its cluster's visibility.
// - `params.mode` 1, the paper's §3.2.2: the visibility of the cluster's disc (radius d_min) from
//   DISC_SAMPLES shadow rays to fixed points of it (the paper filters a cube shadow map with PCSS),
//   traced once per pixel and cluster where a term of the cluster is positive.
// - Mode 0, not in the paper (the default): each of the cluster's member groups (at most 8) with a
//   positive term traces one ray, to a member drawn in proportion to its term (a weighted
//   reservoir of one, `member_draw`), and the group's summed terms count when that member is
//   visible (`members_flush`): unbiased, at most 8 rays a cluster.
// The VPLs come sorted by cluster, then group; a dispatch walks the range [sub_offset, + sub_count)
// of them. What a pixel has of its current cluster or group carries from one range to the next in
// `state`, so a cluster spanning several ranges is traced once.
#import common/bvh.wgsl
#import common/chunk.wgsl
#import common/pixel.wgsl
#import common/gbuffer.wgsl
#import common/rng.wgsl
#import common/sampling.wgsl
#import common/vpl.wgsl

struct LcParams {
    d_min2: f32,
    num_vpls: u32,
    // 0: member groups; 1: the disc.
    mode: u32,
    _a: u32,
}

@group(1) @binding(1) var<uniform> params: LcParams;
@group(1) @binding(2) var<storage, read> gbuffer: array<ShadingPoint>;
// The VPLs sorted by cluster, then member group.
@group(1) @binding(3) var<storage, read> vpls: array<Vpl>;
// The cluster and member group of each sorted VPL: cluster × 8 + group.
@group(1) @binding(4) var<storage, read> cluster_of: array<u32>;
// Two vec4 a cluster: the centre VPL's position with the disc radius in w, its normal.
@group(1) @binding(5) var<storage, read> discs: array<vec4<f32>>;
@group(1) @binding(6) var<storage, read_write> indirect: array<vec4<f32>>;
// Two vec4 a pixel, across the ranges. Disc: (the cluster traced last, its visibility as f32 bits,
// the shadow rays traced so far, -), unused. Members: (the current group, cluster × 8 + group; the
// member drawn; the shadow rays traced so far; the group's terms' weight so far, f32 bits), (the
// group's terms summed so far, f32 bits, -).
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

// The uniform number of pixel i and sorted VPL j in [0, 1) that decides the draw. Twin: member_u.
fn member_u(i: u32, j: u32) -> f32 {
    return f32(pcg_hash(pcg_hash(i) ^ j) >> 8u) * (1.0 / 16777216.0);
}

// A weighted reservoir of one: after w joined a total that is now `total`, whether the member drawn
// becomes the new one (probability w / total). Not in the paper. Twin: member_draw.
fn member_draw(u: f32, w: f32, total: f32) -> bool {
    return u * total < w;
}

// A group's light at (p, n): its summed terms when the member drawn is visible (Eq. (5)'s shadow
// ray), else nothing. Not in the paper. Twin: members_flush.
fn members_flush(p: vec3<f32>, n: vec3<f32>, drawn: u32, terms: vec3<f32>) -> vec3<f32> {
    let v = vpls[drawn];
    if vpl_visible(p, n, v.pos.xyz, v.nrm.xyz) {
        return terms;
    }
    return vec3<f32>(0.0);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = surface_item(gid, nwg);
    if i == INVALID {
        return;
    }
    let sp = gbuffer[i];
    let p = sp.pos.xyz;
    let n = sp.nrm.xyz;
    var sum = vec3<f32>(0.0);
    var cur = INVALID;
    var vis = 0u;
    var traced = 0u;
    var total = 0.0;
    var terms = vec3<f32>(0.0);
    if chunk.sub_offset != 0u {
        let s = state[2u * i];
        cur = s.x;
        vis = s.y;
        traced = s.z;
        total = bitcast<f32>(s.w);
        terms = bitcast<vec3<f32>>(state[2u * i + 1u].xyz);
    }
    let end = min(chunk.sub_offset + chunk.sub_count, params.num_vpls);
    for (var j = chunk.sub_offset; j < end; j++) {
        let t = eq5_vpl_radiance(p, n, sp.albedo.xyz, vpls[j], params.d_min2);
        if any(t > vec3<f32>(0.0)) {
            if params.mode == 1u {
                let c = cluster_of[j] / 8u;
                if c != cur {
                    cur = c;
                    vis = bitcast<u32>(disc_visibility(p, n, c));
                    traced += DISC_SAMPLES;
                }
                sum += t * bitcast<f32>(vis);
            } else {
                let key = cluster_of[j];
                if key != cur {
                    if cur != INVALID {
                        sum += members_flush(p, n, vis, terms);
                        traced += 1u;
                    }
                    cur = key;
                    total = 0.0;
                    terms = vec3<f32>(0.0);
                }
                let w = t.x + t.y + t.z;
                total += w;
                terms += t;
                if member_draw(member_u(i, j), w, total) {
                    vis = j;
                }
            }
        }
    }
    // The last group ends with the last range.
    if params.mode == 0u && end == params.num_vpls && cur != INVALID {
        sum += members_flush(p, n, vis, terms);
        traced += 1u;
        cur = INVALID;
    }
    indirect[i] += vec4<f32>(sum, 0.0);
    state[2u * i] = vec4<u32>(cur, vis, traced, bitcast<u32>(total));
    state[2u * i + 1u] = vec4<u32>(bitcast<vec3<u32>>(terms), 0u);
}
