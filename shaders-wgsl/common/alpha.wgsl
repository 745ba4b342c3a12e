// The alpha test (glTF alphaMode MASK; BLEND is treated as MASK at 0.5): a ray's hit on an
// alpha-tested triangle whose alpha (base colour factor x vertex alpha x base colour texture alpha)
// is below its material's cutoff is no hit. The traversal (bvh.wgsl) asks at each candidate hit,
// so every ray kind sees the same cut-out surfaces. Only leaves marked ALPHA_LEAF run the test, in
// a loop of their own: on lavapipe the mere presence of the test in the one leaf loop slowed every
// ray by ~40% (docs/scenes.md). Inside such a leaf, triangles not flagged in v0.w are plain hits,
// and a scene without any compiles the test out (HAS_ALPHA_TEST). CPU twin: `AlphaMask` in
// crates/core/src/bvh.rs.
#import common/surface.wgsl

// Alpha of one texel, repeat-wrapped.
fn texel_alpha(t: TexInfo, x: i32, y: i32) -> f32 {
    let w = i32(t.width);
    let h = i32(t.height);
    let xi = ((x % w) + w) % w;
    let yi = ((y % h) + h) % h;
    return unpack4x8unorm(texels[t.offset + u32(yi * w + xi)]).w;
}

// Bilinear, repeat-wrapped alpha of texture `index` (alpha is stored linear, no sRGB decode).
fn sample_alpha(index: i32, uv: vec2<f32>) -> f32 {
    let t = tex_info[u32(index)];
    let f = fract(uv) * vec2<f32>(f32(t.width), f32(t.height)) - 0.5;
    let i = vec2<i32>(floor(f));
    let w = f - floor(f);
    let a = texel_alpha(t, i.x, i.y);
    let b = texel_alpha(t, i.x + 1, i.y);
    let c = texel_alpha(t, i.x, i.y + 1);
    let d = texel_alpha(t, i.x + 1, i.y + 1);
    return mix(mix(a, b, w.x), mix(c, d, w.x), w.y);
}

// Whether a hit on `slot` at barycentrics (b1, b2) counts.
fn alpha_passes(slot: u32, b1: f32, b2: f32) -> bool {
    if !HAS_ALPHA_TEST {
        return true;
    }
    // The per-triangle flag: a texel fetch, where a storage load is slow on SIMD software drivers.
    if textureLoad(tri_texels, texel_xy(3u * slot), 0).w == 0.0 {
        return true;
    }
    let m = materials[tri_material(slot)];
    var a = m.base_color.w * tri_vertex_color(slot, b1, b2).w;
    if HAS_TEXTURES && m.tex.x >= 0 {
        a *= sample_alpha(m.tex.x, tri_uv(slot, b1, b2));
    }
    return a >= m.emissive.w;
}
