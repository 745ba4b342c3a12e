// Wang et al. 2009 (seed 001) adapted to VPL lighting (docs/methods.md, "wang"); CPU twin:
// crates/core/src/method/wang/twin.rs. Two entry points, each its own pipeline (crates/core/src/method/wang/mod.rs); the clustering
// of §3.2 is wang_cluster.wgsl:
// - radius: §3.4's R_j, the harmonic mean distance to the surfaces seen from sample point j (summed
//   inverse hit distances of cosine-distributed rays);
// - interp: §3.4's interpolation of the sample points' irradiance with
//   w(s_j) = 1 / (|x - s_j| / R_j + sqrt(2 - 2 n(x).n(s_j))).
// The irradiance at the sample points is gathered by reference.wgsl (every VPL cluster with its own
// shadow ray), the samples being shading points of albedo 1.
#import common/bvh.wgsl
#import common/chunk.wgsl
#import common/gbuffer.wgsl
#import common/rng.wgsl
#import common/sampling.wgsl

struct WangParams {
    width: u32,
    height: u32,
    // s of interp's neighbourhood {-s, 0, s}^2.
    stride: u32,
    _p0: u32,
    _p1: u32,
    seed: u32,
    // R_j's clamp [r_min, r_max] (crates/core/src/method/wang/twin.rs, radius_from_sum).
    r_min: f32,
    r_max: f32,
    // Rays of R_j in all.
    rays: u32,
    _a: u32,
    _b: u32,
    _c: u32,
}

@group(1) @binding(1) var<uniform> params: WangParams;
@group(1) @binding(2) var<storage, read> gbuffer: array<ShadingPoint>;
// The labels interp reads, as a texture (DATA_ROW = 4096 texels a row): on lavapipe a texel fetch
// gathers for a whole SIMD batch, a storage read with a per-lane address is a scalar loop per lane
// (shade.wgsl).
@group(1) @binding(3) var labels_tex: texture_2d<u32>;
// Two vec4 a cluster: its sample point (w = 1: it has one), normal.
@group(1) @binding(5) var points_tex: texture_2d<f32>;
// Per sample point its gathered irradiance times 1/pi (reference.wgsl with albedo 1).
@group(1) @binding(6) var<storage, read> irradiance: array<vec4<f32>>;
@group(1) @binding(7) var<storage, read_write> indirect: array<vec4<f32>>;
// Per sample point x: the summed 1/t of its R_j rays.
@group(1) @binding(8) var<storage, read_write> radius_sum: array<vec4<f32>>;

fn label_at(q: u32) -> u32 {
    return textureLoad(labels_tex, vec2<u32>(q & 4095u, q >> 12u), 0).x;
}

fn point(i: u32) -> vec4<f32> {
    return textureLoad(points_tex, vec2<u32>(i & 4095u, i >> 12u), 0);
}

// The label of the pixel at (x, y) + d * stride, or INVALID outside the image.
fn neighbour(x: i32, y: i32, dx: i32, dy: i32, s: i32) -> u32 {
    let qx = x + dx * s;
    let qy = y + dy * s;
    if qx < 0 || qy < 0 || qx >= i32(params.width) || qy >= i32(params.height) {
        return INVALID;
    }
    return u32(qy) * params.width + u32(qx);
}

@compute @workgroup_size(64)
fn radius(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = chunk_item(gid, nwg);
    if j == INVALID {
        return;
    }
    let p = point(2u * j);
    var sum = 0.0;
    if p.w > 0.0 {
        let n = point(2u * j + 1u).xyz;
        let o = offset_origin(p.xyz, n);
        for (var r = chunk.sub_offset; r < chunk.sub_offset + chunk.sub_count; r++) {
            var st = rng_seed(params.seed, j, r);
            let u1 = rng_next(&st);
            let u2 = rng_next(&st);
            let h = trace_closest(Ray(o, cosine_hemisphere(n, u1, u2), 0.0, INF));
            if h.slot != INVALID {
                sum += 1.0 / max(h.t, 1e-30);
            }
        }
    }
    if chunk.sub_offset == 0u {
        radius_sum[j] = vec4<f32>(sum, 0.0, 0.0, 0.0);
    } else {
        radius_sum[j].x += sum;
    }
}

// R_j from the summed inverse distances (crates/core/src/method/wang/twin.rs, radius_from_sum).
fn radius_of(j: u32) -> f32 {
    let s = radius_sum[j].x;
    var r = params.r_max;
    if s > 0.0 {
        r = f32(params.rays) / s;
    }
    return clamp(r, params.r_min, params.r_max);
}

@compute @workgroup_size(64)
fn interp(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = chunk_item(gid, nwg);
    if m == INVALID {
        return;
    }
    let sp = gbuffer[m];
    let own = label_at(m);
    if sp.pos.w <= 0.0 || own == INVALID || point(2u * own).w <= 0.0 {
        indirect[m] = vec4<f32>(0.0);
        return;
    }
    let x = i32(m % params.width);
    let y = i32(m / params.width);
    let s = i32(params.stride);
    var seen: array<u32, 9>;
    var ns = 0u;
    var sum = vec3<f32>(0.0);
    var wsum = 0.0;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let q = neighbour(x, y, dx, dy, s);
            if q == INVALID {
                continue;
            }
            let j = label_at(q);
            if j == INVALID {
                continue;
            }
            var dup = false;
            for (var i = 0u; i < ns; i++) {
                dup = dup || seen[i] == j;
            }
            if dup {
                continue;
            }
            seen[ns] = j;
            ns += 1u;
            let pj = point(2u * j);
            let nj = point(2u * j + 1u).xyz;
            if pj.w <= 0.0 || (j != own && dot(sp.nrm.xyz, nj) <= 0.0) {
                continue;
            }
            let den = length(sp.pos.xyz - pj.xyz) / radius_of(j) + sqrt(max(0.0, 2.0 - 2.0 * dot(sp.nrm.xyz, nj)));
            if den <= 1e-6 {
                indirect[m] = vec4<f32>(sp.albedo.xyz * irradiance[j].xyz, 0.0);
                return;
            }
            let w = 1.0 / den;
            sum += irradiance[j].xyz * w;
            wsum += w;
        }
    }
    var e = vec3<f32>(0.0);
    if wsum > 0.0 {
        e = sum / wsum;
    }
    indirect[m] = vec4<f32>(sp.albedo.xyz * e, 0.0);
}
