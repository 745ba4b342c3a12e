//! What the window and the offscreen viewer (`view --offscreen`) share: the device, egui and its
//! renderer, the display pass and the reprojection of the shared display path, and one window frame
//! of the viewer from its input to painting into a target (`Painter::frame`, `paint`, `finish`).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::Viewer;

pub struct Painter {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    /// The target's format (the surface's, or the offscreen texture's).
    pub format: wgpu::TextureFormat,
    pub egui: egui::Context,
    pub renderer: egui_wgpu::Renderer,
    /// The display pass (built on first use), the frame's images on this device, and the texture
    /// egui draws with the key of what it holds.
    display: Option<super::display::Display>,
    uploads: super::display::Uploads,
    native: Option<(egui::TextureId, (u32, u32))>,
    drawn: String,
    /// The reprojection of the shared path (built on first use), the key of what it holds, and
    /// whether egui's texture shows it (else the display's output).
    reproject: Option<super::reproject_gpu::Reproject>,
    reprojected: String,
    native_source: bool,
}

impl Painter {
    pub fn new(device: wgpu::Device, queue: wgpu::Queue, format: wgpu::TextureFormat) -> Painter {
        let renderer = egui_wgpu::Renderer::new(&device, format, Default::default());
        Painter {
            device,
            queue,
            format,
            egui: egui::Context::default(),
            renderer,
            display: None,
            uploads: Default::default(),
            native: None,
            drawn: String::new(),
            reproject: None,
            reprojected: String::new(),
            native_source: false,
        }
    }

    /// Draws the image area's view with the display pass when it applies (`Viewer::gpu_view`), only
    /// when what it shows changed, and tells the viewer which texture to paint.
    pub fn draw_display(&mut self, v: &mut Viewer) {
        let Some(gv) = v.gpu_view() else {
            v.gpu_texture = None;
            return;
        };
        let key = gv.key();
        let (note, camera) = (gv.note, gv.camera.clone());
        let display = self
            .display
            .get_or_insert_with(|| super::display::Display::new(&self.device));
        let mut enc = self.device.create_command_encoder(&Default::default());
        let mut remade = false;
        if display.target().is_none() || self.drawn != key {
            let inputs = self.uploads.inputs(&self.device, &self.queue, &gv);
            remade |= display.record(&self.device, &self.queue, &mut enc, &inputs);
            self.drawn = key.clone();
        }
        let shown = match gv.reproject {
            Some((old, new, gbuffer)) => {
                let rkey = format!("{key} {new:?}");
                let r = self
                    .reproject
                    .get_or_insert_with(|| super::reproject_gpu::Reproject::new(&self.device));
                if r.target().is_none() || self.reprojected != rkey || remade {
                    let image = &display.target().expect("drawn").texture;
                    remade |= r.record(
                        &self.device,
                        &self.queue,
                        &mut enc,
                        image,
                        gbuffer,
                        (&old, &new),
                    );
                    self.reprojected = rkey;
                }
                r.target().expect("recorded")
            }
            None => display.target().expect("drawn"),
        };
        self.queue.submit([enc.finish()]);
        let filter = wgpu::FilterMode::Linear;
        let source = gv.reproject.is_some();
        let id = match self.native {
            Some((id, _)) if remade || self.native_source != source => {
                self.renderer.update_egui_texture_from_wgpu_texture(
                    &self.device,
                    &shown.view,
                    filter,
                    id,
                );
                id
            }
            Some((id, _)) => id,
            None => self
                .renderer
                .register_native_texture(&self.device, &shown.view, filter),
        };
        self.native = Some((id, shown.size));
        self.native_source = source;
        v.note = note;
        v.shown_camera = Some(camera);
        v.gpu_texture = self.native;
        v.image_dirty = false;
    }

    /// Uploads the textures egui set this frame.
    pub fn upload_textures(&mut self, textures: &egui::TexturesDelta) {
        for (id, deltas) in &textures.set {
            for delta in deltas {
                self.renderer
                    .update_texture(&self.device, &self.queue, *id, delta);
            }
        }
    }

    pub fn free_textures<'a>(&mut self, freed: impl IntoIterator<Item = &'a egui::TextureId>) {
        for id in freed {
            self.renderer.free_texture(id);
        }
    }

    /// Draws egui's `jobs` into `target` (`size` pixels, of the painter's format); with a `png` path,
    /// also into an offscreen texture of the same size and format, returned with the path for
    /// `save_screenshot`. Submits.
    pub fn paint(
        &mut self,
        target: &wgpu::TextureView,
        size: (u32, u32),
        jobs: &[egui::ClippedPrimitive],
        pixels_per_point: f32,
        png: Option<PathBuf>,
    ) -> Option<(PathBuf, wgpu::Texture)> {
        let sd = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [size.0, size.1],
            pixels_per_point,
        };
        let mut enc = self.device.create_command_encoder(&Default::default());
        let cmds = self
            .renderer
            .update_buffers(&self.device, &self.queue, &mut enc, jobs, &sd);
        let shot = png.map(|path| {
            let tex = crate::gpu::texture_2d(
                &self.device,
                "screenshot",
                size,
                self.format,
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            );
            (path, tex)
        });
        let shot_view = shot
            .as_ref()
            .map(|(_, t)| t.create_view(&Default::default()));
        for target in std::iter::once(target).chain(shot_view.as_ref()) {
            let mut pass = enc
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("egui"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: target,
                        resolve_target: None,
                        depth_slice: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            self.renderer.render(&mut pass, jobs, &sd);
        }
        self.queue
            .submit(cmds.into_iter().chain(std::iter::once(enc.finish())));
        shot
    }

    /// One window frame of the viewer up to painting: the worker's replies, the animation, the
    /// display pass, egui with `input`, the viewer's tick. Returns egui's output, tessellated, with
    /// the textures to free after painting and the app time spent.
    pub fn frame(&mut self, v: &mut Viewer, input: egui::RawInput) -> Frame {
        let started = super::motion::AppTime::start();
        v.poll();
        v.animate_step();
        self.draw_display(v);
        let mut out = self.egui.run_ui(input, |ui| v.ui(ui));
        // Textures are uploaded before the target is asked for (a lost surface returns early) and
        // freed after the frame; egui asks that the delta be cleared once handled.
        let mut textures = std::mem::take(&mut out.textures_delta);
        self.upload_textures(&textures);
        let freed: Vec<egui::TextureId> = std::mem::take(&mut textures.free).into_iter().collect();
        textures.clear();
        v.tick();
        if v.script_started.is_some() {
            v.script_frames += 1;
        }
        let repaint = out
            .viewport_output
            .get(&egui::ViewportId::ROOT)
            .map(|o| o.repaint_delay)
            .unwrap_or(Duration::MAX);
        let jobs = self.egui.tessellate(out.shapes, out.pixels_per_point);
        Frame {
            jobs,
            pixels_per_point: out.pixels_per_point,
            platform: out.platform_output,
            freed,
            repaint,
            // App code ends here; the surface and present may wait for the display.
            app: super::motion::AppTime::stop(started),
        }
    }

    /// After painting and presenting: the viewer measures the window frame, the screenshot (if
    /// any) is saved, egui's freed textures go. Returns the viewer's exit, if it asked for one.
    pub fn finish(
        &mut self,
        v: &mut Viewer,
        f: &Frame,
        shot: Option<(PathBuf, wgpu::Texture)>,
    ) -> Option<Result<(), String>> {
        let now = Instant::now();
        v.presented(now);
        let traffic = crate::gpu::traffic::Traffic::now();
        if v.script_started.is_some() {
            let moving = v.animate || v.moving();
            v.ui_cost
                .frame(moving, f.app, traffic.since(v.traffic_mark), now);
        }
        v.traffic_mark = traffic;
        v.motion.input_at = None;
        self.free_textures(&f.freed);
        if let Some((path, tex)) = shot {
            save_screenshot(self, v, &path, &tex);
        }
        v.exit.take()
    }
}

/// A window frame's egui output, ready to paint.
pub struct Frame {
    pub jobs: Vec<egui::ClippedPrimitive>,
    pub pixels_per_point: f32,
    pub platform: egui::PlatformOutput,
    pub freed: Vec<egui::TextureId>,
    pub repaint: Duration,
    pub app: super::motion::AppTime,
}

/// Reads the screenshot texture back and writes it to `path` as PNG; the outcome goes to the panel
/// (`last_shot`), and ends a script whose last step it was (an error as the exit's error).
fn save_screenshot(g: &Painter, v: &mut Viewer, path: &Path, tex: &wgpu::Texture) {
    let saved = super::screenshot::read_texture_rgb8(&g.device, &g.queue, tex)
        .and_then(|(w, h, rgb)| crate::export::write_png_rgb8(path, w, h, rgb));
    let scripted = v
        .script
        .as_ref()
        .is_some_and(|sc| sc.left == 0 && sc.screenshot.as_deref() == Some(path));
    match saved {
        Ok(()) => {
            v.last_shot = format!("saved {}", path.display());
            if scripted {
                v.exit = Some(Ok(()));
            }
        }
        Err(e) => {
            v.last_shot = format!("{e:#}");
            if scripted {
                v.exit = Some(Err(format!("{e:#}")));
            }
        }
    }
}
