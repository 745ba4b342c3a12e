//! The side panel (scene, camera, settings, stats, reference, screenshots; the error plot is in
//! `plot.rs`) and the image area with its camera input.

use std::sync::atomic::Ordering;

use egui::{Color32, Key, PointerButton, RichText, Sense, Slider, Ui};

use super::camera::Mode as CamMode;
use super::settings::Bookmark;
use super::views::{self, View};
use super::{SliderRanges, UiSettings, Viewer};
use crate::method::{Method, MethodSettings};
use crate::settings::{CentroidNormal, ClusterLight, Weighting, Widget};

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
                // The γ the last frame sampled with: the slider starts there when auto is unticked.
                let gamma_used = self.latest.as_ref().and_then(|l| l.frame.gamma_used);
                let auto_e = self.latest.as_ref().filter(|_| self.s.exposure_auto);
                let auto_e = auto_e.and_then(|l| l.auto_exposure);
                method_controls(ui, &mut self.s);
                clustering_controls(ui, &mut self.s, &self.ranges, gamma_used);
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
                        // The method's report, key by key (colom's: SP iterations, warm start,
                        // visibility rows reused).
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

    /// The VPL-clusters view's dots over the display pass's darkened image (`views::vpl_points` draws
    /// the same into the CPU-composed image): each VPL a grey pixel, each light of a clustered list
    /// a coloured dot of radius 2 pixels, projected with the frame's camera.
    fn vpl_dots(&self, ui: &mut Ui, rect: egui::Rect) {
        let Some(r) = &self.latest else { return };
        let (w, h) = (r.frame.width, r.frame.height);
        let cam = crate::gi::primary::CameraParams::new(&r.job.camera, w, h);
        let px = rect.width() / w as f32;
        let at = |(x, y): (f32, f32)| {
            rect.min + egui::vec2((x.floor() + 0.5) * px, (y.floor() + 0.5) * px)
        };
        let painter = ui.painter_at(rect);
        for p in r.vpls.iter() {
            if let Some(xy) = views::project(&cam, *p) {
                let c = at(xy);
                painter.rect_filled(
                    egui::Rect::from_center_size(c, egui::vec2(px, px)),
                    0.0,
                    Color32::from_gray(200),
                );
            }
        }
        if r.lights_clustered {
            for (i, p) in r.lights.iter().enumerate() {
                if let Some(xy) = views::project(&cam, *p) {
                    let [cr, cg, cb] = views::cluster_colour(i as u32);
                    painter.circle_filled(at(xy), 2.5 * px, Color32::from_rgb(cr, cg, cb));
                }
            }
        }
    }

    /// The GI image, filling the central area, and the camera input over it.
    fn image_area(&mut self, ui: &mut Ui) {
        let ppp = ui.ctx().pixels_per_point();
        let size = ui.available_size();
        let px = [
            ((size.x * ppp) as u32).max(8),
            ((size.y * ppp) as u32).max(8),
        ];
        if px != self.area_px {
            self.area_px = px;
        }
        let (rect, response) = ui.allocate_exact_size(size, Sense::click_and_drag());
        // The split view's divider: a handle over the image that takes drags before the camera.
        let split_view = self.view == View::Split;
        let mut on_divider = false;
        if split_view {
            let x = rect.left() + rect.width() * self.split;
            let handle = egui::Rect::from_x_y_ranges(x - 6.0..=x + 6.0, rect.y_range());
            let h = ui.interact(handle, ui.unique_id().with("split_divider"), Sense::drag());
            if h.dragged()
                && let Some(p) = h.interact_pointer_pos()
            {
                self.split = ((p.x - rect.left()) / rect.width()).clamp(0.0, 1.0);
            }
            on_divider = h.dragged() || h.hovered();
            if on_divider {
                ui.ctx().set_cursor_icon(egui::CursorIcon::ResizeHorizontal);
            }
        }
        // Camera input first, so that this frame's image is already the new camera's.
        if !on_divider {
            self.camera_input(ui, &response);
        }
        if self.gpu_texture.is_none()
            && self.image_stale()
            && let Some(img) = self.current_image()
        {
            match &mut self.texture {
                Some(t) => t.set(img, egui::TextureOptions::LINEAR),
                None => {
                    self.texture = Some(ui.ctx().load_texture(
                        "gi",
                        img,
                        egui::TextureOptions::LINEAR,
                    ))
                }
            }
        }
        let texture = match (self.gpu_texture, &self.texture) {
            (Some((id, _)), _) => Some(id),
            (None, t) => t.as_ref().map(|t| t.id()),
        };
        if let Some(id) = texture {
            ui.painter().image(
                id,
                rect,
                egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
                Color32::WHITE,
            );
        }
        if self.gpu_texture.is_some() && self.view == View::VplPoints {
            self.vpl_dots(ui, rect);
        }
        if split_view && self.note.is_none() {
            let x = rect.left() + rect.width() * self.split;
            ui.painter().line_segment(
                [egui::pos2(x, rect.top()), egui::pos2(x, rect.bottom())],
                egui::Stroke::new(2.0, Color32::WHITE),
            );
            for (label, pos, align) in [
                (
                    "A",
                    egui::pos2(x - 8.0, rect.top() + 8.0),
                    egui::Align2::RIGHT_TOP,
                ),
                (
                    "B",
                    egui::pos2(x + 8.0, rect.top() + 8.0),
                    egui::Align2::LEFT_TOP,
                ),
            ] {
                ui.painter().text(
                    pos,
                    align,
                    label,
                    egui::FontId::proportional(16.0),
                    Color32::WHITE,
                );
            }
        }
        if self.note.is_none()
            && let Some((ramp, labels)) = crate::app::views::colour_bar(self.view, 64)
        {
            let bar = egui::Rect::from_min_size(
                rect.left_bottom() + egui::vec2(12.0, -34.0),
                egui::vec2((rect.width() - 24.0).clamp(40.0, 320.0), 12.0),
            );
            let n = ramp.len() as f32;
            for (i, c) in ramp.iter().enumerate() {
                let x0 = bar.left() + bar.width() * i as f32 / n;
                let x1 = bar.left() + bar.width() * (i + 1) as f32 / n;
                ui.painter().rect_filled(
                    egui::Rect::from_x_y_ranges(x0..=x1, bar.y_range()),
                    0.0,
                    Color32::from_rgb(c[0], c[1], c[2]),
                );
            }
            ui.painter().rect_stroke(
                bar,
                0.0,
                egui::Stroke::new(1.0, Color32::WHITE),
                egui::StrokeKind::Outside,
            );
            for (k, (label, align)) in labels
                .iter()
                .zip([
                    egui::Align2::LEFT_TOP,
                    egui::Align2::CENTER_TOP,
                    egui::Align2::RIGHT_TOP,
                ])
                .enumerate()
            {
                let x = bar.left() + bar.width() * k as f32 / 2.0;
                ui.painter().text(
                    egui::pos2(x, bar.bottom() + 2.0),
                    align,
                    *label,
                    egui::FontId::proportional(12.0),
                    Color32::WHITE,
                );
            }
        }
        if let Some(note) = self.note {
            ui.painter().text(
                rect.left_top() + egui::vec2(8.0, 8.0),
                egui::Align2::LEFT_TOP,
                note,
                egui::FontId::proportional(14.0),
                Color32::YELLOW,
            );
        }
    }

    fn camera_input(&mut self, ui: &mut Ui, response: &egui::Response) {
        let dt = self.ui_dt.clamp(0.0, 0.1);
        let mut c = self.cam;
        let turn = 0.004;
        let drag = response.drag_delta();
        match self.cam_mode {
            CamMode::Fly => {
                if response.dragged_by(PointerButton::Secondary) {
                    c.look(-drag.x * turn, -drag.y * turn);
                }
            }
            CamMode::Orbit => {
                if response.dragged_by(PointerButton::Secondary)
                    || response.dragged_by(PointerButton::Primary)
                {
                    c.orbit(-drag.x * turn, -drag.y * turn);
                }
            }
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                let f = 1.0015f32.powf(scroll);
                match self.cam_mode {
                    CamMode::Fly => self.speed = (self.speed * f).clamp(1e-4, 1e4),
                    CamMode::Orbit => c.zoom(1.0 / f),
                }
            }
        }
        if !ui.ctx().egui_wants_keyboard_input() {
            let (mut m, fast) = ui.input(|i| {
                let k = |key| if i.key_down(key) { 1.0 } else { 0.0 };
                (
                    glam::Vec3::new(
                        k(Key::D) - k(Key::A),
                        k(Key::E) - k(Key::Q),
                        k(Key::W) - k(Key::S),
                    ),
                    i.modifiers.shift,
                )
            });
            if m != glam::Vec3::ZERO {
                if fast {
                    m *= 4.0;
                }
                c.fly(m * self.speed * dt);
                ui.ctx().request_repaint();
            }
            if ui.input(|i| i.key_pressed(Key::R)) {
                c = self.home;
            }
            if ui.input(|i| i.key_pressed(Key::F12)) {
                self.request_png();
            }
            if ui.input(|i| i.key_pressed(Key::F11)) {
                self.save_exr();
            }
        }
        self.set_camera(c);
        if self.moving() {
            ui.ctx().request_repaint();
        }
    }
}

/// The method selector and the chosen method's own knobs (its room's panel section).
fn method_controls(ui: &mut Ui, s: &mut UiSettings) {
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
fn clustering_controls(ui: &mut Ui, s: &mut UiSettings, r: &SliderRanges, gamma_used: Option<u32>) {
    let colom = s.method.method == Method::Colom;
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
    ui.horizontal(|ui| {
        ui.checkbox(&mut s.sp_on, "SP clustering");
        ui.checkbox(&mut s.vpl_on, "VPL clustering");
        ui.checkbox(&mut s.direct_on, "direct");
    });
    adaptation_controls(ui, s, colom);
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
    let cos = s.nt_degrees.to_radians().cos();
    ui.add(
        Slider::new(&mut s.nt_degrees, 0.0..=180.0)
            .suffix("°")
            .text(format!("n_t (cos {cos:.3})")),
    );
    ui.add(Slider::new(&mut s.cluster.iterations, 0..=r.iterations).text("k-means iterations"));
}
