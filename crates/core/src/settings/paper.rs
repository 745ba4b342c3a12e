//! `--paper`: every setting at the choice of Colom, Marques, Santos 2022 (seed 000) where the
//! default departs from it (docs/clustering.md, "The paper exactly"). Options given on the command
//! line win: `--paper --clamp 0.02` is the paper with the default clamp.

use super::{CentroidNormal, ClusterLight, ClusterSettings, FrameSettings, Weighting};

/// n_t: "a threshold of √3/2 (corresponding to the cosine of a maximum angle of π/6)" (§3.2.1); the
/// default 0.866 is the same to three digits.
pub const PAPER_NORMAL_THRESHOLD: f32 = 0.866_025_4;

/// F: "each SP is assigned to 6 clusters (F = 6)" (§4.1).
pub const PAPER_FUZZINESS: u32 = 6;

/// K_SP as a share of the pixels: the paper's intermediate setting, 8k SP clusters at 1024×720
/// (Fig. 10(b), Fig. 1(a); "≈1% of the total shading points", §4.2).
pub const PAPER_SP_SHARE: f64 = 8000.0 / (1024.0 * 720.0);

/// K_VPL as a share of the VPLs: 2k VPL clusters of the Conference Room's 8000 VPLs (Fig. 10(b),
/// Table 1).
pub const PAPER_VPL_SHARE: f64 = 2000.0 / 8000.0;

/// K_SP of the paper's intermediate setting for `pixels` (at least 1).
pub fn paper_sp_clusters(pixels: u32) -> u32 {
    ((pixels as f64 * PAPER_SP_SHARE).round() as u32).max(1)
}

/// K_VPL of the paper's intermediate setting for `vpls` (at least 1).
pub fn paper_vpl_clusters(vpls: u32) -> u32 {
    ((vpls as f64 * PAPER_VPL_SHARE).round() as u32).max(1)
}

/// Sets every setting of `frame` and `cluster` whose default departs from the paper to the paper's
/// choice, except the options `given(id)` says the command line gave (clap ids: `sp_clusters`,
/// `clamp`, ...). Where the paper says nothing (γ, iterations, VPL count, bounces, the initial
/// centroids' strata) the settings stay as they are. Marks `cluster.paper`.
pub fn apply(
    frame: &mut FrameSettings,
    cluster: &mut ClusterSettings,
    given: &dyn Fn(&str) -> bool,
) {
    let c = cluster;
    c.paper = true;
    macro_rules! set {
        ($s:ident . $field:ident = $v:expr) => {
            if !given(stringify!($field)) {
                $s.$field = $v;
            }
        };
    }
    set!(c.cluster_light = ClusterLight::Point);
    set!(c.reseed = false);
    set!(c.ring_fallback = false);
    set!(c.position_fallback = false);
    set!(c.centroid_normal = CentroidNormal::Mean);
    set!(c.normal_threshold = PAPER_NORMAL_THRESHOLD);
    set!(c.fuzziness = PAPER_FUZZINESS);
    set!(c.weighting = Weighting::InverseDistance);
    set!(c.weight_exponent = 1.0);
    // Alg. 2's W: the distances to the centroids (docs/clustering.md, "Distances for the weights").
    set!(c.weights_to_reps = false);
    set!(c.plane_gate = None);
    set!(c.visibility_facing = false);
    set!(c.temporal = false);
    set!(c.target_ms = None);
    // K of the paper's intermediate setting, scaled to this image and VPL count; an explicit 0 (no
    // clustering) stays.
    set!(c.sp_clusters = paper_sp_clusters(frame.pixels()));
    set!(c.vpl_clusters = paper_vpl_clusters(frame.vpls));
    // The paper does not clamp the G-term (its Eq. 5 and 6 have none).
    set!(frame.clamp = 0.0);
    set!(frame.indirect_scale = 1.0);
}

/// The settings with `--paper` and nothing else given (`clap` defaults, then `apply`).
pub fn paper_defaults() -> (FrameSettings, ClusterSettings) {
    let mut f = FrameSettings::DEFAULT;
    let mut c = ClusterSettings::DEFAULT;
    apply(&mut f, &mut c, &|_| false);
    (f, c)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every adaptation off and the paper's numbers; the choices the paper leaves open (γ,
    /// iterations, VPLs) as they were.
    #[test]
    fn paper_sets_the_papers_choices() {
        let (f, c) = paper_defaults();
        let d = ClusterSettings::default();
        assert!(c.paper && !d.paper);
        assert_eq!(c.cluster_light, ClusterLight::Point);
        assert_eq!(c.adaptations(), super::super::Adaptations::none());
        assert_eq!(d.adaptations(), super::super::Adaptations::default());
        assert_eq!(c.normal_threshold, 3f32.sqrt() / 2.0);
        assert_eq!(
            (c.fuzziness, c.weighting, c.weight_exponent),
            (6, Weighting::InverseDistance, 1.0)
        );
        assert_eq!((c.gamma, c.iterations), (d.gamma, d.iterations));
        // 640×480 and 8192 VPLs: 8000 · 307200 / 737280 = 3333, 8192 / 4 = 2048.
        assert_eq!((c.sp_clusters, c.vpl_clusters), (3333, 2048));
        assert_eq!((f.clamp, f.vpls), (0.0, 8192));
        // 1024×720 and 8000 VPLs: the paper's own 8000 / 2000.
        assert_eq!(paper_sp_clusters(1024 * 720), 8000);
        assert_eq!(paper_vpl_clusters(8000), 2000);
    }

    /// An option given on the command line wins over `--paper`.
    #[test]
    fn given_options_win() {
        let mut f = FrameSettings::DEFAULT;
        let mut c = ClusterSettings::DEFAULT;
        f.clamp = 0.01;
        c.cluster_light = ClusterLight::Spread;
        c.sp_clusters = 0;
        let given = |id: &str| matches!(id, "clamp" | "cluster_light" | "sp_clusters");
        apply(&mut f, &mut c, &given);
        assert_eq!(
            (f.clamp, c.cluster_light, c.sp_clusters),
            (0.01, ClusterLight::Spread, 0)
        );
        assert!(!c.reseed && c.paper);
    }
}
