// The viewer's display path on the GPU (`app::display`): what the image area shows, from the GI
// frame's buffers where they were rendered, into an 8-bit texture egui draws. Nothing is read back.
//
// - `log_luminance` + `exposure`: the automatic exposure (Reinhard et al. 2002, Eq. 1: the image's
//   log-average luminance shown as the key 0.18, `exposure::auto_exposure`), reduced on the GPU over
//   A's final radiance, pixels with a finite luminance > 0 only; a fixed exposure is copied through.
// - `display`: one invocation a pixel: the view (final, direct, indirect, SP clusters, VPL clusters'
//   darkened base, reference, error, A|B split, A−B), exposure, sRGB, 8 bits. The FLIP view is
//   the FLIP pass's (`flip.wgsl`), which reads the exposure reduced here.
//
// Its CPU twin is `cpu::display` (tests/display.rs compares them on every view).

#import common/reduce.wgsl

struct DisplayParams {
    // Width, height, view (`VIEW_*`), flags (`FLAG_*`).
    size: vec4<u32>,
    // x: A's factor from render units to the scene's; y: B's; z: the fixed exposure (used without
    // FLAG_AUTO); w: the split view's divider, a fraction of the width.
    scale: vec4<f32>,
}

const VIEW_FINAL: u32 = 0u;
const VIEW_DIRECT: u32 = 1u;
const VIEW_INDIRECT: u32 = 2u;
const VIEW_SP_CLUSTERS: u32 = 3u;
const VIEW_VPL_BASE: u32 = 4u;
const VIEW_REFERENCE: u32 = 5u;
const VIEW_ERROR: u32 = 6u;
const VIEW_SPLIT: u32 = 7u;
const VIEW_DIFF: u32 = 8u;
// VIEW_FLIP (9) is drawn by the FLIP pass (`flip.wgsl`'s `colour`), after this shader's exposure.

// The final view adds the direct light (off: the indirect light alone).
const FLAG_DIRECT: u32 = 1u;
// The exposure is automatic (`exposure` reduces it), else `scale.z`.
const FLAG_AUTO: u32 = 2u;

const F32_MAX: f32 = 3.40282347e38;
const KEY: f32 = 0.18;
// Threads a workgroup of the reduction; `partials` holds one vec2 (sum of ln L, count) a workgroup.
const REDUCE: u32 = 256u;

@group(0) @binding(0) var<uniform> params: DisplayParams;
// A's emission + direct light and indirect light, a vec4 an image pixel, render units.
@group(0) @binding(1) var<storage, read> a_direct: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> a_indirect: array<vec4<f32>>;
// B's (split and A−B views), or A's again.
@group(0) @binding(3) var<storage, read> b_direct: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> b_indirect: array<vec4<f32>>;
// The reference (scene units, a vec4 a pixel), or a stand-in.
@group(0) @binding(5) var<storage, read> reference: array<vec4<f32>>;
// Each pixel's nearest SP cluster (0xffffffff: none), or a stand-in.
@group(0) @binding(6) var<storage, read> labels: array<u32>;
// Per-workgroup partial sums of the exposure's reduction, then the exposure in [0].x.
@group(0) @binding(7) var<storage, read_write> partials: array<vec2<f32>>;
@group(0) @binding(8) var<storage, read_write> exposure_out: array<f32>;
@group(0) @binding(9) var out_image: texture_storage_2d<rgba8unorm, write>;

var<workgroup> wg_sum: array<vec2<f32>, REDUCE>;

fn pixels() -> u32 {
    return params.size.x * params.size.y;
}

// A pixel of a frame in the scene's units, saturating at the largest finite f32 (`GpuFrame::read`).
fn scene_units(p: vec3<f32>, scale: f32) -> vec3<f32> {
    return min(p * scale, vec3<f32>(F32_MAX));
}

// A's emission + direct light and its indirect light, in the scene's units.
fn a_direct_at(i: u32) -> vec3<f32> {
    return scene_units(a_direct[i].xyz, params.scale.x);
}

fn a_indirect_at(i: u32) -> vec3<f32> {
    return scene_units(a_indirect[i].xyz, params.scale.x);
}

// A's radiance (emission + direct + indirect), as `Frame::radiance`.
fn a_radiance(i: u32) -> vec3<f32> {
    return min(a_direct_at(i) + a_indirect_at(i), vec3<f32>(F32_MAX));
}

// The final view's radiance of a frame: direct + indirect, or the indirect light alone.
fn final_of(d: vec3<f32>, e: vec3<f32>) -> vec3<f32> {
    if ((params.size.w & FLAG_DIRECT) != 0u) {
        return d + e;
    }
    return e;
}

fn a_final(i: u32) -> vec3<f32> {
    return final_of(a_direct_at(i), a_indirect_at(i));
}

fn b_final(i: u32) -> vec3<f32> {
    return final_of(scene_units(b_direct[i].xyz, params.scale.y),
                    scene_units(b_indirect[i].xyz, params.scale.y));
}

fn luminance(p: vec3<f32>) -> f32 {
    return 0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z;
}

fn is_finite(x: f32) -> bool {
    return x == x && abs(x) <= F32_MAX;
}

// Reinhard et al. (2002) Eq. 1, the log-average's sum: ln L over this workgroup's pixels with a
// finite L > 0 (`exposure::log_average_luminance`), and their count.
@compute @workgroup_size(256)
fn log_luminance(@builtin(local_invocation_index) t: u32, @builtin(workgroup_id) wg: vec3<u32>,
                 @builtin(num_workgroups) groups: vec3<u32>) {
    let group = wg.y * groups.x + wg.x;
    let i = group * REDUCE + t;
    var s = vec2<f32>(0.0, 0.0);
    if (i < pixels()) {
        let l = luminance(a_radiance(i));
        if (is_finite(l) && l > 0.0) {
            s = vec2<f32>(log(l), 1.0);
        }
    }
    wg_sum[t] = s;
    tree_sum(t);
    if (t == 0u) {
        partials[group] = wg_sum[0];
    }
}

// The exposure: KEY / exp(mean ln L) (Reinhard et al. 2002, Eq. 1–2), clamped to 1e-30..1e30; 1 for
// an image without a lit pixel; the fixed exposure without FLAG_AUTO. One workgroup.
@compute @workgroup_size(256)
fn exposure(@builtin(local_invocation_index) t: u32) {
    let groups = (pixels() + REDUCE - 1u) / REDUCE;
    var s = vec2<f32>(0.0, 0.0);
    for (var g = t; g < groups; g = g + REDUCE) {
        s = s + partials[g];
    }
    wg_sum[t] = s;
    tree_sum(t);
    if (t == 0u) {
        var e = params.scale.z;
        if ((params.size.w & FLAG_AUTO) != 0u) {
            let total = wg_sum[0];
            e = 1.0;
            if (total.y > 0.0) {
                e = clamp(KEY / exp(total.x / total.y), 1e-30, 1e30);
            }
        }
        exposure_out[0] = e;
    }
}

// The sRGB transfer of a linear value, clamped to [0, 1], non-finite as 0 (`export::linear_to_srgb`).
fn linear_to_srgb(x: f32) -> f32 {
    var c = 0.0;
    if (is_finite(x)) {
        c = clamp(x, 0.0, 1.0);
    }
    if (c <= 0.0031308) {
        return 12.92 * c;
    }
    return 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

// An 8-bit channel as `views::tonemap` rounds it: floor(v × 255 + 0.5).
fn quantise(v: f32) -> f32 {
    return floor(v * 255.0 + 0.5) / 255.0;
}

fn tonemap(p: vec3<f32>, e: f32) -> vec3<f32> {
    return vec3<f32>(quantise(linear_to_srgb(p.x * e)), quantise(linear_to_srgb(p.y * e)),
                     quantise(linear_to_srgb(p.z * e)));
}

// The error view's colour ramp (`metrics::ramp`): dark blue, cyan, green, yellow, red.
fn ramp(t: f32) -> vec3<f32> {
    let stops = array<vec3<f32>, 5>(
        vec3<f32>(0.05, 0.05, 0.35), vec3<f32>(0.0, 0.6, 0.9), vec3<f32>(0.1, 0.8, 0.2),
        vec3<f32>(0.95, 0.9, 0.1), vec3<f32>(0.9, 0.1, 0.05));
    let f = t * 4.0;
    let i = min(u32(f), 3u);
    let w = f - f32(i);
    let a = stops[i];
    let b = stops[i + 1u];
    return a + (b - a) * w;
}

// The per-pixel relative error (x − ref)² / (ref² + 0.01), mean over RGB, log10 from 1e-4 to 1 on the
// ramp (`metrics::error_map`).
fn error_colour(x: vec3<f32>, r: vec3<f32>) -> vec3<f32> {
    let d = x - r;
    let e = (d.x * d.x / (r.x * r.x + 0.01) + d.y * d.y / (r.y * r.y + 0.01)
             + d.z * d.z / (r.z * r.z + 0.01)) / 3.0;
    let t = clamp((log(max(e, 1e-12)) / log(10.0) + 4.0) / 4.0, 0.0, 1.0);
    let c = ramp(t);
    return vec3<f32>(quantise(c.x), quantise(c.y), quantise(c.z));
}

fn hsv(h: f32, s: f32, v: f32) -> vec3<f32> {
    let h6 = h * 6.0;
    let f = fract(h6);
    let p = v * (1.0 - s);
    let q = v * (1.0 - s * f);
    let u = v * (1.0 - s * (1.0 - f));
    switch (u32(h6) % 6u) {
        case 0u: { return vec3<f32>(v, u, p); }
        case 1u: { return vec3<f32>(q, v, p); }
        case 2u: { return vec3<f32>(p, v, u); }
        case 3u: { return vec3<f32>(p, q, v); }
        case 4u: { return vec3<f32>(u, p, v); }
        default: { return vec3<f32>(v, p, q); }
    }
}

// A well-spread colour for cluster `i`, 0..255 (`views::cluster_colour`).
fn cluster_colour(i: u32) -> vec3<f32> {
    let h = fract(f32(i) * 0.618034);
    let s = 0.55 + 0.4 * (f32((i * 2654435761u) >> 28u) / 15.0);
    let v = 0.65 + 0.35 * (f32(((i * 40503u) >> 12u) & 7u) / 7.0);
    return floor(hsv(h, s, v) * 255.0 + 0.5);
}

@compute @workgroup_size(8, 8)
fn display(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.size.x || id.y >= params.size.y) {
        return;
    }
    let i = id.y * params.size.x + id.x;
    let e = exposure_out[0];
    var c = vec3<f32>(0.0);
    switch (params.size.z) {
        case VIEW_DIRECT: { c = tonemap(a_direct_at(i), e); }
        case VIEW_INDIRECT: { c = tonemap(a_indirect_at(i), e); }
        case VIEW_SP_CLUSTERS: {
            let id = labels[i];
            if (id != 0xffffffffu) {
                let l = clamp(luminance(a_radiance(i)) * e, 0.0, 1.0);
                c = floor(cluster_colour(id) * (0.6 + 0.4 * sqrt(l))) / 255.0;
            }
        }
        // The final image darkened to a third (integer division of its 8-bit values), under the dots
        // the app draws.
        case VIEW_VPL_BASE: { c = floor(round(tonemap(a_final(i), e) * 255.0) / 3.0) / 255.0; }
        case VIEW_REFERENCE: { c = tonemap(reference[i].xyz, e); }
        case VIEW_ERROR: { c = error_colour(a_radiance(i), reference[i].xyz); }
        case VIEW_SPLIT: {
            let cut = min(u32(round(clamp(params.scale.w, 0.0, 1.0) * f32(params.size.x))),
                          params.size.x);
            if (id.x < cut) {
                c = tonemap(a_final(i), e);
            } else {
                c = tonemap(b_final(i), e);
            }
        }
        case VIEW_DIFF: { c = error_colour(a_final(i), b_final(i)); }
        case VIEW_FINAL, default: { c = tonemap(a_final(i), e); }
    }
    textureStore(out_image, vec2<i32>(id.xy), vec4<f32>(c, 1.0));
}
