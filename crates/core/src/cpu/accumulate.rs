//! CPU twin of `shaders-wgsl/accumulate.wgsl` (`gi::accumulate`): the indirect light blended with
//! the previous frame's accumulated light at the same surface point. G-buffers are 4 × vec4 a pixel
//! (`common/gbuffer.wgsl`: position with w = 1 where a surface is seen, normal, albedo, emission);
//! indirect light and history are a vec4 a pixel (w: the frames the history averages).

use glam::Vec3;

use crate::gi::accumulate::AccumulateParams;

fn v3(a: [f32; 4]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

/// World point `q`'s image position (pixels) and depth along the previous view
/// (`CameraParams::project` with near = 1e-6, as `accumulate.wgsl`'s `project_prev`); depth −1
/// where it lies behind the eye.
pub fn project_prev(p: &AccumulateParams, q: Vec3) -> Vec3 {
    p.prev
        .project(q - p.prev.eye_point(), 1e-6)
        .map_or(Vec3::new(0.0, 0.0, -1.0), |(x, y, z)| Vec3::new(x, y, z))
}

/// History tap `j` shows the surface at depth `z` with normal `n`.
fn same_surface(
    p: &AccumulateParams,
    prev_gbuffer: &[[f32; 4]],
    j: usize,
    z: f32,
    n: Vec3,
) -> bool {
    let (pos, nrm) = (prev_gbuffer[4 * j], prev_gbuffer[4 * j + 1]);
    if pos[3] <= 0.0 || n.dot(v3(nrm)) < p.blend[2] {
        return false;
    }
    let pq = project_prev(p, v3(pos));
    pq.z > 0.0 && (pq.z - z).abs() <= p.blend[1] * z
}

/// The new frame's weight after `frames` frames of history.
pub fn history_alpha(frames: f32, alpha: f32) -> f32 {
    (1.0 / (frames + 1.0)).max(alpha)
}

/// The kernel over every pixel: `indirect` (this frame's, on `gbuffer`) blended with `prev_history`
/// on `prev_gbuffer`; returns the accumulated light (w = the frames it averages).
pub fn accumulate(
    p: &AccumulateParams,
    gbuffer: &[[f32; 4]],
    prev_gbuffer: &[[f32; 4]],
    prev_history: &[[f32; 4]],
    indirect: &[[f32; 4]],
) -> Vec<[f32; 4]> {
    (0..p.pixels() as usize)
        .map(|i| pixel(p, gbuffer, prev_gbuffer, prev_history, indirect[i], i))
        .collect()
}

fn pixel(
    p: &AccumulateParams,
    gbuffer: &[[f32; 4]],
    prev_gbuffer: &[[f32; 4]],
    prev_history: &[[f32; 4]],
    cur: [f32; 4],
    i: usize,
) -> [f32; 4] {
    let fresh = [cur[0], cur[1], cur[2], 1.0];
    let (pos, n) = (gbuffer[4 * i], v3(gbuffer[4 * i + 1]));
    if p.size[2] == 0 || pos[3] <= 0.0 {
        return fresh;
    }
    let (w, h) = (p.size[0] as i32, p.size[1] as i32);
    let mut sum = [0.0f32; 4];
    let mut wsum = 0.0f32;
    let pq = project_prev(p, v3(pos));
    if p.size[3] == 1 {
        if pq.z > 0.0 && same_surface(p, prev_gbuffer, i, pq.z, n) {
            sum = prev_history[i];
            wsum = 1.0;
        }
    } else if pq.z > 0.0 {
        let (fx, fy) = (pq.x - 0.5, pq.y - 0.5);
        let (x0, y0) = (fx.floor() as i32, fy.floor() as i32);
        let (tx, ty) = (fx - x0 as f32, fy - y0 as f32);
        for t in 0..4 {
            let (dx, dy) = (t & 1, t >> 1);
            let bx = if dx == 1 { tx } else { 1.0 - tx };
            let by = if dy == 1 { ty } else { 1.0 - ty };
            let wt = bx * by;
            let (x, y) = (x0 + dx, y0 + dy);
            if wt <= 0.0 || x < 0 || y < 0 || x >= w || y >= h {
                continue;
            }
            let j = (y * w + x) as usize;
            if same_surface(p, prev_gbuffer, j, pq.z, n) {
                for (s, v) in sum.iter_mut().zip(prev_history[j]) {
                    *s += wt * v;
                }
                wsum += wt;
            }
        }
    }
    if wsum <= 1e-6 {
        return fresh;
    }
    let hist = sum.map(|s| s / wsum);
    let a = history_alpha(hist[3], p.blend[0]);
    let mix = |c: usize| hist[c] * (1.0 - a) + cur[c] * a;
    [
        mix(0),
        mix(1),
        mix(2),
        (hist[3] + 1.0).min(1.0 / p.blend[0]),
    ]
}
