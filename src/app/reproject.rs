//! The last finished GI frame shown from the current camera while the next one renders (the Render
//! Cache of Walter et al. 1999, reduced to one frame), in two steps:
//! 1. Depth: every pixel of the frame is splatted forward to where its shading point lands in the new
//!    view, nearest first (a depth test), over a footprint as large as the pixel's projected size;
//!    pixels that saw nothing are carried as directions. This gives each new pixel the surface it
//!    sees (its depth along the new view) or the sky.
//! 2. Colour, gathered backward: each new pixel's surface point is projected into the old frame and
//!    its colour read bilinearly from the four old pixels around it that show the same surface
//!    (within `SAME_DEPTH` of the point's depth off its tangent plane, normal within `SAME_COS`;
//!    weights renormalised over them), so a magnified image is interpolated, not a mosaic of square
//!    splats. The new pixel's point is where its ray meets the splatted point's tangent plane. Where
//!    no tap passes, the splatted colour stays.
//!
//! The holes that remain (newly seen surfaces) are filled from their neighbours by push-pull.

use glam::{Vec3, Vec4};

use crate::gi::primary::CameraParams;

/// A gathered tap shows the same surface when it lies within this fraction of the new point's depth
/// (along the old view) off the point's tangent plane (or, without normals, of its depth)...
const SAME_DEPTH: f32 = 0.03;
/// ... and its normal within this cosine (about 25°) of the splatted pixel's.
const SAME_COS: f32 = 0.9;

/// An image with its shading points, thinned to one pixel a `step` × `step` block (all of them at
/// step 1): what a frame larger than the previews is reprojected from while the camera moves. A
/// block keeps its pixel of least depth (a thin foreground part, a chair's leg one pixel wide, stays
/// whole rather than kept or dropped by where it falls), with the mean colour of the block's pixels
/// that show the same surface as it (an anti-aliased edge, not one sample of it; the test is the
/// gather's: on its tangent plane within `SAME_DEPTH` of its depth and normal within `SAME_COS`, or
/// without normals at its depth).
pub struct Thinned {
    pub step: usize,
    pub size: (u32, u32),
    pub rgba: Vec<u8>,
    pub positions: Vec<[f32; 4]>,
    pub normals: Vec<[f32; 4]>,
}

impl Thinned {
    /// `rgba`, `positions` and `normals` (may be empty) of a `w` × `h` frame seen from `cam` (its
    /// eye and view direction).
    pub fn new(
        rgba: &[u8],
        positions: &[[f32; 4]],
        normals: &[[f32; 4]],
        (w, h): (u32, u32),
        step: usize,
        cam: &CameraParams,
    ) -> Thinned {
        let step = step.max(1);
        let (tw, th) = (w as usize / step, h as usize / step);
        if step == 1 || tw == 0 || th == 0 {
            return Thinned {
                step: 1,
                size: (w, h),
                rgba: rgba.to_vec(),
                positions: positions.to_vec(),
                normals: normals.to_vec(),
            };
        }
        let w = w as usize;
        let (eye, fwd) = (cam.eye_point(), xyz(cam.forward));
        let depth = |i: usize| {
            if sky(positions[i]) {
                f32::INFINITY
            } else {
                (xyz(positions[i]) - eye).dot(fwd)
            }
        };
        let mut out = Thinned {
            step,
            size: (tw as u32, th as u32),
            rgba: Vec::with_capacity(tw * th * 4),
            positions: Vec::with_capacity(tw * th),
            normals: Vec::with_capacity(if normals.is_empty() { 0 } else { tw * th }),
        };
        for k in 0..tw * th {
            let (x0, y0) = (k % tw * step, k / tw * step);
            let block =
                || (y0..y0 + step).flat_map(move |y| (x0..x0 + step).map(move |x| y * w + x));
            let near = block()
                .min_by(|&a, &b| depth(a).total_cmp(&depth(b)))
                .expect("a block has pixels");
            let d = depth(near);
            let same = |i: usize| {
                if !d.is_finite() || sky(positions[i]) {
                    return !d.is_finite() && sky(positions[i]);
                }
                match normals.get(near).map(|&n| xyz(n)) {
                    Some(n) => {
                        n.dot(xyz(positions[i]) - xyz(positions[near])).abs() <= SAME_DEPTH * d
                            && n.dot(xyz(normals[i])) >= SAME_COS
                    }
                    None => (depth(i) - d).abs() <= SAME_DEPTH * d,
                }
            };
            let (mut sum, mut n) = ([0u32; 4], 0u32);
            // The kept pixel counts whatever its own normal (one without a usable normal or
            // point fails the test against itself).
            for i in block().filter(|&i| i == near || same(i)) {
                for c in 0..4 {
                    sum[c] += rgba[i * 4 + c] as u32;
                }
                n += 1;
            }
            out.rgba.extend(sum.map(|c| ((c + n / 2) / n) as u8));
            out.positions.push(positions[near]);
            if !normals.is_empty() {
                out.normals.push(normals[near]);
            }
        }
        out
    }
}

/// A pixel that saw no surface (its point's w is 0, or NaN).
fn sky(p: [f32; 4]) -> bool {
    p[3].is_nan() || p[3] <= 0.0
}

fn xyz(p: [f32; 4]) -> Vec3 {
    Vec3::new(p[0], p[1], p[2])
}

/// `rgba` (sRGB8, `from`'s size) as seen from `to` (the same size): each pixel with a shading point
/// at `positions[i]` (w > 0, normal `normals[i]`; `normals` may be empty: no normal test) moves with
/// it; the others (sky) move as directions behind everything.
pub fn reproject(
    rgba: &[u8],
    positions: &[[f32; 4]],
    normals: &[[f32; 4]],
    from: &CameraParams,
    to: &CameraParams,
) -> Vec<u8> {
    let (w, h) = (from.size[0] as usize, from.size[1] as usize);
    assert_eq!(rgba.len(), w * h * 4);
    assert_eq!(positions.len(), w * h);
    assert_eq!((to.size[0] as usize, to.size[1] as usize), (w, h));
    // Nearer than this fraction of a direction's length counts as behind the eye.
    const NEAR: f32 = 1e-12;
    let (from_eye, to_eye) = (from.eye_point(), to.eye_point());
    let mut depth = vec![f32::INFINITY; w * h];
    let mut out = vec![0u8; w * h * 4];
    let mut filled = vec![false; w * h];
    // The old pixel whose splat each new pixel shows (its normal for the gather's test).
    let mut source = vec![usize::MAX; w * h];
    // Where each pixel lands: (target x, y, depth, footprint in target pixels); None off screen.
    let landed: Vec<Option<(f32, f32, f32, i64)>> = positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            if sky(*p) {
                // Sky: a direction, behind everything.
                let (tx, ty, _) = to.project(from.ray(x, y), NEAR)?;
                return Some((tx, ty, f32::INFINITY, 1));
            }
            let q = Vec4::from(*p).truncate();
            let (tx, ty, z) = to.project(q - to_eye, NEAR)?;
            // The pixel's size here: where its neighbour's point at the same distance lands.
            let dist = (q - from_eye).length();
            let step = from.ray(x + 1.0, y).normalize() - from.ray(x, y).normalize();
            let size = to
                .project(q + step * dist - to_eye, NEAR)
                .map_or(1.0, |n| (n.0 - tx).abs());
            Some((tx, ty, z, ((size - 0.25).ceil() as i64).clamp(1, 3)))
        })
        .collect();
    let inside = |x: i64, y: i64| x >= 0 && y >= 0 && x < w as i64 && y < h as i64;
    // The pixel each lands in, nearest first; then, magnified, the rest of its footprint where no
    // pixel landed.
    for (i, l) in landed.iter().enumerate() {
        let Some((tx, ty, z, _)) = *l else { continue };
        let (xx, yy) = (tx.floor() as i64, ty.floor() as i64);
        if !inside(xx, yy) {
            continue;
        }
        let j = yy as usize * w + xx as usize;
        if !filled[j] || z < depth[j] {
            depth[j] = z;
            filled[j] = true;
            source[j] = i;
            out[j * 4..j * 4 + 4].copy_from_slice(&rgba[i * 4..i * 4 + 4]);
        }
    }
    let landed_in = filled.clone();
    for (i, l) in landed.iter().enumerate() {
        let Some((tx, ty, z, size)) = *l else {
            continue;
        };
        if size == 1 {
            continue;
        }
        let x0 = (tx - 0.5 * (size - 1) as f32).floor() as i64;
        let y0 = (ty - 0.5 * (size - 1) as f32).floor() as i64;
        for yy in y0..y0 + size {
            for xx in x0..x0 + size {
                if !inside(xx, yy) {
                    continue;
                }
                let j = yy as usize * w + xx as usize;
                if !landed_in[j] && (!filled[j] || z < depth[j]) {
                    depth[j] = z;
                    filled[j] = true;
                    source[j] = i;
                    out[j * 4..j * 4 + 4].copy_from_slice(&rgba[i * 4..i * 4 + 4]);
                }
            }
        }
    }
    let old = Old {
        rgba,
        positions,
        normals,
        cam: from,
    };
    gather(&old, to, (&depth, &source), &mut out);
    fill_holes(&mut out, &filled, w, h);
    out
}

/// The frame being reprojected: its image, shading points, normals and camera.
struct Old<'a> {
    rgba: &'a [u8],
    positions: &'a [[f32; 4]],
    normals: &'a [[f32; 4]],
    cam: &'a CameraParams,
}

/// Step 2: every splatted pixel's colour gathered backward, bilinearly over the old pixels that
/// show its surface (or, for the sky, that saw the sky too). `splat`: each new pixel's depth along
/// the new view and the old pixel whose splat it shows (`usize::MAX`: none).
fn gather(old_frame: &Old, to: &CameraParams, splat: (&[f32], &[usize]), out: &mut [u8]) {
    const NEAR: f32 = 1e-12;
    let Old {
        rgba,
        positions,
        normals,
        cam: from,
    } = *old_frame;
    let (depth, source) = splat;
    let (w, h) = (from.size[0] as usize, from.size[1] as usize);
    let (from_eye, to_eye) = (from.eye_point(), to.eye_point());
    let fwd = to.ray(0.5 * w as f32, 0.5 * h as f32).normalize();
    for j in 0..w * h {
        let i = source[j];
        if i == usize::MAX {
            continue;
        }
        let (x, y) = ((j % w) as f32 + 0.5, (j / w) as f32 + 0.5);
        let ray = to.ray(x, y);
        // Where the new pixel's surface point (or sky direction) lies in the old view.
        let (point, old) = if depth[j].is_finite() {
            // The point on this pixel's ray at the splatted depth along the new view...
            let along = ray.dot(fwd);
            if along <= 0.0 {
                continue;
            }
            let flat = to_eye + ray * (depth[j] / along);
            // ... or, better, where the ray meets the splatted point's tangent plane: across a
            // magnified splat's footprint a slanted surface's depth changes.
            let q = match normals.get(i).map(|&n| xyz(n)) {
                Some(n) => {
                    let (qi, dn) = (xyz(positions[i]), ray.dot(n));
                    let t = (qi - to_eye).dot(n) / dn;
                    let hit = to_eye + ray * t;
                    // A grazing ray, or a hit far from the splat (half a footprint is at most a
                    // few percent of its depth), keeps the flat point.
                    let near = (hit - flat).length() <= 0.25 * (flat - to_eye).length();
                    if dn.abs() > 1e-6 && t > 0.0 && near {
                        hit
                    } else {
                        flat
                    }
                }
                None => flat,
            };
            match from.project(q - from_eye, NEAR) {
                Some(o) => (Some(q), o),
                None => continue,
            }
        } else {
            match from.project(ray, NEAR) {
                Some(o) => (None, o),
                None => continue,
            }
        };
        let n = normals.get(i).map(|&n| xyz(n));
        let mut acc = [0.0f32; 4];
        let mut wsum = 0.0f32;
        for (k, wt) in crate::metrics::bilinear_taps(old.0, old.1, w, h) {
            let same = match point {
                // The sky gathers the sky.
                None => sky(positions[k]),
                Some(_) if sky(positions[k]) => false,
                Some(q) => {
                    // On the point's tangent plane where its normal is known (taps on a slanted
                    // surface differ in depth, not in plane distance), else at its depth.
                    let qk = xyz(positions[k]);
                    let depth_ok = match n {
                        Some(n) => n.dot(qk - q).abs() <= SAME_DEPTH * old.2,
                        None => from
                            .project(qk - from_eye, NEAR)
                            .is_some_and(|o| (o.2 - old.2).abs() <= SAME_DEPTH * old.2),
                    };
                    let normal_ok = match (n, normals.get(k)) {
                        (Some(n), Some(&nk)) => n.dot(xyz(nk)) >= SAME_COS,
                        _ => true,
                    };
                    depth_ok && normal_ok
                }
            };
            if same {
                for (c, a) in acc.iter_mut().enumerate() {
                    *a += wt * rgba[k * 4 + c] as f32;
                }
                wsum += wt;
            }
        }
        if wsum > 1e-6 {
            for c in 0..4 {
                out[j * 4 + c] = (acc[c] / wsum).round().clamp(0.0, 255.0) as u8;
            }
        }
    }
}

/// Push-pull: each hole takes the mean of the filled pixels around it at the finest scale that has
/// any (a pyramid of 2×2 means, then back down).
fn fill_holes(img: &mut [u8], filled: &[bool], w: usize, h: usize) {
    if filled.iter().all(|&f| f) || !filled.iter().any(|&f| f) {
        return;
    }
    // Level 0: premultiplied colour sums and weights.
    let mut levels: Vec<(usize, usize, Vec<[f32; 5]>)> = Vec::new();
    let base: Vec<[f32; 5]> = (0..w * h)
        .map(|i| {
            if filled[i] {
                let c = &img[i * 4..i * 4 + 4];
                [c[0] as f32, c[1] as f32, c[2] as f32, c[3] as f32, 1.0]
            } else {
                [0.0; 5]
            }
        })
        .collect();
    levels.push((w, h, base));
    while {
        let (lw, lh, _) = levels.last().unwrap();
        *lw > 1 || *lh > 1
    } {
        let (lw, lh, prev) = levels.last().unwrap();
        let (nw, nh) = (lw.div_ceil(2), lh.div_ceil(2));
        let mut next = vec![[0.0f32; 5]; nw * nh];
        for y in 0..*lh {
            for x in 0..*lw {
                let s = prev[y * lw + x];
                let t = &mut next[(y / 2) * nw + x / 2];
                for c in 0..5 {
                    t[c] += s[c];
                }
            }
        }
        levels.push((nw, nh, next));
    }
    // Pull: a pixel without weight takes its parent's mean.
    for l in (0..levels.len() - 1).rev() {
        let (upper, lower) = levels.split_at_mut(l + 1);
        let (lw, lh, cur) = &mut upper[l];
        let (pw, _, parent) = &lower[0];
        for y in 0..*lh {
            for x in 0..*lw {
                let i = y * *lw + x;
                if cur[i][4] <= 0.0 {
                    let p = parent[(y / 2) * pw + x / 2];
                    if p[4] > 0.0 {
                        cur[i] = [p[0] / p[4], p[1] / p[4], p[2] / p[4], p[3] / p[4], 1.0];
                    }
                }
            }
        }
    }
    let (_, _, l0) = &levels[0];
    for i in 0..w * h {
        if !filled[i] && l0[i][4] > 0.0 {
            for c in 0..4 {
                img[i * 4 + c] = (l0[i][c] / l0[i][4]).round().clamp(0.0, 255.0) as u8;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Camera;
    use glam::Vec3;

    /// A w×h view of the plane z = −5 from `eye` looking down −Z; its pixels' positions and an image
    /// whose red channel is the pixel's column and green its row.
    fn plane(eye: Vec3, w: u32, h: u32) -> (CameraParams, Vec<[f32; 4]>, Vec<u8>) {
        let cam = Camera::look_at("c", eye, eye - Vec3::Z, Vec3::Y, 1.0);
        let p = CameraParams::new(&cam, w, h);
        let mut pos = Vec::new();
        let mut rgba = Vec::new();
        for i in 0..(w * h) as usize {
            let (x, y) = ((i % w as usize) as f32 + 0.5, (i / w as usize) as f32 + 0.5);
            let d = p.ray(x, y);
            let t = (eye.z + 5.0) / -d.z;
            let q = eye + d * t;
            pos.push([q.x, q.y, q.z, 1.0]);
            rgba.extend([(i % w as usize) as u8, (i / w as usize) as u8, 0, 255]);
        }
        (p, pos, rgba)
    }

    /// Thinning a plane facing the eye (one depth) keeps one pixel of each 2×2 block with its
    /// point, and the block's mean colour (every pixel shows the same surface); step 1 keeps all.
    #[test]
    fn thinning_keeps_a_pixel_of_each_block_with_the_blocks_mean_colour() {
        let (p, pos, rgba) = plane(Vec3::ZERO, 33, 24);
        let t = Thinned::new(&rgba, &pos, &[], (33, 24), 2, &p);
        assert_eq!((t.size, t.step), ((16, 12), 2));
        for (k, px) in t.rgba.chunks(4).enumerate() {
            let (x, y) = (k % 16 * 2, k / 16 * 2);
            // The plane's colour is (x, y, 0, 255): the block's mean rounds to x + 1, y + 1.
            assert_eq!(px, [x as u8 + 1, y as u8 + 1, 0, 255], "block {k}");
            let block = [0, 1, 33, 34].map(|o| pos[y * 33 + x + o]);
            assert!(block.contains(&t.positions[k]), "block {k}");
        }
        assert!(t.normals.is_empty());
        let all = Thinned::new(&rgba, &pos, &[], (33, 24), 1, &p);
        assert_eq!((all.size, all.rgba, all.positions), ((33, 24), rgba, pos));
    }

    /// A thin foreground part survives thinning: a line one pixel wide, 1 unit in front of a wall
    /// 5 away, diagonal (pixels (y + 1, y)) and along an odd column (x = 9), thinned by 2, without
    /// normals and with them (the tangent-plane test), and with the top rows sky. Every block it
    /// crosses keeps its point and colour, alone in the block's mean (the wall behind is another
    /// surface); every other block keeps the wall's, or the sky's. Keeping each block's top-left
    /// pixel instead drops both lines (neither passes through an even (x, y)).
    #[test]
    fn thinning_keeps_a_line_one_pixel_wide_whole() {
        let (w, h) = (24u32, 16u32);
        let (p, mut pos, _) = plane(Vec3::ZERO, w, h);
        let mut rgba = vec![100u8; (w * h * 4) as usize];
        let on_line = |x: usize, y: usize| x == y + 1 || x == 9;
        let sky = |y: usize| y < 2;
        for i in 0..(w * h) as usize {
            let (x, y) = (i % w as usize, i / w as usize);
            if sky(y) {
                pos[i] = [0.0; 4];
                rgba[i * 4..i * 4 + 4].copy_from_slice(&[0, 0, 200, 255]);
            } else if on_line(x, y) {
                let q = Vec4::from(pos[i]).truncate() * 0.8;
                pos[i] = q.extend(1.0).into();
                rgba[i * 4..i * 4 + 4].copy_from_slice(&[250, 0, 0, 255]);
            }
        }
        let facing = vec![[0.0, 0.0, 1.0, 0.0]; pos.len()];
        for normals in [&[][..], &facing[..]] {
            let t = Thinned::new(&rgba, &pos, normals, (w, h), 2, &p);
            for k in 0..(12 * 8) as usize {
                let (x0, y0) = (k % 12 * 2, k / 12 * 2);
                let crossed = (y0..y0 + 2).any(|y| (x0..x0 + 2).any(|x| on_line(x, y)));
                let want: &[u8] = match () {
                    _ if sky(y0) => &[0, 0, 200, 255],
                    _ if crossed => &[250, 0, 0, 255],
                    _ => &[100; 4],
                };
                let what = format!("block {k} at ({x0}, {y0}), {} normals", normals.len());
                assert_eq!(&t.rgba[k * 4..k * 4 + 4], want, "{what}");
                let z = t.positions[k][2];
                assert_eq!(t.positions[k][3] > 0.0, !sky(y0), "{what}");
                assert_eq!(
                    !sky(y0) && z > -4.5,
                    !sky(y0) && crossed,
                    "{what}: depth {z}"
                );
            }
        }
    }

    #[test]
    fn the_same_camera_gives_the_same_image() {
        let (p, pos, rgba) = plane(Vec3::ZERO, 32, 24);
        assert_eq!(reproject(&rgba, &pos, &[], &p, &p), rgba);
    }

    #[test]
    fn a_sideways_step_shifts_the_image_by_the_parallax() {
        // The plane is 5 away; a 90°-ish view 32 px wide spans 2·5·tan(0.5)·(32/24) ≈ 7.28 units, so a
        // step of 7.28/32 to the right moves every point one pixel to the left.
        let (p0, pos, rgba) = plane(Vec3::ZERO, 32, 24);
        let span = 2.0 * 5.0 * 0.5f32.tan() * 32.0 / 24.0;
        let (p1, ..) = plane(Vec3::new(span / 32.0, 0.0, 0.0), 32, 24);
        let out = reproject(&rgba, &pos, &[], &p0, &p1);
        for y in 0..24usize {
            for x in 0..31usize {
                let j = (y * 32 + x) * 4;
                assert_eq!((out[j], out[j + 1]), ((x + 1) as u8, y as u8), "({x}, {y})");
            }
            // The last column was not seen before: filled from its neighbours (the column 31).
            let j = (y * 32 + 31) * 4;
            assert_eq!(out[j], 31, "row {y}");
        }
    }

    #[test]
    fn moving_closer_leaves_no_holes_and_keeps_the_centre() {
        let (p0, pos, rgba) = plane(Vec3::ZERO, 32, 24);
        let (p1, ..) = plane(Vec3::new(0.0, 0.0, -2.0), 32, 24);
        let out = reproject(&rgba, &pos, &[], &p0, &p1);
        // Magnified 5/3: still every pixel opaque, the centre pixel's colour near the centre.
        assert!(out.chunks(4).all(|c| c[3] == 255));
        let j = (12 * 32 + 16) * 4;
        assert!((out[j] as i32 - 16).abs() <= 1 && (out[j + 1] as i32 - 12).abs() <= 1);
        // The image grew: the left edge now shows a column nearer the centre than 0.
        assert!(out[(12 * 32) * 4] >= 5, "{}", out[(12 * 32) * 4]);
    }

    /// Magnified (moving closer), the gathered image is interpolated: along the centre row the
    /// red channel (the old column) rises in steps of at most 1, where square splats repeated each
    /// old column over two new ones and jumped by 1 every other pixel.
    #[test]
    fn a_magnified_image_is_interpolated_not_blocky() {
        let (p0, pos, mut rgba) = plane(Vec3::ZERO, 32, 24);
        // Red: 8 × the old column, so an interpolated value between two columns is distinct.
        for (i, c) in rgba.chunks_mut(4).enumerate() {
            c[0] = (8 * (i % 32)) as u8;
        }
        let (p1, ..) = plane(Vec3::new(0.0, 0.0, -2.5), 32, 24);
        let normals = vec![[0.0, 0.0, 1.0, 0.0]; pos.len()];
        let out = reproject(&rgba, &pos, &normals, &p0, &p1);
        let row: Vec<i32> = (4..28).map(|x| out[(12 * 32 + x) * 4] as i32).collect();
        let steps: Vec<i32> = row.windows(2).map(|p| p[1] - p[0]).collect();
        // Magnified 2×: 8 per old column over 2 new pixels, about 4 a pixel, never 0 or 8.
        assert!(steps.iter().all(|&d| (3..=5).contains(&d)), "{row:?}");
        // Every other old column on another surface (normal turned 90°): no tap of another
        // surface is mixed in, so the splatted colours stay (steps of 0 or 8 appear).
        let turned: Vec<[f32; 4]> = (0..pos.len())
            .map(|i| match i % 2 {
                0 => [0.0, 0.0, 1.0, 0.0],
                _ => [1.0, 0.0, 0.0, 0.0],
            })
            .collect();
        let out = reproject(&rgba, &pos, &turned, &p0, &p1);
        let row: Vec<i32> = (4..28).map(|x| out[(12 * 32 + x) * 4] as i32).collect();
        assert!(row.iter().all(|v| v % 8 == 0), "{row:?}");
    }

    /// A floor seen at a slant and approached: the gathered image is interpolated there too. Each new
    /// pixel's point is where its ray meets the splatted point's tangent plane, so on the floor
    /// (depth changing across a splat's footprint) the taps still pass the depth test.
    #[test]
    fn an_approached_floor_is_interpolated_not_blocky() {
        let (w, h) = (32u32, 24u32);
        let view = |eye: Vec3| {
            let cam = Camera::look_at("c", eye, eye + Vec3::new(0.0, -0.6, -1.0), Vec3::Y, 1.0);
            CameraParams::new(&cam, w, h)
        };
        let p0 = view(Vec3::ZERO);
        let (mut pos, mut rgba) = (Vec::new(), Vec::new());
        for i in 0..(w * h) as usize {
            let (x, y) = ((i % w as usize) as f32 + 0.5, (i / w as usize) as f32 + 0.5);
            let d = p0.ray(x, y);
            // The floor y = −1 (every ray of this view goes down).
            let q = d * (1.0 / -d.y);
            pos.push([q.x, q.y, q.z, 1.0]);
            rgba.extend([0, (8 * (i / w as usize)) as u8, 0, 255]);
        }
        let normals = vec![[0.0, 1.0, 0.0, 0.0]; pos.len()];
        let p1 = view(Vec3::new(0.0, 0.0, -0.8));
        let out = reproject(&rgba, &pos, &normals, &p0, &p1);
        let col: Vec<i32> = (2..22)
            .map(|y| out[(y * w as usize + 16) * 4 + 1] as i32)
            .collect();
        // Rows of the old image, 8 apart: an interpolated column never holds one value over three
        // rows (a magnified splat would).
        let runs = col
            .windows(3)
            .filter(|t| t[0] == t[1] && t[1] == t[2])
            .count();
        assert_eq!(runs, 0, "{col:?}");
        // And at the right place: the floor point the new pixel sees, in the old image, read
        // bilinearly, within 2 (of 8 a row), on rows 5–18 (the three farthest and the three
        // nearest are up to 7 off; not followed up).
        for (y, &g) in (2..22).zip(&col).skip(3).take(14) {
            let d = p1.ray(16.5, y as f32 + 0.5);
            let q = Vec3::new(0.0, 0.0, -0.8) + d * (1.0 / -d.y);
            let (_, oy, _) = p0.project(q, 1e-12).unwrap();
            let want = 8.0 * (oy - 0.5);
            assert!(
                (g as f32 - want).abs() <= 2.0,
                "row {y}: {g} vs {want}: {col:?}"
            );
        }
    }

    #[test]
    fn holes_take_their_neighbours_colour() {
        let mut img = vec![0u8; 4 * 4 * 4];
        let mut filled = vec![false; 16];
        for i in [0usize, 1, 4, 5] {
            img[i * 4..i * 4 + 4].copy_from_slice(&[200, 100, 50, 255]);
            filled[i] = true;
        }
        fill_holes(&mut img, &filled, 4, 4);
        assert!(img.chunks(4).all(|c| c == [200, 100, 50, 255]));
    }
}
