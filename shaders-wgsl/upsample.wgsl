// The indirect light at a lower resolution than the image (`--indirect-scale`, crates/core/src/gi/upsample.rs):
// `downsample` builds the render-scale G-buffer from the image's (one representative shading point a
// low-res pixel), the indirect passes run on it unchanged, and `upsample` brings their light back to
// every image pixel with joint bilateral weights (bilinear x plane distance x normal agreement),
// falling back to the low-res tap nearest in depth where no tap matches. CPU twin: crates/core/src/cpu/upsample.rs.
#import common/chunk.wgsl
#import common/gbuffer.wgsl

struct UpsampleParams {
    // image width, height; low-res width, height.
    size: vec4<u32>,
    // xyz: the eye; w: the angle a low-res pixel spans (2 tan(fov / 2) / low-res height).
    eye: vec4<f32>,
}

@group(1) @binding(1) var<uniform> params: UpsampleParams;
@group(1) @binding(2) var<storage, read> image_gbuffer: array<ShadingPoint>;

// The image pixel low-res pixel `i` takes its shading point from: the one holding its centre.
fn representative(i: u32) -> u32 {
    let lx = i % params.size.z;
    let ly = i / params.size.z;
    let fx = min(u32(floor((f32(lx) + 0.5) * f32(params.size.x) / f32(params.size.z))), params.size.x - 1u);
    let fy = min(u32(floor((f32(ly) + 0.5) * f32(params.size.y) / f32(params.size.w))), params.size.y - 1u);
    return fy * params.size.x + fx;
}

// How far below a tap's weight sum the fallback takes over.
const MIN_WEIGHT: f32 = 1e-4;
// The normal term's exponent: max(0, n . n_q)^NORMAL_POWER.
const NORMAL_POWER: f32 = 8.0;

@group(1) @binding(3) var<storage, read_write> low_gbuffer: array<ShadingPoint>;

@compute @workgroup_size(64)
fn downsample(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    if i == 0xffffffffu {
        return;
    }
    low_gbuffer[i] = image_gbuffer[representative(i)];
}

@group(1) @binding(4) var<storage, read> low_indirect: array<vec4<f32>>;
@group(1) @binding(5) var<storage, read_write> image_indirect: array<vec4<f32>>;

// The joint bilateral weight of low-res tap `q` for an image point at `p` with normal `n`, whose
// low-res pixel spans `footprint` at its depth (0 where the tap sees nothing).
fn geometry_weight(p: vec3<f32>, n: vec3<f32>, footprint: f32, q: u32) -> f32 {
    let sq = low_gbuffer[q];
    if sq.pos.w == 0.0 {
        return 0.0;
    }
    let plane = abs(dot(n, sq.pos.xyz - p)) / footprint;
    let facing = max(dot(n, sq.nrm.xyz), 0.0);
    return exp(-plane * plane) * pow(facing, NORMAL_POWER);
}

@compute @workgroup_size(64)
fn upsample(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    if i == 0xffffffffu {
        return;
    }
    let sp = image_gbuffer[i];
    if sp.pos.w == 0.0 {
        image_indirect[i] = vec4<f32>(0.0);
        return;
    }
    let p = sp.pos.xyz;
    let n = sp.nrm.xyz;
    let depth = length(p - params.eye.xyz);
    let footprint = max(depth * params.eye.w, 1e-30);
    let lw = i32(params.size.z);
    let lh = i32(params.size.w);
    // The image point in low-res pixel coordinates (pixel centres at + 0.5).
    let u = (f32(i % params.size.x) + 0.5) * f32(params.size.z) / f32(params.size.x) - 0.5;
    let v = (f32(i / params.size.x) + 0.5) * f32(params.size.w) / f32(params.size.y) - 0.5;
    let x0 = i32(floor(u));
    let y0 = i32(floor(v));
    let fx = u - f32(x0);
    let fy = v - f32(y0);
    var sum = vec3<f32>(0.0);
    var wsum = 0.0;
    for (var t = 0u; t < 4u; t++) {
        let dx = i32(t & 1u);
        let dy = i32(t >> 1u);
        let qx = clamp(x0 + dx, 0, lw - 1);
        let qy = clamp(y0 + dy, 0, lh - 1);
        let q = u32(qy * lw + qx);
        let bx = select(1.0 - fx, fx, dx == 1);
        let by = select(1.0 - fy, fy, dy == 1);
        let w = bx * by * geometry_weight(p, n, footprint, q);
        sum += w * low_indirect[q].xyz;
        wsum += w;
    }
    if wsum > MIN_WEIGHT {
        image_indirect[i] = vec4<f32>(sum / wsum, 0.0);
        return;
    }
    // No tap matches (an edge the low-res G-buffer missed): the 3x3 tap nearest in depth.
    let cx = clamp(i32(floor(u + 0.5)), 0, lw - 1);
    let cy = clamp(i32(floor(v + 0.5)), 0, lh - 1);
    var best = 0xffffffffu;
    var best_gap = 3.4e38;
    for (var t = 0u; t < 9u; t++) {
        let qx = clamp(cx + i32(t % 3u) - 1, 0, lw - 1);
        let qy = clamp(cy + i32(t / 3u) - 1, 0, lh - 1);
        let q = u32(qy * lw + qx);
        let sq = low_gbuffer[q];
        let gap = abs(length(sq.pos.xyz - params.eye.xyz) - depth);
        if sq.pos.w != 0.0 && gap < best_gap {
            best = q;
            best_gap = gap;
        }
    }
    if best == 0xffffffffu {
        image_indirect[i] = vec4<f32>(0.0);
    } else {
        image_indirect[i] = vec4<f32>(low_indirect[best].xyz, 0.0);
    }
}
