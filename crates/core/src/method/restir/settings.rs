//! restir's knobs (ReSTIR DI, Bitterli et al. 2020, over the frame's VPLs; docs/methods.md): the
//! candidates a pixel M, the spatial reuse's neighbours k, radius and iterations, the temporal
//! reuse's confidence cap and the combination (biased or unbiased). Temporal reuse itself is the
//! shared `--temporal` switch.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::settings::{Invalid, Widget, in_range, invalid, knobs};

/// How reservoirs are combined (`--restir-combine`; the paper's §4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Combine {
    /// Alg. 4: W = w_sum / (p̂(y) Σ M): darker where a neighbour cannot see the light it lends.
    #[default]
    Biased,
    /// Alg. 6 with visibility in p̂: Σ M over the inputs whose p̂ · V at the sample is positive,
    /// a shadow ray from each reused neighbour's (and the previous frame's) point.
    Unbiased,
}

impl Combine {
    pub fn name(self) -> &'static str {
        match self {
            Combine::Biased => "biased",
            Combine::Unbiased => "unbiased",
        }
    }
}

impl fmt::Display for Combine {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// restir's light set (`--restir-lights`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RestirLights {
    /// The frame's VPLs, each a point light (the default).
    #[default]
    Vpls,
    /// The resident VPL clusters (step 2, `--vpl-clusters`), each a point light at its
    /// representative with the members' summed flux (the paper's `--cluster-light point`).
    Clusters,
}

impl RestirLights {
    pub fn name(self) -> &'static str {
        match self {
            RestirLights::Vpls => "vpls",
            RestirLights::Clusters => "clusters",
        }
    }
}

impl fmt::Display for RestirLights {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The most candidates a pixel (`--restir-candidates`).
pub const MAX_CANDIDATES: u32 = 1024;
/// The most spatial neighbours an iteration (`--restir-neighbours`; the shader's list holds them).
pub const MAX_NEIGHBOURS: u32 = 16;
/// The most spatial iterations (`--restir-iterations`).
pub const MAX_ITERATIONS: u32 = 8;

knobs! {
    /// restir's knobs, flattened into `method::MethodSettings`.
    pub struct RestirSettings, lists RestirLists, heading super::super::METHOD_HEADING;
    /// restir: initial candidates a pixel, drawn by flux (the paper's M; default 32, the issue's),
    /// 1..=1024. bench sweeps 8 and 32 by default.
    restir_candidates: u32 = 32, parse parse_candidates, sweep [8, 32],
        ui "candidates M" Widget::int(1, 256);
    /// restir: neighbours a spatial iteration reuses (k; default 5, the issue's), 0..=16. bench
    /// sweeps 3 and 5 by default.
    restir_neighbours: u32 = 5, parse parse_neighbours, sweep [3, 5],
        ui "neighbours k" Widget::int(0, 16);
    /// restir: the radius the spatial neighbours are drawn in, in pixels at 1080 lines (scaled by
    /// the frame's height / 1080; default 30, the issue's), (0, 1000].
    restir_radius: f32 = 30.0, parse parse_radius, ui "radius (px at 1080p)" Widget::log(1.0, 200.0);
    /// restir: spatial iterations (n; default 2), 0..=8. bench sweeps 1 and 2 by default.
    restir_iterations: u32 = 2, parse parse_iterations, sweep [1, 2],
        ui "spatial iterations" Widget::int(0, 4);
    /// restir, with `--temporal on`: the previous frame's reservoir counts at most this many times
    /// the current pixel's candidates (the confidence cap; default 20, the issue's), (0, 1000].
    restir_cap: f32 = 20.0, parse parse_cap, ui "confidence cap (× M)" Widget::log(1.0, 100.0);
    /// restir: `biased` (the paper's Alg. 4, the default) or `unbiased` (Alg. 6 with a shadow ray
    /// from each reused pixel's point to the sample).
    restir_combine: Combine = Combine::Biased, parse parse_combine,
        ui "combination" Widget::Choice(&[("biased", "biased"), ("unbiased", "unbiased")]);
    /// restir: its lights, `vpls` (the frame's VPLs, the default) or `clusters` (the resident VPL
    /// clusters of `--vpl-clusters`, each a point light at its representative with the summed
    /// flux).
    restir_lights: RestirLights = RestirLights::Vpls, parse parse_lights,
        ui "lights" Widget::Choice(&[("vpls", "VPLs"), ("clusters", "VPL clusters")]);
}

pub fn parse_candidates(v: &str) -> Result<u32, Invalid> {
    in_range(
        v,
        |m: u32| (1..=MAX_CANDIDATES).contains(&m),
        "must be a count in 1..=1024",
    )
}

pub fn parse_neighbours(v: &str) -> Result<u32, Invalid> {
    in_range(v, |k: u32| k <= MAX_NEIGHBOURS, "must be a count in 0..=16")
}

pub fn parse_iterations(v: &str) -> Result<u32, Invalid> {
    in_range(v, |n: u32| n <= MAX_ITERATIONS, "must be a count in 0..=8")
}

pub fn parse_radius(v: &str) -> Result<f32, Invalid> {
    in_range(
        v,
        |r: f32| r > 0.0 && r <= 1000.0,
        "must be pixels at 1080 lines in (0, 1000]",
    )
}

pub fn parse_cap(v: &str) -> Result<f32, Invalid> {
    in_range(
        v,
        |c: f32| c > 0.0 && c <= 1000.0,
        "must be a multiple of the candidates in (0, 1000]",
    )
}

pub fn parse_lights(v: &str) -> Result<RestirLights, Invalid> {
    match v.trim() {
        "vpls" => Ok(RestirLights::Vpls),
        "clusters" => Ok(RestirLights::Clusters),
        _ => invalid("must be vpls or clusters"),
    }
}

pub fn parse_combine(v: &str) -> Result<Combine, Invalid> {
    match v.trim() {
        "biased" => Ok(Combine::Biased),
        "unbiased" => Ok(Combine::Unbiased),
        _ => invalid("must be biased or unbiased"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn restir_knob_ranges() {
        assert!(parse_candidates("0").is_err() && parse_candidates("1025").is_err());
        assert_eq!(parse_candidates("1"), Ok(1));
        assert_eq!(parse_candidates("1024"), Ok(1024));
        assert!(parse_neighbours("17").is_err());
        assert_eq!(parse_neighbours("0"), Ok(0));
        assert_eq!(parse_neighbours("16"), Ok(16));
        assert!(parse_iterations("9").is_err());
        assert_eq!(parse_iterations("8"), Ok(8));
        assert!(parse_radius("0").is_err() && parse_radius("1001").is_err());
        assert!(parse_radius("nan").is_err() && parse_cap("inf").is_err());
        assert_eq!(parse_radius("1000"), Ok(1000.0));
        assert!(parse_cap("0").is_err());
        assert_eq!(parse_cap("1000"), Ok(1000.0));
        assert_eq!(parse_combine("unbiased"), Ok(Combine::Unbiased));
        assert_eq!(parse_combine("biased"), Ok(Combine::Biased));
        assert!(parse_combine("fair").is_err());
        let d = RestirSettings::default();
        assert_eq!(
            (
                d.restir_candidates,
                d.restir_neighbours,
                d.restir_iterations
            ),
            (32, 5, 2)
        );
        assert_eq!(d.restir_combine, Combine::Biased);
    }
}
