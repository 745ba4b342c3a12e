// Step 1 of the paper's frame: light particles from the emitters (chosen by power), a VPL at every
// diffuse hit, cosine-distributed bounces, Russian roulette after the first bounce (crates/core/src/gi/vpl_trace.rs).
// Path k writes its VPLs to slots k * MAX_DEPTH + b; the host keeps the first N in path order.
#import common/bvh.wgsl
#import common/lights.wgsl
#import common/rng.wgsl
#import common/chunk.wgsl
#import common/vpl.wgsl

struct TraceParams {
    max_depth: u32,
    // Number of entries in source_cdf: [area emitters, punctual light 0, 1, ...].
    num_sources: u32,
    // Radius and centre of the scene's bounding sphere (for directional lights).
    radius: f32,
    // Index of this wave's first path (paths are numbered globally for the random numbers).
    path_base: u32,
    center: vec4<f32>,
}

@group(1) @binding(1) var<uniform> params: TraceParams;
// Inclusive CDF over light sources by power; w of entry i unused.
@group(1) @binding(2) var<storage, read> source_cdf: array<vec4<f32>>;
@group(1) @binding(3) var<storage, read_write> vpls_out: array<Vpl>;
@group(1) @binding(4) var<storage, read_write> path_len: array<u32>;

fn uniform_sphere(u1: f32, u2: f32) -> vec3<f32> {
    let z = 1.0 - 2.0 * u1;
    let r = sqrt(max(0.0, 1.0 - z * z));
    let phi = 2.0 * PI * u2;
    return vec3<f32>(r * cos(phi), r * sin(phi), z);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let path = chunk_item(gid, nwg);
    if path == INVALID {
        return;
    }
    var rng = rng_seed(params.path_base + path, chunk.seed, 0x68e31da4u);
    // Choose a source by power: x of source_cdf is the CDF, y the source's selection probability.
    let u = rng_next(&rng);
    var src = 0u;
    while src + 1u < params.num_sources && source_cdf[src].x <= u {
        src += 1u;
    }
    let p_src = source_cdf[src].y;
    var origin: vec3<f32>;
    var dir: vec3<f32>;
    var flux: vec3<f32>;
    var normal_offset = vec3<f32>(0.0);
    if src == 0u && HAS_EMITTERS && scene.num_emitters > 0u {
        // Area light: point by power over triangles then uniform, direction cosine about its normal.
        let ls = sample_emitter(rng_next(&rng), rng_next(&rng), rng_next(&rng));
        origin = ls.p;
        dir = cosine_hemisphere(ls.n, rng_next(&rng), rng_next(&rng));
        // Le cos / (p_src * pdf_area * cos/pi)
        flux = ls.le * PI / (p_src * ls.pdf_area);
        normal_offset = ls.n;
    } else {
        let l = lights[src - 1u];
        let kind = u32(l.pos_kind.w);
        let intensity = l.color_cos_inner.xyz;
        if kind == 2u {
            // Sun: parallel rays from a disc covering the scene's bounding sphere.
            let d = l.dir_cos_outer.xyz;
            let b = onb(d);
            let r = params.radius * sqrt(rng_next(&rng));
            let phi = 2.0 * PI * rng_next(&rng);
            origin = params.center.xyz - d * (2.0 * params.radius) + b[0] * (r * cos(phi)) + b[1] * (r * sin(phi));
            dir = d;
            flux = intensity * PI * params.radius * params.radius / p_src;
        } else if kind == 1u {
            // Spot: uniform in the outer cone, weighted by the glTF falloff.
            let co = l.dir_cos_outer.w;
            let ci = l.color_cos_inner.w;
            let cz = 1.0 - rng_next(&rng) * (1.0 - co);
            let sz = sqrt(max(0.0, 1.0 - cz * cz));
            let phi = 2.0 * PI * rng_next(&rng);
            dir = normalize(onb(l.dir_cos_outer.xyz) * vec3<f32>(sz * cos(phi), sz * sin(phi), cz));
            origin = l.pos_kind.xyz;
            let t = clamp((cz - co) / max(ci - co, 1e-4), 0.0, 1.0);
            flux = intensity * (t * t) * 2.0 * PI * (1.0 - co) / p_src;
        } else {
            origin = l.pos_kind.xyz;
            dir = uniform_sphere(rng_next(&rng), rng_next(&rng));
            flux = intensity * 4.0 * PI / p_src;
        }
    }
    var count = 0u;
    var o = origin;
    if any(normal_offset != vec3<f32>(0.0)) {
        o = offset_origin(origin, normal_offset);
    }
    for (var depth = 0u; depth < params.max_depth; depth++) {
        let hit = trace_closest(Ray(o, dir, 0.0, INF));
        if hit.slot == INVALID {
            break;
        }
        let s = surface_at(hit.slot, hit.u, hit.v, dir);
        let p = o + hit.t * dir;
        // Shading normals (Veach 1997, section 5.3): the camera side weighs incident light by the
        // shading cosine, a particle arrives with power per geometric area, so the irradiance it
        // stands for is its flux times cos_s / cos_g of its incoming direction (s.n and s.ng both
        // face the side it came from; light behind the shading hemisphere counts for nothing, as in
        // the direct pass and the path tracer).
        let cos_g_in = dot(-dir, s.ng);
        let cos_s_in = max(dot(-dir, s.n), 0.0);
        // Reflected flux: the particle's flux times the albedo.
        flux *= s.albedo * (cos_s_in / max(cos_g_in, 1e-6));
        if all(flux <= vec3<f32>(0.0)) {
            break;
        }
        // A VPL is a patch of the surface: it radiates about its geometric normal (projected area).
        vpls_out[path * params.max_depth + count] = Vpl(vec4<f32>(p, 1.0), vec4<f32>(s.ng, 0.0), vec4<f32>(flux, 0.0));
        count += 1u;
        // Russian roulette after the first bounce, by the largest albedo channel.
        if depth >= 1u {
            let q = clamp(max(s.albedo.x, max(s.albedo.y, s.albedo.z)), 0.05, 0.95);
            if rng_next(&rng) >= q {
                break;
            }
            flux /= q;
        }
        // Bounce: cosine about the shading normal; the VPL's radiance leaves along it weighted by the
        // geometric cosine (its intensity above), so the flux takes cos_g / cos_s. Below the
        // geometric surface nothing leaves (the path tracer ends there too).
        dir = cosine_hemisphere(s.n, rng_next(&rng), rng_next(&rng));
        let cos_g_out = dot(dir, s.ng);
        if cos_g_out <= 0.0 {
            break;
        }
        flux *= cos_g_out / max(dot(dir, s.n), 1e-6);
        o = offset_origin(p, s.ng);
    }
    path_len[path] = count;
}
