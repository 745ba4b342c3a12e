// Light sampling: emissive triangles chosen by power (CDF in `emitters`), and punctual lights.
#import common/surface.wgsl
#import common/sampling.wgsl

// A point on an emitter: position, its shading normal, emitted radiance, pdf in area measure
// (including the probability of choosing the triangle).
struct EmitterSample {
    p: vec3<f32>,
    n: vec3<f32>,
    le: vec3<f32>,
    pdf_area: f32,
}

// The emitter whose CDF interval contains u (binary search).
fn emitter_index(u: f32) -> u32 {
    var lo = 0u;
    var hi = scene.num_emitters - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if emitters[mid].cdf <= u {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

fn sample_emitter(u0: f32, u1: f32, u2: f32) -> EmitterSample {
    let i = emitter_index(u0);
    let e = emitters[i];
    let b = sample_triangle(u1, u2);
    var s: EmitterSample;
    s.p = tri_point(e.slot, b.x, b.y);
    s.n = tri_shading_normal(e.slot, b.x, b.y);
    let m = materials[tri_material(e.slot)];
    s.le = material_emission(m, tri_uv(e.slot, b.x, b.y));
    s.pdf_area = (e.power / scene.emit_power) / e.area;
    return s;
}

// Irradiance at normal incidence from punctual light i at p, with the unit direction towards the light
// and the distance (INF for directional lights).
struct PunctualSample {
    wi: vec3<f32>,
    dist: f32,
    e: vec3<f32>,
}

fn punctual_sample(i: u32, p: vec3<f32>) -> PunctualSample {
    let l = lights[i];
    let kind = u32(l.pos_kind.w);
    var s: PunctualSample;
    if kind == 2u {
        s.wi = -l.dir_cos_outer.xyz;
        s.dist = INF;
        s.e = l.color_cos_inner.xyz;
        return s;
    }
    let d = l.pos_kind.xyz - p;
    let d2 = max(dot(d, d), 1e-30);
    s.dist = sqrt(d2);
    s.wi = d / s.dist;
    var falloff = 1.0;
    if kind == 1u {
        // glTF spot cone: smooth between the outer and inner cone cosines.
        let cd = dot(l.dir_cos_outer.xyz, -s.wi);
        let co = l.dir_cos_outer.w;
        let ci = l.color_cos_inner.w;
        let t = clamp((cd - co) / max(ci - co, 1e-4), 0.0, 1.0);
        falloff = t * t;
    }
    s.e = l.color_cos_inner.xyz * falloff / d2;
    return s;
}
