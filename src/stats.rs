//! The stats JSON of docs/design.md, "Stats JSON" (a contract: extend it, never break it).

use std::collections::BTreeMap;

use serde::Serialize;

#[derive(Clone, Debug, Serialize)]
pub struct Settings {
    pub vpls: u32,
    pub vpl_clusters: u32,
    pub sp_clusters: u32,
    pub fuzziness: u32,
    /// γ asked; with `gamma_auto` the auto rule's choice for this size and K (`kmeans::resolve_gamma`).
    pub gamma: u32,
    /// γ was `auto` (the default): `gamma` is what the rule chose.
    pub gamma_auto: bool,
    pub normal_threshold: f32,
    pub iterations: u32,
    pub weighting: String,
    /// p of the inverse-distance weights (w'_f = dist^-p; Eq. 10: 1).
    pub weight_exponent: f32,
    pub reference: bool,
    pub seed: u32,
    pub direct_samples: u32,
    pub light_scale: f32,
    /// The PNG exposure used: with `exposure_auto` the one `exposure::auto_exposure` chose for this
    /// image (its log-average luminance shown as 0.18); EXR is never scaled.
    pub exposure: f32,
    /// `--exposure auto` (the default).
    pub exposure_auto: bool,
    /// G-term clamp as a fraction of the scene diagonal.
    pub clamp: f32,
    /// γ and n_t as the SP k-means used them (`kmeans::effective_gamma`,
    /// `effective_normal_threshold`): γ is at most pixels / K (absent when no SP clustering ran),
    /// n_t at most 1 − 2⁻²⁰.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gamma_used: Option<u32>,
    pub normal_threshold_used: f32,
    /// The indirect bounce budget.
    pub bounces: u32,
    /// Samples per pixel of `--path-trace` (the frame is the path tracer's alone; the VPL and
    /// clustering settings above were not used).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub path_trace_spp: Option<u32>,
    /// The plane gate of the fuzzy F lists in degrees (`--plane-gate`; not in the paper): absent
    /// when off or when it had nothing to gate (no SP clustering, or F = 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub plane_gate_deg: Option<f32>,
    /// Temporal reuse (`--temporal`).
    pub temporal: bool,
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct Counts {
    pub triangles: u64,
    pub vpls: u64,
    pub shading_points: u64,
    pub sp_clusters_used: u64,
    pub vpl_clusters_used: u64,
    pub shadow_rays: u64,
    pub emissive_triangles: u64,
    pub punctual_lights: u64,
    /// Alg. 1 iterations the SP clustering ran (0: none ran).
    pub sp_iterations: u32,
    /// SP centroids a temporal warm start kept from the previous render (absent: a cold start).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sp_warm_kept: Option<u32>,
    /// Rows of the visibility matrix copied from the previous render (kept representatives).
    pub visibility_rows_reused: u32,
}

#[derive(Clone, Debug, Serialize)]
pub struct ErrorStats {
    pub mse: f64,
    pub rel_mse: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Stats {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub adapter: String,
    pub settings: Settings,
    pub counts: Counts,
    pub passes: Vec<String>,
    /// GPU timestamp durations; with `--repeat N` the mean of the 3 best of N (the paper's method).
    pub timings_ms: BTreeMap<String, f64>,
    pub repeat: u32,
    pub mean_luminance: f64,
    pub bvh_build_ms: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<ErrorStats>,
}

/// Every timing key of the contract, so readers can index them; passes that did not run read 0.
pub const TIMING_KEYS: &[&str] = &[
    "vpl_trace",
    "vpl_cluster",
    "primary",
    "sp_cluster",
    "visibility",
    "shade",
    "direct",
    "reference",
    "gather",
    "frame",
];

/// Mean of the `k` smallest values (all of them if fewer): the paper's "3-best" timing.
pub fn mean_of_best(values: &[f64], k: usize) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let k = k.clamp(1, v.len());
    v[..k].iter().sum::<f64>() / k as f64
}

/// Per-key mean of the 3 best over several runs' timings, with every contract key present.
pub fn best_of_runs(runs: &[BTreeMap<String, f64>]) -> BTreeMap<String, f64> {
    let mut keys: Vec<String> = TIMING_KEYS.iter().map(|s| s.to_string()).collect();
    for r in runs {
        for k in r.keys() {
            if !keys.contains(k) {
                keys.push(k.clone());
            }
        }
    }
    keys.into_iter()
        .map(|k| {
            let vals: Vec<f64> = runs
                .iter()
                .map(|r| r.get(&k).copied().unwrap_or(0.0))
                .collect();
            (k, mean_of_best(&vals, 3))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn best_three_of_ten() {
        let v = [9.0, 1.0, 8.0, 2.0, 7.0, 3.0, 6.0, 4.0, 5.0, 10.0];
        assert_eq!(mean_of_best(&v, 3), 2.0);
        assert_eq!(mean_of_best(&[5.0], 3), 5.0);
        assert_eq!(mean_of_best(&[], 3), 0.0);
    }

    #[test]
    fn every_contract_key_present() {
        let mut r = BTreeMap::new();
        r.insert("primary".to_string(), 2.0);
        let b = best_of_runs(&[r]);
        for k in TIMING_KEYS {
            assert!(b.contains_key(*k), "{k}");
        }
        assert_eq!(b["primary"], 2.0);
        assert_eq!(b["vpl_trace"], 0.0);
    }
}
