//! The CPU twin of the GPU reprojection (`app::reproject_gpu`, `shaders-wgsl/reproject.wgsl`): the
//! same splats, depth keys, least-index ties and hole fill, in the same f32 operations.

use glam::Vec3;

use crate::gi::primary::CameraParams;

const NONE: u32 = u32::MAX;
const SKY_DEPTH: u32 = 0x7f7f_ffff;

fn axis(v: [f32; 4]) -> Vec3 {
    Vec3::new(v[0], v[1], v[2])
}

/// The offset `d` from camera `c`'s eye on its `(w, h)` image: the continuous pixel coordinates
/// and the view depth; `None` behind (or almost at) the eye. Used by this twin and a method module's twin that reprojects
/// (`Stages::prev_pixel`).
pub fn project_new(c: &CameraParams, d: Vec3, (w, h): (u32, u32)) -> Option<(f32, f32, f32)> {
    let z = d.dot(axis(c.forward));
    if z.is_nan() || z <= 1e-6 * d.length() {
        return None;
    }
    let (r, u) = (axis(c.right), axis(c.up));
    let sx = d.dot(r) / (z * r.dot(r));
    let sy = d.dot(u) / (z * u.dot(u));
    Some(((sx + 1.0) * 0.5 * w as f32, (1.0 - sy) * 0.5 * h as f32, z))
}

/// Old pixel `i`'s splat: centre, depth key, footprint half width.
fn splat_of(
    old: &CameraParams,
    new: &CameraParams,
    gbuffer: &[[f32; 4]],
    i: usize,
) -> Option<((f32, f32), u32, i32)> {
    let (w, h) = (old.size[0], old.size[1]);
    let pos = gbuffer[4 * i];
    if pos[3] > 0.0 {
        let p = Vec3::new(pos[0], pos[1], pos[2]);
        let (x, y, z) = project_new(new, p - axis(new.eye), (w, h))?;
        let old_z = (p - axis(old.eye)).dot(axis(old.forward));
        let grow = (old_z / z).clamp(1.0, 3.0);
        let key = z.to_bits().min(SKY_DEPTH - 1);
        Some(((x, y), key, (grow * 0.5 - 0.5).ceil() as i32))
    } else {
        let (px, py) = ((i as u32 % w) as f32 + 0.5, (i as u32 / w) as f32 + 0.5);
        let sx = 2.0 * px / w as f32 - 1.0;
        let sy = 1.0 - 2.0 * py / h as f32;
        let d = axis(old.forward) + sx * axis(old.right) + sy * axis(old.up);
        let (x, y, _) = project_new(new, d, (w, h))?;
        Some(((x, y), SKY_DEPTH, 0))
    }
}

/// `rgba` (the old frame as displayed, RGBA8, `old`'s size) with its G-buffer (4 vec4s a pixel,
/// render units) shown from `new`: RGBA8 of the same size.
pub fn reproject(
    rgba: &[u8],
    gbuffer: &[[f32; 4]],
    old: &CameraParams,
    new: &CameraParams,
) -> Vec<u8> {
    let (w, h) = (old.size[0] as i32, old.size[1] as i32);
    let n = (w * h) as usize;
    let mut depth = vec![NONE; n];
    let mut source = vec![NONE; n];
    let targets = |((cx, cy), _, half): ((f32, f32), u32, i32)| {
        let (x0, y0) = (cx.floor() as i32, cy.floor() as i32);
        (-half..=half).flat_map(move |dy| {
            (-half..=half).filter_map(move |dx| {
                let (x, y) = (x0 + dx, y0 + dy);
                (x >= 0 && y >= 0 && x < w && y < h).then_some((y * w + x) as usize)
            })
        })
    };
    let splats: Vec<_> = (0..n).map(|i| splat_of(old, new, gbuffer, i)).collect();
    for s in splats.iter().flatten() {
        for t in targets(*s) {
            depth[t] = depth[t].min(s.1);
        }
    }
    for (i, s) in splats.iter().enumerate() {
        if let Some(s) = s {
            for t in targets(*s) {
                if depth[t] == s.1 {
                    source[t] = source[t].min(i as u32);
                }
            }
        }
    }
    let mut out = vec![0u8; 4 * n];
    for t in 0..n {
        let (x, y) = (t as i32 % w, t as i32 / w);
        let c: [u8; 3] = if source[t] != NONE {
            let s = source[t] as usize * 4;
            [rgba[s], rgba[s + 1], rgba[s + 2]]
        } else {
            let (mut sum, mut k) = ([0f32; 3], 0f32);
            for dy in -3..=3 {
                for dx in -3..=3 {
                    let (qx, qy) = (x + dx, y + dy);
                    if qx >= 0 && qy >= 0 && qx < w && qy < h {
                        let q = source[(qy * w + qx) as usize];
                        if q != NONE {
                            for c in 0..3 {
                                sum[c] += rgba[q as usize * 4 + c] as f32;
                            }
                            k += 1.0;
                        }
                    }
                }
            }
            if k > 0.0 {
                sum.map(|s| (s / k + 0.5).floor() as u8)
            } else {
                [0, 0, 0]
            }
        };
        out[4 * t..4 * t + 4].copy_from_slice(&[c[0], c[1], c[2], 255]);
    }
    out
}
