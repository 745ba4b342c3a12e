// Surface attributes at a hit: interpolated shading normal, texture coordinates, albedo, emission.
#import common/scene.wgsl

struct Surface {
    p: vec3<f32>,
    // Shading normal, flipped to the side the ray came from.
    n: vec3<f32>,
    // Geometric normal, flipped the same way.
    ng: vec3<f32>,
    albedo: vec3<f32>,
    // Emitted radiance towards the ray origin (zero from an emitter's back side).
    emission: vec3<f32>,
    material: u32,
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        return c / 12.92;
    }
    return pow((c + 0.055) / 1.055, 2.4);
}

fn fetch_texel(t: TexInfo, x: i32, y: i32) -> vec4<f32> {
    let w = i32(t.width);
    let h = i32(t.height);
    let xi = ((x % w) + w) % w;
    let yi = ((y % h) + h) % h;
    let c = unpack4x8unorm(texels[t.offset + u32(yi * w + xi)]);
    return vec4<f32>(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z), c.w);
}

// Bilinear, repeat-wrapped, sRGB-decoded texture lookup.
fn sample_texture(index: i32, uv: vec2<f32>) -> vec4<f32> {
    if !HAS_TEXTURES || index < 0 {
        return vec4<f32>(1.0);
    }
    let t = tex_info[u32(index)];
    let f = fract(uv) * vec2<f32>(f32(t.width), f32(t.height)) - 0.5;
    let i = vec2<i32>(floor(f));
    let w = f - floor(f);
    let a = fetch_texel(t, i.x, i.y);
    let b = fetch_texel(t, i.x + 1, i.y);
    let c = fetch_texel(t, i.x, i.y + 1);
    let d = fetch_texel(t, i.x + 1, i.y + 1);
    return mix(mix(a, b, w.x), mix(c, d, w.x), w.y);
}

fn tri_material(slot: u32) -> u32 {
    return bitcast<u32>(textureLoad(shade_texels, texel_xy(4u * slot + 3u), 0).w);
}

fn tri_uv(slot: u32, b1: f32, b2: f32) -> vec2<f32> {
    let s = load_tri_shade(slot);
    let uv0 = vec2<f32>(s.n0.w, s.n1.w);
    let uv1 = vec2<f32>(s.n2.w, s.extra.x);
    let uv2 = vec2<f32>(s.extra.y, s.extra.z);
    return (1.0 - b1 - b2) * uv0 + b1 * uv1 + b2 * uv2;
}

fn tri_geometric_normal(slot: u32) -> vec3<f32> {
    let t = load_tri(slot);
    return normalize(cross(t.v1.xyz - t.v0.xyz, t.v2.xyz - t.v0.xyz));
}

fn tri_shading_normal(slot: u32, b1: f32, b2: f32) -> vec3<f32> {
    let s = load_tri_shade(slot);
    let n = (1.0 - b1 - b2) * s.n0.xyz + b1 * s.n1.xyz + b2 * s.n2.xyz;
    let l = length(n);
    if !(l > 1e-12) {
        return tri_geometric_normal(slot);
    }
    return n / l;
}

fn tri_point(slot: u32, b1: f32, b2: f32) -> vec3<f32> {
    let t = load_tri(slot);
    return (1.0 - b1 - b2) * t.v0.xyz + b1 * t.v1.xyz + b2 * t.v2.xyz;
}

// Emitted radiance of a material at uv (front side).
fn material_emission(m: Material, uv: vec2<f32>) -> vec3<f32> {
    var e = m.emissive.xyz;
    if HAS_TEXTURES && m.tex.y >= 0 {
        e *= sample_texture(m.tex.y, uv).xyz;
    }
    return e;
}

// Interpolated vertex colour (COLOR_0), white without vertex colours.
fn tri_vertex_color(slot: u32, b1: f32, b2: f32) -> vec4<f32> {
    if !HAS_VERTEX_COLORS {
        return vec4<f32>(1.0);
    }
    return (1.0 - b1 - b2) * tri_colors[3u * slot] + b1 * tri_colors[3u * slot + 1u] + b2 * tri_colors[3u * slot + 2u];
}

// Base colour factor x texture x vertex colour (`color`: white without vertex colours).
fn material_albedo(m: Material, uv: vec2<f32>, color: vec3<f32>) -> vec3<f32> {
    var a = m.base_color.xyz;
    if HAS_TEXTURES && m.tex.x >= 0 {
        a *= sample_texture(m.tex.x, uv).xyz;
    }
    if HAS_VERTEX_COLORS {
        a *= color;
    }
    return clamp(a, vec3<f32>(0.0), vec3<f32>(1.0));
}

// The surface seen by a ray travelling along `dir` that hit `slot` at barycentrics (b1, b2).
fn surface_at(slot: u32, b1: f32, b2: f32, dir: vec3<f32>) -> Surface {
    var s: Surface;
    s.material = tri_material(slot);
    let m = materials[s.material];
    let uv = tri_uv(slot, b1, b2);
    s.p = tri_point(slot, b1, b2);
    var ng = tri_geometric_normal(slot);
    var n = tri_shading_normal(slot, b1, b2);
    // Emitters emit on the side their shading normal points to.
    let front = dot(n, dir) < 0.0;
    s.emission = select(vec3<f32>(0.0), material_emission(m, uv), front);
    // Two-sided diffuse: face both normals towards the viewer.
    if dot(ng, dir) > 0.0 {
        ng = -ng;
    }
    if dot(n, ng) < 0.0 {
        n = -n;
    }
    s.n = n;
    s.ng = ng;
    s.albedo = material_albedo(m, uv, tri_vertex_color(slot, b1, b2).xyz);
    return s;
}
