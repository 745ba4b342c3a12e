//! What the image area shows, composed on the UI thread from the worker's last frame as sRGB8 RGBA:
//! the final image (direct + indirect, or indirect alone with direct off), its direct or indirect
//! part, SP clusters (a colour per cluster, like the paper's Fig. 4), VPLs and VPL clusters projected
//! as dots, the reference, and the false-colour error against it.

use glam::Vec3;

use crate::export::linear_to_srgb;
use crate::gi::primary::CameraParams;
use crate::metrics;
use crate::scene::Camera;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum View {
    Final,
    Direct,
    Indirect,
    SpClusters,
    VplPoints,
    Reference,
    Error,
    /// The per-pixel FLIP error of the tone-mapped frame against the reference.
    Flip,
    /// A/B: the current settings left of a draggable divider, the pinned B settings right of it,
    /// same camera.
    Split,
    /// A against B: the per-pixel relative difference (as the error view, B as the reference).
    Diff,
}

impl View {
    pub const ALL: [View; 10] = [
        View::Final,
        View::Direct,
        View::Indirect,
        View::SpClusters,
        View::VplPoints,
        View::Reference,
        View::Error,
        View::Flip,
        View::Split,
        View::Diff,
    ];
    pub fn name(self) -> &'static str {
        match self {
            View::Final => "final",
            View::Direct => "direct",
            View::Indirect => "indirect",
            View::SpClusters => "SP clusters",
            View::VplPoints => "VPL clusters",
            View::Reference => "reference",
            View::Error => "error",
            View::Flip => "FLIP",
            View::Split => "A|B split",
            View::Diff => "A−B",
        }
    }
    /// Views that need the reference image.
    pub fn needs_reference(self) -> bool {
        matches!(self, View::Reference | View::Error | View::Flip)
    }
    /// A file-name-friendly name.
    pub fn slug(self) -> &'static str {
        match self {
            View::SpClusters => "spclusters",
            View::VplPoints => "vpls",
            View::Flip => "flip",
            View::Split => "split",
            View::Diff => "diff",
            v => v.name(),
        }
    }
}

/// The displayed radiance: direct + indirect, or indirect alone (direct off).
pub fn final_image(direct: &[[f32; 3]], indirect: &[[f32; 3]], with_direct: bool) -> Vec<[f32; 3]> {
    if with_direct {
        direct
            .iter()
            .zip(indirect)
            .map(|(a, b)| [a[0] + b[0], a[1] + b[1], a[2] + b[2]])
            .collect()
    } else {
        indirect.to_vec()
    }
}

/// Exposure, clamp, sRGB, opaque RGBA8.
pub fn tonemap(img: &[[f32; 3]], exposure: f32) -> Vec<u8> {
    let mut lut_in = Vec::with_capacity(img.len() * 4);
    for p in img {
        for c in p {
            lut_in.push((linear_to_srgb(c * exposure) * 255.0 + 0.5) as u8);
        }
        lut_in.push(255);
    }
    lut_in
}

/// A well-spread colour for cluster `i` (golden-ratio hue steps).
pub fn cluster_colour(i: u32) -> [u8; 3] {
    let h = (i as f32 * 0.618_034).fract();
    let s = 0.55 + 0.4 * ((i.wrapping_mul(2_654_435_761) >> 28) as f32 / 15.0);
    let v = 0.65 + 0.35 * ((i.wrapping_mul(40_503) >> 12 & 7) as f32 / 7.0);
    hsv(h, s, v).map(|c| (c * 255.0 + 0.5) as u8)
}

fn hsv(h: f32, s: f32, v: f32) -> [f32; 3] {
    let h6 = h * 6.0;
    let f = h6.fract();
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    match h6 as u32 % 6 {
        0 => [v, t, p],
        1 => [q, v, p],
        2 => [p, v, t],
        3 => [p, q, v],
        4 => [t, p, v],
        _ => [v, p, q],
    }
}

/// SP clusters: each pixel in its nearest cluster's colour, shaded a little by the final image.
pub fn sp_clusters(ids: &[u32], shade: &[[f32; 3]], exposure: f32) -> Vec<u8> {
    let mut out = Vec::with_capacity(ids.len() * 4);
    for (id, p) in ids.iter().zip(shade) {
        let c = if *id == u32::MAX {
            [0, 0, 0]
        } else {
            let l = (metrics::luminance(*p) * exposure).clamp(0.0, 1.0);
            cluster_colour(*id).map(|c| (c as f32 * (0.6 + 0.4 * l.sqrt())) as u8)
        };
        out.extend_from_slice(&[c[0], c[1], c[2], 255]);
    }
    out
}

/// Projects a world point to pixel coordinates (None behind the camera or outside the image).
pub fn project(cam: &CameraParams, p: Vec3) -> Option<(f32, f32)> {
    let (x, y, _) = cam.project(p - cam.eye_point(), 1e-6)?;
    let (w, h) = (cam.size[0] as f32, cam.size[1] as f32);
    (x >= 0.0 && y >= 0.0 && x < w && y < h).then_some((x, y))
}

/// VPLs as small grey dots and the light list (VPL-cluster representatives) as larger coloured dots,
/// over the darkened final image.
pub fn vpl_points(
    base: &[u8],
    camera: &Camera,
    width: u32,
    height: u32,
    vpls: &[Vec3],
    lights: &[Vec3],
    clustered: bool,
) -> Vec<u8> {
    let mut out: Vec<u8> = base
        .chunks(4)
        .flat_map(|p| [p[0] / 3, p[1] / 3, p[2] / 3, 255])
        .collect();
    let cam = CameraParams::new(camera, width, height);
    let mut dot = |x: f32, y: f32, r: i32, c: [u8; 3]| {
        for dy in -r..=r {
            for dx in -r..=r {
                if dx * dx + dy * dy > r * r {
                    continue;
                }
                let (px, py) = (x as i32 + dx, y as i32 + dy);
                if px >= 0 && py >= 0 && (px as u32) < width && (py as u32) < height {
                    let i = (py as u32 * width + px as u32) as usize * 4;
                    out[i..i + 3].copy_from_slice(&c);
                }
            }
        }
    };
    for p in vpls {
        if let Some((x, y)) = project(&cam, *p) {
            dot(x, y, 0, [200, 200, 200]);
        }
    }
    if clustered {
        for (i, p) in lights.iter().enumerate() {
            if let Some((x, y)) = project(&cam, *p) {
                dot(x, y, 2, cluster_colour(i as u32));
            }
        }
    }
    out
}

/// False-colour relative error (`metrics::error_map`), RGBA8.
pub fn error(img: &[[f32; 3]], reference: &[[f32; 3]]) -> Vec<u8> {
    metrics::error_map(img, reference)
        .chunks(3)
        .flat_map(|c| [c[0], c[1], c[2], 255])
        .collect()
}

/// The FLIP map of `img` against `reference` (both shown with `exposure`), magma, opaque RGBA8.
pub fn flip(img: &[[f32; 3]], reference: &[[f32; 3]], w: u32, h: u32, exposure: f32) -> Vec<u8> {
    let map = metrics::flip_map(metrics::FlipInputs {
        x: img,
        reference,
        width: w,
        height: h,
        exposure,
    });
    metrics::flip_error_map(&map, w, h)
        .chunks(3)
        .flat_map(|c| [c[0], c[1], c[2], 255])
        .collect()
}

/// The colour scale of an error view: `n` colours from its low end to its high end, and the labels
/// of its ends and middle.
pub fn colour_bar(view: View, n: usize) -> Option<(Vec<[u8; 3]>, [&'static str; 3])> {
    let ramp: Vec<[u8; 3]> = match view {
        View::Error | View::Diff => (0..n)
            .map(|i| {
                metrics::ramp(i as f32 / (n - 1).max(1) as f32).map(|c| (c * 255.0 + 0.5) as u8)
            })
            .collect(),
        View::Flip => {
            let map: Vec<f32> = (0..n).map(|i| i as f32 / (n - 1).max(1) as f32).collect();
            metrics::flip_error_map(&map, n as u32, 1)
                .chunks(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect()
        }
        _ => return None,
    };
    let labels = match view {
        View::Error => ["rel. error 1e-4", "1e-2", "1"],
        View::Diff => ["rel. A−B 1e-4", "1e-2", "1"],
        _ => ["FLIP 0", "0.5", "1"],
    };
    Some((ramp, labels))
}

/// The split view: `a`'s columns left of `split` (a fraction of the width), `b`'s from there on,
/// both RGBA8 of `w` × `h`.
pub fn split(a: &[u8], b: &[u8], w: u32, h: u32, split: f32) -> Vec<u8> {
    let cut = ((split.clamp(0.0, 1.0) * w as f32).round() as usize).min(w as usize);
    let mut out = a.to_vec();
    for y in 0..h as usize {
        let row = y * w as usize * 4;
        out[row + cut * 4..row + w as usize * 4]
            .copy_from_slice(&b[row + cut * 4..row + w as usize * 4]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_takes_a_left_and_b_right() {
        let a = vec![1u8; 4 * 4 * 2];
        let b = vec![2u8; 4 * 4 * 2];
        let s = split(&a, &b, 4, 2, 0.5);
        for y in 0..2 {
            for x in 0..4 {
                assert_eq!(s[(y * 4 + x) * 4], if x < 2 { 1 } else { 2 });
            }
        }
        assert_eq!(split(&a, &b, 4, 2, 0.0), b);
        assert_eq!(split(&a, &b, 4, 2, 1.0), a);
        // The diff view has the error view's colour bar; final has none.
        assert!(colour_bar(View::Diff, 8).is_some() && colour_bar(View::Final, 8).is_none());
    }

    #[test]
    fn projection_hits_the_image_centre() {
        let cam = Camera::look_at("t", Vec3::ZERO, -Vec3::Z, Vec3::Y, 1.0);
        let p = CameraParams::new(&cam, 64, 32);
        let (x, y) = project(&p, Vec3::new(0.0, 0.0, -3.0)).unwrap();
        assert!((x - 32.0).abs() < 1e-3 && (y - 16.0).abs() < 1e-3);
        assert!(project(&p, Vec3::new(0.0, 0.0, 3.0)).is_none());
        let (x, y) = project(&p, Vec3::new(0.1, 0.1, -3.0)).unwrap();
        assert!(x > 32.0 && y < 16.0);
    }

    #[test]
    fn cluster_colours_differ() {
        let c: std::collections::HashSet<_> = (0..64).map(cluster_colour).collect();
        assert!(c.len() > 60);
    }
}
