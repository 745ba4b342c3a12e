//! The CVRTGI method's knobs (Cosin Ayerbe & Patow 2022, seed 003; `method::cvrtgi`, docs/cvrtgi.md),
//! declared once with `knobs!`, and their value parsers.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::settings::{Invalid, Widget, in_range, invalid, knobs};

/// How a face takes the light of a cluster its rays found (`--cluster-gather`; docs/cvrtgi.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ClusterGather {
    /// Not in the paper: as `AnyHit`, each cluster's light scaled so that the faces whose rays
    /// met it receive, in all, the flux its VPLs send into the scene (`escape`).
    #[default]
    Conserved,
    /// The paper's §4.4: a cluster any of the face's rays met gives its whole light, as a point
    /// at its light's position (and its lit voxels one by one when near).
    AnyHit,
}

impl ClusterGather {
    pub fn name(self) -> &'static str {
        match self {
            ClusterGather::Conserved => "conserved",
            ClusterGather::AnyHit => "any-hit",
        }
    }
}

impl fmt::Display for ClusterGather {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The most voxels along the longest axis of the scene (`--voxel-res`): the paper's largest grid
/// (256³). The per-face visibility cache holds `--face-rays` cluster ids for every exposed voxel
/// face (about 12 N² faces for a closed room), 256 × 64 rays is already ~200 MiB, past one storage
/// binding on lavapipe (128 MiB); `method::cvrtgi` checks the actual size against the adapter.
pub const MAX_VOXEL_RES: u32 = 256;

knobs! {
    /// The knobs of the CVRTGI method (Cosin Ayerbe & Patow 2022, seed 003; `method::cvrtgi`,
    /// docs/methods.md), flattened into `method::MethodSettings` and so into `render`, `view` and
    /// (as lists) `bench`.
    pub struct CvrtgiSettings, lists CvrtgiLists, heading "CVRTGI (voxel clusters)";
    /// Voxels along the longest axis of the scene bounds (§4.1), 1..=256.
    voxel_res: u32 = 32, parse parse_voxel_res, ui "voxels (longest axis)" Widget::int(8, 128);
    /// Spacing in voxels of the SLIC seeds (§4.2, Achanta et al.'s S), 1..=64. Fewer, larger
    /// clusters are found by more of a face's rays (docs/cvrtgi.md measures 4, 6 and 8).
    cluster_step: u32 = 8, parse parse_cluster_step, ui "SLIC seed spacing" Widget::int(1, 32);
    /// Iterations of Alg. 1's loop (the paper: 10), 0..=100.
    cluster_iterations: u32 = 10, parse parse_cluster_iterations;
    /// Eq. (1)'s angle in degrees: a voxel joins a cluster whose normal is within it (the paper:
    /// 35), (0, 180].
    cluster_angle: f32 = 35.0, parse parse_cluster_angle;
    /// Rays per exposed voxel face for the cluster visibility cache (§4.3; the paper: 32..128,
    /// 128 by default), 1..=1024.
    face_rays: u32 = 128, parse parse_face_rays, ui "rays per face" Widget::int_log(8, 512);
    /// Clusters nearer than this many voxels to a face give their lit voxels one by one instead of
    /// the cluster as one light (§4.4), [0, 64].
    near_voxels: f32 = 2.0, parse parse_near_voxels;
    /// Radius r of the Gaussian filter over same-direction faces of neighbouring voxels (§4.4: a
    /// 5³ kernel is r = 2), 0..=4.
    filter_radius: u32 = 2, parse parse_filter_radius;
    /// Times the filter is applied (the paper: twice), 0..=8.
    filter_passes: u32 = 2, parse parse_filter_passes, ui "filter passes" Widget::int(0, 8);
    /// How a face takes a cluster its rays met: `any-hit` (§4.4: the whole cluster as a point
    /// light) or `conserved` (not in the paper, the default: the same, scaled per cluster so that
    /// the faces whose rays met it receive, in all, the flux it sends) (docs/cvrtgi.md).
    cluster_gather: ClusterGather = ClusterGather::Conserved, parse parse_cluster_gather,
        ui "cluster light" Widget::Choice(&[("conserved", "conserved"), ("any-hit", "any hit (paper)")]);
    /// Rays per VPL that find where its light goes (not in the paper): its flux is weighed by the
    /// fraction that leaves its surface (past a tenth of a voxel), and `conserved` takes the
    /// fraction that meets a surface as what it sends; 0: every VPL counts whole, as the paper's
    /// lit voxels. 0..=256.
    escape_rays: u32 = 16, parse parse_escape_rays, ui "escape rays per VPL" Widget::int(0, 64);
}

pub fn parse_cluster_gather(v: &str) -> Result<ClusterGather, Invalid> {
    match v.trim() {
        "conserved" => Ok(ClusterGather::Conserved),
        "any-hit" => Ok(ClusterGather::AnyHit),
        _ => invalid("must be conserved or any-hit"),
    }
}

pub fn parse_escape_rays(v: &str) -> Result<u32, Invalid> {
    in_range(v, |n: u32| n <= 256, "must be 0..=256")
}

pub fn parse_voxel_res(v: &str) -> Result<u32, Invalid> {
    match v.trim().parse::<u32>() {
        Ok(0) => invalid("must be at least 1 (voxels along the scene's longest axis)"),
        Ok(n) if n > MAX_VOXEL_RES => invalid(format!(
            "at most {MAX_VOXEL_RES}: beyond it the per-face cluster visibility cache outgrows GPU memory"
        )),
        Ok(n) => Ok(n),
        Err(_) => invalid("must be a whole number 1..=256"),
    }
}

pub fn parse_cluster_step(v: &str) -> Result<u32, Invalid> {
    in_range(v, |n: u32| (1..=64).contains(&n), "must be 1..=64 voxels")
}

pub fn parse_cluster_iterations(v: &str) -> Result<u32, Invalid> {
    in_range(v, |n: u32| n <= 100, "must be 0..=100")
}

pub fn parse_cluster_angle(v: &str) -> Result<f32, Invalid> {
    in_range(
        v,
        |d: f32| d > 0.0 && d <= 180.0,
        "must be an angle in (0, 180] degrees",
    )
}

pub fn parse_face_rays(v: &str) -> Result<u32, Invalid> {
    in_range(v, |n: u32| (1..=1024).contains(&n), "must be 1..=1024")
}

pub fn parse_near_voxels(v: &str) -> Result<f32, Invalid> {
    in_range(
        v,
        |d: f32| (0.0..=64.0).contains(&d),
        "must be a number of voxels in [0, 64]",
    )
}

pub fn parse_filter_radius(v: &str) -> Result<u32, Invalid> {
    in_range(v, |n: u32| n <= 4, "must be 0..=4 (a (2r+1)³ kernel)")
}

pub fn parse_filter_passes(v: &str) -> Result<u32, Invalid> {
    in_range(v, |n: u32| n <= 8, "must be 0..=8")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cvrtgi_parsers_refuse_zero_and_beyond_memory() {
        assert_eq!(parse_voxel_res("32"), Ok(32));
        assert_eq!(parse_voxel_res("256"), Ok(256));
        let zero = parse_voxel_res("0").unwrap_err().0;
        assert!(zero.contains("at least 1"), "{zero}");
        let big = parse_voxel_res("257").unwrap_err().0;
        assert!(big.contains("memory") && !big.contains('\n'), "{big}");
        assert!(parse_voxel_res("x").is_err());
        assert!(parse_cluster_step("0").is_err() && parse_cluster_step("65").is_err());
        assert!(parse_cluster_angle("0").is_err() && parse_cluster_angle("NaN").is_err());
        assert!(parse_face_rays("0").is_err() && parse_face_rays("1025").is_err());
        assert!(parse_near_voxels("-1").is_err());
        assert!(parse_filter_radius("5").is_err() && parse_filter_passes("9").is_err());
        // The edges: the last value in on each side (cargo-mutants: a `<=` turned `<` survived).
        assert_eq!(parse_voxel_res("1"), Ok(1));
        assert_eq!(parse_cluster_step("1"), Ok(1));
        assert_eq!(parse_cluster_step("64"), Ok(64));
        assert_eq!(parse_cluster_iterations("0"), Ok(0));
        assert_eq!(parse_cluster_iterations("100"), Ok(100));
        assert!(parse_cluster_iterations("101").is_err());
        assert_eq!(parse_cluster_angle("180"), Ok(180.0));
        assert_eq!(parse_cluster_angle("0.01"), Ok(0.01));
        assert!(parse_cluster_angle("180.1").is_err());
        assert_eq!(parse_face_rays("1"), Ok(1));
        assert_eq!(parse_face_rays("1024"), Ok(1024));
        assert_eq!(parse_near_voxels("0"), Ok(0.0));
        assert_eq!(parse_near_voxels("64"), Ok(64.0));
        assert!(parse_near_voxels("64.1").is_err());
        assert_eq!(parse_filter_radius("0"), Ok(0));
        assert_eq!(parse_filter_radius("4"), Ok(4));
        assert_eq!(parse_filter_passes("0"), Ok(0));
        assert_eq!(parse_filter_passes("8"), Ok(8));
        assert_eq!(parse_cluster_gather("any-hit"), Ok(ClusterGather::AnyHit));
        assert_eq!(
            parse_cluster_gather("conserved"),
            Ok(ClusterGather::Conserved)
        );
        assert!(parse_cluster_gather("any").is_err());
        assert_eq!(parse_escape_rays("0"), Ok(0));
        assert_eq!(parse_escape_rays("256"), Ok(256));
        assert!(parse_escape_rays("257").is_err());
        let c = CvrtgiSettings::default();
        let j = serde_json::to_string(&c).unwrap();
        assert_eq!(serde_json::from_str::<CvrtgiSettings>(&j).unwrap(), c);
    }
}
