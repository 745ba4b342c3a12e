//! The image area: the GI image filling the central panel, the split view's divider, the VPL
//! dots, the colour bar and the view's note over it, and the camera input it takes.

use egui::{Color32, Key, PointerButton, Sense, Ui};

use crate::app::Viewer;
use crate::app::camera::Mode as CamMode;
use crate::app::views::{self, View};

impl Viewer {
    /// The GI image, filling the central area, and the camera input over it.
    pub(super) fn image_area(&mut self, ui: &mut Ui) {
        let size = ui.available_size();
        self.track_area_size(ui, size);
        let (rect, response) = ui.allocate_exact_size(size, Sense::click_and_drag());
        let split_view = self.view == View::Split;
        let on_divider = split_view && self.split_divider(ui, rect);
        // Camera input first, so that this frame's image is already the new camera's.
        if !on_divider {
            self.camera_input(ui, &response);
        }
        self.upload_image(ui);
        self.paint_image(ui, rect);
        if split_view && self.note.is_none() {
            self.paint_split_labels(ui, rect);
        }
        if self.note.is_none()
            && let Some((ramp, labels)) = views::colour_bar(self.view, 64)
        {
            paint_colour_bar(ui, rect, &ramp, &labels);
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

    /// The image area's size in physical pixels (at least 8 × 8), which the GI frames follow.
    fn track_area_size(&mut self, ui: &Ui, size: egui::Vec2) {
        let ppp = ui.ctx().pixels_per_point();
        let px = [
            ((size.x * ppp) as u32).max(8),
            ((size.y * ppp) as u32).max(8),
        ];
        if px != self.area_px {
            self.area_px = px;
        }
    }

    /// The split view's divider: a handle over the image that takes drags before the camera.
    /// Returns whether the pointer is on it (dragging or hovering).
    fn split_divider(&mut self, ui: &mut Ui, rect: egui::Rect) -> bool {
        let x = rect.left() + rect.width() * self.split;
        let handle = egui::Rect::from_x_y_ranges(x - 6.0..=x + 6.0, rect.y_range());
        let h = ui.interact(handle, ui.unique_id().with("split_divider"), Sense::drag());
        if h.dragged()
            && let Some(p) = h.interact_pointer_pos()
        {
            self.split = ((p.x - rect.left()) / rect.width()).clamp(0.0, 1.0);
        }
        let on_divider = h.dragged() || h.hovered();
        if on_divider {
            ui.ctx().set_cursor_icon(egui::CursorIcon::ResizeHorizontal);
        }
        on_divider
    }

    /// Without the display pass's texture: the view composed on the CPU into the egui texture,
    /// when it is stale.
    fn upload_image(&mut self, ui: &Ui) {
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
    }

    /// The display pass's texture (or the CPU-composed one) over `rect`, and the VPL dots over
    /// the display pass's VPL-clusters view.
    fn paint_image(&self, ui: &mut Ui, rect: egui::Rect) {
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
    }

    /// The split view's divider line, with "A" left of it and "B" right of it.
    fn paint_split_labels(&self, ui: &Ui, rect: egui::Rect) {
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

/// A false-colour view's scale at the bottom left of `rect`: the ramp's colours in a framed bar,
/// its three labels (low, middle, high) under it.
fn paint_colour_bar(ui: &Ui, rect: egui::Rect, ramp: &[[u8; 3]], labels: &[&str; 3]) {
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
