//! Error metrics of docs/design.md, "Error metrics". FLIP through NVIDIA's C++ (`flip`,
//! `flip_map`) and from its definition in Rust (`ldr_flip`: the GPU pass's filters and constants,
//! and its CPU twin).

pub mod ldr_flip;

/// The paper's MSE: mean over pixels and RGB channels of (x − ref)², both clamped to [0, 1].
pub fn mse(x: &[[f32; 3]], reference: &[[f32; 3]]) -> f64 {
    assert_eq!(x.len(), reference.len());
    let mut s = 0.0f64;
    for (a, b) in x.iter().zip(reference) {
        for c in 0..3 {
            let d = a[c].clamp(0.0, 1.0) as f64 - b[c].clamp(0.0, 1.0) as f64;
            s += d * d;
        }
    }
    s / (3 * x.len().max(1)) as f64
}

/// Scale-free relative MSE: mean of (x − ref)² / (ref² + 0.01), unclamped.
pub fn rel_mse(x: &[[f32; 3]], reference: &[[f32; 3]]) -> f64 {
    assert_eq!(x.len(), reference.len());
    let mut s = 0.0f64;
    for (a, b) in x.iter().zip(reference) {
        for c in 0..3 {
            let (a, b) = (a[c] as f64, b[c] as f64);
            s += (a - b) * (a - b) / (b * b + 0.01);
        }
    }
    s / (3 * x.len().max(1)) as f64
}

/// How much the clustering error itself changes between two frames (the flicker a user sees): the
/// mean over pixels and RGB channels of ((x_t − ref_t) − (x_{t−1} − ref_{t−1}))², every value clamped
/// to [0, 1] as for `mse`.
pub fn instability(
    x: &[[f32; 3]],
    reference: &[[f32; 3]],
    x_prev: &[[f32; 3]],
    reference_prev: &[[f32; 3]],
) -> f64 {
    assert!(
        x.len() == reference.len() && x.len() == x_prev.len() && x.len() == reference_prev.len()
    );
    let c = |v: f32| v.clamp(0.0, 1.0) as f64;
    let mut s = 0.0f64;
    for i in 0..x.len() {
        for ch in 0..3 {
            let d =
                (c(x[i][ch]) - c(reference[i][ch])) - (c(x_prev[i][ch]) - c(reference_prev[i][ch]));
            s += d * d;
        }
    }
    s / (3 * x.len().max(1)) as f64
}

/// The pixels of a `w` × `h` image (row-major) around image point (x, y) (pixel centres at
/// half-integers) with their bilinear weights: up to four (index, weight) pairs, the ones off the
/// image or of weight 0 left out (the caller renormalises over those it keeps).
pub fn bilinear_taps(x: f32, y: f32, w: usize, h: usize) -> impl Iterator<Item = (usize, f32)> {
    let (fx, fy) = (x - 0.5, y - 0.5);
    let (x0, y0) = (fx.floor(), fy.floor());
    let (tx, ty) = (fx - x0, fy - y0);
    [
        (0, 0, (1.0 - tx) * (1.0 - ty)),
        (1, 0, tx * (1.0 - ty)),
        (0, 1, (1.0 - tx) * ty),
        (1, 1, tx * ty),
    ]
    .into_iter()
    .filter_map(move |(dx, dy, wt)| {
        let (xx, yy) = (x0 as i64 + dx, y0 as i64 + dy);
        let inside = xx >= 0 && yy >= 0 && xx < w as i64 && yy < h as i64;
        (wt > 0.0 && inside).then(|| (yy as usize * w + xx as usize, wt))
    })
}

/// One frame of a camera path as `instability_world` reads it: the image, its reference, and per
/// pixel the surface point (w > 0 where the primary ray hit) and its normal, row-major.
pub struct PathFrame<'a> {
    pub x: &'a [[f32; 3]],
    pub reference: &'a [[f32; 3]],
    pub positions: &'a [[f32; 4]],
    pub normals: &'a [[f32; 4]],
    pub width: usize,
}

/// Two surface points are the same when their depths along the previous view agree within this
/// fraction of the depth...
pub const SAME_SURFACE_DEPTH: f32 = 0.02;
/// ... and their normals within this cosine (about 25°).
pub const SAME_SURFACE_COS: f32 = 0.9;

/// Flicker where the eye sees it: for each pixel of `cur` with a surface point, that point is
/// projected into the previous frame (`project_prev`: world point → pixel x, y, pixel centres at
/// half-integers, and depth; `None` behind the eye), and its error (x − ref, channels clamped to [0, 1] as
/// for `mse`) is compared with the previous frame's error there, bilinearly over the four pixels
/// around it that show the same surface (depth within `SAME_SURFACE_DEPTH`, normal within
/// `SAME_SURFACE_COS`; the weights renormalised over those). The mean squared difference over the
/// matched pixels and channels; `None` when no pixel matched. Unlike `instability`, a shadow edge
/// of the reference that moves across pixels as the camera moves does not count: only a change of
/// the error at a surface point does.
pub fn instability_world(
    cur: &PathFrame,
    prev: &PathFrame,
    project_prev: impl Fn(glam::Vec3) -> Option<(f32, f32, f32)>,
) -> Option<f64> {
    use glam::Vec3;
    let c = |v: f32| v.clamp(0.0, 1.0) as f64;
    let err = |f: &PathFrame, i: usize, ch: usize| c(f.x[i][ch]) - c(f.reference[i][ch]);
    let (w, h) = (prev.width, prev.x.len() / prev.width.max(1));
    let xyz = |p: [f32; 4]| Vec3::new(p[0], p[1], p[2]);
    let (mut sum, mut matched) = (0.0f64, 0usize);
    for i in 0..cur.x.len() {
        let p = cur.positions[i];
        if p[3].is_nan() || p[3] <= 0.0 {
            continue;
        }
        let Some((px, py, z)) = project_prev(xyz(p)) else {
            continue;
        };
        let n = xyz(cur.normals[i]);
        let mut acc = [0.0f64; 3];
        let mut wsum = 0.0f64;
        for (j, wt) in bilinear_taps(px, py, w, h) {
            let q = prev.positions[j];
            if q[3].is_nan() || q[3] <= 0.0 || n.dot(xyz(prev.normals[j])) < SAME_SURFACE_COS {
                continue;
            }
            match project_prev(xyz(q)) {
                Some((_, _, zq)) if (zq - z).abs() <= SAME_SURFACE_DEPTH * z => {}
                _ => continue,
            }
            for (ch, a) in acc.iter_mut().enumerate() {
                *a += wt as f64 * err(prev, j, ch);
            }
            wsum += wt as f64;
        }
        if wsum <= 1e-6 {
            continue;
        }
        matched += 1;
        for (ch, a) in acc.iter().enumerate() {
            let d = err(cur, i, ch) - a / wsum;
            sum += d * d;
        }
    }
    (matched > 0).then(|| sum / (3 * matched) as f64)
}

/// Rec. 709 luminance.
pub fn luminance(p: [f32; 3]) -> f32 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

pub fn mean_luminance(img: &[[f32; 3]]) -> f64 {
    img.iter().map(|p| luminance(*p) as f64).sum::<f64>() / img.len().max(1) as f64
}

/// A false-colour image of the per-pixel relative error (mean over RGB of (x − ref)² / (ref² + 0.01)),
/// log10 mapped from 1e-4 (dark blue) to 1 (red), RGB8.
pub fn error_map(x: &[[f32; 3]], reference: &[[f32; 3]]) -> Vec<u8> {
    x.iter()
        .zip(reference)
        .flat_map(|(a, b)| {
            let e = rel_mse(&[*a], &[*b]);
            let t = ((e.max(1e-12).log10() + 4.0) / 4.0).clamp(0.0, 1.0) as f32;
            ramp(t).map(|c| (c * 255.0 + 0.5) as u8)
        })
        .collect()
}

/// Display values as a PNG shows them: radiance × exposure (in f64), clamped to [0, 1], sRGB
/// transfer, not quantised (`export::to_srgb8` is this × 255, rounded).
pub fn display(radiance: &[[f32; 3]], exposure: f32) -> Vec<[f32; 3]> {
    radiance
        .iter()
        .map(|p| {
            p.map(|c| {
                let v = (c as f64 * exposure as f64).min(1.0) as f32;
                crate::export::linear_to_srgb(if c.is_nan() { 0.0 } else { v })
            })
        })
        .collect()
}

/// What a FLIP map compares: `x` against `reference`, both `width` × `height` (row-major) and
/// tone-mapped with `exposure` (`export::to_srgb8`). The input of `flip_map` and of its twin
/// `ldr_flip::flip_map`.
#[derive(Clone, Copy, Debug)]
pub struct FlipInputs<'a> {
    pub x: &'a [[f32; 3]],
    pub reference: &'a [[f32; 3]],
    pub width: u32,
    pub height: u32,
    pub exposure: f32,
}

impl FlipInputs<'_> {
    /// The pixels, `width` × `height`; panics unless both images hold that many.
    pub fn pixels(&self) -> usize {
        let n = self.width as usize * self.height as usize;
        assert_eq!(self.x.len(), n, "x is not {}x{}", self.width, self.height);
        assert_eq!(
            self.reference.len(),
            n,
            "reference is not {}x{}",
            self.width,
            self.height
        );
        n
    }
}

/// The per-pixel FLIP error (Andersson et al. 2020, "FLIP: A difference evaluator for alternating
/// images", NVIDIA's implementation through the `nv-flip` crate) of `p.x` against `p.reference`,
/// both tone-mapped as the PNG and the viewer show them (`export::to_srgb8` with `p.exposure`:
/// × exposure, clamped, sRGB, 8 bits), at FLIP's default 67 pixels per degree. Each value is in
/// [0, 1].
pub fn flip_map(p: FlipInputs) -> Vec<f32> {
    if p.pixels() == 0 {
        return Vec::new();
    }
    let img = |i: &[[f32; 3]]| {
        nv_flip::FlipImageRgb8::with_data(
            p.width,
            p.height,
            &crate::export::to_srgb8(i, p.exposure),
        )
    };
    nv_flip::flip(
        img(p.reference),
        img(p.x),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    )
    .to_vec()
}

/// Mean FLIP error of `x` against `reference` (`flip_map`): 0 for identical images, at most 1.
pub fn flip(x: &[[f32; 3]], reference: &[[f32; 3]], width: u32, height: u32, exposure: f32) -> f64 {
    let p = FlipInputs {
        x,
        reference,
        width,
        height,
        exposure,
    };
    mean(&flip_map(p))
}

fn mean(v: &[f32]) -> f64 {
    v.iter().map(|&e| e as f64).sum::<f64>() / v.len().max(1) as f64
}

/// A FLIP map (`flip_map`) as FLIP draws it: the magma colour map from 0 (black) to 1 (pale
/// yellow), RGB8.
pub fn flip_error_map(map: &[f32], width: u32, height: u32) -> Vec<u8> {
    nv_flip::FlipImageFloat::with_data(width, height, map)
        .apply_color_lut(&nv_flip::magma_lut())
        .to_vec()
}

/// A pixel without an SP cluster (the sky, or no clustering) in a label image.
pub const NO_LABEL: u32 = u32::MAX;

/// The error of the light's steps between neighbouring pixels: the paper's artifact is a step in
/// the indirect light where the nearest SP cluster changes (its Fig. 5), which hard clustering
/// shows and fuzzy clustering blends away, while the mean error barely moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BorderError {
    /// Mean over border pairs (4-neighbours whose nearest SP clusters differ, where the reference
    /// steps by at most `SMOOTH_STEP`) and RGB channels of ((x_p − x_q) − (ref_p − ref_q))², display
    /// values (`display`).
    pub border: f64,
    /// The same over interior pairs (both in one cluster).
    pub interior: f64,
    /// border ÷ interior: how much more the steps are wrong across cluster borders than inside
    /// clusters (1: borders invisible in the gradient). `None` when either count is 0 or interior
    /// is 0.
    pub ratio: Option<f64>,
    /// Mean FLIP over border pixels (a pixel with a 4-neighbour in another cluster), when a FLIP map
    /// was given.
    pub flip_border: Option<f64>,
    pub border_pairs: u64,
    pub interior_pairs: u64,
}

/// The largest step of the reference between two neighbours (in display values, any channel) for
/// the pair to count: the artifact is a step where the reference is smooth; at an edge of geometry
/// or texture the reference steps itself and the clustering's error there is not a border's.
pub const SMOOTH_STEP: f32 = 0.02;

/// `BorderError` of `x` against `reference` (display values, e.g. `display` of each with the same
/// exposure) over a `width` × `height` label image of each pixel's nearest SP cluster (`NO_LABEL`
/// pixels and pairs with one are left out); `flip` is an optional per-pixel FLIP map of the same
/// size. `None` when no pair has two labels.
pub fn border_error(
    x: &[[f32; 3]],
    reference: &[[f32; 3]],
    labels: &[u32],
    width: u32,
    height: u32,
    flip: Option<&[f32]>,
) -> Option<BorderError> {
    let (w, h) = (width as usize, height as usize);
    assert!(x.len() == w * h && reference.len() == w * h && labels.len() == w * h);
    let mut sums = [0.0f64; 2];
    let mut counts = [0u64; 2];
    let mut on_border = vec![false; w * h];
    let mut pair = |p: usize, q: usize| {
        if labels[p] == NO_LABEL || labels[q] == NO_LABEL {
            return;
        }
        if (0..3).any(|c| (reference[p][c] - reference[q][c]).abs() > SMOOTH_STEP) {
            return;
        }
        let b = labels[p] != labels[q];
        if b {
            on_border[p] = true;
            on_border[q] = true;
        }
        let mut s = 0.0;
        for c in 0..3 {
            let d = (x[p][c] as f64 - x[q][c] as f64)
                - (reference[p][c] as f64 - reference[q][c] as f64);
            s += d * d;
        }
        sums[b as usize] += s / 3.0;
        counts[b as usize] += 1;
    };
    for y in 0..h {
        for i in 0..w {
            let p = y * w + i;
            if i + 1 < w {
                pair(p, p + 1);
            }
            if y + 1 < h {
                pair(p, p + w);
            }
        }
    }
    if counts[0] + counts[1] == 0 {
        return None;
    }
    let m = |k: usize| sums[k] / counts[k].max(1) as f64;
    let (interior, border) = (m(0), m(1));
    let flip_border = flip.filter(|_| counts[1] > 0).map(|f| {
        assert_eq!(f.len(), w * h);
        let v: Vec<f32> = (0..w * h).filter(|&p| on_border[p]).map(|p| f[p]).collect();
        mean(&v)
    });
    Some(BorderError {
        border,
        interior,
        ratio: (counts[0] > 0 && counts[1] > 0 && interior > 0.0).then(|| border / interior),
        flip_border,
        border_pairs: counts[1],
        interior_pairs: counts[0],
    })
}

/// A blue → cyan → green → yellow → red ramp (the rel_mse error map's).
pub fn ramp(t: f32) -> [f32; 3] {
    let stops = [
        [0.05, 0.05, 0.35],
        [0.0, 0.6, 0.9],
        [0.1, 0.8, 0.2],
        [0.95, 0.9, 0.1],
        [0.9, 0.1, 0.05],
    ];
    let f = t * (stops.len() - 1) as f32;
    let i = (f as usize).min(stops.len() - 2);
    let w = f - i as f32;
    let (a, b) = (stops[i], stops[i + 1]);
    [0, 1, 2].map(|c| a[c] + (b[c] - a[c]) * w)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand-worked: the previous frame is 2 × 1 pixels showing points (0, 0, 1) and (1, 0, 1),
    /// errors 0.1 and 0.3 (x against a black reference); the view maps a point to pixel
    /// x = p.x + 0.5 at depth p.z. A current pixel at (0.5, 0, 1) lands between the two centres:
    /// the previous error there is 0.2, its own is 0.25, so (0.05)^2 = 0.0025.
    #[test]
    fn instability_world_by_hand() {
        let project = |p: glam::Vec3| Some((p.x + 0.5, 0.5, p.z));
        let (black, up) = ([[0.0; 3]; 2], [[0.0, 0.0, -1.0, 0.0]; 2]);
        let prev_x = [[0.1; 3], [0.3; 3]];
        let mut prev_pos = [[0.0, 0.0, 1.0, 1.0], [1.0, 0.0, 1.0, 1.0]];
        fn frame<'a>(
            x: &'a [[f32; 3]],
            black: &'a [[f32; 3]],
            pos: &'a [[f32; 4]],
            up: &'a [[f32; 4]],
        ) -> PathFrame<'a> {
            PathFrame {
                x,
                reference: black,
                positions: pos,
                normals: up,
                width: 2,
            }
        }
        let cur_pos = [[0.5, 0.0, 1.0, 1.0]];
        let cur = PathFrame {
            x: &[[0.25; 3]],
            reference: &[[0.0; 3]],
            positions: &cur_pos,
            normals: &[[0.0, 0.0, -1.0, 0.0]],
            width: 1,
        };
        let v = instability_world(&cur, &frame(&prev_x, &black, &prev_pos, &up), project).unwrap();
        assert!((v - 0.0025).abs() < 1e-9, "{v}");
        // The second pixel shows another surface (depth 2, not 1): only the first is taken.
        prev_pos[1][2] = 2.0;
        let v = instability_world(&cur, &frame(&prev_x, &black, &prev_pos, &up), project).unwrap();
        assert!((v - 0.15f64.powi(2)).abs() < 1e-9, "{v}");
        // Another normal on both: nothing matches. A pixel that saw the sky is not measured.
        let side = [[1.0, 0.0, 0.0, 0.0]; 2];
        let turned = PathFrame {
            normals: &side,
            ..frame(&prev_x, &black, &prev_pos, &up)
        };
        assert_eq!(instability_world(&cur, &turned, project), None);
        let sky = PathFrame {
            positions: &[[0.5, 0.0, 1.0, 0.0]],
            ..cur
        };
        assert_eq!(
            instability_world(&sky, &frame(&prev_x, &black, &prev_pos, &up), project),
            None
        );
    }

    /// An error that moves with the surface is no flicker: the camera moved one pixel, the errors
    /// stayed on their points. The screen-space `instability` counts it, `instability_world` not.
    #[test]
    fn an_error_moving_with_the_surface_is_not_flicker() {
        let prev_pos = [
            [0.0, 0.0, 1.0, 1.0],
            [1.0, 0.0, 1.0, 1.0],
            [2.0, 0.0, 1.0, 1.0],
        ];
        let cur_pos = [
            [1.0, 0.0, 1.0, 1.0],
            [2.0, 0.0, 1.0, 1.0],
            [3.0, 0.0, 1.0, 1.0],
        ];
        let up = [[0.0, 0.0, -1.0, 0.0]; 3];
        let black = [[0.0; 3]; 3];
        let prev_x = [[0.1; 3], [0.3; 3], [0.6; 3]];
        let cur_x = [[0.3; 3], [0.6; 3], [0.9; 3]];
        let prev = PathFrame {
            x: &prev_x,
            reference: &black,
            positions: &prev_pos,
            normals: &up,
            width: 3,
        };
        let cur = PathFrame {
            x: &cur_x,
            reference: &black,
            positions: &cur_pos,
            normals: &up,
            width: 3,
        };
        let project = |p: glam::Vec3| Some((p.x + 0.5, 0.5, p.z));
        assert_eq!(instability_world(&cur, &prev, project), Some(0.0));
        assert!(instability(&cur_x, &black, &prev_x, &black) > 0.05);
    }

    #[test]
    fn instability_is_the_change_of_the_clamped_error() {
        // Two pixels, worked by hand. Pixel 0: error (0.5 - 0.25) = 0.25 now, (0.25 - 0.25) = 0 before:
        // 0.0625 in each channel. Pixel 1: x = 3 clamps to 1, ref 0.5: error 0.5 now and before: 0.
        let x = [[0.5; 3], [3.0; 3]];
        let r = [[0.25; 3], [0.5; 3]];
        let xp = [[0.25; 3], [1.0; 3]];
        let rp = [[0.25; 3], [0.5; 3]];
        assert_eq!(instability(&x, &r, &xp, &rp), 0.0625 / 2.0);
        // The same error pattern in both frames is stable whatever the images.
        assert_eq!(instability(&x, &r, &x, &r), 0.0);
        // Only the change of the error counts: both images brighter by the same amount is 0.
        let x2 = [[0.75; 3], [1.0; 3]];
        let r2 = [[0.5; 3], [0.5; 3]];
        assert_eq!(
            instability(&x2, &r2, &[[0.5; 3], [1.0; 3]], &[[0.25; 3], [0.5; 3]]),
            0.0
        );
    }

    #[test]
    fn mse_clamps_and_rel_mse_does_not() {
        let a = [[2.0, 0.5, 0.0]];
        let b = [[1.0, 0.0, 0.0]];
        assert!((mse(&a, &b) - 0.25 / 3.0).abs() < 1e-12);
        let r = (1.0 / 1.01 + 0.25 / 0.01) / 3.0;
        assert!((rel_mse(&a, &b) - r).abs() < 1e-9);
        assert_eq!(mse(&b, &b), 0.0);
    }

    /// FLIP of an image against itself is 0; against a different one it is positive, at most 1, and
    /// grows with the difference; every value of the map is finite.
    #[test]
    fn flip_is_zero_for_identical_images_and_grows_with_the_difference() {
        let (w, h) = (32u32, 24u32);
        let img: Vec<[f32; 3]> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32 / w as f32, (i / w) as f32 / h as f32);
                [x, y, 0.5 * (x + y)]
            })
            .collect();
        let map = flip_map(FlipInputs {
            x: &img,
            reference: &img,
            width: w,
            height: h,
            exposure: 1.0,
        });
        assert!(map.iter().all(|e| e.is_finite()));
        assert_eq!(flip(&img, &img, w, h, 1.0), 0.0);
        let off = |k: f32| -> Vec<[f32; 3]> { img.iter().map(|p| p.map(|c| c * k)).collect() };
        let small = flip(&off(0.9), &img, w, h, 1.0);
        let large = flip(&off(0.5), &img, w, h, 1.0);
        assert!(
            small > 0.0 && small < large && large <= 1.0,
            "{small} {large}"
        );
        // Black against white is FLIP's largest error.
        let black = vec![[0.0f32; 3]; (w * h) as usize];
        let white = vec![[1.0f32; 3]; (w * h) as usize];
        let e = flip(&black, &white, w, h, 1.0);
        assert!(e > 0.5 && e <= 1.0, "{e}");
        assert_eq!(flip_error_map(&map, w, h).len(), (w * h * 3) as usize);
        // The exposure is applied before the comparison: radiance halved and exposure doubled is
        // the same picture.
        let half = off(0.5);
        assert_eq!(
            flip(&half, &img, w, h, 1.0),
            flip(&off(0.25), &half, w, h, 2.0)
        );
    }

    /// Hand-worked: a 4×2 image in two clusters (columns 0–1 and 2–3). The reference is flat 0.5;
    /// the test has 0.5 in the left cluster and 0.6 in the right one: a step of 0.1 across the
    /// border and none inside. Pairs: 3 horizontal a row (1 across the border) and 4 vertical, so 2
    /// border pairs with error 0.01 and 8 interior pairs with 0.
    #[test]
    fn border_error_of_a_known_step() {
        let (w, h) = (4u32, 2u32);
        let labels = [0, 0, 1, 1, 0, 0, 1, 1];
        let reference = vec![[0.5f32; 3]; 8];
        let x: Vec<[f32; 3]> = (0..8)
            .map(|i| if i % 4 < 2 { [0.5; 3] } else { [0.6; 3] })
            .collect();
        let b = border_error(&x, &reference, &labels, w, h, None).unwrap();
        assert_eq!((b.border_pairs, b.interior_pairs), (2, 8));
        assert!((b.border - 0.01).abs() < 1e-7, "{}", b.border);
        assert_eq!(b.interior, 0.0);
        assert_eq!(b.ratio, None);
        // Add a step of 0.05 inside the left cluster (pixel 0 at 0.55): interior pairs (0,1) and
        // (0,4) get 0.0025 each, 0.005 / 8 in all; the ratio is 0.01 / 0.000625 = 16.
        let mut x2 = x.clone();
        x2[0] = [0.55; 3];
        let flip_map = [0.0, 0.2, 0.4, 0.0, 0.0, 0.2, 0.4, 0.0];
        let b = border_error(&x2, &reference, &labels, w, h, Some(&flip_map)).unwrap();
        assert!((b.interior - 0.000625).abs() < 1e-8, "{}", b.interior);
        assert!((b.ratio.unwrap() - 16.0).abs() < 1e-3, "{:?}", b.ratio);
        // Border pixels are columns 1 and 2: FLIP 0.2, 0.4, 0.2, 0.4.
        assert!((b.flip_border.unwrap() - 0.3).abs() < 1e-7);
        // The same step in the reference is no error at all.
        let b = border_error(&x, &x, &labels, w, h, None).unwrap();
        assert_eq!((b.border, b.interior), (0.0, 0.0));
        // Where the reference itself steps (an edge), the pair takes no part: a step of 0.4 between
        // the clusters in the reference leaves only the 8 interior pairs.
        let edge: Vec<[f32; 3]> = (0..8)
            .map(|i| if i % 4 < 2 { [0.5; 3] } else { [0.9; 3] })
            .collect();
        let b = border_error(&x, &edge, &labels, w, h, None).unwrap();
        assert_eq!((b.border_pairs, b.interior_pairs), (0, 8));
        // Unlabelled pixels take no part; an image without a labelled pair has no measure.
        let none = [NO_LABEL; 8];
        assert_eq!(border_error(&x, &reference, &none, w, h, None), None);
        let mut some = labels;
        some[1] = NO_LABEL;
        some[5] = NO_LABEL;
        let b = border_error(&x, &reference, &some, w, h, None).unwrap();
        assert_eq!((b.border_pairs, b.interior_pairs), (0, 5));
        assert_eq!(b.ratio, None);
    }

    #[test]
    fn display_matches_the_png() {
        let img = [[0.0, 0.5, 2.0], [0.001, 0.2, f32::NAN]];
        let d = display(&img, 1.5);
        let png = crate::export::to_srgb8(&img, 1.5);
        for (i, v) in d.iter().flatten().enumerate() {
            assert!(v.is_finite());
            assert_eq!((v * 255.0 + 0.5) as u8, png[i]);
        }
    }
}
