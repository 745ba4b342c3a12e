//! CPU twin of `shaders-wgsl/restir.wgsl` (ReSTIR DI over the VPLs, `method::restir`): the
//! reservoir's update, the combination of reservoirs (biased and unbiased), W, the alias draw and
//! each stage of a pixel with the same random numbers.
//!
//! For tests only (`tests/restir.rs` checks the shader against it): no production code calls it.

use glam::Vec3;

use super::{HISTORY, RestirParams, UNBIASED};
use crate::cpu::shading::CpuScene;
use crate::cpu::vpl::eq5_vpl_radiance;
use crate::gi::primary::{CameraParams, ShadingPoint};
use crate::gi::rng::{rng_next, rng_seed};
use crate::gi::vpl_trace::Vpl;
use crate::metrics::luminance;

/// No sample.
pub const NONE: u32 = u32::MAX;

/// A reservoir of one sample: the VPL y, the sum of the weights seen, the candidates it stands
/// for (M) and the sample's unbiased contribution weight W.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reservoir {
    pub y: u32,
    pub w_sum: f32,
    pub m: f32,
    pub w: f32,
}

impl Reservoir {
    pub const EMPTY: Reservoir = Reservoir {
        y: NONE,
        w_sum: 0.0,
        m: 0.0,
        w: 0.0,
    };

    /// From the shader's packing (y, then f32 bits).
    pub fn from_gpu(r: [u32; 4]) -> Reservoir {
        Reservoir {
            y: r[0],
            w_sum: f32::from_bits(r[1]),
            m: f32::from_bits(r[2]),
            w: f32::from_bits(r[3]),
        }
    }

    /// Alg. 2's update: `w` joins w_sum and y becomes the sample with probability w / w_sum
    /// (`u` uniform in [0, 1)). Twin of `res_update`.
    pub fn update(&mut self, y: u32, w: f32, u: f32) {
        self.w_sum += w;
        if w > 0.0 && u * self.w_sum < w {
            self.y = y;
        }
    }

    /// Alg. 4's step: reservoir `q` counted as `m` candidates streamed in with weight
    /// p̂(q.y) W_q m, `p_hat_y` the target at this pixel of q's sample. Twin of `res_merge`.
    pub fn merge(&mut self, q: &Reservoir, p_hat_y: f32, m: f32, u: f32) {
        let w = if q.y != NONE && q.w > 0.0 {
            p_hat_y * q.w * m
        } else {
            0.0
        };
        self.update(q.y, w, u);
        self.m += m;
    }
}

/// W = w_sum / (z p̂(y)), 0 where either is 0 (z: Σ M biased, the unbiased Z). Twin of
/// `res_weight`.
pub fn weight(w_sum: f32, p_hat: f32, z: f32) -> f32 {
    if p_hat > 0.0 && z > 0.0 {
        w_sum / (z * p_hat)
    } else {
        0.0
    }
}

/// The VPL that the alias table draws with `u1` (the column) and `u2` (kept or aliased). Twin of
/// `alias_draw`.
pub fn alias_draw(table: &[[u32; 4]], u1: f32, u2: f32) -> u32 {
    let n = table.len() as u32;
    let k = ((u1 * n as f32) as u32).min(n - 1);
    let a = table[k as usize];
    if u2 < f32::from_bits(a[0]) { k } else { a[1] }
}

/// One frame's inputs to the stages: the scene (visibility), the G-buffer, the VPLs, the alias
/// table and the uniform the GPU ran with; `prev_sps` the previous frame's G-buffer.
pub struct Stages<'a> {
    pub cs: &'a CpuScene<'a>,
    pub sps: &'a [ShadingPoint],
    pub prev_sps: &'a [ShadingPoint],
    pub vpls: &'a [Vpl],
    pub table: &'a [[u32; 4]],
    pub params: RestirParams,
}

fn axis(a: [f32; 4]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

fn view_depth(c: &CameraParams, q: Vec3) -> f32 {
    (q - axis(c.eye)).dot(axis(c.forward))
}

impl Stages<'_> {
    fn d_min2(&self) -> f32 {
        self.params.tol[0]
    }

    /// Eq. (5)'s term of VPL y at `sp` without visibility (0 for no VPL). Twin of `term`.
    pub fn term(&self, sp: &ShadingPoint, y: u32) -> Vec3 {
        match self.vpls.get(y as usize) {
            Some(v) => eq5_vpl_radiance(sp.pos, sp.normal, sp.albedo, v, self.d_min2()),
            None => Vec3::ZERO,
        }
    }

    /// The target p̂: the term's luminance. Twin of `p_hat`.
    pub fn p_hat(&self, sp: &ShadingPoint, y: u32) -> f32 {
        luminance(self.term(sp, y).into())
    }

    fn visible(&self, sp: &ShadingPoint, y: u32) -> bool {
        self.cs
            .vpl_visible(sp.pos, sp.normal, &self.vpls[y as usize])
    }

    fn seed(&self) -> u32 {
        self.params.opts[2]
    }

    fn unbiased(&self) -> bool {
        self.params.opts[1] & UNBIASED != 0
    }

    /// Unbiased: W = 0 where the sample is hidden from the pixel; the rays traced. Twin of
    /// `own_visibility`.
    fn own_visibility(&self, sp: &ShadingPoint, r: &mut Reservoir) -> u32 {
        if !self.unbiased() || r.w.is_nan() || r.w <= 0.0 {
            return 0;
        }
        if !self.visible(sp, r.y) {
            r.w = 0.0;
        }
        1
    }

    /// Stage 0 of pixel i: its reservoir and the shadow rays it traced. Twin of `initial`.
    pub fn initial(&self, i: u32) -> (Reservoir, u32) {
        let sp = &self.sps[i as usize];
        let mut r = Reservoir::EMPTY;
        if !sp.valid || self.vpls.is_empty() {
            return (r, 0);
        }
        let mut rng = rng_seed(i, self.seed(), 0);
        let m = self.params.dims[3];
        for _ in 0..m {
            let u1 = rng_next(&mut rng);
            let u2 = rng_next(&mut rng);
            let u3 = rng_next(&mut rng);
            let j = alias_draw(self.table, u1, u2);
            let pdf = f32::from_bits(self.table[j as usize][2]);
            let w = if pdf > 0.0 {
                self.p_hat(sp, j) / pdf
            } else {
                0.0
            };
            r.update(j, w, u3);
        }
        r.m = m as f32;
        r.w = weight(r.w_sum, self.p_hat(sp, r.y), r.m);
        let mut traced = 0;
        if r.w > 0.0 {
            traced = 1;
            if !self.visible(sp, r.y) {
                r.w = 0.0;
            }
        }
        (r, traced)
    }

    fn same_surface(&self, c: &CameraParams, q: &ShadingPoint, z: f32, n: Vec3) -> bool {
        if !q.valid || n.dot(q.normal) < self.params.tol2[0] {
            return false;
        }
        let zq = view_depth(c, q.pos);
        zq > 0.0 && (zq - z).abs() <= self.params.tol[3] * z
    }

    /// The previous frame's pixel showing `sp`'s point, if any. Twin of `prev_pixel`.
    pub fn prev_pixel(&self, sp: &ShadingPoint) -> Option<u32> {
        let c = &self.params.prev;
        let d = sp.pos - axis(c.eye);
        let (w, h) = (self.params.dims[0], self.params.dims[1]);
        let (x, y, z) = crate::cpu::reproject::project_new(c, d, (w, h))?;
        if !(x >= 0.0 && y >= 0.0 && x < w as f32 && y < h as f32) {
            return None;
        }
        let j = x as u32 + y as u32 * w;
        self.same_surface(c, &self.prev_sps[j as usize], z, sp.normal)
            .then_some(j)
    }

    /// Stage 1 of pixel i: `cur` its reservoir, `prev` the previous frame's final ones. Returns the
    /// reservoir and the shadow rays traced. Twin of `temporal`.
    pub fn temporal(&self, i: u32, cur: &[Reservoir], prev: &[Reservoir]) -> (Reservoir, u32) {
        let sp = &self.sps[i as usize];
        let own = cur[i as usize];
        let j = match sp.valid && self.params.opts[1] & HISTORY != 0 {
            true => self.prev_pixel(sp),
            false => None,
        };
        let Some(j) = j else {
            return (own, 0);
        };
        let p = prev[j as usize];
        let mp = p.m.min(self.params.tol[2] * self.params.dims[3] as f32);
        let mut rng = rng_seed(i, self.seed(), 1);
        let mut r = Reservoir::EMPTY;
        r.merge(&own, self.p_hat(sp, own.y), own.m, rng_next(&mut rng));
        r.merge(&p, self.p_hat(sp, p.y), mp, rng_next(&mut rng));
        let ph = self.p_hat(sp, r.y);
        let mut z = r.m;
        let mut traced = 0;
        if self.unbiased() && ph > 0.0 {
            z = own.m;
            let q = &self.prev_sps[j as usize];
            if self.p_hat(q, r.y) > 0.0 {
                traced += 1;
                if self.visible(q, r.y) {
                    z += mp;
                }
            }
        }
        r.w = weight(r.w_sum, ph, z);
        traced += self.own_visibility(sp, &mut r);
        (r, traced)
    }

    /// Stage 2 of pixel i, iteration `iteration`, over the reservoirs `input`. Returns the
    /// reservoir and the shadow rays traced. Twin of `spatial`.
    pub fn spatial(&self, i: u32, input: &[Reservoir], iteration: u32) -> (Reservoir, u32) {
        let sp = &self.sps[i as usize];
        let own = input[i as usize];
        if !sp.valid {
            return (own, 0);
        }
        let mut rng = rng_seed(i, self.seed(), 2 + iteration);
        let mut r = Reservoir::EMPTY;
        r.merge(&own, self.p_hat(sp, own.y), own.m, rng_next(&mut rng));
        let (w, h) = (self.params.dims[0], self.params.dims[1]);
        let px = (i % w) as f32 + 0.5;
        let py = (i / w) as f32 + 0.5;
        let z = view_depth(&self.params.cam, sp.pos);
        let mut picked = Vec::new();
        for _ in 0..self.params.opts[0] {
            let u1 = rng_next(&mut rng);
            let u2 = rng_next(&mut rng);
            let u3 = rng_next(&mut rng);
            let rad = self.params.tol[1] * u1.sqrt();
            let th = 6.283_185_5 * u2;
            let nx = (px + rad * th.cos()).floor();
            let ny = (py + rad * th.sin()).floor();
            if !(nx >= 0.0 && ny >= 0.0 && nx < w as f32 && ny < h as f32) {
                continue;
            }
            let j = nx as u32 + ny as u32 * w;
            if j == i || !self.same_surface(&self.params.cam, &self.sps[j as usize], z, sp.normal) {
                continue;
            }
            let q = input[j as usize];
            r.merge(&q, self.p_hat(sp, q.y), q.m, u3);
            picked.push(j);
        }
        let ph = self.p_hat(sp, r.y);
        let mut zm = r.m;
        let mut traced = 0;
        if self.unbiased() && ph > 0.0 {
            zm = own.m;
            for &j in &picked {
                let q = &self.sps[j as usize];
                if self.p_hat(q, r.y) > 0.0 {
                    traced += 1;
                    if self.visible(q, r.y) {
                        zm += input[j as usize].m;
                    }
                }
            }
        }
        r.w = weight(r.w_sum, ph, zm);
        traced += self.own_visibility(sp, &mut r);
        (r, traced)
    }

    /// Stage 3 of pixel i: its reservoir's light f(y) V(y) W and the shadow rays traced. Twin of
    /// `shade`.
    pub fn shade(&self, i: u32, r: &Reservoir) -> (Vec3, u32) {
        let sp = &self.sps[i as usize];
        if !sp.valid || r.y == NONE || r.w.is_nan() || r.w <= 0.0 {
            return (Vec3::ZERO, 0);
        }
        let c = self.term(sp, r.y);
        if c.max_element() <= 0.0 {
            return (Vec3::ZERO, 0);
        }
        match self.visible(sp, r.y) {
            true => (c * r.w, 1),
            false => (Vec3::ZERO, 1),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand-worked: weights 1, 3 then 0 streamed with u = 0.5: the first is taken (0.5 · 1 < 1),
    /// the second replaces it (0.5 · 4 < 3), the zero weight never does; W = w_sum / (M p̂).
    #[test]
    fn reservoir_update_and_weight_by_hand() {
        let mut r = Reservoir::EMPTY;
        r.update(7, 1.0, 0.5);
        assert_eq!(r.y, 7);
        r.update(9, 3.0, 0.5);
        assert_eq!((r.y, r.w_sum), (9, 4.0));
        r.update(11, 0.0, 0.0);
        assert_eq!(r.y, 9);
        r.update(12, 4.0, 0.99);
        assert_eq!((r.y, r.w_sum), (9, 8.0));
        assert_eq!(weight(8.0, 2.0, 4.0), 1.0);
        assert_eq!(weight(8.0, 0.0, 4.0), 0.0);
        assert_eq!(weight(8.0, 2.0, 0.0), 0.0);
        // A merged reservoir counts its M and weighs p̂ W M; an empty or zero-W one weighs 0.
        let mut s = Reservoir::EMPTY;
        let q = Reservoir {
            y: 3,
            w_sum: 5.0,
            m: 4.0,
            w: 0.5,
        };
        s.merge(&q, 2.0, 4.0, 0.3);
        assert_eq!((s.y, s.w_sum, s.m), (3, 4.0, 4.0));
        s.merge(&Reservoir::EMPTY, 9.0, 2.0, 0.0);
        assert_eq!((s.y, s.w_sum, s.m), (3, 4.0, 6.0));
    }

    /// Resampled importance sampling with the reservoir is unbiased: the mean of f(y) W over many
    /// seeds is Σ f. Closed form on 4 "lights" with f = p̂ = (1, 2, 3, 4) and source pdf p = (0.4,
    /// 0.3, 0.2, 0.1): the mean of p̂(y) W over 200,000 runs of M = 3 candidates is Σ p̂ = 10 within
    /// 4 standard errors.
    #[test]
    fn ris_is_unbiased_on_four_lights() {
        let p_hat = [1.0f32, 2.0, 3.0, 4.0];
        let p = [0.4f32, 0.3, 0.2, 0.1];
        let cdf = [0.4f32, 0.7, 0.9, 1.0];
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        let runs = 200_000u32;
        for run in 0..runs {
            let mut rng = rng_seed(run, 1, 2);
            let mut r = Reservoir::EMPTY;
            for _ in 0..3 {
                let u = rng_next(&mut rng);
                let j = cdf.iter().position(|&c| u < c).unwrap_or(3);
                r.update(j as u32, p_hat[j] / p[j], rng_next(&mut rng));
            }
            r.m = 3.0;
            let ph = p_hat[r.y as usize];
            let est = (ph * weight(r.w_sum, ph, r.m)) as f64;
            sum += est;
            sum2 += est * est;
        }
        let mean = sum / runs as f64;
        let se = ((sum2 / runs as f64 - mean * mean) / runs as f64).sqrt();
        assert!((mean - 10.0).abs() < 4.0 * se, "mean {mean}, se {se}");
    }
}
