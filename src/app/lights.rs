//! Lights that move: the panel's "Lights" section edits the scene's punctual lights (suns, point and
//! spot lights: add, move, re-colour, re-scale, delete) and scales its emissive surfaces. Every
//! change goes to the GI worker as one `Job::Lights` (`Renderer::set_lights`); the next frame traces
//! the VPLs again and clusters them (from the last clustering with temporal reuse on), and the panel
//! shows what that cost.

use egui::{DragValue, RichText, Slider, Ui};
use glam::Vec3;

use super::Viewer;
use super::worker::Job;
use crate::scene::{LightKind, PunctualLight};

/// The status line of a scene with nothing that emits.
pub const NO_LIGHT: &str =
    "the scene has no light; add one in the Lights section (or --sun, --point)";

/// The lights as the panel edits them.
#[derive(Clone, Debug, PartialEq)]
pub struct LightSet {
    pub lights: Vec<PunctualLight>,
    /// Factor on every emissive material of the scene as loaded.
    pub emitter_scale: f32,
}

impl LightSet {
    /// Whether anything emits: a punctual light with power, or emissive triangles scaled above 0.
    pub fn has_light(&self, emissive_triangles: usize) -> bool {
        self.lights.iter().any(PunctualLight::emits)
            || (emissive_triangles > 0 && self.emitter_scale > 0.0)
    }
}

/// A sun from above and a little aside (irradiance 3, white).
pub fn new_sun() -> PunctualLight {
    PunctualLight {
        kind: LightKind::Directional,
        position: Vec3::ZERO,
        direction: -Vec3::new(0.3, 1.0, 0.2).normalize(),
        color: Vec3::ONE,
        intensity: 3.0,
    }
}

/// A point light at the centre of `bounds`, bright enough for an irradiance of about 1 at a quarter
/// of the scene's diagonal.
pub fn new_point(bounds: (Vec3, Vec3)) -> PunctualLight {
    let d = 0.25 * (bounds.1 - bounds.0).length();
    PunctualLight {
        kind: LightKind::Point,
        position: 0.5 * (bounds.0 + bounds.1),
        direction: -Vec3::Y,
        color: Vec3::ONE,
        intensity: (d * d).max(1e-12),
    }
}

/// Azimuth and elevation in degrees of the direction towards a sun (`-direction`).
pub fn sun_angles(direction: Vec3) -> (f32, f32) {
    let to = -direction.normalize_or(Vec3::Y);
    (
        to.x.atan2(to.z).to_degrees(),
        to.y.clamp(-1.0, 1.0).asin().to_degrees(),
    )
}

/// The direction a sun's light travels for azimuth and elevation in degrees (`sun_angles`' inverse).
pub fn sun_direction(azimuth: f32, elevation: f32) -> Vec3 {
    let (a, e) = (azimuth.to_radians(), elevation.to_radians());
    -Vec3::new(e.cos() * a.sin(), e.sin(), e.cos() * a.cos())
}

impl Viewer {
    pub(super) fn lights_section(&mut self, ui: &mut Ui) {
        let Some(info) = &self.info else { return };
        let has_light = info.has_light;
        let bounds = info.bounds;
        let emissive = info.emissive_triangles;
        let extent = (bounds.1 - bounds.0).length().max(1e-12);
        let mut set = self.lights.clone();
        // Open from the start in a scene without light, where it is the first thing to use.
        egui::CollapsingHeader::new("Lights")
            .default_open(!has_light)
            .show(ui, |ui| {
                if emissive > 0 {
                    ui.add(
                        Slider::new(&mut set.emitter_scale, 0.0..=100.0)
                            .logarithmic(true)
                            .text("emissive surfaces ×"),
                    );
                }
                let mut delete = None;
                for (i, l) in set.lights.iter_mut().enumerate() {
                    ui.separator();
                    ui.horizontal(|ui| {
                        let kind = match l.kind {
                            LightKind::Directional => "sun",
                            LightKind::Point => "point",
                            LightKind::Spot { .. } => "spot",
                        };
                        ui.label(RichText::new(format!("{kind} {i}")).strong());
                        let mut rgb = l.color.to_array();
                        if ui.color_edit_button_rgb(&mut rgb).changed() {
                            l.color = Vec3::from(rgb);
                        }
                        if ui.small_button("delete").clicked() {
                            delete = Some(i);
                        }
                    });
                    let what = match l.kind {
                        LightKind::Directional => "irradiance",
                        _ => "intensity",
                    };
                    let top = 1e6f32.max(l.intensity);
                    ui.add(
                        Slider::new(&mut l.intensity, 0.0..=top)
                            .logarithmic(true)
                            .text(what),
                    );
                    match l.kind {
                        LightKind::Directional => {
                            let (mut az, mut el) = sun_angles(l.direction);
                            let a = ui.add(Slider::new(&mut az, -180.0..=180.0).text("azimuth °"));
                            let e = ui.add(Slider::new(&mut el, -90.0..=90.0).text("elevation °"));
                            if a.changed() || e.changed() {
                                l.direction = sun_direction(az, el);
                            }
                        }
                        _ => {
                            ui.horizontal(|ui| {
                                let speed = extent * 0.002;
                                for (name, v) in [
                                    ("x", &mut l.position.x),
                                    ("y", &mut l.position.y),
                                    ("z", &mut l.position.z),
                                ] {
                                    ui.add(
                                        DragValue::new(v).speed(speed).prefix(format!("{name} ")),
                                    );
                                }
                            });
                        }
                    }
                }
                if let Some(i) = delete {
                    set.lights.remove(i);
                }
                ui.horizontal(|ui| {
                    if ui.button("+ sun").clicked() {
                        set.lights.push(new_sun());
                    }
                    if ui.button("+ point light").clicked() {
                        set.lights.push(new_point(bounds));
                    }
                });
                if let Some((trace, cluster)) = self.last_relight {
                    ui.label(format!(
                        "VPLs last traced in {trace:.0} ms + clustered in {cluster:.0} ms (GPU)"
                    ));
                }
            });
        if set != self.lights {
            self.set_lights(set);
        }
    }

    /// Sends the lights to the worker; the views that depend on them (the reference, the plot) are
    /// dropped as by a camera move.
    pub fn set_lights(&mut self, set: LightSet) {
        self.worker
            .send(Job::Lights(set.lights.clone(), set.emitter_scale));
        self.lights = set;
        self.camera_moved();
        self.last_sent = None;
        let emissive = self.info.as_ref().map_or(0, |i| i.emissive_triangles);
        if !self.lights.has_light(emissive) {
            self.status = NO_LIGHT.into();
        } else if self.status.contains(NO_LIGHT) {
            self.status.clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sun_angles_round_trip_and_point_where_expected() {
        // Straight overhead: the light travels down.
        assert!((sun_direction(0.0, 90.0) - (-Vec3::Y)).length() < 1e-6);
        // Azimuth 90° at the horizon: the sun is towards +X, its light travels along -X.
        assert!((sun_direction(90.0, 0.0) - (-Vec3::X)).length() < 1e-6);
        for (az, el) in [(10.0, 20.0), (-120.0, 45.0), (170.0, -30.0)] {
            let (a, e) = sun_angles(sun_direction(az, el));
            assert!((a - az).abs() < 1e-3 && (e - el).abs() < 1e-3, "{az} {el}");
        }
        let (a, e) = sun_angles(new_sun().direction);
        assert!(e > 45.0 && a.is_finite());
    }

    #[test]
    fn light_sets_know_whether_anything_emits() {
        let mut s = LightSet {
            lights: vec![],
            emitter_scale: 1.0,
        };
        assert!(s.has_light(2));
        assert!(!s.has_light(0));
        s.emitter_scale = 0.0;
        assert!(!s.has_light(2));
        s.lights.push(new_point((Vec3::ZERO, Vec3::ONE)));
        assert!(s.has_light(0));
        s.lights[0].intensity = 0.0;
        assert!(!s.has_light(0));
    }
}
