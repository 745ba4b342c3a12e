//! Error metrics of docs/design.md, "Error metrics".

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

/// A blue → cyan → green → yellow → red ramp.
fn ramp(t: f32) -> [f32; 3] {
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
}
