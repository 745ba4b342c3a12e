// Step 6: Eq. (6) per pixel: every light (VPL-cluster representative with the cluster's summed flux,
// or a VPL) with the approximate visibility of Eq. (8) (uniform over the pixel's F SP clusters) or
// Eq. (9) (inverse-distance weights, Eq. 10); F = 1 is hard clustering. CPU twin: src/cpu/shade.rs.
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
    _a: u32,
    _b: u32,
    _c: u32,
}

@group(1) @binding(1) var<uniform> params: ShadeParams;
@group(1) @binding(2) var<storage, read> gbuffer: array<ShadingPoint>;
@group(1) @binding(3) var<storage, read> lights_in: array<Vpl>;
@group(1) @binding(4) var<storage, read> bits: array<u32>;
@group(1) @binding(5) var<storage, read> assign: array<u32>;
@group(1) @binding(6) var<storage, read> weights: array<f32>;
@group(1) @binding(7) var<storage, read_write> indirect: array<vec4<f32>>;

const MAX_F: u32 = 16u;

// Ṽ(p, p_c) of Eq. (8) / (9) for light c.
fn approx_visibility(c: u32, rows: ptr<function, array<u32, MAX_F>>, w: ptr<function, array<f32, MAX_F>>, nf: u32) -> f32 {
    var v = 0.0;
    let word = c / 32u;
    let bit = 1u << (c % 32u);
    for (var j = 0u; j < nf; j++) {
        if (bits[(*rows)[j] * params.words + word] & bit) != 0u {
            v += (*w)[j];
        }
    }
    return v;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let m = chunk_item(gid, nwg);
    if m == INVALID {
        return;
    }
    let sp = gbuffer[m];
    if sp.pos.w <= 0.0 {
        indirect[m] = vec4<f32>(0.0);
        return;
    }
    let f = clamp(params.f, 1u, MAX_F);
    var rows: array<u32, MAX_F>;
    var w: array<f32, MAX_F>;
    var nf = 0u;
    for (var j = 0u; j < f; j++) {
        let k = assign[m * f + j];
        if k != INVALID {
            rows[nf] = k;
            w[nf] = weights[m * f + j];
            nf += 1u;
        }
    }
    if params.weighted == 0u {
        for (var j = 0u; j < nf; j++) {
            w[j] = 1.0 / f32(nf);
        }
    }
    var sum = vec3<f32>(0.0);
    for (var c = 0u; c < params.num_lights; c++) {
        let t = vpl_term(sp.pos.xyz, sp.nrm.xyz, sp.albedo.xyz, lights_in[c], params.d_min2);
        if any(t > vec3<f32>(0.0)) {
            sum += t * approx_visibility(c, &rows, &w, nf);
        }
    }
    indirect[m] = vec4<f32>(sum, 0.0);
}
