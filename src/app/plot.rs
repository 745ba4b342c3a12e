//! The panel's error plot: time against MSE or FLIP, one series per mode, on log axes.

use egui::{Color32, RichText, Ui};
use egui_plot::{Plot, Points};

use super::Viewer;

impl Viewer {
    /// Time against error, one series per mode: log axes, re-fitted whenever points arrive; the
    /// wheel and drags zoom and pan only with "zoom" ticked; the legend below the plot.
    pub(super) fn error_plot(&mut self, ui: &mut Ui) {
        ui.horizontal(|ui| {
            ui.selectable_value(&mut self.plot_flip, false, "MSE");
            ui.selectable_value(&mut self.plot_flip, true, "FLIP");
            ui.checkbox(&mut self.plot_zoom, "zoom");
            if ui.small_button("clear").clicked() {
                self.points.clear();
            }
        });
        if self.points.is_empty() {
            return;
        }
        let mut series: Vec<&str> = self.points.iter().map(|p| p.series.as_str()).collect();
        series.sort();
        series.dedup();
        let flip = self.plot_flip;
        let items: Vec<(String, Color32, Vec<[f64; 2]>)> = series
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let pts = self
                    .points
                    .iter()
                    .filter(|p| p.series == *name)
                    .map(|p| {
                        let e = if flip { p.flip } else { p.mse };
                        [p.ms.max(1e-3).log10(), e.max(1e-12).log10()]
                    })
                    .collect();
                (name.to_string(), series_colour(i), pts)
            })
            .collect();
        // The fitted range: the points' with a margin, at least 0.6 decades on each axis so that a
        // 1-2-5 tick (and its label) always falls inside it.
        let range = |axis: usize| {
            let vs = items
                .iter()
                .flat_map(|(_, _, p)| p.iter().map(move |q| q[axis]));
            let (lo, hi) = vs.fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
            let (mid, half) = ((lo + hi) / 2.0, ((hi - lo) / 2.0 * 1.15).max(0.3));
            (mid - half, mid + half)
        };
        let (x_range, y_range) = (range(0), range(1));
        let refit = self.points.len() != self.plot_fitted || !self.plot_zoom;
        self.plot_fitted = self.points.len();
        let zoom = self.plot_zoom;
        let mut plot = Plot::new("error_plot")
            .height(200.0)
            .x_axis_label("GPU ms (log)")
            .y_axis_label(if flip { "FLIP (log)" } else { "MSE (log)" })
            .x_grid_spacer(log_marks)
            .y_grid_spacer(log_marks)
            .x_axis_formatter(|m, _| pow10_label(m.value))
            .y_axis_formatter(|m, _| pow10_label(m.value))
            .label_formatter(move |h| match h {
                egui_plot::HoverPosition::NearDataPoint {
                    plot_name,
                    position: p,
                    ..
                } => Some(format!(
                    "{plot_name}\n{:.1} ms, {} {:.3e}",
                    10f64.powf(p.x),
                    if flip { "FLIP" } else { "MSE" },
                    10f64.powf(p.y)
                )),
                egui_plot::HoverPosition::Elsewhere { .. } => None,
            })
            .allow_zoom(zoom)
            .allow_scroll(zoom)
            .allow_drag(zoom)
            .allow_boxed_zoom(zoom)
            .auto_bounds(egui::Vec2b::new(true, true))
            .include_x(x_range.0)
            .include_x(x_range.1)
            .include_y(y_range.0)
            .include_y(y_range.1);
        if refit {
            plot = plot.reset();
        }
        plot.show(ui, |p| {
            for (name, colour, pts) in &items {
                p.points(
                    Points::new(name.as_str(), pts.clone())
                        .radius(4.0)
                        .color(*colour),
                );
            }
        });
        ui.horizontal_wrapped(|ui| {
            for (name, colour, _) in &items {
                // A painted dot: egui's default fonts have no glyph for "●".
                let (dot, _) = ui.allocate_exact_size(egui::vec2(8.0, 8.0), egui::Sense::hover());
                ui.painter().circle_filled(dot.center(), 3.5, *colour);
                ui.label(RichText::new(name).color(*colour).small());
            }
        });
    }
}

/// The plot's series colours.
fn series_colour(i: usize) -> Color32 {
    const C: [Color32; 6] = [
        Color32::from_rgb(240, 120, 60),
        Color32::from_rgb(80, 170, 255),
        Color32::from_rgb(120, 220, 110),
        Color32::from_rgb(230, 200, 60),
        Color32::from_rgb(200, 120, 230),
        Color32::from_rgb(230, 230, 230),
    ];
    C[i % C.len()]
}

/// Grid marks of a log10 axis: 1, 2 and 5 times each power of ten in range (the decades strongest).
fn log_marks(input: egui_plot::GridInput) -> Vec<egui_plot::GridMark> {
    let (lo, hi) = input.bounds;
    let mut out = Vec::new();
    if !(lo.is_finite() && hi.is_finite()) || hi - lo > 40.0 {
        return out;
    }
    let fine = hi - lo < 3.0;
    for k in lo.floor() as i32..=hi.ceil() as i32 {
        for (m, step) in [(1.0f64, 1.0), (2.0, 0.3), (5.0, 0.3)] {
            if m != 1.0 && !fine {
                continue;
            }
            let v = k as f64 + m.log10();
            if v >= lo && v <= hi {
                out.push(egui_plot::GridMark {
                    value: v,
                    step_size: step,
                });
            }
        }
    }
    out
}

/// The value 10^v of a log10 axis, short: 300, 0.02, 2e-5.
pub fn pow10_label(v: f64) -> String {
    let x = 10f64.powf(v);
    if (0.01..10000.0).contains(&x) {
        let s = format!("{x:.2}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{x:.0e}")
    }
}
