//! lightcluster's knobs (LightCluster, seed 002; docs/methods.md): d_init of §3.1.2's d_min. The
//! cluster count is its outcome.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::settings::{Invalid, Widget, in_range, invalid, knobs};

/// What a cluster's shadow rays aim at (`--lightcluster-visibility`; docs/methods.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LcVisibility {
    /// Not in the paper: one ray to a target member of each of the cluster's member groups, each
    /// VPL taking its group's visibility (`cluster::split_members`).
    #[default]
    Members,
    /// The paper's §3.2.2: `DISC_SAMPLES` rays to points of a disc of radius d_min at the centre,
    /// every member taking the fraction seen.
    Disc,
}

impl LcVisibility {
    pub fn name(self) -> &'static str {
        match self {
            LcVisibility::Members => "members",
            LcVisibility::Disc => "disc",
        }
    }
}

impl fmt::Display for LcVisibility {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

knobs! {
    /// lightcluster's knobs, flattened into `method::MethodSettings`.
    pub struct LightClusterSettings, lists LightClusterLists, heading super::super::METHOD_HEADING;
    /// lightcluster: d_init of d_min = d_init (1 − |C_pos| / z_far), in scene diagonals, (0, 10];
    /// the cluster count is its outcome (the paper's scenes used 0.1–1.6 scene units and 4–80
    /// clusters: its Table 1 has 80, 44, 26 and 10 for Sponza, 13 to 4 and 12 to 7 for the
    /// others). bench sweeps 1, 1.2, 1.8, 2 and 2.2 by default: 28 and 7 clusters on the
    /// conference room, 28, 12 and 8 on the Cornell box (docs/methods.md).
    d_init: f32 = 1.0, parse parse_d_init, sweep [1.0, 1.2, 1.8, 2.0, 2.2],
        ui "d_init (scene diagonals)" Widget::log(0.001, 10.0);
    /// lightcluster: what a cluster's shadow rays aim at: `members` (not in the paper, the
    /// default: a target member of each of up to 8 member groups, every VPL taking its group's
    /// visibility) or `disc` (§3.2.2: 8 points of a disc of radius d_min, every VPL taking the
    /// fraction seen) (docs/methods.md).
    lightcluster_visibility: LcVisibility = LcVisibility::Members, parse parse_lc_visibility,
        ui "rays to" Widget::Choice(&[("members", "member VPLs"), ("disc", "the disc (paper)")]);
}

pub fn parse_lc_visibility(v: &str) -> Result<LcVisibility, Invalid> {
    match v.trim() {
        "members" => Ok(LcVisibility::Members),
        "disc" => Ok(LcVisibility::Disc),
        _ => invalid("must be members or disc"),
    }
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
        assert_eq!(parse_lc_visibility("disc"), Ok(LcVisibility::Disc));
        assert_eq!(parse_lc_visibility("members"), Ok(LcVisibility::Members));
        assert!(parse_lc_visibility("points").is_err());
        assert_eq!(LcVisibility::default(), LcVisibility::Members);
    }
}
