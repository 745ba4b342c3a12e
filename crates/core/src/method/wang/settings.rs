//! wang's knobs (Wang et al. 2009, seed 001; docs/methods.md): Eq. (2)'s α. Its K is the SP
//! clustering's (`--sp-clusters`) and its iterations the k-means' (`--iterations`).

use crate::settings::{Invalid, Widget, in_range, knobs};

knobs! {
    /// wang's knobs, flattened into `method::MethodSettings`.
    pub struct WangSettings, lists WangLists, heading super::super::METHOD_HEADING;
    /// wang: α of Eq. (2), the position term's weight with positions in scene diagonals, (0, 100]
    /// (the paper: 0.1–0.5).
    wang_alpha: f32 = 0.3, parse parse_wang_alpha,
        ui "α (Eq. 2: position against normal)" Widget::log(0.01, 100.0);
}

pub fn parse_wang_alpha(v: &str) -> Result<f32, Invalid> {
    in_range(
        v,
        |a: f32| a > 0.0 && a <= 100.0,
        "must be a number in (0, 100]",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alpha_range() {
        assert!(parse_wang_alpha("0").is_err() && parse_wang_alpha("-1").is_err());
        assert!(parse_wang_alpha("NaN").is_err() && parse_wang_alpha("101").is_err());
        assert_eq!(parse_wang_alpha("0.3"), Ok(0.3));
        // The edges (cargo-mutants: a `<=` turned `<` survived the out-of-range tests alone).
        assert_eq!(parse_wang_alpha("100"), Ok(100.0));
        assert_eq!(parse_wang_alpha("0.001"), Ok(0.001));
        assert_eq!(WangSettings::default().wang_alpha, 0.3);
    }
}
