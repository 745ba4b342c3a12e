//! CPU twins of `visibility.wgsl` (step 5) and `shade.wgsl` (step 6, Eq. 6 with Eq. 8 / 9).

use glam::Vec3;

use super::kmeans::RepPoint;
use super::shading::{CpuScene, ShadingPoint};
use super::vpl::vpl_term;
use crate::gi::vpl_trace::Vpl;

/// The visibility bit matrix: row k (SP cluster with representative point `reps[k]`, or none), bit c
/// set when light c's representative is visible from it. Returns (bits, words per row).
pub fn visibility_bits(cpu: &CpuScene, reps: &[RepPoint], lights: &[Vpl]) -> (Vec<u32>, usize) {
    let words = lights.len().div_ceil(32).max(1);
    let mut bits = vec![0u32; reps.len() * words];
    for (k, rep) in reps.iter().enumerate() {
        if !rep.valid {
            continue;
        }
        for (c, l) in lights.iter().enumerate() {
            let d = Vec3::new(l.pos[0], l.pos[1], l.pos[2]) - rep.pos;
            let ln = Vec3::new(l.nrm[0], l.nrm[1], l.nrm[2]);
            if rep.nrm.dot(d) <= 0.0 || ln.dot(d) >= 0.0 {
                continue;
            }
            if cpu.vpl_visible(rep.pos, rep.nrm, l) {
                bits[k * words + c / 32] |= 1 << (c % 32);
            }
        }
    }
    (bits, words)
}

/// Eq. (6) for one pixel: Σ_c I_c ρ G Ṽ, with Ṽ the weighted (Eq. 9) or uniform (Eq. 8) mean of the
/// visibility of the pixel's SP clusters (`assign` / `weights`: its F entries, u32::MAX unused).
#[allow(clippy::too_many_arguments)]
pub fn shade(
    sp: &ShadingPoint,
    lights: &[Vpl],
    bits: &[u32],
    words: usize,
    assign: &[u32],
    weights: &[f32],
    weighted: bool,
    d_min2: f32,
) -> Vec3 {
    if !sp.valid {
        return Vec3::ZERO;
    }
    let rows: Vec<(usize, f32)> = assign
        .iter()
        .zip(weights)
        .filter(|(k, _)| **k != u32::MAX)
        .map(|(&k, &w)| (k as usize, w))
        .collect();
    let nf = rows.len();
    let mut sum = Vec3::ZERO;
    for (c, l) in lights.iter().enumerate() {
        let t = vpl_term(sp.pos, sp.normal, sp.albedo, l, d_min2);
        if t.max_element() <= 0.0 {
            continue;
        }
        let v: f32 = rows
            .iter()
            .filter(|(k, _)| bits[k * words + c / 32] & (1 << (c % 32)) != 0)
            .map(|&(_, w)| if weighted { w } else { 1.0 / nf as f32 })
            .sum();
        sum += t * v;
    }
    sum
}
