// Scene data shared by every pass: bind group 0, laid out by crates/core/src/gi/scene_gpu.rs.
// Triangle arrays are in BVH slot order (see crates/core/src/bvh.rs).

struct SceneInfo {
    num_tris: u32,
    num_nodes: u32,
    num_emitters: u32,
    num_lights: u32,
    // Sum of emitter powers (area x luminance of emitted radiance), the emitter CDF's total.
    emit_power: f32,
    // Ray offset scale: 1e-5 x the scene's diagonal (scale-free self-intersection guard).
    eps: f32,
    extent: f32,
    _pad: u32,
}

// BVH2 in depth-first preorder with skip links (crates/core/src/bvh.rs): an inner node's first child follows it;
// `index` is the inner node's skip link (next node after its subtree) or the leaf's first triangle slot.
// Stored as two texels of `bvh_texels` (min | prim_count, max | index); see bvh.wgsl for why textures.
// A leaf holding an alpha-tested triangle has ALPHA_LEAF set in prim_count (alpha.wgsl).
struct BvhNode {
    min: vec3<f32>,
    prim_count: u32,
    max: vec3<f32>,
    index: u32,
}

// v0.w is the alpha test's per-triangle flag (1: alpha-tested, 0: opaque); see alpha.wgsl.
struct Tri {
    v0: vec4<f32>,
    v1: vec4<f32>,
    v2: vec4<f32>,
}

// Shading normals and texture coordinates: n0..n2 carry u0, v0, u1 in w; `extra` is (v1, u2, v2, material).
struct TriShade {
    n0: vec4<f32>,
    n1: vec4<f32>,
    n2: vec4<f32>,
    extra: vec4<f32>,
}

struct Material {
    base_color: vec4<f32>,
    // xyz: emitted radiance; w: the alpha test's cutoff (0 for opaque materials).
    emissive: vec4<f32>,
    // x: base colour texture, y: emissive texture (-1 = none).
    tex: vec4<i32>,
}

struct TexInfo {
    offset: u32,
    width: u32,
    height: u32,
    _pad: u32,
}

// An emissive triangle with its CDF value (inclusive prefix sum of power, normalised to 1).
struct Emitter {
    slot: u32,
    cdf: f32,
    area: f32,
    power: f32,
}

// kind: 0 point, 1 spot, 2 directional. dir: direction light travels. color = colour x intensity.
struct Light {
    pos_kind: vec4<f32>,
    dir_cos_outer: vec4<f32>,
    color_cos_inner: vec4<f32>,
}

@group(0) @binding(0) var<uniform> scene: SceneInfo;
@group(0) @binding(1) var bvh_texels: texture_2d<u32>;
// Shading normals and uvs, 4 texels (n0, n1, n2, extra of TriShade) a triangle: a texture rather than a
// storage buffer so that a scene is not limited by one storage binding (128 MiB on lavapipe: 2.1 M
// triangles at 64 bytes); data textures hold 33.5 M texels (crates/core/src/gi/scene_gpu.rs, MAX_TEXELS).
@group(0) @binding(3) var shade_texels: texture_2d<f32>;
@group(0) @binding(4) var<storage, read> materials: array<Material>;
@group(0) @binding(5) var<storage, read> tex_info: array<TexInfo>;
@group(0) @binding(6) var<storage, read> texels: array<u32>;
@group(0) @binding(7) var<storage, read> emitters: array<Emitter>;
@group(0) @binding(8) var<storage, read> lights: array<Light>;
// The triangles' vertices, 3 texels (v0, v1, v2) each, for the traversal and the shading.
@group(0) @binding(9) var tri_texels: texture_2d<f32>;
// Linear vertex colours (COLOR_0), 3 per triangle slot; one unused entry without HAS_VERTEX_COLORS.
@group(0) @binding(10) var<storage, read> tri_colors: array<vec4<f32>>;

// Texel i of a data texture: TEXEL_ROW (4096) texels a row (crates/core/src/gi/scene_gpu.rs).
fn texel_xy(i: u32) -> vec2<u32> {
    return vec2<u32>(i & 4095u, i >> 12u);
}

fn load_tri(slot: u32) -> Tri {
    return Tri(
        textureLoad(tri_texels, texel_xy(3u * slot), 0),
        textureLoad(tri_texels, texel_xy(3u * slot + 1u), 0),
        textureLoad(tri_texels, texel_xy(3u * slot + 2u), 0),
    );
}

fn load_tri_shade(slot: u32) -> TriShade {
    return TriShade(
        textureLoad(shade_texels, texel_xy(4u * slot), 0),
        textureLoad(shade_texels, texel_xy(4u * slot + 1u), 0),
        textureLoad(shade_texels, texel_xy(4u * slot + 2u), 0),
        textureLoad(shade_texels, texel_xy(4u * slot + 3u), 0),
    );
}

// Pipeline-overridable switches: a scene without textures or punctual lights compiles those paths out.
override HAS_TEXTURES: bool = true;
override HAS_EMITTERS: bool = true;
override HAS_PUNCTUAL: bool = true;
// Without alpha-tested triangles the traversal is compiled without the alpha test (alpha.wgsl).
override HAS_ALPHA_TEST: bool = true;
override HAS_VERTEX_COLORS: bool = true;

const PI: f32 = 3.14159265358979;
const INF: f32 = 3.4028235e38;
const INVALID: u32 = 0xffffffffu;
const ALPHA_LEAF: u32 = 0x80000000u;

fn max_abs3(p: vec3<f32>) -> f32 {
    let a = abs(p);
    return max(a.x, max(a.y, a.z));
}

// Offsets a ray origin off a surface along `n` by a scale-free distance.
fn offset_origin(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return p + n * (scene.eps + 4e-6 * max_abs3(p));
}
