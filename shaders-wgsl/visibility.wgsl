// Step 5: one shadow ray per (SP-cluster representative, light representative) pair, stored as a bit
// matrix: bit c of row k is V(p_k, p_c). Lights are VPL-cluster representatives (or the VPLs
// themselves when VPLs are not clustered). Each invocation fills one 32-bit word of a row.
#import common/bvh.wgsl
#import common/chunk.wgsl
#import common/vpl.wgsl

// VisParams, declared in Rust (crates/core/src/method/colom/visibility.rs: its fields' meaning).
#import rust/VisParams

@group(1) @binding(1) var<uniform> params: VisParams;
// SP-cluster representatives as points (kmeans.wgsl `rep_points`): position with w > 0 when the
// cluster has one, then normal.
@group(1) @binding(2) var<storage, read> rep_points: array<vec4<f32>>;
// Lights as 3 texels each (pos, nrm, flux), 4096 texels a row (texel fetches are vector code on
// lavapipe, per-lane storage reads scalar loops; see shade.wgsl).
@group(1) @binding(4) var lights_tex: texture_2d<f32>;

fn light_texel(i: u32) -> vec4<f32> {
    return textureLoad(lights_tex, vec2<u32>(i & 4095u, i >> 12u), 0);
}
@group(1) @binding(5) var<storage, read_write> bits: array<u32>;
// The previous frame's matrix (one word when not reused).
@group(1) @binding(6) var<storage, read> prev_bits: array<u32>;

// Not in the paper, and no change to V: the triangle the representative at p lies on (a closest
// hit along -n from vpl_visible's ray origin, no farther than twice its offset), INVALID where none
// is found; without the facing test a light under the representative's plane tries it first
// (shadow_ray_blocked_by), before a walk. With the facing test those pairs get no ray at all.
fn surface_under(p: vec3<f32>, n: vec3<f32>) -> u32 {
    if params.facing != 0u {
        return INVALID;
    }
    let o = offset_origin(p, n);
    return trace_closest(Ray(o, -n, 0.0, 2.0 * length(o - p))).slot;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    if i == INVALID {
        return;
    }
    let k = i / params.words;
    let w = i % params.words;
    let rep = rep_points[2u * k];
    // A representative the warm start kept (normal w = 1) with the same lights sees what it saw.
    if k < params.reuse_rows && rep.w > 0.0 && rep_points[2u * k + 1u].w == 1.0 {
        bits[i] = prev_bits[i];
        return;
    }
    var word = 0u;
    if rep.w > 0.0 {
        let p = rep.xyz;
        let n = rep_points[2u * k + 1u].xyz;
        let c0 = w * 32u;
        let c1 = min(c0 + 32u, params.num_lights);
        let under = surface_under(p, n);
        // First the pairs that need no walk, then a walk for each of the others: a SIMD batch
        // walks as many rays as its lane with the most, not one per light.
        var todo = 0u;
        for (var c = c0; c < c1; c++) {
            let l = Vpl(light_texel(3u * c), light_texel(3u * c + 1u), vec4<f32>(0.0));
            let d = l.pos.xyz - p;
            let behind = dot(n, d) <= 0.0;
            // With the facing test, only pairs that can exchange light get a ray (both cosines
            // positive); the paper's V is pure visibility (Eq. 6 applies the pixel's own cosines).
            if params.facing != 0u && (behind || dot(l.nrm.xyz, d) >= 0.0) {
                continue;
            }
            // A light under the representative's plane: its ray starts into the surface the
            // representative lies on, which mostly blocks it right there.
            if behind && under != INVALID && shadow_ray_blocked_by(under, p, n, l.pos.xyz, l.nrm.xyz) {
                continue;
            }
            todo |= 1u << (c - c0);
        }
        while todo != 0u {
            let b = firstTrailingBit(todo);
            todo &= todo - 1u;
            if vpl_visible(p, n, light_texel(3u * (c0 + b)).xyz, light_texel(3u * (c0 + b) + 1u).xyz) {
                word |= 1u << b;
            }
        }
    }
    bits[i] = word;
}
