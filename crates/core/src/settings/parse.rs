//! The settings' value parsers: one line of error each (`cli::parse` prefixes the option and the
//! value), used by the command line (with the feature `cli`), `knobs!`'s `set` and the viewer.

use std::str::FromStr;

use super::*;
use crate::exposure::Exposure;

pub fn in_range<T: PartialOrd + Copy + FromStr>(
    v: &str,
    ok: impl Fn(T) -> bool,
    what: &str,
) -> Result<T, Invalid> {
    match v.trim().parse::<T>() {
        Ok(x) if ok(x) => Ok(x),
        _ => invalid(what),
    }
}

pub fn parse_fuzziness(v: &str) -> Result<u32, Invalid> {
    in_range(v, |f: u32| (1..=MAX_F).contains(&f), "must be 1..16")
}

pub fn parse_gamma(v: &str) -> Result<Gamma, Invalid> {
    v.parse()
}

pub fn parse_normal_threshold(v: &str) -> Result<f32, Invalid> {
    in_range(
        v,
        |x: f32| (-1.0..=1.0).contains(&x),
        "must be a cosine in [-1, 1]",
    )
}

pub fn parse_iterations(v: &str) -> Result<u32, Invalid> {
    in_range(v, |i: u32| i <= 1000, "must be 0..=1000")
}

pub fn parse_weight_exponent(v: &str) -> Result<f32, Invalid> {
    in_range(
        v,
        |p: f32| (0.0..=64.0).contains(&p),
        "must be a number in [0, 64]",
    )
}

pub fn parse_temporal_alpha(v: &str) -> Result<f32, Invalid> {
    in_range(
        v,
        |a: f32| a > 0.0 && a <= 1.0,
        "must be a number in (0, 1]",
    )
}

pub fn parse_plane_gate(v: &str) -> Result<f32, Invalid> {
    in_range(
        v,
        |d: f32| d > 0.0 && d <= 90.0,
        "must be an angle in (0, 90] degrees",
    )
}

/// A `bench --plane-gate` item: `off` (the paper: `None`) or an angle in (0, 90] degrees.
pub fn parse_plane_gate_or_off(v: &str) -> Result<Option<f32>, Invalid> {
    if v.trim().eq_ignore_ascii_case("off") {
        return Ok(None);
    }
    parse_plane_gate(v)
        .map(Some)
        .map_err(|_| Invalid("must be off or an angle in (0, 90] degrees".into()))
}

pub fn parse_target_ms(v: &str) -> Result<f64, Invalid> {
    in_range(
        v,
        |x: f64| x.is_finite() && x > 0.0 && x <= 1e7,
        "must be a time in ms, > 0 and at most 1e7",
    )
}

pub fn parse_on_off(v: &str) -> Result<bool, Invalid> {
    match v.trim() {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => invalid("expected `on` or `off`"),
    }
}

pub fn parse_side(v: &str) -> Result<u32, Invalid> {
    in_range(v, |s: u32| (1..=MAX_SIDE).contains(&s), "must be 1..16384")
}

pub fn parse_bounces(v: &str) -> Result<u32, Invalid> {
    in_range(v, |b: u32| (1..=MAX_BOUNCES).contains(&b), "must be 1..64")
}

pub fn parse_direct_samples(v: &str) -> Result<u32, Invalid> {
    in_range(
        v,
        |n: u32| (1..=MAX_DIRECT_SAMPLES).contains(&n),
        "must be 1..=65536",
    )
}

pub fn parse_exposure(v: &str) -> Result<Exposure, Invalid> {
    Exposure::parse(v).map_err(Invalid)
}

pub fn parse_clamp(v: &str) -> Result<f32, Invalid> {
    in_range(v, |c: f32| (0.0..1.0).contains(&c), "must be in [0, 1)")
}

pub fn parse_indirect_scale(v: &str) -> Result<f32, Invalid> {
    in_range(
        v,
        |x: f32| x > 0.0 && x <= 1.0,
        "must be a fraction of the image's size in (0, 1]",
    )
}

pub fn parse_light_scale(v: &str) -> Result<f32, Invalid> {
    in_range(
        v,
        |x: f32| x.is_finite() && x >= 0.0,
        "must be a finite number >= 0",
    )
}

pub fn parse_warmup_ms(v: &str) -> Result<f64, Invalid> {
    in_range(
        v,
        |ms: f64| (0.0..=60_000.0).contains(&ms),
        "must be milliseconds from 0 to 60000",
    )
}
