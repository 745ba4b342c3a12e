// Step 6: Eq. (6) per pixel: every light (VPL-cluster representative with the cluster's summed flux,
// or a VPL) with the approximate visibility of Eq. (8) (uniform over the pixel's F SP clusters) or
// Eq. (9) (inverse-distance weights, Eq. 10); F = 1 is hard clustering. CPU twin: crates/core/src/cpu/shade.rs.
#import common/chunk.wgsl
#import common/gbuffer.wgsl
#import common/vpl.wgsl

struct ShadeParams {
    num_lights: u32,
    words: u32,
    f: u32,
    // 0: uniform (Eq. 8), 1: inverse-distance weights (Eq. 9).
    weighted: u32,
    d_min2: f32,
    // The image the pixels lie in (width, height): a workgroup shades one TILE × TILE tile.
    width: u32,
    height: u32,
    _c: u32,
}

@group(1) @binding(1) var<uniform> params: ShadeParams;
@group(1) @binding(2) var<storage, read> gbuffer: array<ShadingPoint>;
// Lights as 2 texels each (pack_lights: pos.xyz and the normal's code, flux.rgb and the spread's
// code), DATA_ROW (4096) texels a row: on lavapipe a texel fetch gathers a whole texel per lane
// with vector code, a storage read is a branchy scalar loop per lane, and the walk's cost is its
// fetches (docs/bvh.md, "Lights in two texels").
@group(1) @binding(3) var lights_tex: texture_2d<u32>;
@group(1) @binding(4) var<storage, read> bits: array<u32>;
@group(1) @binding(5) var<storage, read> assign: array<u32>;
@group(1) @binding(6) var<storage, read> weights: array<f32>;
@group(1) @binding(7) var<storage, read_write> indirect: array<vec4<f32>>;

const MAX_F: u32 = 16u;
// F of the pipeline (crates/core/src/method/colom/shade.rs builds one per F in use). A constant trip count lets the driver
// unroll the loops over the F slots, so `rows`, `w` and `rw` live in registers; with a run-time F a GPU
// spills them to local memory and re-reads them for every light.
override F: u32 = 6u;
// Visibility patterns a word's table holds (eq6_indirect), at most MAX_PATTERNS; 0: every light runs
// Eq. (9)'s loop. crates/core/src/method/colom/shade.rs sets it (`shade::patterns`); the image is the same bit for bit.
const MAX_PATTERNS: u32 = 8u;
override PATTERNS: u32 = 0u;

// Not in the paper, and no change to its result (docs/clustering.md, "Lights no point of a tile can
// see"): main shades tiles of TILE × TILE pixels, one a workgroup (tile_pixel). With TILE_CULL the
// entry point tile_box first bounds each tile's shading points, and in each submission tile_mask
// marks the lights that may light some point of a tile (may_light_box), a bit each: a pixel's walk
// skips the others. Without it every light the visibility rows see is walked
// (crates/core/src/method/colom/shade.rs, `tile_cull`).
const TILE: u32 = 8u;
override TILE_CULL: bool = true;
// Each tile's box (the entry point tile_box): position min (w = 1 when the tile has a valid
// point), position max, normal min, normal max.
@group(1) @binding(8) var<storage, read_write> tile_boxes: array<vec4<f32>>;
// This submission's masks (the entry point tile_mask): word w of the chunk's tile k, at
// k * chunk_words() + w, has bit b set when light 32 (chunk.sub_offset + w) + b may light the tile.
@group(1) @binding(9) var<storage, read_write> tile_masks: array<u32>;
// The lights as the step before wrote them (VPL-cluster lights or VPLs), read once a frame by
// pack_lights, whose two texels a light (packed_lights) are copied into lights_tex.
@group(1) @binding(10) var<storage, read> lights_in: array<Vpl>;
@group(1) @binding(11) var<storage, read_write> packed_lights: array<vec4<u32>>;

// The bit words of this submission: [chunk.sub_offset, + chunk_words()).
fn chunk_words() -> u32 {
    return min(chunk.sub_count, params.words - min(chunk.sub_offset, params.words));
}

// Pixel of item i: the tile i / 64 (row-major over the image's tiles), in it pixel i % 64 (row-major);
// INVALID outside the image.
fn tile_pixel(i: u32) -> u32 {
    if i == INVALID {
        return INVALID;
    }
    let tiles_x = (params.width + TILE - 1u) / TILE;
    let t = i / (TILE * TILE);
    let l = i % (TILE * TILE);
    let x = (t % tiles_x) * TILE + l % TILE;
    let y = (t / tiles_x) * TILE + l / TILE;
    if x >= params.width || y >= params.height {
        return INVALID;
    }
    return y * params.width + x;
}

// Not in the paper (docs/clustering.md, "Lights no point of a tile can see"): whether light `v` may
// add to Eq. (6) at some point with position in [lo, hi] and normal in [nlo, nhi] (boxes). False
// when, over the boxes, Eq. (5)'s cosine at the light, n_v · (p - x_v), or the one at the point,
// n · (x_v - p), is at most `slack`: their maxima over boxes are sums over the axes of the largest
// product at a corner. The slack (1e-5 of the largest coordinate) counts a cosine at the rounding of
// the coordinates as 0: a light in the tile's plane. CPU twin: cpu::shade::may_light_box.
fn may_light_box(lo: vec3<f32>, hi: vec3<f32>, nlo: vec3<f32>, nhi: vec3<f32>, v: Vpl) -> bool {
    let x = v.pos.xyz;
    let n = v.nrm.xyz;
    let at_light = max(n * (lo - x), n * (hi - x));
    let a = x - lo;
    let b = x - hi;
    let at_point = max(max(nlo * a, nlo * b), max(nhi * a, nhi * b));
    let scale = max(max(abs(lo), abs(hi)), abs(x));
    let slack = 1e-5 * max(scale.x, max(scale.y, scale.z));
    return dot(at_light, vec3<f32>(1.0)) > slack && dot(at_point, vec3<f32>(1.0)) > slack;
}

// Word w of this submission's lights for the chunk's tile k (invocation k * chunk_words() + w,
// before main): the lights may_light_box keeps for the tile's box; none for a tile with no
// shading point.
@compute @workgroup_size(64)
fn tile_mask(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    let words = chunk_words();
    if words == 0u || i >= (chunk.count / (TILE * TILE)) * words {
        return;
    }
    let t = chunk.offset / (TILE * TILE) + i / words;
    let b0 = tile_boxes[4u * t];
    var word = 0u;
    if b0.w > 0.0 {
        let lo = b0.xyz;
        let hi = tile_boxes[4u * t + 1u].xyz;
        let nlo = tile_boxes[4u * t + 2u].xyz;
        let nhi = tile_boxes[4u * t + 3u].xyz;
        let c0 = (chunk.sub_offset + i % words) * 32u;
        for (var c = c0; c < min(c0 + 32u, params.num_lights); c++) {
            if may_light_box(lo, hi, nlo, nhi, load_light(c)) {
                word |= 1u << (c - c0);
            }
        }
    }
    tile_masks[i] = word;
}

// The items of a width × height image: 64 a tile (crates/core/src/method/colom/shade.rs `tile_items`).
fn tile_items(width: u32, height: u32) -> u32 {
    return ((width + TILE - 1u) / TILE) * ((height + TILE - 1u) / TILE) * TILE * TILE;
}

// The box of tile t's valid shading points into tile_boxes (one invocation a tile, before main).
@compute @workgroup_size(64)
fn tile_box(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let t = chunk_item(gid, nwg);
    if t == INVALID || t >= tile_items(params.width, params.height) / (TILE * TILE) {
        return;
    }
    var lo = vec3<f32>(0.0);
    var hi = vec3<f32>(0.0);
    var nlo = vec3<f32>(0.0);
    var nhi = vec3<f32>(0.0);
    var valid = false;
    for (var i = 0u; i < TILE * TILE; i++) {
        let m = tile_pixel(t * TILE * TILE + i);
        if m != INVALID {
            let sp = gbuffer[m];
            if sp.pos.w > 0.0 {
                if valid {
                    lo = min(lo, sp.pos.xyz);
                    hi = max(hi, sp.pos.xyz);
                    nlo = min(nlo, sp.nrm.xyz);
                    nhi = max(nhi, sp.nrm.xyz);
                } else {
                    lo = sp.pos.xyz;
                    hi = sp.pos.xyz;
                    nlo = sp.nrm.xyz;
                    nhi = sp.nrm.xyz;
                }
                valid = true;
            }
        }
    }
    tile_boxes[4u * t] = vec4<f32>(lo, select(0.0, 1.0, valid));
    tile_boxes[4u * t + 1u] = vec4<f32>(hi, 0.0);
    tile_boxes[4u * t + 2u] = vec4<f32>(nlo, 0.0);
    tile_boxes[4u * t + 3u] = vec4<f32>(nhi, 0.0);
}

// Not in the paper (docs/bvh.md, "Lights in two texels"): unit normal n as 32 bits, its
// octahedral coordinates (Cigolle et al. 2014, "A survey of efficient representations for
// independent unit vectors") each rounded to a multiple of 2^-14, as 16-bit integers (x low, y
// high). An axis is exact; any other normal lies within cpu::shade::OCT_ERROR radians of its decoding. CPU twin:
// cpu::shade::oct_encode.
fn oct_encode(n: vec3<f32>) -> u32 {
    let l1 = abs(n.x) + abs(n.y) + abs(n.z);
    var e = select(vec2<f32>(0.0), n.xy / l1, l1 > 0.0);
    if n.z < 0.0 {
        e = oct_wrap(e);
    }
    let q = vec2<i32>(round(clamp(e, vec2<f32>(-1.0), vec2<f32>(1.0)) * 16384.0));
    return (u32(q.x) & 0xffffu) | (u32(q.y) << 16u);
}

// The octahedral map's fold of the lower half (z < 0) over the upper one, either way (it is its own
// inverse): (1 - |e.yx|) with the signs of e, +1 at ±0. CPU twin: cpu::shade::oct_wrap.
fn oct_wrap(e: vec2<f32>) -> vec2<f32> {
    return (1.0 - abs(e.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), e >= vec2<f32>(0.0));
}

// The unit normal of oct_encode's code. The octahedron's point is exact (multiples of 2^-14); only
// the normalisation rounds. CPU twin: cpu::shade::oct_decode.
fn oct_decode(code: u32) -> vec3<f32> {
    let e = vec2<f32>(f32(i32(code << 16u) >> 16u), f32(i32(code) >> 16u)) * (1.0 / 16384.0);
    var n = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    if n.z < 0.0 {
        n = vec3<f32>(oct_wrap(e), n.z);
    }
    return n * inverseSqrt(dot(n, n));
}

// Not in the paper: the spread's share s (flux.w, in [0, 1]) and r^2 (nrm.w, >= 0) of a cluster
// light (eq5_cluster_radiance) as 32 bits: r^2 rounded to 11 mantissa bits (relative error at most
// 2^-12) in the high 19, s rounded to a multiple of 2^-12 in the low 13. CPU twin:
// cpu::shade::spread_encode.
fn spread_encode(s: f32, r2: f32) -> u32 {
    let r = ((bitcast<u32>(max(r2, 0.0)) + 0x800u) & 0x7ffff000u) << 1u;
    return r | u32(round(clamp(s, 0.0, 1.0) * 4096.0));
}

// (s, r^2) of spread_encode's code, both exact. CPU twin: cpu::shade::spread_decode.
fn spread_decode(code: u32) -> vec2<f32> {
    return vec2<f32>(f32(code & 0x1fffu) * (1.0 / 4096.0), bitcast<f32>((code >> 1u) & 0x7ffff000u));
}

// Light c's two texels into packed_lights (one invocation a light, once a frame, before the
// walk): pos.xyz and oct_encode of the normal, flux.rgb and spread_encode of (s, r^2). Position
// and flux keep every bit. CPU twin: cpu::shade::stored_light.
@compute @workgroup_size(64)
fn pack_lights(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let c = gid.x + gid.y * nwg.x * 64u;
    if c >= params.num_lights {
        return;
    }
    let v = lights_in[c];
    packed_lights[2u * c] = vec4<u32>(bitcast<vec3<u32>>(v.pos.xyz), oct_encode(v.nrm.xyz));
    packed_lights[2u * c + 1u] = vec4<u32>(bitcast<vec3<u32>>(v.flux.xyz), spread_encode(v.flux.w, v.nrm.w));
}

fn light_texel(i: u32) -> vec4<u32> {
    return textureLoad(lights_tex, vec2<u32>(i & 4095u, i >> 12u), 0);
}

// Light c as pack_lights stored it.
fn load_light(c: u32) -> Vpl {
    let a = light_texel(2u * c);
    let b = light_texel(2u * c + 1u);
    let sr = spread_decode(b.w);
    return Vpl(vec4<f32>(bitcast<vec3<f32>>(a.xyz), 1.0), vec4<f32>(oct_decode(a.w), sr.y), vec4<f32>(bitcast<vec3<f32>>(b.xyz), sr.x));
}

// Eq. (8) as weights: 1/F' for each of the pixel's F' used slots (rows[j] != INVALID), 0 for the
// others, written to `w`, so that eq9_weighted_visibility with them is Eq. (8)'s mean. CPU twin:
// cpu::shade::eq8_mean_weights. Arrays go by pointer, never by value (docs/architecture.md, "WGSL
// for real GPUs": a by-value array is copied through local memory on every call).
fn eq8_mean_weights(rows: ptr<function, array<u32, MAX_F>>, w: ptr<function, array<f32, MAX_F>>) {
    var nf = 0u;
    for (var j = 0u; j < F; j++) {
        nf += select(0u, 1u, (*rows)[j] != INVALID);
    }
    for (var j = 0u; j < F; j++) {
        (*w)[j] = select(0.0, 1.0 / f32(nf), (*rows)[j] != INVALID);
    }
}

// Eq. (9): Ṽ(p, p_c) = Σ_f w_f V(p_f, p_c) over the pixel's slots, V(p_f, p_c) being bit b of row
// f's word `rw[f]` (Eq. 8 with eq8_mean_weights). Summed over f in order. CPU twin:
// cpu::shade::eq9_weighted_visibility.
fn eq9_weighted_visibility(w: ptr<function, array<f32, MAX_F>>, rw: ptr<function, array<u32, MAX_F>>, b: u32) -> f32 {
    var v = 0.0;
    for (var j = 0u; j < F; j++) {
        v += select(0.0, (*w)[j], (((*rw)[j] >> b) & 1u) != 0u);
    }
    return v;
}

// The lights of a word that every slot sees as it sees light b (the same visibility pattern over
// the F slots, bit b's), as a mask: Eq. (9)'s Ṽ is one value over them. An unused slot's word is 0,
// the same for every light. CPU twin: cpu::shade::same_visibility.
fn same_visibility(rw: ptr<function, array<u32, MAX_F>>, b: u32) -> u32 {
    var same = 0xffffffffu;
    for (var j = 0u; j < F; j++) {
        let r = (*rw)[j];
        same &= select(~r, r, ((r >> b) & 1u) != 0u);
    }
    return same;
}

// Eq. (6) over this dispatch's lights: Σ_c I_c ρ G Ṽ(p, p_c), the lights being the VPL-cluster
// representatives (or the VPLs) of words [chunk.sub_offset, + chunk.sub_count). Lights 32 at a time:
// one bit word per row serves 32 lights, and a light no row sees (Ṽ = 0, which would add exactly
// zero) is skipped, and so is one the tile's mask (at tile_masks[mask_base]) has not (its terms
// are 0: docs/clustering.md, "Lights no point of a tile can see"). Ṽ (Eq. 9, over j in order) depends only on a light's visibility pattern over the
// F slots, and a word's lights fall in few patterns (all slots see the light, or a shadow edge
// crosses some): a word's first PATTERNS patterns and their Ṽ are found once (a table in registers),
// and a light picks its Ṽ from the table with PATTERNS selects instead of an F-slot loop; a light of
// a further pattern runs the loop. PATTERNS = 0 (the default) runs the loop for every light. A light
// adding nothing (t = 0: it faces away or lies behind the pixel) skips Ṽ. Lights are summed
// in increasing order, each with Ṽ bit for bit as eq9_weighted_visibility gives it, so the sum is the
// same as a plain loop over all lights. CPU twin: cpu::shade::eq6_indirect.
fn eq6_indirect(sp: ShadingPoint, rows: ptr<function, array<u32, MAX_F>>, w: ptr<function, array<f32, MAX_F>>, mask_base: u32) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    var rw: array<u32, MAX_F>;
    var masks: array<u32, MAX_PATTERNS>;
    var vs: array<f32, MAX_PATTERNS>;
    // This dispatch's words [chunk.sub_offset, + chunk_words()) (crates/core/src/method/colom/shade.rs
    // bounds them: lavapipe ends all loops of a SIMD batch after 65,535 trips, and this walk takes one
    // a light).
    for (var wd = chunk.sub_offset; wd < chunk.sub_offset + chunk_words(); wd++) {
        var todo = 0u;
        for (var j = 0u; j < F; j++) {
            rw[j] = 0u;
            if (*rows)[j] != INVALID {
                rw[j] = bits[(*rows)[j] * params.words + wd];
            }
            todo |= rw[j];
        }
        if TILE_CULL {
            todo &= tile_masks[mask_base + wd - chunk.sub_offset];
        }
        // The table: pattern k's lights and Ṽ, in the order of their first lights.
        var rest = todo;
        for (var k = 0u; k < PATTERNS; k++) {
            masks[k] = 0u;
            vs[k] = 0.0;
            if rest != 0u {
                let first = firstTrailingBit(rest);
                masks[k] = rest & same_visibility(&rw, first);
                vs[k] = eq9_weighted_visibility(w, &rw, first);
                rest &= ~masks[k];
            }
        }
        while todo != 0u {
            let b = firstTrailingBit(todo);
            todo &= todo - 1u;
            let t = eq5_cluster_radiance(sp.pos.xyz, sp.nrm.xyz, sp.albedo.xyz, load_light(wd * 32u + b), params.d_min2);
            if any(t > vec3<f32>(0.0)) {
                var v = 0.0;
                // PATTERNS is a pipeline constant: a driver keeps one branch.
                if PATTERNS == 0u {
                    v = eq9_weighted_visibility(w, &rw, b);
                } else {
                    for (var k = 0u; k < PATTERNS; k++) {
                        v = select(v, vs[k], ((masks[k] >> b) & 1u) != 0u);
                    }
                    // A light past the table's patterns.
                    if ((rest >> b) & 1u) != 0u {
                        v = eq9_weighted_visibility(w, &rw, b);
                    }
                }
                sum += t * v;
            }
        }
    }
    return sum;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let item = chunk_item(gid, nwg);
    let m = tile_pixel(item);
    if m == INVALID {
        return;
    }
    let sp = gbuffer[m];
    if sp.pos.w <= 0.0 {
        indirect[m] = vec4<f32>(0.0);
        return;
    }
    // Slot j keeps its place; an unused slot (INVALID) has weight 0 and an empty row, so it adds
    // exactly +0 to Ṽ and the sums are those of a loop over the used slots alone.
    var rows: array<u32, MAX_F>;
    var w: array<f32, MAX_F>;
    for (var j = 0u; j < F; j++) {
        let k = assign[m * F + j];
        rows[j] = k;
        w[j] = 0.0;
        if k != INVALID {
            // Eq. (10)'s weights, from the final assignment.
            w[j] = weights[m * F + j];
        }
    }
    if params.weighted == 0u {
        eq8_mean_weights(&rows, &w);
    }
    // The first of the tile's masks (tile_mask; chunks are whole tiles).
    let mask_base = ((item - chunk.offset) / (TILE * TILE)) * chunk_words();
    let sum = eq6_indirect(sp, &rows, &w, mask_base);
    // The first range of words writes the pixel, the others add to it.
    if chunk.sub_offset == 0u {
        indirect[m] = vec4<f32>(sum, 0.0);
    } else {
        indirect[m] += vec4<f32>(sum, 0.0);
    }
}
