//! restir's candidate distribution: the VPLs drawn in proportion to their flux's luminance from an
//! alias table (Walker 1977, Vose's construction), built on the CPU once per VPL set and read by
//! `restir.wgsl`'s `alias_draw` (CPU twin: `super::twin::alias_draw`).

use crate::gi::vpl_trace::Vpl;
use crate::metrics::luminance;

/// A VPL's column: the probability its column keeps it, its alias, its source pdf p(j) =
/// luminance(flux_j) / Σ luminance(flux) (the last two f32 as bits), unused. What the shader reads.
pub type Column = [u32; 4];

/// The alias table of `vpls` by flux luminance; all pdfs 0 (and every column keeping itself) when
/// no VPL has positive luminance.
pub fn build(vpls: &[Vpl]) -> Vec<Column> {
    let n = vpls.len();
    let lum: Vec<f64> = vpls
        .iter()
        .map(|v| {
            let l = luminance([v.flux[0], v.flux[1], v.flux[2]]) as f64;
            if l.is_finite() && l > 0.0 { l } else { 0.0 }
        })
        .collect();
    let total: f64 = lum.iter().sum();
    if n == 0 || total <= 0.0 {
        return (0..n as u32)
            .map(|j| [1f32.to_bits(), j, 0f32.to_bits(), 0])
            .collect();
    }
    // Vose: columns scaled to mean 1, the small ones topped up from the large ones.
    let mut scaled: Vec<f64> = lum.iter().map(|l| l * n as f64 / total).collect();
    let mut prob = vec![1.0f64; n];
    let mut alias: Vec<u32> = (0..n as u32).collect();
    let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&j| scaled[j] < 1.0);
    while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
        prob[s] = scaled[s];
        alias[s] = l as u32;
        scaled[l] -= 1.0 - scaled[s];
        if scaled[l] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    // What is left is 1 up to rounding.
    (0..n)
        .map(|j| {
            [
                (prob[j] as f32).to_bits(),
                alias[j],
                ((lum[j] / total) as f32).to_bits(),
                0,
            ]
        })
        .collect()
}

/// The probability that `table` draws each VPL (its pdf as drawn: each column 1/n, split between
/// the column's VPL and its alias).
pub fn drawn_pdf(table: &[Column]) -> Vec<f64> {
    let n = table.len();
    let mut p = vec![0.0f64; n];
    for (k, c) in table.iter().enumerate() {
        let keep = f32::from_bits(c[0]) as f64;
        p[k] += keep / n as f64;
        p[c[1] as usize] += (1.0 - keep) / n as f64;
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vpl(flux: [f32; 3]) -> Vpl {
        Vpl {
            pos: [0.0; 4],
            nrm: [0.0, 1.0, 0.0, 0.0],
            flux: [flux[0], flux[1], flux[2], 0.0],
        }
    }

    /// The table draws each VPL with its source pdf (luminance / total): checked exactly against
    /// hand-worked sums (1, 2, 3, 0, 4 of 10; measured error 3e-8, the f32 rounding of the kept
    /// probabilities).
    #[test]
    fn alias_table_draws_by_flux_luminance() {
        let flux = [1.0, 2.0, 3.0, 0.0, 4.0];
        let vpls: Vec<Vpl> = flux.iter().map(|&f| vpl([f, f, f])).collect();
        let t = build(&vpls);
        let want = [0.1, 0.2, 0.3, 0.0, 0.4];
        for (j, (&p, w)) in drawn_pdf(&t).iter().zip(want).enumerate() {
            assert!((p - w).abs() < 1e-6, "VPL {j}: drawn {p}, want {w}");
            let pdf = f32::from_bits(t[j][2]) as f64;
            assert!((pdf - w).abs() < 1e-6, "VPL {j}: pdf {pdf}, want {w}");
        }
        // No light: every pdf 0.
        let dark = build(&[vpl([0.0; 3]), vpl([0.0; 3])]);
        assert!(dark.iter().all(|c| f32::from_bits(c[2]) == 0.0));
        assert!(build(&[]).is_empty());
    }

    /// On many random fluxes too (xorshift): the drawn pdf is the source pdf within 1e-6.
    #[test]
    fn alias_table_random_fluxes() {
        let mut next = crate::test_rng::unit_floats(0x9e3779b97f4a7c15);
        let vpls: Vec<Vpl> = (0..1000)
            .map(|_| vpl([next() * 3.0, next(), next() * next()]))
            .collect();
        let t = build(&vpls);
        for (j, p) in drawn_pdf(&t).iter().enumerate() {
            let pdf = f32::from_bits(t[j][2]) as f64;
            assert!((p - pdf).abs() < 1e-6, "VPL {j}: drawn {p}, pdf {pdf}");
        }
    }
}
