//! lightcluster's knobs (LightCluster, seed 002; docs/methods.md): d_init of §3.1.2's d_min. The
//! cluster count is its outcome.

use crate::settings::{Invalid, in_range, knobs};

knobs! {
    /// lightcluster's knobs, flattened into `method::MethodSettings`.
    pub struct LightClusterSettings, lists LightClusterLists, heading super::super::METHOD_HEADING;
    /// lightcluster: d_init of d_min = d_init (1 − |C_pos| / z_far), in scene diagonals, (0, 10];
    /// the cluster count is its outcome (the paper's scenes used 0.1–1.6 scene units and 4–40
    /// clusters). bench sweeps 1, 1.2, 1.8, 2 and 2.2 by default: 28 and 7 clusters on the
    /// conference room, 28, 12 and 8 on the Cornell box (docs/methods.md).
    d_init: f32 = 1.0, parse parse_d_init, sweep [1.0, 1.2, 1.8, 2.0, 2.2];
}

pub fn parse_d_init(v: &str) -> Result<f32, Invalid> {
    in_range(
        v,
        |d: f32| d > 0.0 && d <= 10.0,
        "must be a distance in (0, 10] scene diagonals",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn d_init_range() {
        assert!(parse_d_init("0").is_err() && parse_d_init("-0.1").is_err());
        assert!(parse_d_init("inf").is_err() && parse_d_init("11").is_err());
        assert_eq!(parse_d_init("0.5"), Ok(0.5));
        // The edges (cargo-mutants: a `<=` turned `<` survived the out-of-range tests alone).
        assert_eq!(parse_d_init("10"), Ok(10.0));
        assert_eq!(parse_d_init("0.001"), Ok(0.001));
    }
}
