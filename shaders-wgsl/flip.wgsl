// LDR FLIP on the GPU (`app::flip`): the per-pixel FLIP error (Andersson et al. 2020, "FLIP: A
// Difference Evaluator for Alternating Images") of a frame against a reference, both shown as the
// viewer shows them, its mean, and its magma picture. It follows NVIDIA's reference code (the C++
// the `nv-flip` crate wraps: `image.h` `FLIP`, `color.h`), constant for constant; its CPU twin is
// `cpu::flip`, and `metrics::flip_map` (NVIDIA's C++) is the oracle (tests/flip.rs).
//
// - `filter_x`: a row tile of 64 pixels (+ the filters' reach) of both images into workgroup memory:
//   radiance × exposure → 8-bit sRGB exactly as `export::to_srgb8` writes it (a binary search over the
//   steps of its byte, `cpu::flip::srgb8_thresholds`) → FLIP's linear value of that byte → XYZ →
//   YCxCz; then the horizontal CSF filters (Y, Cx, Cz's two Gaussians) and the horizontal feature
//   filters (first and second derivative, Gaussian) of the achromatic channel normalised to [0, 1].
// - `filter_y`: the vertical filters; the filtered colours back to linear RGB clamped to [0, 1],
//   CIELab, Hunt, HyAB, ^qc, the remap by pc·cmax and pt; the edge and point differences, the feature
//   difference ((max / √2)^qf); the error colour^(1 − feature). Edges clamp, as FLIP's.
// - `mean_partial` + `mean_final`: the mean error, a tree sum a workgroup and one workgroup over the
//   partials.
// - `colour`: the map through FLIP's magma LUT (`tensor::colorMap`) into the display's texture.

#import common/reduce.wgsl

struct FlipParams {
    // Width, height, pixels, 0.
    size: vec4<u32>,
    // x: A's factor from render units to the scene's; y: cmax; z: pc · cmax; w: 0.
    consts: vec4<f32>,
    // The CSF taps (Y, Cx, Cz's first, Cz's second), from −SPATIAL_RADIUS (`spatial_filters`).
    spatial: array<vec4<f32>, SPATIAL_TAPS>,
    // The feature taps (Gaussian, first, second derivative, 0), from −FEATURE_RADIUS.
    feature: array<vec4<f32>, FEATURE_TAPS>,
    // 256 scalars each, four a vec4: the least linear value of each sRGB byte (`srgb8_thresholds`),
    // FLIP's linear value of each byte (`srgb8_linear`), magma as 0xBBGGRR.
    thresholds: array<vec4<f32>, 64>,
    linear: array<vec4<f32>, 64>,
    magma: array<vec4<u32>, 64>,
}

// The filters' reach at FLIP's default 67 pixels per degree (`cpu::flip::spatial_radius`,
// `feature_radius`; a unit test checks them): constant trip counts.
const SPATIAL_RADIUS: u32 = 10u;
const SPATIAL_TAPS: u32 = 21u;
const FEATURE_RADIUS: u32 = 9u;
const FEATURE_TAPS: u32 = 19u;

// Pixels a workgroup of `filter_x` filters, and its tile with the CSF's reach (the wider) each side.
const ROW: u32 = 64u;
const TILE: u32 = 84u;
const REDUCE: u32 = 256u;

const F32_MAX: f32 = 3.40282347e38;

// FLIP's constants (`sharedflip.h`).
const QC: f32 = 0.7;
const PT: f32 = 0.95;
// The feature difference's exponent qf = 0.5 is a square root here; its normalisation 1 / √2.
const INV_SQRT_2: f32 = f32(1.0) / sqrt(f32(2.0));

@group(0) @binding(0) var<uniform> params: FlipParams;
// A's emission + direct light and indirect light, a vec4 an image pixel, render units.
@group(0) @binding(1) var<storage, read> a_direct: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> a_indirect: array<vec4<f32>>;
// The reference, a vec4 a pixel, the scene's units.
@group(0) @binding(3) var<storage, read> reference: array<vec4<f32>>;
// The exposure both are shown with, in [0] (the display pass's).
@group(0) @binding(4) var<storage, read> exposure: array<f32>;
// `filter_x`'s output, two images of n each: the reference's horizontal CSF sums (Y, Cx, Cz1, Cz2)
// then A's; the reference's horizontal feature sums (d, dd, g, 0) then A's.
@group(0) @binding(5) var<storage, read_write> csf: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> features: array<vec4<f32>>;
// The FLIP error of each pixel.
@group(0) @binding(7) var<storage, read_write> flip_map: array<f32>;
// [0]: the mean error; [1 + g]: workgroup g's sum.
@group(0) @binding(8) var<storage, read_write> sums: array<f32>;
@group(0) @binding(9) var out_image: texture_storage_2d<rgba8unorm, write>;

// The row tile in YCxCz: the reference's TILE entries, then A's.
var<workgroup> tile: array<vec3<f32>, 2u * TILE>;
var<workgroup> wg_sum: array<f32, REDUCE>;

fn width() -> u32 {
    return params.size.x;
}

fn pixels() -> u32 {
    return params.size.z;
}

// A pixel of A in the scene's units (`display.wgsl`'s `a_radiance`, `Frame::radiance`).
fn a_radiance(i: u32) -> vec3<f32> {
    let s = params.consts.x;
    let d = min(a_direct[i].xyz * s, vec3<f32>(F32_MAX));
    let e = min(a_indirect[i].xyz * s, vec3<f32>(F32_MAX));
    return min(d + e, vec3<f32>(F32_MAX));
}

// NaN by its bits (a driver may fold x != x away).
fn is_nan(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7fffffffu) > 0x7f800000u;
}

fn threshold(k: u32) -> f32 {
    return params.thresholds[k >> 2u][k & 3u];
}

// FLIP's linear value of a radiance channel `c` shown at exposure `e` (`export::to_srgb8`: NaN as 0;
// c · e, a NaN product (∞ · 0) as 1 as Rust's `min` takes it, clamped to 1, sRGB, 8 bits; then
// FLIP's sRGB → linear of the byte ÷ 255).
fn linear8(c: f32, e: f32) -> f32 {
    var v = c * e;
    if (is_nan(v)) {
        v = 1.0;
    }
    if (is_nan(c)) {
        v = 0.0;
    }
    v = min(v, 1.0);
    // The largest byte whose step v reaches (entry 0 is 0: −∞ and negatives give byte 0).
    var b = 0u;
    for (var step = 128u; step > 0u; step = step >> 1u) {
        if (v >= threshold(b + step)) {
            b = b + step;
        }
    }
    return params.linear[b >> 2u][b & 3u];
}

// Linear RGB → XYZ (D65), FLIP's matrix: quotients of f32 values divided in f32 as its C++ does
// (module constants: naga evaluates them, in f32, before the driver sees them).
const A11: f32 = f32(10135552.0) / f32(24577794.0);
const A12: f32 = f32(8788810.0) / f32(24577794.0);
const A13: f32 = f32(4435075.0) / f32(24577794.0);
const A21: f32 = f32(2613072.0) / f32(12288897.0);
const A22: f32 = f32(8788810.0) / f32(12288897.0);
const A23: f32 = f32(887015.0) / f32(12288897.0);
const A31: f32 = f32(1425312.0) / f32(73733382.0);
const A32: f32 = f32(8788810.0) / f32(73733382.0);
const A33: f32 = f32(70074185.0) / f32(73733382.0);

fn linear_rgb_to_xyz(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(A11 * c.x + A12 * c.y + A13 * c.z, A21 * c.x + A22 * c.y + A23 * c.z,
                     A31 * c.x + A32 * c.y + A33 * c.z);
}

fn xyz_to_linear_rgb(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(3.241003275 * c.x + -1.537398934 * c.y + -0.498615861 * c.z,
                     -0.969224334 * c.x + 1.875930071 * c.y + 0.041554224 * c.z,
                     0.055639423 * c.x + -0.204011202 * c.y + 1.057148933 * c.z);
}

const ILLUMINANT: vec3<f32> = vec3<f32>(0.950428545, 1.000000000, 1.088900371);
const INV_ILLUMINANT: vec3<f32> = vec3<f32>(1.052156925, 1.000000000, 0.918357670);

fn xyz_to_ycxcz(c: vec3<f32>) -> vec3<f32> {
    let v = c * INV_ILLUMINANT;
    return vec3<f32>(116.0 * v.y - 16.0, 500.0 * (v.x - v.y), 200.0 * (v.y - v.z));
}

fn ycxcz_to_xyz(c: vec3<f32>) -> vec3<f32> {
    let y = (c.x + 16.0) / 116.0;
    let cx = c.y / 500.0;
    let cz = c.z / 200.0;
    return vec3<f32>(y + cx, y, y - cz) * ILLUMINANT;
}

// CIELab's f (`XYZ2CIELab`): the cube root above (6/29)³, else the line t / (3 (6/29)²) + 4/29.
const DELTA: f32 = f32(6.0) / f32(29.0);
const DELTA_SQ: f32 = DELTA * DELTA;
const DELTA_CUBE: f32 = DELTA * DELTA_SQ;
const LAB_FACTOR: f32 = f32(1.0) / (f32(3.0) * DELTA_SQ);
const LAB_TERM: f32 = f32(4.0) / f32(29.0);
const ONE_THIRD: f32 = f32(1.0) / f32(3.0);

fn lab_f(t: f32) -> f32 {
    if (t > DELTA_CUBE) {
        return pow(t, ONE_THIRD);
    }
    return LAB_FACTOR * t + LAB_TERM;
}

// CIELab of a linear RGB colour (D65) with the Hunt adjustment of a*, b* (0.01 · L* · chroma).
fn lab_hunt(rgb: vec3<f32>) -> vec3<f32> {
    let v = linear_rgb_to_xyz(rgb) * INV_ILLUMINANT;
    let f = vec3<f32>(lab_f(v.x), lab_f(v.y), lab_f(v.z));
    let l = 116.0 * f.y - 16.0;
    let a = 500.0 * (f.x - f.y);
    let b = 200.0 * (f.y - f.z);
    return vec3<f32>(l, 0.01 * l * a, 0.01 * l * b);
}

fn hyab(p: vec3<f32>, q: vec3<f32>) -> f32 {
    let d = p - q;
    return abs(d.x) + sqrt(d.y * d.y + d.z * d.z);
}

// x^y for x ≥ 0 as C's powf gives it at x = 0 (0, or 1 for y = 0).
fn pow0(x: f32, y: f32) -> f32 {
    if (x <= 0.0) {
        return select(0.0, 1.0, y == 0.0);
    }
    return pow(x, y);
}

// YCxCz of a radiance shown at exposure `e`, as FLIP reads the 8-bit image.
fn ycxcz(c: vec3<f32>, e: f32) -> vec3<f32> {
    let l = vec3<f32>(linear8(c.x, e), linear8(c.y, e), linear8(c.z, e));
    return xyz_to_ycxcz(linear_rgb_to_xyz(l));
}

// The horizontal CSF sums of tile entry `t` (the pixel's, from tile entry `base`): (Y, Cx, Cz1, Cz2).
fn csf_x(base: u32, t: u32) -> vec4<f32> {
    var s = vec4<f32>(0.0);
    for (var k = 0u; k < SPATIAL_TAPS; k = k + 1u) {
        let w = params.spatial[k];
        let p = tile[base + t + k];
        s = s + vec4<f32>(w.x * p.x, w.y * p.y, w.z * p.z, w.w * p.z);
    }
    return s;
}

// The horizontal feature sums of tile entry `t` (from `base`): (first derivative, second,
// Gaussian, 0) of (Y + 16) / 116.
const ONE_OVER_116: f32 = f32(1.0) / f32(116.0);
const SIXTEEN_OVER_116: f32 = f32(16.0) / f32(116.0);

fn features_x(base: u32, t: u32) -> vec4<f32> {
    var s = vec4<f32>(0.0);
    for (var k = 0u; k < FEATURE_TAPS; k = k + 1u) {
        let w = params.feature[k];
        let p = tile[base + t + SPATIAL_RADIUS - FEATURE_RADIUS + k];
        let y = p.x * ONE_OVER_116 + SIXTEEN_OVER_116;
        s = s + vec4<f32>(w.y * y, w.z * y, w.x * y, 0.0);
    }
    return s;
}

@compute @workgroup_size(64)
fn filter_x(@builtin(local_invocation_index) t: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let y = wg.y;
    let x0 = wg.x * ROW;
    let e = exposure[0];
    for (var j = 0u; j < 2u; j = j + 1u) {
        let k = t + j * ROW;
        if (k < TILE) {
            let x = clamp(i32(x0 + k) - i32(SPATIAL_RADIUS), 0, i32(width()) - 1);
            let i = y * width() + u32(x);
            tile[k] = ycxcz(reference[i].xyz, e);
            tile[TILE + k] = ycxcz(a_radiance(i), e);
        }
    }
    workgroupBarrier();
    let x = x0 + t;
    if (x >= width()) {
        return;
    }
    let n = pixels();
    let i = y * width() + x;
    csf[i] = csf_x(0u, t);
    csf[n + i] = csf_x(TILE, t);
    features[i] = features_x(0u, t);
    features[n + i] = features_x(TILE, t);
}

// The vertical CSF of image `img` (0: reference, 1: A) at (x, y), in Hunt-adjusted Lab.
fn csf_lab(img: u32, x: u32, y: u32) -> vec3<f32> {
    let base = img * pixels();
    let h = i32(params.size.y);
    var s = vec4<f32>(0.0);
    for (var k = 0u; k < SPATIAL_TAPS; k = k + 1u) {
        let yy = u32(clamp(i32(y + k) - i32(SPATIAL_RADIUS), 0, h - 1));
        s = s + params.spatial[k] * csf[base + yy * width() + x];
    }
    let rgb = xyz_to_linear_rgb(ycxcz_to_xyz(vec3<f32>(s.x, s.y, s.z + s.w)));
    return lab_hunt(clamp(rgb, vec3<f32>(0.0), vec3<f32>(1.0)));
}

// The edge and point strengths of image `img` (0: reference, 1: A) at (x, y).
fn edge_point(img: u32, x: u32, y: u32) -> vec2<f32> {
    let base = img * pixels();
    let h = i32(params.size.y);
    var dx = 0.0;
    var ddx = 0.0;
    var dy = 0.0;
    var ddy = 0.0;
    for (var k = 0u; k < FEATURE_TAPS; k = k + 1u) {
        let yy = u32(clamp(i32(y + k) - i32(FEATURE_RADIUS), 0, h - 1));
        let w = params.feature[k];
        let p = features[base + yy * width() + x];
        dx = dx + w.x * p.x;
        ddx = ddx + w.x * p.y;
        dy = dy + w.y * p.z;
        ddy = ddy + w.z * p.z;
    }
    return vec2<f32>(sqrt(dx * dx + dy * dy), sqrt(ddx * ddx + ddy * ddy));
}

@compute @workgroup_size(64)
fn filter_y(@builtin(global_invocation_id) id: vec3<u32>) {
    let x = id.x;
    let y = id.y;
    if (x >= width()) {
        return;
    }
    let cmax = params.consts.y;
    let pccmax = params.consts.z;
    var cd = pow0(hyab(csf_lab(0u, x, y), csf_lab(1u, x, y)), QC);
    if (cd < pccmax) {
        cd = cd * (PT / pccmax);
    } else {
        cd = PT + ((cd - pccmax) / (cmax - pccmax)) * (1.0 - PT);
    }
    let r = edge_point(0u, x, y);
    let a = edge_point(1u, x, y);
    let d = abs(r - a);
    let fd = sqrt(INV_SQRT_2 * max(d.x, d.y));
    flip_map[y * width() + x] = pow0(cd, 1.0 - fd);
}

// The sum of every invocation's `s` over the workgroup (a tree in `wg_sum`); every invocation
// calls it, and gets the sum.
fn workgroup_sum(t: u32, s: f32) -> f32 {
    wg_sum[t] = s;
    tree_sum(t);
    return wg_sum[0];
}

// The sum of the map over this workgroup's pixels into sums[1 + workgroup].
@compute @workgroup_size(256)
fn mean_partial(@builtin(local_invocation_index) t: u32, @builtin(workgroup_id) wg: vec3<u32>,
                @builtin(num_workgroups) groups: vec3<u32>) {
    let group = wg.y * groups.x + wg.x;
    let i = group * REDUCE + t;
    var s = 0.0;
    if (i < pixels()) {
        s = flip_map[i];
    }
    let total = workgroup_sum(t, s);
    if (t == 0u) {
        sums[1u + group] = total;
    }
}

// The mean error into sums[0]. One workgroup.
@compute @workgroup_size(256)
fn mean_final(@builtin(local_invocation_index) t: u32) {
    let groups = (pixels() + REDUCE - 1u) / REDUCE;
    var s = 0.0;
    for (var g = t; g < groups; g = g + REDUCE) {
        s = s + sums[1u + g];
    }
    let total = workgroup_sum(t, s);
    if (t == 0u) {
        sums[0] = total / f32(max(pixels(), 1u));
    }
}

// The map in FLIP's magma colours (`tensor::colorMap`: entry ⌊v · 255 + 0.5⌋ mod 256), opaque.
@compute @workgroup_size(8, 8)
fn colour(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= width() || id.y >= params.size.y) {
        return;
    }
    let v = flip_map[id.y * width() + id.x];
    let k = u32(max(v * 255.0 + 0.5, 0.0)) % 256u;
    let c = params.magma[k >> 2u][k & 3u];
    let rgb = vec3<f32>(f32(c & 255u), f32((c >> 8u) & 255u), f32((c >> 16u) & 255u)) / 255.0;
    textureStore(out_image, vec2<i32>(id.xy), vec4<f32>(rgb, 1.0));
}
