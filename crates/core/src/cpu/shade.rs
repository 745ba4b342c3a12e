//! CPU twins of `visibility.wgsl` (step 5) and `shade.wgsl` (step 6, Eq. 6 with Eq. 8 / 9).

use glam::Vec3;

use super::kmeans::RepPoint;
use super::shading::CpuScene;
use super::vpl::eq5_cluster_light;
use crate::gi::primary::ShadingPoint;
use crate::gi::vpl_trace::Vpl;
use crate::settings::ClusterLight;

/// The visibility bit matrix: row k (SP cluster with representative point `reps[k]`, or none), bit c
/// set when light c's representative is visible from it (with `facing`, only when they also face
/// each other). Returns (bits, words per row).
pub fn visibility_bits(
    cpu: &CpuScene,
    reps: &[RepPoint],
    lights: &[Vpl],
    facing: bool,
) -> (Vec<u32>, usize) {
    let words = lights.len().div_ceil(32).max(1);
    let mut bits = vec![0u32; reps.len() * words];
    for (k, rep) in reps.iter().enumerate() {
        if !rep.valid {
            continue;
        }
        for (c, l) in lights.iter().enumerate() {
            let d = Vec3::new(l.pos[0], l.pos[1], l.pos[2]) - rep.pos;
            let ln = Vec3::new(l.nrm[0], l.nrm[1], l.nrm[2]);
            if facing && (rep.nrm.dot(d) <= 0.0 || ln.dot(d) >= 0.0) {
                continue;
            }
            if cpu.vpl_visible(rep.pos, rep.nrm, l) {
                bits[k * words + c / 32] |= 1 << (c % 32);
            }
        }
    }
    (bits, words)
}

/// The visibility bit matrix a pixel's slots read (`visibility_bits`): rows of `words` words.
#[derive(Clone, Copy)]
pub struct Bits<'a> {
    pub bits: &'a [u32],
    pub words: usize,
}

impl Bits<'_> {
    /// V(p_f, p_c) of SP cluster `row` and light `c`.
    pub fn visible(&self, row: u32, c: usize) -> bool {
        self.bits[row as usize * self.words + c / 32] & (1 << (c % 32)) != 0
    }
}

/// A pixel's F slots: its SP clusters (`u32::MAX` unused) and their Eq. (10) weights, used as they
/// are (`weighted`, Eq. 9) or replaced by Eq. (8)'s uniform weights.
#[derive(Clone, Copy)]
pub struct Slots<'a> {
    pub assign: &'a [u32],
    pub weights: &'a [f32],
    pub weighted: bool,
}

/// Eq. (8) as weights: 1/F' for each of the F' used slots, 0 for the others (twin of
/// `eq8_mean_weights` in shade.wgsl).
pub fn eq8_mean_weights(assign: &[u32]) -> Vec<f32> {
    let nf = assign.iter().filter(|&&k| k != u32::MAX).count();
    assign
        .iter()
        .map(|&k| if k != u32::MAX { 1.0 / nf as f32 } else { 0.0 })
        .collect()
}

/// Eq. (9): Ṽ(p, p_c) = Σ_f w_f V(p_f, p_c), summed over the slots in order (twin of
/// `eq9_weighted_visibility` in shade.wgsl; with `eq8_mean_weights` it is Eq. 8).
pub fn eq9_weighted_visibility(w: &[f32], visible: impl Fn(usize) -> bool) -> f32 {
    w.iter()
        .enumerate()
        .filter(|&(f, _)| visible(f))
        .map(|(_, &w)| w)
        .sum()
}

/// The lights of a 32-light word that every slot sees as it sees light `b` (its visibility pattern
/// over the slots), as a mask; `rw[f]` is slot f's word (0 for an unused slot). Twin of
/// `same_visibility` in shade.wgsl, whose pattern table gives each light of a pattern the Ṽ of its
/// first light.
pub fn same_visibility(rw: &[u32], b: u32) -> u32 {
    rw.iter().fold(u32::MAX, |same, &r| {
        same & if (r >> b) & 1 != 0 { r } else { !r }
    })
}

/// Eq. (6) for one pixel: Σ_c I_c ρ G Ṽ(p, p_c) over the lights, each a point or spread as `light`
/// says (twin of `eq6_indirect` in shade.wgsl).
pub fn eq6_indirect(
    sp: &ShadingPoint,
    lights: &[Vpl],
    bits: &Bits,
    slots: &Slots,
    d_min2: f32,
    light: ClusterLight,
) -> Vec3 {
    if !sp.valid {
        return Vec3::ZERO;
    }
    let w = if slots.weighted {
        slots.weights.to_vec()
    } else {
        eq8_mean_weights(slots.assign)
    };
    let mut sum = Vec3::ZERO;
    for (c, l) in lights.iter().enumerate() {
        let t = eq5_cluster_light(sp.pos, sp.normal, sp.albedo, l, d_min2, light);
        if t.max_element() <= 0.0 {
            continue;
        }
        let row = |f: usize| slots.assign[f];
        let v = eq9_weighted_visibility(&w, |f| row(f) != u32::MAX && bits.visible(row(f), c));
        sum += t * v;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand-worked: slot words 0b1101 (lights 0, 2, 3), 0b0111 (lights 0, 1, 2) and an unused slot
    /// (0). Lights 0 and 2: both slots (pattern 11-); light 1: slot 1 only (01-); light 3: slot 0
    /// only (10-); lights 4..31: none (00-).
    #[test]
    fn same_visibility_by_hand() {
        let rw = [0b1101, 0b0111, 0];
        assert_eq!(same_visibility(&rw, 0), 0b0101);
        assert_eq!(same_visibility(&rw, 2), 0b0101);
        assert_eq!(same_visibility(&rw, 1), 0b0010);
        assert_eq!(same_visibility(&rw, 3), 0b1000);
        assert_eq!(same_visibility(&rw, 4), !0b1111);
        // One slot: the lights it sees, or those it does not.
        assert_eq!(same_visibility(&[0xf0f0_0000], 20), 0xf0f0_0000);
        assert_eq!(same_visibility(&[0xf0f0_0000], 0), 0x0f0f_ffff);
    }
}
