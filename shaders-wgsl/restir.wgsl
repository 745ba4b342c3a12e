// ReSTIR DI (Bitterli, Wyman, Pharr, Shirley, Novák, Jarosz 2020) over the frame's VPLs
// (docs/methods.md, "restir"; crates/core/src/method/restir/). CPU twin: crates/core/src/method/restir/twin.rs.
// One kernel, its stage in `chunk.seed` (low byte; the spatial iteration above it), each a bounded
// dispatch over pixel ranges:
// - 0, initial: M candidates drawn by flux from the alias table (resampled importance sampling),
//   target p̂ = luminance of Eq. (5)'s term without visibility (`eq5_vpl_radiance`, the clamp
//   d_min as the reference's), one reservoir of one sample; a shadow ray to the sample (W = 0 when
//   it is hidden: the paper's visibility reuse).
// - 1, temporal: the previous frame's reservoir at the pixel's point (reprojected, the same-surface
//   test of accumulate.wgsl), its M capped at `cap` × M, combined with the pixel's.
// - 2, spatial: k neighbours drawn in a disc of `radius` pixels that pass the same-surface test
//   against the pixel, combined with it; n iterations, each reading the last one's reservoirs.
// - 3, shade: the reservoir's light, f(y) V(y) W, added to `indirect` (one shadow ray).
// Combination (the paper's §4): biased, W = w_sum / (p̂(y) Σ M); unbiased, Σ M over the inputs
// whose p̂ · V at y is positive (a shadow ray from each reused point), and W = 0 where y is hidden
// from the pixel (one more ray), so that every reservoir's samples lie where its p̂ · V is positive,
// what the next combination's Z assumes.
#import common/bvh.wgsl
#import common/camera.wgsl
#import common/chunk.wgsl
#import common/gbuffer.wgsl
#import common/rng.wgsl
#import common/vpl.wgsl

struct RestirParams {
    cam: CameraParams,
    // The previous frame's camera (its size the same; `opts.y` bit 2 says whether there is one).
    prev: CameraParams,
    // width, height, VPLs, candidates M.
    dims: vec4<u32>,
    // neighbours k; flags (1: unbiased, 2: a history); the frame's seed; -.
    opts: vec4<u32>,
    // d_min^2; the spatial radius in pixels; the confidence cap (x M); the depth tolerance.
    tol: vec4<f32>,
    // The normals' cosine tolerance; -, -, -.
    tol2: vec4<f32>,
}

@group(1) @binding(1) var<uniform> params: RestirParams;
@group(1) @binding(2) var<storage, read> gbuffer: array<ShadingPoint>;
@group(1) @binding(3) var<storage, read> prev_gbuffer: array<ShadingPoint>;
@group(1) @binding(4) var<storage, read> vpls: array<Vpl>;
// A VPL: (its probability of being kept when its column is drawn (f32 bits), its alias, its
// source pdf p(j) = luminance(flux_j) / sum (f32 bits), -) (`method::restir::alias`).
@group(1) @binding(5) var<storage, read> alias_table: array<vec4<u32>>;
// Reservoirs, one a pixel: (the VPL y, w_sum, M, W), the last three f32 bits.
@group(1) @binding(6) var<storage, read> res_in: array<vec4<u32>>;
@group(1) @binding(7) var<storage, read> res_prev: array<vec4<u32>>;
@group(1) @binding(8) var<storage, read_write> res_out: array<vec4<u32>>;
@group(1) @binding(9) var<storage, read_write> indirect: array<vec4<f32>>;
// Shadow rays a pixel traced this frame.
@group(1) @binding(10) var<storage, read_write> rays: array<u32>;

const NONE: u32 = 0xffffffffu;
const UNBIASED: u32 = 1u;
const HISTORY: u32 = 2u;

struct Reservoir {
    y: u32,
    w_sum: f32,
    m: f32,
    w: f32,
}

fn res_load(r: vec4<u32>) -> Reservoir {
    return Reservoir(r.x, bitcast<f32>(r.y), bitcast<f32>(r.z), bitcast<f32>(r.w));
}

fn res_pack(r: Reservoir) -> vec4<u32> {
    return vec4<u32>(r.y, bitcast<u32>(r.w_sum), bitcast<u32>(r.m), bitcast<u32>(r.w));
}

fn lum(c: vec3<f32>) -> f32 {
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}

// Eq. (5)'s term of VPL y at shading point sp, without visibility (the reference's). Twin: term.
fn term(sp: ShadingPoint, y: u32) -> vec3<f32> {
    if y >= params.dims.z {
        return vec3<f32>(0.0);
    }
    return eq5_vpl_radiance(sp.pos.xyz, sp.nrm.xyz, sp.albedo.xyz, vpls[y], params.tol.x);
}

// The target function p̂: the term's luminance. Twin: p_hat.
fn p_hat(sp: ShadingPoint, y: u32) -> f32 {
    return lum(term(sp, y));
}

// V of Eq. (5) between sp and VPL y (`bvh.wgsl`'s traversal, the reference's offsets).
fn visible(sp: ShadingPoint, y: u32) -> bool {
    let v = vpls[y];
    return vpl_visible(sp.pos.xyz, sp.nrm.xyz, v.pos.xyz, v.nrm.xyz);
}

// The weighted reservoir's update (Alg. 2): w joins w_sum, and y is the sample with probability
// w / w_sum. Twin: Reservoir::update.
fn res_update(r: ptr<function, Reservoir>, y: u32, w: f32, u: f32) {
    (*r).w_sum += w;
    if w > 0.0 && u * (*r).w_sum < w {
        (*r).y = y;
    }
}

// Input q (a reservoir of another pixel or frame, counted as m) streamed into r at shading point
// sp: weight p̂_sp(q.y) W_q m (Alg. 4). Twin: Reservoir::merge.
fn res_merge(r: ptr<function, Reservoir>, q: Reservoir, sp: ShadingPoint, m: f32, u: f32) {
    var w = 0.0;
    if q.y != NONE && q.w > 0.0 {
        w = p_hat(sp, q.y) * q.w * m;
    }
    res_update(r, q.y, w, u);
    (*r).m += m;
}

// W = w_sum / (z p̂(y)), 0 where p̂(y) or z is 0. Twin: weight.
fn res_weight(w_sum: f32, ph: f32, z: f32) -> f32 {
    if ph > 0.0 && z > 0.0 {
        return w_sum / (z * ph);
    }
    return 0.0;
}

// A VPL drawn from the alias table with two uniform numbers. Twin: alias_draw.
fn alias_draw(u1: f32, u2: f32) -> u32 {
    let n = params.dims.z;
    let k = min(u32(u1 * f32(n)), n - 1u);
    let a = alias_table[k];
    if u2 < bitcast<f32>(a.x) {
        return k;
    }
    return a.y;
}

// Depth of q along camera c's view.
fn view_depth(c: CameraParams, q: vec3<f32>) -> f32 {
    return dot(q - c.eye.xyz, c.forward.xyz);
}

// `sp` and `q` show the same surface (accumulate.wgsl's test: depths along the view within a
// fraction, normals within a cosine), q's depth along camera c against `z`.
fn same_surface(c: CameraParams, q: ShadingPoint, z: f32, n: vec3<f32>) -> bool {
    if q.pos.w <= 0.0 || dot(n, q.nrm.xyz) < params.tol2.x {
        return false;
    }
    let zq = view_depth(c, q.pos.xyz);
    return zq > 0.0 && abs(zq - z) <= params.tol.w * z;
}

// The previous frame's pixel that shows sp's point (nearest to its projection), NONE where none
// does. Twin: prev_pixel.
fn prev_pixel(sp: ShadingPoint) -> u32 {
    let c = params.prev;
    let d = sp.pos.xyz - c.eye.xyz;
    let z = dot(d, c.forward.xyz);
    if !(z > 1e-6 * length(d)) {
        return NONE;
    }
    let r = c.right.xyz;
    let u = c.up.xyz;
    let sx = dot(d, r) / (z * dot(r, r));
    let sy = dot(d, u) / (z * dot(u, u));
    let x = (sx + 1.0) * 0.5 * f32(params.dims.x);
    let y = (1.0 - sy) * 0.5 * f32(params.dims.y);
    if !(x >= 0.0 && y >= 0.0 && x < f32(params.dims.x) && y < f32(params.dims.y)) {
        return NONE;
    }
    let j = u32(x) + u32(y) * params.dims.x;
    if !same_surface(c, prev_gbuffer[j], z, sp.nrm.xyz) {
        return NONE;
    }
    return j;
}

// Unbiased: a combined reservoir's W is 0 where its sample is hidden from the pixel (one shadow
// ray), as the initial one's, so that every reservoir's samples lie where p̂ · V is positive (what
// the next combination's Z counts). Twin: the end of temporal and spatial.
fn own_visibility(i: u32, sp: ShadingPoint, r: ptr<function, Reservoir>) {
    if (params.opts.y & UNBIASED) != 0u && (*r).w > 0.0 {
        rays[i] += 1u;
        if !visible(sp, (*r).y) {
            (*r).w = 0.0;
        }
    }
}

fn initial(i: u32, sp: ShadingPoint) {
    var r = Reservoir(NONE, 0.0, 0.0, 0.0);
    var traced = 0u;
    if sp.pos.w > 0.0 && params.dims.z > 0u {
        var rng = rng_seed(i, params.opts.z, 0u);
        for (var c = 0u; c < params.dims.w; c++) {
            let u1 = rng_next(&rng);
            let u2 = rng_next(&rng);
            let u3 = rng_next(&rng);
            let j = alias_draw(u1, u2);
            let pdf = bitcast<f32>(alias_table[j].z);
            var w = 0.0;
            if pdf > 0.0 {
                w = p_hat(sp, j) / pdf;
            }
            res_update(&r, j, w, u3);
        }
        r.m = f32(params.dims.w);
        r.w = res_weight(r.w_sum, p_hat(sp, r.y), r.m);
        if r.w > 0.0 {
            traced = 1u;
            if !visible(sp, r.y) {
                r.w = 0.0;
            }
        }
    }
    res_out[i] = res_pack(r);
    rays[i] = traced;
}

fn temporal(i: u32, sp: ShadingPoint) {
    let cur = res_load(res_in[i]);
    var j = NONE;
    if sp.pos.w > 0.0 && (params.opts.y & HISTORY) != 0u {
        j = prev_pixel(sp);
    }
    if j == NONE {
        res_out[i] = res_in[i];
        return;
    }
    let prev = res_load(res_prev[j]);
    let mp = min(prev.m, params.tol.z * f32(params.dims.w));
    var rng = rng_seed(i, params.opts.z, 1u);
    var r = Reservoir(NONE, 0.0, 0.0, 0.0);
    res_merge(&r, cur, sp, cur.m, rng_next(&rng));
    res_merge(&r, prev, sp, mp, rng_next(&rng));
    let ph = p_hat(sp, r.y);
    var z = r.m;
    if (params.opts.y & UNBIASED) != 0u && ph > 0.0 {
        z = cur.m;
        let q = prev_gbuffer[j];
        if p_hat(q, r.y) > 0.0 {
            rays[i] += 1u;
            if visible(q, r.y) {
                z += mp;
            }
        }
    }
    r.w = res_weight(r.w_sum, ph, z);
    own_visibility(i, sp, &r);
    res_out[i] = res_pack(r);
}

fn spatial(i: u32, sp: ShadingPoint, iteration: u32) {
    if sp.pos.w <= 0.0 {
        res_out[i] = res_in[i];
        return;
    }
    let own = res_load(res_in[i]);
    var rng = rng_seed(i, params.opts.z, 2u + iteration);
    var r = Reservoir(NONE, 0.0, 0.0, 0.0);
    res_merge(&r, own, sp, own.m, rng_next(&rng));
    let w = params.dims.x;
    let h = params.dims.y;
    let px = f32(i % w) + 0.5;
    let py = f32(i / w) + 0.5;
    let z = view_depth(params.cam, sp.pos.xyz);
    var picked: array<u32, 16>;
    var count = 0u;
    for (var s = 0u; s < params.opts.x; s++) {
        let u1 = rng_next(&rng);
        let u2 = rng_next(&rng);
        let u3 = rng_next(&rng);
        let rad = params.tol.y * sqrt(u1);
        let th = 6.2831855 * u2;
        let nx = floor(px + rad * cos(th));
        let ny = floor(py + rad * sin(th));
        if !(nx >= 0.0 && ny >= 0.0 && nx < f32(w) && ny < f32(h)) {
            continue;
        }
        let j = u32(nx) + u32(ny) * w;
        if j == i || !same_surface(params.cam, gbuffer[j], z, sp.nrm.xyz) {
            continue;
        }
        let q = res_load(res_in[j]);
        res_merge(&r, q, sp, q.m, u3);
        picked[count] = j;
        count++;
    }
    let ph = p_hat(sp, r.y);
    var zm = r.m;
    if (params.opts.y & UNBIASED) != 0u && ph > 0.0 {
        zm = own.m;
        for (var s = 0u; s < count; s++) {
            let j = picked[s];
            let q = gbuffer[j];
            if p_hat(q, r.y) > 0.0 {
                rays[i] += 1u;
                if visible(q, r.y) {
                    zm += res_load(res_in[j]).m;
                }
            }
        }
    }
    r.w = res_weight(r.w_sum, ph, zm);
    own_visibility(i, sp, &r);
    res_out[i] = res_pack(r);
}

fn shade(i: u32, sp: ShadingPoint) {
    let r = res_load(res_in[i]);
    if sp.pos.w <= 0.0 || r.y == NONE || !(r.w > 0.0) {
        return;
    }
    let c = term(sp, r.y);
    if any(c > vec3<f32>(0.0)) {
        rays[i] += 1u;
        if visible(sp, r.y) {
            indirect[i] += vec4<f32>(c * r.w, 0.0);
        }
    }
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = chunk_item(gid, nwg);
    if i != INVALID {
        run_stage(i, gbuffer[i]);
    }
}

// The chunk's stage (the seed's low byte) on pixel i, whose shading point is `sp`.
fn run_stage(i: u32, sp: ShadingPoint) {
    let stage = chunk.seed & 0xffu;
    switch stage {
        case 0u: {
            initial(i, sp);
        }
        case 1u: {
            temporal(i, sp);
        }
        case 2u: {
            spatial(i, sp, chunk.seed >> 8u);
        }
        default: {
            shade(i, sp);
        }
    }
}
