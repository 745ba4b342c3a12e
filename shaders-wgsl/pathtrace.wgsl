// A diffuse path tracer over the same BVH and materials, to check the VPL reference's own bias
// (crates/core/src/gi/pathtrace.rs). Same primary ray per pixel centre as the G-buffer; next-event estimation at
// every vertex (emitters are not hit by bounce rays: diffuse-only NEE); cosine bounces and the same
// Russian roulette as the VPL particles; at most max_vertices surface vertices. With NEE off it counts
// emission where bounce rays land instead.
#import common/bvh.wgsl
#import common/lights.wgsl
#import common/rng.wgsl
#import common/chunk.wgsl

// false: no next-event estimation; emission is counted where bounce rays hit emitters (BSDF sampling
// only), an independent estimator used to test the light sampling.
override NEE: bool = true;

struct PtParams {
    width: u32,
    height: u32,
    max_vertices: u32,
    // Samples this dispatch adds per pixel.
    spp: u32,
    eye: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    forward: vec4<f32>,
}

@group(1) @binding(1) var<uniform> params: PtParams;
@group(1) @binding(2) var<storage, read_write> accum: array<vec4<f32>>;

fn shadow_free(p: vec3<f32>, n: vec3<f32>, q: vec3<f32>, tmax_scale: f32) -> bool {
    let o = offset_origin(p, n);
    let d = q - o;
    let dist = length(d);
    if !(dist > 0.0) {
        return false;
    }
    return !trace_any(Ray(o, d / dist, 0.0, dist * tmax_scale));
}

// Direct light at a surface point (one area sample + every punctual light), as direct.wgsl.
fn nee(p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, rng: ptr<function, u32>) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    if HAS_EMITTERS && scene.num_emitters > 0u {
        let ls = sample_emitter(rng_next(rng), rng_next(rng), rng_next(rng));
        let d = ls.p - p;
        let d2 = dot(d, d);
        if d2 > 0.0 {
            let wi = d * inverseSqrt(d2);
            let cp = dot(n, wi);
            let cl = dot(ls.n, -wi);
            if cp > 0.0 && cl > 0.0 && ls.pdf_area > 0.0 && shadow_free(p, n, ls.p + ls.n * scene.eps, 1.0 - 1e-4) {
                sum += ls.le * cp * cl / (d2 * ls.pdf_area);
            }
        }
    }
    if HAS_PUNCTUAL {
        for (var l = 0u; l < scene.num_lights; l++) {
            let ps = punctual_sample(l, p);
            let cp = dot(n, ps.wi);
            if cp <= 0.0 {
                continue;
            }
            var tmax = INF;
            if ps.dist < INF {
                tmax = ps.dist * (1.0 - 1e-4);
            }
            if !trace_any(Ray(offset_origin(p, n), ps.wi, 0.0, tmax)) {
                sum += ps.e * cp;
            }
        }
    }
    return albedo / PI * sum;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let px = chunk_item(gid, nwg);
    if px == INVALID {
        return;
    }
    let x = f32(px % params.width) + 0.5;
    let y = f32(px / params.width) + 0.5;
    let sx = 2.0 * x / f32(params.width) - 1.0;
    let sy = 1.0 - 2.0 * y / f32(params.height);
    let dir0 = normalize(params.forward.xyz + sx * params.right.xyz + sy * params.up.xyz);
    var total = vec3<f32>(0.0);
    for (var s = 0u; s < params.spp; s++) {
        var rng = rng_seed(px, chunk.seed, s);
        var o = params.eye.xyz;
        var dir = dir0;
        var throughput = vec3<f32>(1.0);
        for (var v = 0u; v < params.max_vertices; v++) {
            let hit = trace_closest(Ray(o, dir, 0.0, INF));
            if hit.slot == INVALID {
                break;
            }
            let surf = surface_at(hit.slot, hit.u, hit.v, dir);
            let p = o + hit.t * dir;
            if NEE {
                if v == 0u {
                    total += surf.emission;
                }
                total += throughput * nee(p, surf.n, surf.albedo, &rng);
            } else {
                total += throughput * surf.emission;
            }
            throughput *= surf.albedo;
            // Russian roulette from the second bounce on, like the VPL particles.
            if v >= 2u {
                let q = clamp(max(surf.albedo.x, max(surf.albedo.y, surf.albedo.z)), 0.05, 0.95);
                if rng_next(&rng) >= q {
                    break;
                }
                throughput /= q;
            }
            dir = cosine_hemisphere(surf.n, rng_next(&rng), rng_next(&rng));
            // Shading normals: a direction sampled about the shading normal that goes below the
            // geometric surface carries nothing (the VPL particles end there too).
            if dot(dir, surf.ng) <= 0.0 {
                break;
            }
            o = offset_origin(p, surf.ng);
        }
    }
    accum[px] += vec4<f32>(total, f32(params.spp));
}
