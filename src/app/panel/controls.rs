//! The panel's method and clustering controls: the method selector and the chosen method's
//! declared knobs, the paper's adaptations, and colom's clustering knobs.

use egui::{Slider, Ui};

use crate::app::{SliderRanges, UiSettings};
use crate::method::{Method, MethodSettings};
use crate::settings::{CentroidNormal, ClusterLight, Weighting, Widget};

/// The method selector and the chosen method's own knobs (its room's panel section).
pub(super) fn method_controls(ui: &mut Ui, s: &mut UiSettings) {
    ui.horizontal(|ui| {
        ui.label("method");
        for r in crate::method::ROOMS {
            ui.selectable_value(&mut s.method.method, r.method, r.method.name())
                .on_hover_text(r.about);
        }
    });
    knob_controls(ui, &mut s.method);
}

/// The chosen method's own knobs, drawn from their declarations (`knobs!`'s `ui "label"
/// control`): a slider over the declared range and scale, or a radio button a value. A value
/// goes back through the knob's parser, so the panel sets only what `--option` would accept.
fn knob_controls(ui: &mut Ui, m: &mut MethodSettings) {
    for c in m.controls() {
        let Some(text) = m.knob(c.name) else {
            continue;
        };
        let next = match c.widget {
            Widget::Slider {
                lo,
                hi,
                log,
                integer,
            } => {
                let Ok(old) = text.parse::<f64>() else {
                    continue;
                };
                let mut v = old;
                let slider = Slider::new(&mut v, lo..=hi).logarithmic(log).text(c.label);
                ui.add(if integer { slider.integer() } else { slider });
                (v != old).then(|| match integer {
                    true => format!("{}", v.round()),
                    false => format!("{v}"),
                })
            }
            Widget::Choice(values) => {
                let mut pick = None;
                ui.horizontal(|ui| {
                    ui.label(c.label);
                    for &(value, label) in values {
                        if ui.radio(text == value, label).clicked() && text != value {
                            pick = Some(value.to_string());
                        }
                    }
                });
                pick
            }
        };
        if let Some(t) = next {
            // A value its parser refuses leaves the knob as it was.
            let _ = m.set_column(c.name, &t);
        }
    }
}

/// "the paper" (`--paper`) and each adaptation of the paper's method as its own switch
/// (docs/clustering.md, "The paper exactly").
fn adaptation_controls(ui: &mut Ui, s: &mut UiSettings, colom: bool) {
    let mut paper = s.cluster.paper;
    let w = (s.frame.width, s.frame.height);
    if ui
        .checkbox(&mut paper, "the paper")
        .on_hover_text(
            "Every setting at the paper's choice (--paper): point cluster lights, no re-seeding, \
             no fallbacks, mean centroid normals, n_t = √3/2, F 6, weighted, the paper's K ratios, \
             no G-term clamp",
        )
        .changed()
    {
        s.set_paper(paper, w.0, w.1);
    }
    ui.horizontal(|ui| {
        ui.label("cluster lights");
        ui.selectable_value(&mut s.cluster.cluster_light, ClusterLight::Point, "point")
            .on_hover_text("The paper: the representative VPL with the summed flux");
        ui.selectable_value(&mut s.cluster.cluster_light, ClusterLight::Spread, "spread")
            .on_hover_text(
                "Not in the paper: the other members' flux no closer than their RMS distance",
            );
    });
    ui.add_enabled_ui(colom, |ui| {
        ui.horizontal(|ui| {
            ui.checkbox(&mut s.cluster.reseed, "re-seed")
                .on_hover_text("Not in the paper: empty clusters re-seeded (--reseed)");
            ui.checkbox(&mut s.cluster.ring_fallback, "rings")
                .on_hover_text("Not in the paper: search beyond the 27 cells (--ring-fallback)");
            ui.checkbox(&mut s.cluster.position_fallback, "by position")
                .on_hover_text(
                    "Not in the paper: no centroid passing n_t: the nearest by position \
                     (--position-fallback)",
                );
            let mut unit = s.cluster.centroid_normal == CentroidNormal::Normalised;
            ui.checkbox(&mut unit, "unit normals")
                .on_hover_text("Not in the paper: centroid normals normalised (--centroid-normal)");
            s.cluster.centroid_normal = if unit {
                CentroidNormal::Normalised
            } else {
                CentroidNormal::Mean
            };
        });
    });
}

/// colom's clustering: the weighting, which clusterings run, the time budget, temporal reuse and
/// the paper's knobs (K, K_VPL, VPLs, F, p, the plane gate, γ, n_t, iterations); the knobs only
/// colom uses are greyed out for the other methods.
pub(super) fn clustering_controls(
    ui: &mut Ui,
    s: &mut UiSettings,
    r: &SliderRanges,
    gamma_used: Option<u32>,
) {
    let colom = s.method.method == Method::Colom;
    weighting_controls(ui, s, colom);
    ui.horizontal(|ui| {
        ui.checkbox(&mut s.sp_on, "SP clustering");
        ui.checkbox(&mut s.vpl_on, "VPL clustering");
        ui.checkbox(&mut s.direct_on, "direct");
    });
    adaptation_controls(ui, s, colom);
    budget_and_temporal_controls(ui, s);
    count_sliders(ui, s, r);
    fuzzy_controls(ui, s, r, colom);
    gamma_controls(ui, s, r, gamma_used);
    let cos = s.nt_degrees.to_radians().cos();
    ui.add(
        Slider::new(&mut s.nt_degrees, 0.0..=180.0)
            .suffix("°")
            .text(format!("n_t (cos {cos:.3})")),
    );
    ui.add(Slider::new(&mut s.cluster.iterations, 0..=r.iterations).text("k-means iterations"));
}

/// colom's weighting: hard, fuzzy with uniform weights, or weighted by distance.
fn weighting_controls(ui: &mut Ui, s: &mut UiSettings, colom: bool) {
    ui.add_enabled_ui(colom, |ui| {
        ui.horizontal(|ui| {
            ui.selectable_value(&mut s.cluster.weighting, Weighting::Hard, "hard");
            ui.selectable_value(
                &mut s.cluster.weighting,
                Weighting::Uniform,
                "fuzzy (uniform)",
            );
            ui.selectable_value(
                &mut s.cluster.weighting,
                Weighting::InverseDistance,
                "weighted",
            );
        });
    });
}

/// The time budget (K_SP and K_VPL chosen to hold a GPU time a frame), temporal reuse and its α.
fn budget_and_temporal_controls(ui: &mut Ui, s: &mut UiSettings) {
    ui.horizontal(|ui| {
        let mut on = s.cluster.target_ms.is_some();
        ui.checkbox(&mut on, "time budget")
            .on_hover_text("K_SP and K_VPL chosen to hold this GPU time a frame");
        let mut ms = s.cluster.target_ms.unwrap_or(500.0);
        ui.add_enabled(
            on,
            egui::DragValue::new(&mut ms)
                .range(1.0..=100_000.0)
                .speed(5.0)
                .suffix(" ms"),
        );
        s.cluster.target_ms = on.then_some(ms);
    });
    ui.checkbox(&mut s.cluster.temporal, "temporal reuse")
        .on_hover_text(
            "Reproject the last frame while moving, start the clusterings from the last \
             frame's, accumulate the direct light at rest (docs/temporal.md)",
        );
    ui.add_enabled(
        s.cluster.temporal,
        Slider::new(&mut s.cluster.temporal_alpha, 0.05..=1.0).text("α (indirect history)"),
    )
    .on_hover_text(
        "The new frame's weight in the indirect light accumulated at each surface point while \
         moving (--temporal-alpha; 1: none)",
    );
}

/// How many SP clusters, VPL clusters and VPLs, on logarithmic sliders.
fn count_sliders(ui: &mut Ui, s: &mut UiSettings, r: &SliderRanges) {
    ui.add_enabled(
        s.sp_on,
        Slider::new(&mut s.cluster.sp_clusters, 1..=r.sp_clusters)
            .logarithmic(true)
            .text("K (SP clusters)"),
    );
    ui.add_enabled(
        s.vpl_on,
        Slider::new(&mut s.cluster.vpl_clusters, 1..=r.vpl_clusters)
            .logarithmic(true)
            .text("K_VPL"),
    );
    ui.add(
        Slider::new(&mut s.frame.vpls, 0..=r.vpls)
            .logarithmic(true)
            .text("VPLs"),
    );
}

/// colom's fuzzy assignment: F, the weights' exponent p and whom they are measured to, and the
/// plane gate on slots 2..F; greyed out where the weighting does not use them.
fn fuzzy_controls(ui: &mut Ui, s: &mut UiSettings, r: &SliderRanges, colom: bool) {
    ui.add_enabled(
        colom && s.cluster.weighting != Weighting::Hard,
        Slider::new(&mut s.cluster.fuzziness, 1..=16).text("F (fuzziness)"),
    );
    ui.add_enabled(
        colom && s.cluster.weighting == Weighting::InverseDistance,
        Slider::new(&mut s.cluster.weight_exponent, 0.0..=r.weight_exponent)
            .text("p (weights = dist^-p; Eq. 10: 1)"),
    );
    ui.add_enabled(
        colom && s.cluster.weighting == Weighting::InverseDistance,
        egui::Checkbox::new(&mut s.cluster.weights_to_reps, "weights to representatives"),
    )
    .on_hover_text(
        "Eq. (10)'s distances to the SP clusters' representatives (the paper's text) instead of \
         their centroids (Alg. 2); view --weights-to-reps",
    );
    ui.add_enabled_ui(colom && s.cluster.weighting != Weighting::Hard, |ui| {
        ui.horizontal(|ui| {
            ui.checkbox(&mut s.plane_gate_on, "plane gate")
                .on_hover_text(
                    "Not in the paper: slots 2..F keep only SP clusters whose centroid \
                         lies within this angle of the pixel's tangent plane",
                );
            ui.add_enabled(
                s.plane_gate_on,
                Slider::new(&mut s.plane_gate_deg, r.plane_gate_min..=90.0)
                    .suffix("°")
                    .text("angle"),
            );
        });
    });
}

/// γ, the downsampling of the pixels clustered: automatic, or a slider that starts from the γ
/// last used when automatic is switched off.
fn gamma_controls(ui: &mut Ui, s: &mut UiSettings, r: &SliderRanges, gamma_used: Option<u32>) {
    ui.horizontal(|ui| {
        let auto = ui.checkbox(&mut s.gamma_auto, "auto γ").on_hover_text(
            "γ from the pixels and K: the largest in 4..16 that keeps 40 sampled \
                 points a cluster and 19,200 in all (docs/clustering.md)",
        );
        if auto.changed()
            && !s.gamma_auto
            && let Some(g) = gamma_used
        {
            s.gamma = g.clamp(1, r.gamma);
        }
        ui.add_enabled(
            !s.gamma_auto,
            Slider::new(&mut s.gamma, 1..=r.gamma).text("γ (downsampling)"),
        );
    });
}
