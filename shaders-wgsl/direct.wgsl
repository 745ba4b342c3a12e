// Direct light per shading point: stratified area-light samples (emitters chosen by power) and every
// punctual light, each with its own shadow ray; emission is added. CPU twin: `CpuScene::direct` (crates/core/src/cpu/shading.rs).
#import common/bvh.wgsl
#import common/lights.wgsl
#import common/rng.wgsl
#import common/chunk.wgsl
#import common/gbuffer.wgsl

struct DirectParams {
    // Area-light samples per pixel (stratified over the emitter CDF).
    spp: u32,
    _a: u32,
    _b: u32,
    _c: u32,
}

@group(1) @binding(1) var<uniform> params: DirectParams;
@group(1) @binding(2) var<storage, read> gbuffer: array<ShadingPoint>;
@group(1) @binding(3) var<storage, read_write> radiance: array<vec4<f32>>;

// Shadow ray from SP p (normal n) to point q: true if unblocked.
fn visible(p: vec3<f32>, n: vec3<f32>, q: vec3<f32>) -> bool {
    let o = offset_origin(p, n);
    let d = q - o;
    let dist = length(d);
    if !(dist > 0.0) {
        return false;
    }
    let ray = Ray(o, d / dist, 0.0, dist * (1.0 - 1e-4) - scene.eps);
    return !trace_any(ray);
}

// Random numbers restart every RNG_BLOCK samples from a stream seeded by the block, so a sub range that
// starts at a block boundary needs no earlier draws (crates/core/src/gi/direct.rs splits the samples that way).
// With at most RNG_BLOCK samples the stream is the single one of block 0.
const RNG_BLOCK: u32 = 64u;

// This chunk's share of the direct light: the area-light samples and punctual lights in its sub range
// [chunk.sub_offset, + chunk.sub_count) of (spp area samples, then num_lights lights). Each invocation
// walks a bounded range: lavapipe ends every loop of a SIMD batch after 65,535 trips in all
// (LP_MAX_TGSI_LOOP_ITERATIONS), so thousands of samples in one invocation silently lost most of them.
fn direct_light(sp: ShadingPoint, pixel: u32) -> vec3<f32> {
    let p = sp.pos.xyz;
    let n = sp.nrm.xyz;
    var sum = vec3<f32>(0.0);
    let first = chunk.sub_offset;
    let end = chunk.sub_offset + chunk.sub_count;
    // Area samples [0, spp), then the punctual lights (the host sets spp = 0 without emitters).
    let spp = params.spp;
    if HAS_EMITTERS && scene.num_emitters > 0u {
        var rng = 0u;
        var area_sum = vec3<f32>(0.0);
        for (var s = first; s < min(end, spp); s++) {
            if s % RNG_BLOCK == 0u {
                rng = rng_seed(pixel, chunk.seed, 0x9e3779b9u + s / RNG_BLOCK);
            }
            let u0 = (f32(s) + rng_next(&rng)) / f32(spp);
            let ls = sample_emitter(min(u0, 0.99999994), rng_next(&rng), rng_next(&rng));
            let d = ls.p - p;
            let d2 = dot(d, d);
            if !(d2 > 0.0) {
                continue;
            }
            let wi = d * inverseSqrt(d2);
            let cos_p = dot(n, wi);
            let cos_l = dot(ls.n, -wi);
            if cos_p <= 0.0 || cos_l <= 0.0 || ls.pdf_area <= 0.0 {
                continue;
            }
            if visible(p, n, ls.p + ls.n * scene.eps) {
                area_sum += ls.le * cos_p * cos_l / (d2 * ls.pdf_area);
            }
        }
        sum += area_sum / f32(max(spp, 1u));
    }
    if HAS_PUNCTUAL {
        for (var l = max(first, spp) - spp; l < min(max(end, spp) - spp, scene.num_lights); l++) {
            let ps = punctual_sample(l, p);
            let cos_p = dot(n, ps.wi);
            if cos_p <= 0.0 || all(ps.e == vec3<f32>(0.0)) {
                continue;
            }
            let o = offset_origin(p, n);
            var tmax = INF;
            if ps.dist < INF {
                tmax = ps.dist * (1.0 - 1e-4);
            }
            if !trace_any(Ray(o, ps.wi, 0.0, tmax)) {
                sum += ps.e * cos_p;
            }
        }
    }
    return sp.albedo.xyz / PI * sum;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    if i == INVALID {
        return;
    }
    let sp = gbuffer[i];
    var c = vec3<f32>(0.0);
    if sp.pos.w > 0.0 {
        c = direct_light(sp, i);
    }
    // The first sub range writes the pixel (with its emission), the others add to it.
    if chunk.sub_offset == 0u {
        if sp.pos.w > 0.0 {
            c = sp.emission.xyz + c;
        }
        radiance[i] = vec4<f32>(c, 1.0);
    } else {
        radiance[i] += vec4<f32>(c, 0.0);
    }
}
