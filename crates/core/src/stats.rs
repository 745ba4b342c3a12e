//! The stats JSON of docs/design.md, "Stats JSON" (a contract: extend it, never break it).

use std::collections::BTreeMap;

use serde::Serialize;

use crate::exposure::Exposure;
use crate::method::MethodSettings;
use crate::metrics;
use crate::render::{Frame, RenderSettings};
use crate::scene::Scene;
use crate::settings::{ClusterSettings, FrameSettings, Gamma, LightSettings};

/// The settings block: the settings types as they are (`crate::settings`), with the values the
/// frame resolved (γ and exposure as used, F in effect, the VPLs traced) and what only a frame knows.
#[derive(Clone, Debug, Serialize)]
pub struct Settings {
    /// F is the F in effect (1 for hard), γ the γ asked or, with `gamma_auto`, the one the rule chose
    /// for this size and K (`Gamma::resolve`); the plane gate only when it gated a fuzzy frame.
    #[serde(flatten)]
    pub cluster: ClusterSettings,
    /// The method and every method's knobs (`method::MethodSettings`).
    #[serde(flatten)]
    pub method: MethodSettings,
    /// `vpls` as traced; `exposure` the PNG exposure used (with `exposure_auto` the one
    /// `exposure::auto_exposure` chose for this image); EXR is never scaled.
    #[serde(flatten)]
    pub frame: FrameSettings,
    #[serde(flatten)]
    pub lights: LightSettings,
    /// γ was `auto` (the default): `gamma` is what the rule chose.
    pub gamma_auto: bool,
    /// `--exposure auto` (the default).
    pub exposure_auto: bool,
    pub reference: bool,
    /// γ and n_t as the SP k-means used them (`Gamma::effective`, at most 1 − 2⁻²⁰): γ is at most
    /// pixels / K (absent when no SP clustering ran).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gamma_used: Option<u32>,
    pub normal_threshold_used: f32,
    /// Samples per pixel of `--path-trace` (the frame is the path tracer's alone; the VPL and
    /// clustering settings above were not used).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub path_trace_spp: Option<u32>,
}

impl Settings {
    /// The block of a frame rendered with `s` and `lights`, written with `exposure`.
    pub fn new(
        s: &RenderSettings,
        lights: &LightSettings,
        frame: &Frame,
        exposure: f32,
        path_trace_spp: Option<u32>,
    ) -> Settings {
        let c = &s.cluster;
        let pixels = frame.width * frame.height;
        Settings {
            cluster: ClusterSettings {
                fuzziness: c.f(),
                gamma: Gamma::Fixed(c.gamma.resolve(pixels, c.sp_clusters)),
                plane_gate: c
                    .plane_gate
                    .filter(|_| frame.gamma_used.is_some() && c.f() > 1),
                ..c.clone()
            },
            method: s.method,
            frame: FrameSettings {
                vpls: frame.vpls,
                exposure: Exposure::Fixed(exposure),
                ..s.frame
            },
            lights: lights.clone(),
            gamma_auto: c.gamma.is_auto(),
            exposure_auto: s.frame.exposure.is_auto(),
            reference: s.reference,
            gamma_used: frame.gamma_used,
            normal_threshold_used: c.normal_threshold_used(),
            path_trace_spp,
        }
    }
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
    /// The method's own report under its name (`Frame::report`: e.g. an SP clustering's
    /// iterations, a voxel grid's sizes; absent for a method without one).
    #[serde(flatten)]
    pub method: BTreeMap<String, serde_json::Value>,
}

impl Counts {
    /// What `frame` of `scene` counted; `emissive_triangles` as uploaded.
    pub fn new(scene: &Scene, frame: &Frame, emissive_triangles: u64) -> Counts {
        Counts {
            triangles: scene.triangles.len() as u64,
            vpls: frame.vpls as u64,
            sp_clusters_used: frame.sp_clusters_used as u64,
            vpl_clusters_used: frame.vpl_clusters_used as u64,
            shading_points: frame.shading_points as u64,
            shadow_rays: frame.shadow_rays,
            emissive_triangles,
            punctual_lights: scene.lights.len() as u64,
            method: (frame.report.iter())
                .map(|(m, v)| (m.name().to_string(), v.clone()))
                .collect(),
        }
    }
}

/// The error block (docs/design.md, "Error metrics").
#[derive(Clone, Debug, Serialize)]
pub struct ErrorStats {
    pub mse: f64,
    pub rel_mse: f64,
    /// Mean FLIP of the tone-mapped images (both with the reference's exposure).
    pub flip: f64,
    /// The error of the steps across SP-cluster borders (`metrics::BorderError::border`); absent
    /// when the frame clustered no shading points.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub border: Option<f64>,
    /// The same inside clusters (`metrics::BorderError::interior`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interior: Option<f64>,
    /// border ÷ interior.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub border_ratio: Option<f64>,
    /// Mean FLIP over the pixels next to an SP-cluster border.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flip_border: Option<f64>,
}

impl ErrorStats {
    /// Every measure of `x` against `reference` (`width` × `height`), tone-mapped with `exposure`
    /// (the reference's), with the cluster borders of `labels` (each pixel's nearest SP cluster,
    /// `metrics::NO_LABEL` where none); also the per-pixel FLIP map.
    pub fn measure(
        x: &[[f32; 3]],
        reference: &[[f32; 3]],
        width: u32,
        height: u32,
        exposure: f32,
        labels: Option<&[u32]>,
    ) -> (ErrorStats, Vec<f32>) {
        let map = metrics::flip_map(metrics::FlipInputs {
            x,
            reference,
            width,
            height,
            exposure,
        });
        let border = labels.and_then(|l| {
            metrics::border_error(
                &metrics::display(x, exposure),
                &metrics::display(reference, exposure),
                l,
                width,
                height,
                Some(&map),
            )
        });
        let e = ErrorStats {
            mse: metrics::mse(x, reference),
            rel_mse: metrics::rel_mse(x, reference),
            flip: map.iter().map(|&v| v as f64).sum::<f64>() / map.len().max(1) as f64,
            border: border.map(|b| b.border),
            interior: border.map(|b| b.interior),
            border_ratio: border.and_then(|b| b.ratio),
            flip_border: border.and_then(|b| b.flip_border),
        };
        (e, map)
    }

    /// One line for stderr: `MSE … rel_mse … FLIP …` and the border measures when there are.
    pub fn line(&self) -> String {
        let mut s = format!(
            "MSE {:.4e}  rel_mse {:.4e}  FLIP {:.4}",
            self.mse, self.rel_mse, self.flip
        );
        if let (Some(b), Some(i)) = (self.border, self.interior) {
            s += &format!("  border {b:.3e} (interior {i:.3e}");
            if let Some(r) = self.border_ratio {
                s += &format!(", ratio {r:.2}");
            }
            s += ")";
        }
        if let Some(f) = self.flip_border {
            s += &format!("  FLIP at borders {f:.4}");
        }
        s
    }
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
    /// Milliseconds of GPU work run before the timed renders (`--warmup-ms`, crates/core/src/gpu/warmup.rs).
    pub warmup_ms: f64,
    /// The driver (`gpu::driver_name`) and whether the adapter is "software" (lavapipe: its times
    /// say little about a GPU's) or "hardware".
    pub driver: String,
    pub device_type: String,
    pub mean_luminance: f64,
    /// The indirect light alone (`Frame::indirect`, linear): where the methods differ, about a
    /// quarter of the image's light in the built-in rooms.
    pub mean_luminance_indirect: f64,
    pub bvh_build_ms: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<ErrorStats>,
    /// With `--target-ms`: the budget and the frames that chose the K's (`settings` holds the K's
    /// chosen, the last step's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target: Option<Target>,
}

/// `--target-ms`: the budget and each frame the controller rendered (`render::budget`).
#[derive(Clone, Debug, Serialize)]
pub struct Target {
    pub target_ms: f64,
    pub steps: Vec<crate::render::budget::Step>,
}
