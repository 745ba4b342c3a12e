//! LDR FLIP from its definition, the FLIP pass's (`app::flip`, `shaders-wgsl/flip.wgsl`) filters
//! and constants and its CPU twin: LDR FLIP (Andersson et al.
//! 2020, "FLIP: A Difference Evaluator for Alternating Images") written from its definition as
//! NVIDIA's reference code computes it (the C++ that the `nv-flip` crate wraps, `image.h`,
//! `color.h`, `sharedflip.h`), in f32 and in its order of operations, so that it reproduces
//! `metrics::flip_map` (which calls that code) to rounding. The filter weights and constants here are
//! also what the pass uploads.
//!
//! The steps: both images tone-mapped as `export::to_srgb8` shows them (× exposure, clamped, sRGB, 8
//! bits); sRGB → linear RGB → XYZ → YCxCz; the contrast sensitivity filters (separable, clamp at the
//! edges) on Y, Cx and Cz (Cz: a sum of two Gaussians, split in two separable filters); back to
//! linear RGB clamped to [0, 1]; CIELab with the Hunt adjustment; HyAB; the colour error's remap
//! (exponent qc, [0, pc·cmax] → [0, pt], the rest → (pt, 1]); on the achromatic channel the edge
//! (first derivative) and point (second derivative) detectors of Gaussians of σ = w/2 · ppd; the
//! feature difference ((max |Δedge|, |Δpoint|) / √2)^qf; error = colour^(1 − feature).

// FLIP's decimal constants are written as its C++ writes them (each rounds to the same f32).
#![allow(clippy::excessive_precision)]

/// The pixels per degree of arc FLIP is evaluated at: `nv_flip::DEFAULT_PIXELS_PER_DEGREE` (67).
pub const PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// FLIP's π (`sharedflip.h`: 3.14159265358979f, the same f32).
const PI: f32 = std::f32::consts::PI;
/// Colour error exponent, its cut-off fraction of cmax and the error it maps to.
const QC: f32 = 0.7;
pub const PC: f32 = 0.4;
const PT: f32 = 0.95;
/// Feature detector width (degrees) and exponent.
const GW: f32 = 0.082;
const QF: f32 = 0.5;
/// The CSF's Gaussians: Y, Cx, Cz's first (a1, b1), Cz's second (a2, b2).
const A1: [f32; 3] = [1.0, 1.0, 34.1];
const B1: [f32; 3] = [0.0047, 0.0053, 0.04];
const A2: [f32; 3] = [0.0, 0.0, 13.5];
const B2: [f32; 3] = [1.0e-5, 1.0e-5, 0.025];

/// D65 and its inverse, as FLIP writes them.
const ILLUMINANT: [f32; 3] = [0.950428545, 1.000000000, 1.088900371];
const INV_ILLUMINANT: [f32; 3] = [1.052156925, 1.000000000, 0.918357670];

/// The CSF filters' radius in pixels at `ppd` (`calculateSpatialFilterRadius`): 10 at 67.
pub fn spatial_radius(ppd: f32) -> usize {
    let max_b = B1.iter().chain(&B2).copied().fold(f32::MIN, f32::max);
    let pi_sq = PI * PI;
    (3.0 * (max_b / (2.0 * pi_sq)).sqrt() * ppd).ceil() as usize
}

/// The separable CSF weights at `ppd` (`setSpatialFilters`): per tap (Y, Cx, Cz's first, Cz's
/// second), Y and Cx normalised to sum 1, Cz's two by the norm of their sums.
pub fn spatial_filters(ppd: f32) -> Vec<[f32; 4]> {
    let r = spatial_radius(ppd) as i32;
    let dx = 1.0 / ppd;
    let pi_sq = PI * PI;
    let gaussian = |x2: f32, a: f32, b: f32| a * (PI / b).sqrt() * (-pi_sq * x2 / b).exp();
    let gaussian_sqrt =
        |x2: f32, a: f32, b: f32| (a * (PI / b).sqrt()).sqrt() * (-pi_sq * x2 / b).exp();
    let mut w: Vec<[f32; 4]> = (-r..=r)
        .map(|x| {
            let ix = x as f32 * dx;
            let ix2 = ix * ix;
            [
                gaussian(ix2, A1[0], B1[0]),
                gaussian(ix2, A1[1], B1[1]),
                gaussian_sqrt(ix2, A1[2], B1[2]),
                gaussian_sqrt(ix2, A2[2], B2[2]),
            ]
        })
        .collect();
    let mut sum = [0.0f32; 4];
    for t in &w {
        for c in 0..4 {
            sum[c] += t[c];
        }
    }
    let norm = [1.0 / sum[0], 1.0 / sum[1]];
    let norm_cz = 1.0 / (sum[2] * sum[2] + sum[3] * sum[3]).sqrt();
    for t in &mut w {
        *t = [
            t[0] * norm[0],
            t[1] * norm[1],
            t[2] * norm_cz,
            t[3] * norm_cz,
        ];
    }
    w
}

/// The feature detectors' standard deviation in pixels at `ppd`: w/2 · ppd.
fn feature_sigma(ppd: f32) -> f32 {
    0.5 * GW * ppd
}

/// The feature filters' radius at `ppd`: ⌈3σ⌉, 9 at 67.
pub fn feature_radius(ppd: f32) -> usize {
    (3.0 * feature_sigma(ppd)).ceil() as usize
}

/// The separable feature weights at `ppd` (`setFeatureFilter`): per tap (Gaussian, its first
/// derivative, its second), the Gaussian normalised to sum 1 and each derivative's positive and
/// negative weights to sum 1 and −1.
pub fn feature_filter(ppd: f32) -> Vec<[f32; 3]> {
    let sd = feature_sigma(ppd);
    let r = feature_radius(ppd) as i32;
    let (mut g_sum, mut dg_neg, mut dg_pos, mut ddg_neg, mut ddg_pos) =
        (0.0f32, 0.0, 0.0, 0.0, 0.0);
    let mut w: Vec<[f32; 3]> = (-r..=r)
        .map(|x| {
            let xf = x as f32;
            let g = (-(xf * xf) / (2.0 * sd * sd)).exp();
            g_sum += g;
            let dg = -xf * g;
            if dg > 0.0 {
                dg_pos += dg;
            } else {
                dg_neg -= dg;
            }
            let ddg = (xf * xf / (sd * sd) - 1.0) * g;
            if ddg > 0.0 {
                ddg_pos += ddg;
            } else {
                ddg_neg -= ddg;
            }
            [g, dg, ddg]
        })
        .collect();
    for t in &mut w {
        *t = [
            t[0] / g_sum,
            t[1] / if t[1] > 0.0 { dg_pos } else { dg_neg },
            t[2] / if t[2] > 0.0 { ddg_pos } else { ddg_neg },
        ];
    }
    w
}

fn srgb_to_linear(s: f32) -> f32 {
    if s <= 0.04045 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_rgb_to_xyz(c: [f32; 3]) -> [f32; 3] {
    let m = [
        [
            10135552.0f32 / 24577794.0f32,
            8788810.0f32 / 24577794.0f32,
            4435075.0f32 / 24577794.0f32,
        ],
        [
            2613072.0f32 / 12288897.0f32,
            8788810.0f32 / 12288897.0f32,
            887015.0f32 / 12288897.0f32,
        ],
        [
            1425312.0f32 / 73733382.0f32,
            8788810.0f32 / 73733382.0f32,
            70074185.0f32 / 73733382.0f32,
        ],
    ];
    m.map(|r| r[0] * c[0] + r[1] * c[1] + r[2] * c[2])
}

fn xyz_to_linear_rgb(c: [f32; 3]) -> [f32; 3] {
    let m = [
        [3.241003275f32, -1.537398934, -0.498615861],
        [-0.969224334, 1.875930071, 0.041554224],
        [0.055639423, -0.204011202, 1.057148933],
    ];
    m.map(|r| r[0] * c[0] + r[1] * c[1] + r[2] * c[2])
}

fn xyz_to_ycxcz(c: [f32; 3]) -> [f32; 3] {
    let [x, y, z] = [0, 1, 2].map(|i| c[i] * INV_ILLUMINANT[i]);
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn ycxcz_to_xyz(c: [f32; 3]) -> [f32; 3] {
    let y = (c[0] + 16.0) / 116.0;
    let cx = c[1] / 500.0;
    let cz = c[2] / 200.0;
    let v = [y + cx, y, y - cz];
    [0, 1, 2].map(|i| v[i] * ILLUMINANT[i])
}

fn xyz_to_lab(c: [f32; 3]) -> [f32; 3] {
    let delta = 6.0f32 / 29.0;
    let delta_sq = delta * delta;
    let delta_cube = delta * delta_sq;
    let factor = 1.0 / (3.0 * delta_sq);
    let term = 4.0f32 / 29.0;
    let [x, y, z] = [0, 1, 2].map(|i| {
        let t = c[i] * INV_ILLUMINANT[i];
        if t > delta_cube {
            t.powf(1.0 / 3.0)
        } else {
            factor * t + term
        }
    });
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn hunt(l: f32, c: f32) -> f32 {
    0.01 * l * c
}

fn hyab(a: [f32; 3], b: [f32; 3]) -> f32 {
    (a[0] - b[0]).abs() + ((a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2])).sqrt()
}

/// CIELab with the Hunt adjustment of a linear RGB colour.
fn lab_hunt(rgb: [f32; 3]) -> [f32; 3] {
    let lab = xyz_to_lab(linear_rgb_to_xyz(rgb));
    [lab[0], hunt(lab[0], lab[1]), hunt(lab[0], lab[2])]
}

/// The largest colour distance, green to blue, raised to qc (`computeMaxDistance`): cmax.
pub fn max_distance() -> f32 {
    hyab(lab_hunt([0.0, 1.0, 0.0]), lab_hunt([0.0, 0.0, 1.0])).powf(QC)
}

/// An 8-bit sRGB colour (as FLIP reads an LDR image, ÷ 255) in YCxCz.
pub fn srgb8_to_ycxcz(p: [u8; 3]) -> [f32; 3] {
    xyz_to_ycxcz(linear_rgb_to_xyz(
        p.map(|c| srgb_to_linear(c as f32 / 255.0)),
    ))
}

/// An 8-bit channel as `export::to_srgb8` writes a clamped linear value `v` (already × exposure).
fn srgb8(v: f32) -> u8 {
    (crate::export::linear_to_srgb(v) * 255.0 + 0.5) as u8
}

/// Where `export::to_srgb8`'s 8-bit value steps: entry k (1..=255) is the least linear value
/// (× exposure, clamped to [0, 1]) it writes as k or more; entry 0 is 0. The pass finds a channel's
/// byte by a binary search over these, which reproduces the CPU's `powf` and rounding exactly.
pub fn srgb8_thresholds() -> [f32; 256] {
    let mut t = [0.0f32; 256];
    let top = 1.0f32.to_bits();
    for (k, e) in t.iter_mut().enumerate().skip(1) {
        // The least bit pattern in [0, 1] (positive floats order as their bits) with srgb8 ≥ k.
        let (mut lo, mut hi) = (0u32, top);
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            if srgb8(f32::from_bits(mid)) as usize >= k {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        *e = f32::from_bits(lo);
    }
    t
}

/// FLIP's linear value of each 8-bit sRGB value (`sRGB2LinearRGB(b / 255)`).
pub fn srgb8_linear() -> [f32; 256] {
    std::array::from_fn(|b| srgb_to_linear(b as f32 / 255.0))
}

/// The colour error's remap of a HyAB distance (`computeColorDifference`'s end).
pub fn remap_colour(hyab: f32) -> f32 {
    let cmax = max_distance();
    let pccmax = PC * cmax;
    let d = hyab.powf(QC);
    if d < pccmax {
        d * (PT / pccmax)
    } else {
        PT + ((d - pccmax) / (cmax - pccmax)) * (1.0 - PT)
    }
}

/// The per-pixel LDR FLIP error of `p.x` against `p.reference`, both tone-mapped with
/// `export::to_srgb8` at `p.exposure`, at `PIXELS_PER_DEGREE`: what `metrics::flip_map` computes
/// through NVIDIA's C++.
pub fn flip_map(p: crate::metrics::FlipInputs) -> Vec<f32> {
    p.pixels();
    let (x, reference) = (p.x, p.reference);
    let (w, h) = (p.width as usize, p.height as usize);
    let ycxcz = |img: &[[f32; 3]]| -> Vec<[f32; 3]> {
        crate::export::to_srgb8(img, p.exposure)
            .chunks_exact(3)
            .map(|p| srgb8_to_ycxcz([p[0], p[1], p[2]]))
            .collect()
    };
    let (r, t) = (ycxcz(reference), ycxcz(x));
    let ppd = PIXELS_PER_DEGREE;
    let sf = spatial_filters(ppd);
    let ff = feature_filter(ppd);
    let (sr, fr) = (sf.len() as i64 / 2, ff.len() as i64 / 2);
    let at =
        |x: i64, y: i64| y.clamp(0, h as i64 - 1) as usize * w + x.clamp(0, w as i64 - 1) as usize;
    let cmax = max_distance();
    let pccmax = PC * cmax;
    // Horizontal passes: the CSF (Y·wY, Cx·wCx, Cz·wCz1, Cz·wCz2) and the features (dx, ddx, g) of
    // the achromatic channel normalised to [0, 1].
    let horizontal = |img: &[[f32; 3]]| -> (Vec<[f32; 4]>, Vec<[f32; 3]>) {
        let mut csf = vec![[0.0f32; 4]; w * h];
        let mut feat = vec![[0.0f32; 3]; w * h];
        for y in 0..h as i64 {
            for x in 0..w as i64 {
                let mut a = [0.0f32; 4];
                for (k, wt) in sf.iter().enumerate() {
                    let p = img[at(x + k as i64 - sr, y)];
                    a[0] += wt[0] * p[0];
                    a[1] += wt[1] * p[1];
                    a[2] += wt[2] * p[2];
                    a[3] += wt[3] * p[2];
                }
                let mut f = [0.0f32; 3];
                for (k, wt) in ff.iter().enumerate() {
                    let yn = img[at(x + k as i64 - fr, y)][0] * (1.0 / 116.0) + 16.0 / 116.0;
                    f[0] += wt[1] * yn;
                    f[1] += wt[2] * yn;
                    f[2] += wt[0] * yn;
                }
                csf[at(x, y)] = a;
                feat[at(x, y)] = f;
            }
        }
        (csf, feat)
    };
    let (rc, rf) = horizontal(&r);
    let (tc, tf) = horizontal(&t);
    let mut out = vec![0.0f32; w * h];
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            let colour = |c: &[[f32; 4]]| {
                let mut a = [0.0f32; 4];
                for (k, wt) in sf.iter().enumerate() {
                    let p = c[at(x, y + k as i64 - sr)];
                    for i in 0..4 {
                        a[i] += wt[i] * p[i];
                    }
                }
                let rgb = xyz_to_linear_rgb(ycxcz_to_xyz([a[0], a[1], a[2] + a[3]]));
                lab_hunt(rgb.map(|v| v.clamp(0.0, 1.0)))
            };
            let mut cd = hyab(colour(&rc), colour(&tc)).powf(QC);
            cd = if cd < pccmax {
                cd * (PT / pccmax)
            } else {
                PT + ((cd - pccmax) / (cmax - pccmax)) * (1.0 - PT)
            };
            // (edge, point) of one image.
            let features = |f: &[[f32; 3]]| {
                let (mut dx, mut ddx, mut dy, mut ddy) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
                for (k, wt) in ff.iter().enumerate() {
                    let p = f[at(x, y + k as i64 - fr)];
                    dx += wt[0] * p[0];
                    ddx += wt[0] * p[1];
                    dy += wt[1] * p[2];
                    ddy += wt[2] * p[2];
                }
                ((dx * dx + dy * dy).sqrt(), (ddx * ddx + ddy * ddy).sqrt())
            };
            let (er, pr) = features(&rf);
            let (et, pt) = features(&tf);
            let fd = ((1.0 / 2.0f32.sqrt()) * (er - et).abs().max((pr - pt).abs())).powf(QF);
            out[at(x, y)] = cd.powf(1.0 - fd);
        }
    }
    out
}

/// The magma LUT's entry for a FLIP value (`tensor::colorMap`): ⌊v · 255 + 0.5⌋ mod 256.
pub fn magma_index(v: f32) -> usize {
    (v * 255.0 + 0.5) as i32 as usize % 256
}

#[cfg(test)]
mod tests {
    use super::*;

    /// FLIP's filter sizes at 67 pixels per degree: the CSF's radius ⌈3 · √(0.04 / 2π²) · 67⌉ =
    /// ⌈9.05⌉ = 10, the features' ⌈3 · 0.041 · 67⌉ = ⌈8.24⌉ = 9; the weights' sums as normalised.
    #[test]
    fn filters_at_default_ppd() {
        assert_eq!(PIXELS_PER_DEGREE, 67.0);
        assert_eq!(spatial_radius(PIXELS_PER_DEGREE), 10);
        assert_eq!(feature_radius(PIXELS_PER_DEGREE), 9);
        let s = spatial_filters(PIXELS_PER_DEGREE);
        assert_eq!(s.len(), 21);
        let sum = |i: usize| s.iter().map(|t| t[i]).sum::<f32>();
        assert!((sum(0) - 1.0).abs() < 1e-6 && (sum(1) - 1.0).abs() < 1e-6);
        assert!((sum(2).hypot(sum(3)) - 1.0).abs() < 1e-6);
        let f = feature_filter(PIXELS_PER_DEGREE);
        assert_eq!(f.len(), 19);
        let g: f32 = f.iter().map(|t| t[0]).sum();
        let pos = |i: usize| f.iter().map(|t| t[i].max(0.0)).sum::<f32>();
        let neg = |i: usize| f.iter().map(|t| t[i].min(0.0)).sum::<f32>();
        assert!((g - 1.0).abs() < 1e-6);
        for i in [1, 2] {
            assert!((pos(i) - 1.0).abs() < 1e-6 && (neg(i) + 1.0).abs() < 1e-6);
        }
    }

    /// Hand-worked: white is Y = 116 · 1 − 16 = 100 with no chroma (D65's white point), black Y = −16;
    /// cmax is HyAB(green, blue)^0.7 in Hunt-adjusted Lab, HyAB = |87.7362 − 32.2982| +
    /// |(−75.6099, 72.9812) − (25.5781, −34.8364)| = 203.3017 (worked in f64 from FLIP's matrix and
    /// D65, outside this code), so cmax = 41.276; an error of 0 remaps to 0 and cmax to 1.
    #[test]
    fn colour_space_by_hand() {
        let white = srgb8_to_ycxcz([255; 3]);
        assert!((white[0] - 100.0).abs() < 1e-4, "{white:?}");
        assert!(white[1].abs() < 1e-3 && white[2].abs() < 1e-3, "{white:?}");
        let black = srgb8_to_ycxcz([0; 3]);
        assert!((black[0] + 16.0).abs() < 1e-6 && black[1] == 0.0 && black[2] == 0.0);
        let d = max_distance().powf(1.0 / QC);
        assert!((d - 203.3017).abs() < 2e-3, "HyAB(green, blue) {d}");
        assert!((max_distance() - 41.2761).abs() < 1e-3);
        assert_eq!(remap_colour(0.0), 0.0);
        assert!((remap_colour(d) - 1.0).abs() < 1e-5);
        assert_eq!(magma_index(0.0), 0);
        assert_eq!(magma_index(1.0), 255);
    }

    /// The byte found through `srgb8_thresholds` (as the pass searches them) is `export::to_srgb8`'s
    /// at every step, on both sides of it, and at 100 000 values spread over [0, 1].
    #[test]
    fn thresholds_reproduce_to_srgb8() {
        let t = srgb8_thresholds();
        let search = |v: f32| {
            let mut b = 0usize;
            let mut step = 128;
            while step > 0 {
                if v >= t[b + step] {
                    b += step;
                }
                step /= 2;
            }
            b as u8
        };
        let cpu = |v: f32| crate::export::to_srgb8(&[[v; 3]], 1.0)[0];
        for k in 1..256 {
            assert!(t[k] > t[k - 1], "step {k}");
            let v = t[k];
            assert_eq!(cpu(v) as usize, k, "at step {k}");
            let below = f32::from_bits(v.to_bits() - 1);
            assert_eq!(search(below), cpu(below), "below step {k}");
            assert_eq!(search(v), cpu(v));
        }
        for i in 0..=100_000 {
            let v = i as f32 / 100_000.0;
            assert_eq!(search(v), cpu(v), "{v}");
        }
    }

    /// The twin against NVIDIA's C++ (`metrics::flip_map`) on a gradient against a noisy copy, an
    /// image of edges and dots against a shifted copy, a constant offset and identical images.
    /// Measured on this VM (x86-64, glibc): bit-equal on all four (the same f32 operations in the
    /// same order, the same libm); the bound leaves room for another libm's powf/expf.
    #[test]
    fn twin_matches_nv_flip() {
        let (w, h) = (40u32, 30u32);
        for (k, (a, b)) in test_pairs(w, h).into_iter().enumerate() {
            let p = crate::metrics::FlipInputs {
                x: &a,
                reference: &b,
                width: w,
                height: h,
                exposure: 1.0,
            };
            let (nv, twin) = (crate::metrics::flip_map(p), flip_map(p));
            let worst = nv
                .iter()
                .zip(&twin)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0f32, f32::max);
            println!("twin vs nv-flip, pair {k}: max abs {worst:.2e}");
            assert!(twin.iter().all(|v| v.is_finite()));
            assert!(worst <= 1e-6, "pair {k}: {worst}");
        }
    }

    /// An image pair (x, reference).
    type Pair = (Vec<[f32; 3]>, Vec<[f32; 3]>);

    /// Test image pairs of `w` × `h`.
    fn test_pairs(w: u32, h: u32) -> Vec<Pair> {
        let (w, h) = (w as usize, h as usize);
        let mut s = 12345u32;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            (s >> 8) as f32 / 16777216.0
        };
        let grad: Vec<[f32; 3]> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32 / w as f32, (i / w) as f32 / h as f32);
                [x, y, 0.5 * (x + y)]
            })
            .collect();
        let noisy: Vec<[f32; 3]> = grad
            .iter()
            .map(|p| p.map(|c| (c + 0.1 * (rnd() - 0.5)).max(0.0)))
            .collect();
        let edges = |shift: usize| -> Vec<[f32; 3]> {
            (0..w * h)
                .map(|i| {
                    let (x, y) = (i % w + shift, i / w);
                    if (x / 7 + y / 5) % 2 == 0 {
                        [0.8, 0.3, 0.1]
                    } else if x % 9 == 4 && y % 9 == 4 {
                        [1.0; 3]
                    } else {
                        [0.05, 0.1, 0.4]
                    }
                })
                .collect()
        };
        let offset: Vec<[f32; 3]> = grad.iter().map(|p| [p[0] + 0.1, p[1], p[2]]).collect();
        vec![
            (noisy, grad.clone()),
            (edges(1), edges(0)),
            (offset, grad.clone()),
            (grad.clone(), grad),
        ]
    }
}
