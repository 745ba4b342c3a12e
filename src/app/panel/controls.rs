//! The panel's method and settings controls: the method selector, "the paper", and every control
//! the settings declare (`KnobWidget`s of the chosen method's knobs, `ClusterSettings` and
//! `FrameSettings`), drawn from their declarations: a slider over the declared range and scale,
//! a choice, a toggle, a word or a number, or a cosine as an angle.

use egui::{Slider, Ui};
use serde_json::Value;

use crate::app::UiSettings;
use crate::settings::{Controlled, KnobWidget, Range, Widget};

/// The method selector and the chosen method's own knobs (its entry's panel section).
pub(super) fn method_controls(ui: &mut Ui, s: &mut UiSettings) {
    ui.horizontal(|ui| {
        ui.label("method");
        for r in crate::method::REGISTRY {
            ui.selectable_value(&mut s.method.method, r.method, r.method.name())
                .on_hover_text(r.about);
        }
    });
    draw_all(ui, &mut s.method, |_| false);
}

/// "the paper" (`--paper`), the direct light, and every control of `ClusterSettings` and
/// `FrameSettings`; a control used only by the paper's method (`paper_only`) is greyed out for
/// methods with knobs of their own, one that does not apply with the other settings (its
/// declaration's `if`) too.
pub(super) fn settings_controls(ui: &mut Ui, s: &mut UiSettings) {
    ui.horizontal(|ui| {
        let mut paper = s.cluster.paper;
        let w = (s.frame.width, s.frame.height);
        if ui
            .checkbox(&mut paper, "the paper")
            .on_hover_text(
                "Every setting at the paper's choice (--paper): point cluster lights, no \
                 re-seeding, no fallbacks, mean centroid normals, n_t = √3/2, F 6, weighted, the \
                 paper's K ratios, no G-term clamp",
            )
            .changed()
        {
            s.set_paper(paper, w.0, w.1);
        }
        ui.checkbox(&mut s.direct_on, "direct light");
    });
    let own_settings = s.method.entry_with_own_settings().is_some();
    draw_all(ui, &mut s.cluster, |c| c.paper_only && own_settings);
    draw_all(ui, &mut s.frame, |_| false);
}

/// Every control of `s`, greyed out where it does not apply (its declaration's `if`) or where
/// `greyed` says so.
fn draw_all(ui: &mut Ui, s: &mut impl Controlled, greyed: impl Fn(&KnobWidget) -> bool) {
    for c in s.controls() {
        let enabled = s.control_enabled(c.name) && !greyed(c);
        if let Some(v) = s.control(c.name)
            && let Some(next) = draw(ui, c, &v, enabled)
        {
            // A value the field refuses (a knob's parser) leaves it as it was.
            s.set_control(c.name, next);
        }
    }
}

/// A slider over [lo, hi], widened to hold `x` (a value given on the command line outside the
/// usual range stays as it was: egui clamps a slider's value into its range).
fn slider(ui: &mut Ui, x: &mut f64, r: Range, label: &str) {
    let slider = Slider::new(x, r.lo.min(*x)..=r.hi.max(*x))
        .logarithmic(r.log)
        .text(label);
    ui.add(if r.integer { slider.integer() } else { slider });
}

/// Draws control `c` showing serde value `v`; the new value when the user changed it.
fn draw(ui: &mut Ui, c: &KnobWidget, v: &Value, enabled: bool) -> Option<Value> {
    ui.add_enabled_ui(enabled, |ui| match c.widget {
        Widget::Slider(r) => {
            let old = v.as_f64()?;
            let mut x = old;
            slider(ui, &mut x, r, c.label);
            (x != old).then(|| Widget::number(r.integer, x))
        }
        Widget::Choice(values) => {
            let now = v.as_str()?;
            let mut pick = None;
            ui.horizontal_wrapped(|ui| {
                ui.label(c.label);
                for &(value, label) in values {
                    if ui.radio(now == value, label).clicked() && now != value {
                        pick = Some(Value::from(value));
                    }
                }
            });
            pick
        }
        Widget::Toggle => {
            let old = v.as_bool()?;
            let mut on = old;
            ui.checkbox(&mut on, c.label);
            (on != old).then_some(Value::Bool(on))
        }
        Widget::Or {
            word,
            off,
            slider: r,
            start,
        } => {
            // The number the slider showed last, kept while the word is ticked.
            let id = egui::Id::unique(("settings control", c.name));
            let is_off = off.is(v);
            let kept = ui.data(|d| d.get_temp::<f64>(id)).unwrap_or(start);
            let old = if is_off { kept } else { v.as_f64()? };
            let (mut word_on, mut x) = (is_off, old);
            ui.horizontal_wrapped(|ui| {
                ui.checkbox(&mut word_on, word);
                ui.add_enabled_ui(!word_on, |ui| slider(ui, &mut x, r, c.label));
            });
            ui.data_mut(|d| d.insert_temp(id, x));
            match (word_on, is_off) {
                (true, true) => None,
                (true, false) => Some(off.value()),
                (false, _) if is_off || x != old => Some(Widget::number(r.integer, x)),
                (false, _) => None,
            }
        }
        Widget::Cosine => {
            let cos = v.as_f64()?;
            let old = cos.clamp(-1.0, 1.0).acos().to_degrees();
            let mut deg = old;
            let label = format!("{} (cos {cos:.3})", c.label);
            ui.add(Slider::new(&mut deg, 0.0..=180.0).suffix("°").text(label));
            (deg != old).then(|| Value::from(deg.to_radians().cos()))
        }
    })
    .inner
}
