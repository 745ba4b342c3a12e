//! The side panel (scene, camera, settings, stats, reference, screenshots; the error plot is in
//! `plot.rs`; the method and clustering controls in `controls.rs`) and the image area with its
//! camera input (`image.rs`).

use std::sync::atomic::Ordering;

use egui::{Color32, Key, RichText, Slider, Ui};

use super::Viewer;
use super::bookmarks::Bookmark;
use super::camera::Mode as CamMode;
use super::views::View;
use controls::{method_controls, settings_controls};

mod controls;
mod image;

pub const PANEL_WIDTH: f32 = 380.0;
/// The height of the stats strip under the image (Stats | Reference & error, Screenshots). The
/// default window is the image area plus the panel's width and this height: 1020 × 730 for the
/// default 640 × 480 area, which fits a 1280 × 800 screen with a taskbar and shows the panel's
/// Camera, Lights and View & clustering sections without scrolling.
pub const STATS_HEIGHT: f32 = 250.0;

impl Viewer {
    /// The whole window's UI.
    pub fn ui(&mut self, ui: &mut Ui) {
        egui::Panel::left("panel")
            .resizable(true)
            .default_size(PANEL_WIDTH)
            .size_range(PANEL_WIDTH * 0.8..=PANEL_WIDTH * 3.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    // Long lines wrap instead of being cut at the panel's edge; rows 2 px apart
                    // (egui's 3) so that Camera, Lights and View & clustering fit 730 px.
                    ui.style_mut().wrap_mode = Some(egui::TextWrapMode::Wrap);
                    ui.spacing_mut().item_spacing.y = 2.0;
                    self.panel(ui)
                });
            });
        egui::Panel::bottom("stats")
            .resizable(true)
            .default_size(STATS_HEIGHT)
            .size_range(60.0..=STATS_HEIGHT * 4.0)
            .show(ui, |ui| {
                // The strip keeps its height (scroll areas that fill it, not shrink to content).
                ui.columns(2, |cols| {
                    let scroll = |id| {
                        egui::ScrollArea::vertical()
                            .id_salt(id)
                            .auto_shrink([false, false])
                    };
                    scroll("stats").show(&mut cols[0], |ui| {
                        ui.style_mut().wrap_mode = Some(egui::TextWrapMode::Wrap);
                        self.stats_section(ui)
                    });
                    scroll("reference").show(&mut cols[1], |ui| {
                        ui.style_mut().wrap_mode = Some(egui::TextWrapMode::Wrap);
                        self.reference_section(ui);
                        self.screenshot_section(ui);
                    });
                });
            });
        egui::CentralPanel::no_frame()
            .frame(egui::Frame::NONE.fill(Color32::from_gray(20)))
            .show(ui, |ui| self.image_area(ui));
    }

    fn panel(&mut self, ui: &mut Ui) {
        match &self.info {
            Some(i) => {
                ui.horizontal_wrapped(|ui| {
                    ui.heading("fuzzy-vpl");
                    ui.label(format!("{} — {} triangles", i.spec, i.triangles));
                });
                ui.label(RichText::new(&i.adapter).small().weak());
            }
            None if !self.worker_gone => {
                ui.heading("fuzzy-vpl");
                ui.horizontal(|ui| {
                    ui.spinner();
                    ui.label(format!("loading {}", self.spec));
                });
            }
            None => {
                ui.heading("fuzzy-vpl");
                ui.label(format!("{}: not loaded", self.spec));
            }
        }
        if let Some((spec, _)) = &self.loading {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label(format!("loading {spec}"));
            });
        }
        if !self.status.is_empty() {
            ui.colored_label(Color32::from_rgb(255, 170, 60), &self.status);
        }
        self.scene_section(ui);
        self.camera_section(ui);
        self.lights_section(ui);
        self.settings_section(ui);
    }

    fn scene_section(&mut self, ui: &mut Ui) {
        egui::CollapsingHeader::new("Scene")
            .default_open(false)
            .show(ui, |ui| {
                ui.horizontal(|ui| {
                    let field = ui.add(
                        egui::TextEdit::singleline(&mut self.path_field)
                            .desired_width(PANEL_WIDTH - 110.0)
                            .hint_text("path.glb or builtin:NAME"),
                    );
                    let enter = field.lost_focus() && ui.input(|i| i.key_pressed(Key::Enter));
                    if ui.button("Load").clicked() || enter {
                        let p = self.path_field.trim().to_string();
                        if !p.is_empty() {
                            self.open(p);
                        }
                    }
                });
                ui.horizontal(|ui| {
                    if ui
                        .add_enabled(self.dialog.is_none(), egui::Button::new("Open…"))
                        .clicked()
                    {
                        self.open_dialog();
                    }
                    for b in ["builtin:cornell", "builtin:conference"] {
                        if ui.small_button(&b[8..]).clicked() {
                            self.open(b.to_string());
                        }
                    }
                });
                ui.label(RichText::new("or drop a .gltf / .glb on the window").weak());
            });
    }

    /// The system file dialog on its own thread (rfd; xdg portal, else zenity). Where neither exists
    /// it returns nothing and the path field is the way in.
    fn open_dialog(&mut self) {
        let (tx, rx) = std::sync::mpsc::channel();
        let wake = self.wake.clone();
        std::thread::spawn(move || {
            let picked = rfd::FileDialog::new()
                .add_filter("glTF", &["gltf", "glb"])
                .pick_file();
            let _ = tx.send(picked);
            wake();
        });
        self.dialog = Some(rx);
        self.status =
            "file dialog open (if none appears, no portal/zenity: type a path above)".into();
    }

    fn camera_section(&mut self, ui: &mut Ui) {
        egui::CollapsingHeader::new("Camera")
            .default_open(true)
            .show(ui, |ui| {
                ui.horizontal(|ui| {
                    ui.selectable_value(&mut self.cam_mode, CamMode::Fly, "fly");
                    ui.selectable_value(&mut self.cam_mode, CamMode::Orbit, "orbit");
                    if ui.button("reset").clicked() {
                        self.reset_camera();
                    }
                    ui.label(
                        RichText::new(match self.cam_mode {
                            CamMode::Fly => "right-drag: look\nWASD/QE: move · wheel: speed",
                            CamMode::Orbit => "drag: orbit · wheel: zoom\nWASD: move",
                        })
                        .small()
                        .weak(),
                    );
                });
                ui.add(
                    Slider::new(&mut self.speed, 1e-4..=1e4)
                        .logarithmic(true)
                        .text("speed /s"),
                );
                let cams: Vec<_> = self
                    .info
                    .as_ref()
                    .map(|i| i.cameras.clone())
                    .unwrap_or_default();
                if !cams.is_empty() {
                    ui.horizontal_wrapped(|ui| {
                        ui.label("glTF:");
                        for (i, c) in cams.iter().enumerate() {
                            let name = if c.name.is_empty() {
                                format!("#{i}")
                            } else {
                                c.name.clone()
                            };
                            if ui.small_button(name).clicked() {
                                let d = self.cam.distance;
                                self.set_camera(super::camera::ViewCamera::from_camera(c, d));
                            }
                        }
                    });
                }
                ui.horizontal(|ui| {
                    ui.add(
                        egui::TextEdit::singleline(&mut self.bookmark_name)
                            .desired_width(150.0)
                            .hint_text("bookmark name"),
                    );
                    if ui.button("add bookmark").clicked() {
                        let name = if self.bookmark_name.trim().is_empty() {
                            format!("view {}", self.bookmarks.bookmarks.len() + 1)
                        } else {
                            self.bookmark_name.trim().to_string()
                        };
                        self.bookmarks
                            .bookmarks
                            .push(Bookmark::new(name, &self.cam));
                        self.bookmark_name.clear();
                        self.save_bookmarks();
                    }
                });
                let mut go = None;
                let mut delete = None;
                for (i, b) in self.bookmarks.bookmarks.iter().enumerate() {
                    ui.horizontal(|ui| {
                        if ui.small_button("go").clicked() {
                            go = Some(b.camera());
                        }
                        if ui.small_button("x").clicked() {
                            delete = Some(i);
                        }
                        ui.label(&b.name);
                    });
                }
                if let Some(c) = go {
                    self.set_camera(c);
                }
                if let Some(i) = delete {
                    self.bookmarks.bookmarks.remove(i);
                    self.save_bookmarks();
                }
            });
    }

    fn settings_section(&mut self, ui: &mut Ui) {
        egui::CollapsingHeader::new("View & clustering")
            .default_open(true)
            .show(ui, |ui| {
                ui.horizontal_wrapped(|ui| {
                    for v in View::ALL {
                        ui.selectable_value(&mut self.view, v, v.name());
                    }
                    if ui
                        .button("pin as B")
                        .on_hover_text(
                            "Keep the current settings as B; the A|B split and A−B views render \
                             both for the same camera while A changes",
                        )
                        .clicked()
                    {
                        self.b = Some(self.s.clone());
                        if !matches!(self.view, View::Split | View::Diff) {
                            self.view = View::Split;
                        }
                    }
                    if self.b.is_some() && ui.button("unpin B").clicked() {
                        self.b = None;
                    }
                });
                if let Some(b) = &self.b {
                    ui.label(
                        RichText::new(format!("A: {}\nB: {}", self.s.short(), b.short()))
                            .small(),
                    );
                }
                ui.separator();
                let auto_e = self.latest.as_ref().filter(|_| self.s.exposure_auto);
                let auto_e = auto_e.and_then(|l| l.auto_exposure);
                method_controls(ui, &mut self.s);
                settings_controls(ui, &mut self.s);
                ui.separator();
                let (s, r) = (&mut self.s, &self.ranges);
                ui.horizontal(|ui| {
                    ui.checkbox(&mut s.exposure_auto, "auto").on_hover_text(
                        "the frame's log-average luminance shown as middle grey 0.18 \
                         (Reinhard et al. 2002)",
                    );
                    s.exposure = auto_e.unwrap_or(s.exposure);
                    ui.add_enabled(
                        !s.exposure_auto,
                        Slider::new(&mut s.exposure, r.exposure.0..=r.exposure.1)
                            .logarithmic(true)
                            .text("exposure"),
                    );
                });
                ui.add(Slider::new(&mut s.render_scale, 0.1..=1.0).text("render scale"));
                if let ((w, h), Some(lower)) = self.gi_size() {
                    let most = self.info.as_ref().map_or(0, |i| i.max_pixels);
                    ui.colored_label(
                        Color32::from_rgb(255, 170, 60),
                        format!(
                            "image lowered to {lower:.2} of the area ({w}x{h}): the GI device holds at most {most} pixels a frame"
                        ),
                    );
                }
            });
    }

    fn stats_section(&mut self, ui: &mut Ui) {
        egui::CollapsingHeader::new("Stats")
            .default_open(true)
            .show(ui, |ui| {
                // The window redraws only on input or a new frame: a long gap before this frame
                // means it was idle, not slow.
                if self.ui_dt > 0.5 || self.ui_dt <= 0.0 {
                    ui.label("UI idle (redraws on input or a new frame)");
                } else {
                    ui.label(format!("UI {:.0} fps", 1.0 / self.ui_dt));
                }
                let Some(r) = &self.latest else {
                    ui.label("no GI frame yet");
                    return;
                };
                let f = &r.frame;
                let busy = self.pending != r.job.id;
                ui.label(format!(
                    "GI {}×{}: {:.0} ms GPU, {:.0} ms wall{}",
                    f.width,
                    f.height,
                    f.timings_ms.get("frame").copied().unwrap_or(0.0),
                    r.wall_ms,
                    if busy { " (next one rendering…)" } else { "" }
                ));
                if let Some(t) = r.job.settings.cluster.target_ms {
                    let c = &r.job.settings.cluster;
                    ui.label(format!(
                        "time budget {t:.0} ms: K_SP {} · K_VPL {}{}",
                        c.sp_clusters,
                        c.vpl_clusters,
                        if r.job.preview { " (moving)" } else { "" }
                    ));
                }
                if let Some(e) = self.live_error {
                    ui.label(
                        RichText::new(format!(
                            "MSE {:.3e} · rel MSE {:.3e} · FLIP {:.4}",
                            e.mse, e.rel_mse, e.flip
                        ))
                        .color(Color32::LIGHT_GREEN),
                    );
                }
                // Pass names and times on one line each (the panel's wrapping would break them).
                ui.style_mut().wrap_mode = Some(egui::TextWrapMode::Extend);
                egui::Grid::new("timings").striped(true).show(ui, |ui| {
                    for p in f
                        .passes
                        .iter()
                        .map(|p| p.name())
                        .chain([crate::render::FRAME_KEY])
                        .filter(|p| f.timings_ms.contains_key(*p))
                    {
                        ui.label(p);
                        ui.label(format!("{:.1} ms", f.timings_ms[p]));
                        ui.end_row();
                    }
                });
                ui.style_mut().wrap_mode = Some(egui::TextWrapMode::Wrap);
                ui.label(format!(
                    "VPLs {} · VPL clusters {}",
                    f.vpls, f.vpl_clusters_used
                ));
                if let Some(g) = f.gamma_used {
                    ui.label(format!("γ used {g}"));
                }
                if let Some((n, spp, ms)) = r.refined {
                    ui.label(format!(
                        "direct light: {spp} samples a pixel ({n} frames at rest, {ms:.0} ms each)"
                    ));
                }
                // Counts the GPU keeps: read back each frame only while this section is open.
                let counts = egui::CollapsingHeader::new("Counts (read back each frame)")
                    .default_open(false)
                    .show(ui, |ui| {
                        ui.label(format!(
                            "SPs {} · SP clusters {}",
                            f.shading_points, f.sp_clusters_used
                        ));
                        // The method's report, key by key (the paper's: SP iterations, warm
                        // start, visibility rows reused).
                        let report = f.report.as_ref().and_then(|(_, v)| v.as_object());
                        for (key, v) in report.into_iter().flatten() {
                            ui.label(format!("{} {v}", key.replace('_', " ")));
                        }
                        ui.label(format!("shadow rays {}", f.shadow_rays));
                    });
                self.show_counts = counts.openness > 0.0;
            });
    }

    fn reference_section(&mut self, ui: &mut Ui) {
        egui::CollapsingHeader::new("Reference & error")
            .default_open(true)
            .show(ui, |ui| {
                let running = self.reference.as_ref().filter(|r| r.image.is_none());
                match running {
                    Some(r) => {
                        let frac = r.control.fraction();
                        let done = r.control.done.load(Ordering::Relaxed);
                        let all = r.control.total.load(Ordering::Relaxed);
                        let secs = r.started.elapsed().as_secs_f32();
                        ui.add(egui::ProgressBar::new(frac).text(format!(
                            "reference {:.0}% ({done}/{all}) {secs:.0} s",
                            frac * 100.0
                        )));
                        ui.ctx()
                            .request_repaint_after(std::time::Duration::from_millis(250));
                        if ui.button("cancel").clicked() {
                            self.cancel_reference();
                        }
                    }
                    None => {
                        let label = if self.reference.is_some() {
                            "recompute reference"
                        } else {
                            "compute reference (unclustered)"
                        };
                        if ui
                            .add_enabled(self.info.is_some(), egui::Button::new(label))
                            .clicked()
                        {
                            self.start_reference();
                        }
                        if let Some(r) = &self.reference
                            && r.image.is_some()
                        {
                            ui.label(format!(
                                "reference {}×{} in {:.1} s",
                                r.job.settings.frame.width, r.job.settings.frame.height, r.secs
                            ));
                        }
                    }
                }
                let here = self
                    .latest
                    .as_ref()
                    .is_some_and(|r| self.reference_for_view(r));
                ui.label(
                    RichText::new(format!(
                        "{} reference(s) kept, one per view and reference setting{}",
                        self.refs.len(),
                        if here { "; this view has one" } else { "" }
                    ))
                    .small(),
                );
                let was = self.refs_on_disk;
                ui.checkbox(
                    &mut self.refs_on_disk,
                    "keep references as EXR beside the scene",
                )
                .on_hover_text(
                    self.refs_dir()
                        .map_or("no folder for this scene".into(), |d| {
                            d.display().to_string()
                        }),
                );
                if self.refs_on_disk && !was {
                    self.refs_missing.clear();
                }
                if !self.points.is_empty() {
                    self.error_plot(ui);
                }
            });
    }

    fn screenshot_section(&mut self, ui: &mut Ui) {
        egui::CollapsingHeader::new("Screenshots")
            .default_open(true)
            .show(ui, |ui| {
                ui.label(RichText::new("keys: F11 EXR · F12 PNG").small().weak());
                ui.horizontal(|ui| {
                    if ui.button("EXR (radiance)").clicked() {
                        self.save_exr();
                    }
                    if ui.button("PNG (window)").clicked() {
                        self.request_png();
                    }
                });
                let line = if self.last_shot.is_empty() {
                    format!("files go to {}", self.shot_dir.display())
                } else {
                    self.last_shot.clone()
                };
                ui.label(RichText::new(line).small());
            });
    }
}
