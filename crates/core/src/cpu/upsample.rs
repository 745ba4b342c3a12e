//! CPU twin of `shaders-wgsl/upsample.wgsl` (`gi::upsample`): the render-scale G-buffer taken from the
//! image's, and the joint bilateral upsampling of the indirect light. G-buffers are 4 × vec4 a pixel
//! (`common/gbuffer.wgsl`: position with w = 1 where a surface is seen, normal, albedo, emission).

use glam::Vec3;

/// The kernel's uniform: image and low-res sizes, the eye and a low-res pixel's angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geometry {
    pub image: (u32, u32),
    pub low: (u32, u32),
    pub eye: Vec3,
    /// The angle one low-res pixel spans (2 tan(fov / 2) / low-res height).
    pub pixel_angle: f32,
}

/// Below this weight sum the fallback (the 3×3 tap nearest in depth) takes over.
pub const MIN_WEIGHT: f32 = 1e-4;
/// The normal term's exponent.
pub const NORMAL_POWER: f32 = 8.0;

impl Geometry {
    /// The twin's view of the numbers the kernels read.
    pub fn of(p: &crate::gi::upsample::UpsampleParams) -> Geometry {
        Geometry {
            image: (p.size[0], p.size[1]),
            low: (p.size[2], p.size[3]),
            eye: Vec3::from_slice(&p.eye[..3]),
            pixel_angle: p.eye[3],
        }
    }
}

/// The image pixel low-res pixel `i` takes its shading point from: the one holding its centre.
pub fn representative(g: &Geometry, i: u32) -> u32 {
    let (w, h) = g.image;
    let (lw, lh) = g.low;
    let (lx, ly) = (i % lw, i / lw);
    let fx = (((lx as f32 + 0.5) * w as f32 / lw as f32).floor() as u32).min(w - 1);
    let fy = (((ly as f32 + 0.5) * h as f32 / lh as f32).floor() as u32).min(h - 1);
    fy * w + fx
}

/// The render-scale G-buffer: each low-res pixel's representative shading point.
pub fn downsample(g: &Geometry, image_gbuffer: &[[f32; 4]]) -> Vec<[f32; 4]> {
    (0..g.low.0 * g.low.1)
        .flat_map(|i| {
            let r = representative(g, i) as usize * 4;
            image_gbuffer[r..r + 4].to_vec()
        })
        .collect()
}

fn xyz(v: [f32; 4]) -> Vec3 {
    Vec3::new(v[0], v[1], v[2])
}

/// Low-res tap `q`'s geometric weight for an image point `p` with normal `n` whose low-res pixel
/// spans `footprint`: exp(-(plane distance / footprint)²) × max(0, n·n_q)^8; 0 where it sees nothing.
fn geometry_weight(low: &[[f32; 4]], p: Vec3, n: Vec3, footprint: f32, q: usize) -> f32 {
    let (pos, nrm) = (low[q * 4], low[q * 4 + 1]);
    if pos[3] == 0.0 {
        return 0.0;
    }
    let plane = n.dot(xyz(pos) - p).abs() / footprint;
    (-plane * plane).exp() * n.dot(xyz(nrm)).max(0.0).powf(NORMAL_POWER)
}

/// The indirect light of every image pixel from the low-res one (`low_indirect`, vec4 a pixel).
pub fn upsample(
    g: &Geometry,
    image_gbuffer: &[[f32; 4]],
    low_gbuffer: &[[f32; 4]],
    low_indirect: &[[f32; 4]],
) -> Vec<[f32; 4]> {
    let (w, h) = g.image;
    let (lw, lh) = (g.low.0 as i32, g.low.1 as i32);
    (0..w * h)
        .map(|i| {
            let sp = image_gbuffer[i as usize * 4];
            if sp[3] == 0.0 {
                return [0.0; 4];
            }
            let (p, n) = (xyz(sp), xyz(image_gbuffer[i as usize * 4 + 1]));
            let depth = (p - g.eye).length();
            let footprint = (depth * g.pixel_angle).max(1e-30);
            let u = ((i % w) as f32 + 0.5) * lw as f32 / w as f32 - 0.5;
            let v = ((i / w) as f32 + 0.5) * lh as f32 / h as f32 - 0.5;
            let (x0, y0) = (u.floor() as i32, v.floor() as i32);
            let (fx, fy) = (u - x0 as f32, v - y0 as f32);
            let (mut sum, mut wsum) = (Vec3::ZERO, 0.0f32);
            for t in 0..4 {
                let (dx, dy) = (t & 1, t >> 1);
                let qx = (x0 + dx).clamp(0, lw - 1);
                let qy = (y0 + dy).clamp(0, lh - 1);
                let q = (qy * lw + qx) as usize;
                let bx = if dx == 1 { fx } else { 1.0 - fx };
                let by = if dy == 1 { fy } else { 1.0 - fy };
                let wt = bx * by * geometry_weight(low_gbuffer, p, n, footprint, q);
                sum += wt * xyz(low_indirect[q]);
                wsum += wt;
            }
            if wsum > MIN_WEIGHT {
                return (sum / wsum).extend(0.0).into();
            }
            let cx = ((u + 0.5).floor() as i32).clamp(0, lw - 1);
            let cy = ((v + 0.5).floor() as i32).clamp(0, lh - 1);
            let mut best: Option<(usize, f32)> = None;
            for t in 0..9 {
                let qx = (cx + t % 3 - 1).clamp(0, lw - 1);
                let qy = (cy + t / 3 - 1).clamp(0, lh - 1);
                let q = (qy * lw + qx) as usize;
                let pos = low_gbuffer[q * 4];
                let gap = ((xyz(pos) - g.eye).length() - depth).abs();
                if pos[3] != 0.0 && best.is_none_or(|(_, b)| gap < b) {
                    best = Some((q, gap));
                }
            }
            best.map_or([0.0; 4], |(q, _)| xyz(low_indirect[q]).extend(0.0).into())
        })
        .collect()
}
