//! The window: winit event loop, the window's own wgpu device and surface, egui input and rendering,
//! and the PNG screenshot (egui rendered a second time into an offscreen texture and read back).

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Result, anyhow};
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::window::{Window, WindowId};

use super::panel::{PANEL_WIDTH, STATS_HEIGHT};
use super::{Unavailable, ViewOptions, Viewer};

/// The one-line message for a window that cannot open.
fn no_display(detail: &str) -> String {
    let var = |k| std::env::var(k).ok().filter(|v| !v.is_empty());
    let what = match (var("DISPLAY"), var("WAYLAND_DISPLAY")) {
        (None, None) => "no display (DISPLAY and WAYLAND_DISPLAY are unset)".to_string(),
        (Some(d), _) => format!("cannot open a window on DISPLAY={d}"),
        (None, Some(w)) => format!("cannot open a window on WAYLAND_DISPLAY={w}"),
    };
    // winit's errors start with the source location; keep only its last clause.
    let detail = detail
        .rsplit(": ")
        .next()
        .unwrap_or(detail)
        .trim_end_matches('.');
    format!("{what} ({detail}); render headless with `fuzzy-vpl render` instead")
}

/// The surface size for a window of `size` physical pixels on a device whose textures are at most
/// `max_side` px a side: configuring a surface beyond the device's limit is a wgpu panic, so a
/// larger window is drawn only in its top-left part.
pub fn surface_size(size: winit::dpi::PhysicalSize<u32>, max_side: u32) -> (u32, u32) {
    (
        size.width.clamp(1, max_side.max(1)),
        size.height.clamp(1, max_side.max(1)),
    )
}

/// The worker's "a reply is waiting".
#[derive(Debug, Clone, Copy)]
pub struct Wake;

struct Gfx {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    state: egui_winit::State,
    /// The device, egui and the display passes (shared with `view --offscreen`).
    p: super::painter::Painter,
}

struct App {
    opts: Option<ViewOptions>,
    proxy: EventLoopProxy<Wake>,
    gfx: Option<Gfx>,
    viewer: Option<Viewer>,
    result: Result<()>,
    last_frame: Instant,
    redraw_at: Option<Instant>,
}

pub fn run(opts: ViewOptions) -> Result<()> {
    let event_loop = EventLoop::<Wake>::with_user_event()
        .build()
        .map_err(|e| Unavailable(no_display(&e.to_string())))?;
    let mut app = App {
        proxy: event_loop.create_proxy(),
        opts: Some(opts),
        gfx: None,
        viewer: None,
        result: Ok(()),
        last_frame: Instant::now(),
        redraw_at: None,
    };
    event_loop.run_app(&mut app).map_err(|e| {
        Unavailable(format!(
            "the window's event loop failed ({e}); render headless with `fuzzy-vpl render`"
        ))
    })?;
    let viewer = app.viewer.take();
    if let Some(v) = &viewer {
        summary(v);
    }
    // The worker may be inside a long frame: leave without waiting for it.
    std::mem::forget(viewer);
    app.result
}

/// A scripted run's last line on stderr: window and GI frames and their rates.
pub(super) fn summary(v: &Viewer) {
    if v.script.is_none() {
        return;
    }
    let secs = v.script_started.map_or(0.0, |t| t.elapsed().as_secs_f64());
    eprintln!(
        "view: {} window frames ({:.1} fps over the last {secs:.1} s), {} GI frames, mean {:.0} ms wall",
        v.ui_frames,
        v.script_frames as f64 / secs.max(1e-9),
        v.gi_frames,
        v.gi_ms_sum / v.gi_frames.max(1) as f64
    );
}

/// The window's device for display path `path`, and (shared) the handles the GI worker renders
/// with: shared, the GI renders on it, so it gets the limits and features the GI asks for
/// (`gpu::required_limits`, with the adapter's texture size for the surface); split, the default
/// limits at the adapter's resolution.
pub(super) fn device_for(
    instance: &wgpu::Instance,
    adapter: &wgpu::Adapter,
    path: super::DisplayPath,
) -> Result<(
    wgpu::Device,
    wgpu::Queue,
    Option<super::worker::SharedDevice>,
)> {
    let shared = path == super::DisplayPath::Shared;
    let max_side = adapter.limits().max_texture_dimension_2d;
    let (required_limits, required_features) = match shared {
        true => (
            wgpu::Limits {
                max_texture_dimension_2d: max_side,
                ..crate::gpu::required_limits(&adapter.limits())
            },
            adapter.features() & crate::gpu::wanted_features(),
        ),
        false => (
            wgpu::Limits::default().using_resolution(adapter.limits()),
            wgpu::Features::empty(),
        ),
    };
    let made = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("fuzzy-vpl window"),
        required_limits,
        required_features,
        ..Default::default()
    }));
    let (device, queue) = made.map_err(|e| {
        Unavailable(format!(
            "cannot open the window's GPU device ({e}); render headless with `fuzzy-vpl render`"
        ))
    })?;
    let handles = shared.then(|| super::worker::SharedDevice {
        instance: instance.clone(),
        adapter: adapter.clone(),
        device: device.clone(),
        queue: queue.clone(),
    });
    Ok((device, queue, handles))
}

impl App {
    fn fail(&mut self, el: &ActiveEventLoop, e: anyhow::Error) {
        self.result = Err(e);
        el.exit();
    }

    fn init(&mut self, el: &ActiveEventLoop) -> Result<()> {
        let opts = self.opts.take().expect("init once");
        let attrs = Window::default_attributes()
            .with_title(format!("fuzzy-vpl — {}", opts.spec))
            .with_inner_size(winit::dpi::LogicalSize::new(
                opts.width as f64 + PANEL_WIDTH as f64,
                opts.height as f64 + STATS_HEIGHT as f64,
            ));
        let window = Arc::new(
            el.create_window(attrs)
                .map_err(|e| Unavailable(no_display(&e.to_string())))?,
        );
        let instance = crate::gpu::instance();
        let surface = instance.create_surface(window.clone()).map_err(|e| {
            Unavailable(format!(
                "no GPU adapter can draw into the window ({e}); install mesa-vulkan-drivers, or render headless with `fuzzy-vpl render`"
            ))
        })?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: Some(&surface),
            apply_limit_buckets: false,
        }))
        .map_err(|e| {
            Unavailable(format!(
                "no GPU adapter for the window ({e}); install mesa-vulkan-drivers, or render headless with `fuzzy-vpl render`"
            ))
        })?;
        // The default limits cap textures, and so the surface, at 8192 px a side: ask for the
        // adapter's real size limit (lavapipe: 16384) so wide windows (or several monitors) present.
        let max_side = adapter.limits().max_texture_dimension_2d;
        let size = window.inner_size();
        if size.width > max_side || size.height > max_side {
            return Err(Unavailable(format!(
                "--width/--height {}x{}: the window would be {}x{} px (with the {PANEL_WIDTH} px panel and the {STATS_HEIGHT} px stats strip), more than the {max_side} px a side this adapter can present",
                opts.width, opts.height, size.width, size.height
            ))
            .into());
        }
        let software = adapter.get_info().device_type == wgpu::DeviceType::Cpu;
        let path = opts.display_path.resolve(software);
        let (device, queue, shared) = device_for(&instance, &adapter, path)?;
        let caps = surface.get_capabilities(&adapter);
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| {
                matches!(
                    f,
                    wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
                )
            })
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| Unavailable("the window's surface offers no format".into()))?;
        let (width, height) = surface_size(size, device.limits().max_texture_dimension_2d);
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width,
            height,
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            view_formats: vec![],
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(&device, &config);
        let painter = super::painter::Painter::new(device.clone(), queue.clone(), format);
        let state = egui_winit::State::new(
            painter.egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(device.limits().max_texture_dimension_2d as usize),
        );
        let proxy = self.proxy.clone();
        let wake: Arc<dyn Fn() + Send + Sync> = Arc::new(move || {
            let _ = proxy.send_event(Wake);
        });
        let ppp = window.scale_factor() as f32;
        let mut viewer = Viewer::new(opts, wake, shared);
        viewer.area_px = [
            (viewer.area_px[0] as f32 * ppp) as u32,
            (viewer.area_px[1] as f32 * ppp) as u32,
        ];
        self.viewer = Some(viewer);
        self.gfx = Some(Gfx {
            window,
            surface,
            config,
            state,
            p: painter,
        });
        Ok(())
    }

    fn redraw(&mut self, el: &ActiveEventLoop) -> Result<()> {
        let (Some(g), Some(v)) = (&mut self.gfx, &mut self.viewer) else {
            return Ok(());
        };
        self.last_frame = Instant::now();
        self.redraw_at = None;
        let input = g.state.take_egui_input(&g.window);
        let mut f = g.p.frame(v, input);
        g.state
            .handle_platform_output(&g.window, std::mem::take(&mut f.platform));
        let repaint = f.repaint;
        let Some(frame) = g.surface_texture() else {
            g.p.free_textures(&f.freed);
            g.window.request_redraw();
            return Ok(());
        };
        let shot = g.present(frame, &f, v.png_request.take());
        if let Some(done) = g.p.finish(v, &f, shot) {
            if let Err(e) = done {
                return Err(anyhow!(e));
            }
            el.exit();
            return Ok(());
        }
        let delay = redraw_delay(v, repaint);
        if delay < Duration::from_secs(3600) {
            self.redraw_at = Some(Instant::now() + delay);
        }
        Ok(())
    }
}

impl Gfx {
    /// The surface's next texture; `None` when there is none this time (an outdated or lost
    /// surface is configured again).
    fn surface_texture(&mut self) -> Option<wgpu::SurfaceTexture> {
        match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => Some(t),
            other => {
                if matches!(
                    other,
                    wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost
                ) {
                    self.surface.configure(&self.p.device, &self.config);
                }
                None
            }
        }
    }

    /// Paints egui's output into the surface's `frame` and presents it.
    fn present(
        &mut self,
        frame: wgpu::SurfaceTexture,
        f: &super::painter::Frame,
        png: Option<PathBuf>,
    ) -> Option<(PathBuf, wgpu::Texture)> {
        let view = frame.texture.create_view(&Default::default());
        let size = (self.config.width, self.config.height);
        let shot = self.p.paint(&view, size, &f.jobs, f.pixels_per_point, png);
        self.window.pre_present_notify();
        self.p.queue.present(frame);
        shot
    }
}

/// How long until the next redraw: scripted runs, moving cameras and reprojected images draw
/// continuously; otherwise egui says when (`repaint`; at most 100 ms apart while a script waits).
pub(super) fn redraw_delay(v: &Viewer, repaint: Duration) -> Duration {
    if v.animate || v.moving() || v.script_started.is_some() || v.image_stale() {
        Duration::ZERO
    } else if v.script.is_some() {
        repaint.min(Duration::from_millis(100))
    } else {
        repaint
    }
}

impl ApplicationHandler<Wake> for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.gfx.is_none()
            && self.opts.is_some()
            && let Err(e) = self.init(el)
        {
            self.fail(el, e);
        }
    }

    fn user_event(&mut self, _el: &ActiveEventLoop, _e: Wake) {
        if let Some(g) = &self.gfx {
            g.window.request_redraw();
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(g) = &mut self.gfx else { return };
        if let Some(v) = &mut self.viewer
            && matches!(
                event,
                WindowEvent::KeyboardInput { .. }
                    | WindowEvent::CursorMoved { .. }
                    | WindowEvent::MouseInput { .. }
                    | WindowEvent::MouseWheel { .. }
            )
        {
            v.motion.input_at.get_or_insert_with(Instant::now);
        }
        let resp = g.state.on_window_event(&g.window, &event);
        match event {
            WindowEvent::CloseRequested => el.exit(),
            WindowEvent::Resized(size) => {
                let max_side = g.p.device.limits().max_texture_dimension_2d;
                (g.config.width, g.config.height) = surface_size(size, max_side);
                if let Some(v) = &mut self.viewer
                    && (size.width > max_side || size.height > max_side)
                {
                    v.status = format!(
                        "the window ({}x{} px) is larger than the {max_side} px a side this adapter presents: only the top-left {}x{} px are drawn",
                        size.width, size.height, g.config.width, g.config.height
                    );
                }
                g.surface.configure(&g.p.device, &g.config);
                g.window.request_redraw();
            }
            WindowEvent::DroppedFile(path) => {
                if let Some(v) = &mut self.viewer {
                    v.open(path.to_string_lossy().into_owned());
                }
                g.window.request_redraw();
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(el) {
                    self.fail(el, e);
                }
            }
            _ => {
                if resp.repaint {
                    g.window.request_redraw();
                }
            }
        }
    }

    fn about_to_wait(&mut self, el: &ActiveEventLoop) {
        match self.redraw_at {
            Some(t) => {
                let min = self
                    .viewer
                    .as_ref()
                    .map_or(Duration::from_millis(16), |v| v.min_frame());
                let t = t.max(self.last_frame + min);
                if Instant::now() >= t {
                    self.redraw_at = None;
                    if let Some(g) = &self.gfx {
                        g.window.request_redraw();
                    }
                    el.set_control_flow(ControlFlow::Wait);
                } else {
                    el.set_control_flow(ControlFlow::WaitUntil(t));
                }
            }
            None => el.set_control_flow(ControlFlow::Wait),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use winit::dpi::PhysicalSize;

    #[test]
    fn surface_size_stays_within_the_device_limit() {
        assert_eq!(surface_size(PhysicalSize::new(640, 480), 8192), (640, 480));
        assert_eq!(surface_size(PhysicalSize::new(0, 0), 8192), (1, 1));
        assert_eq!(surface_size(PhysicalSize::new(8193, 72), 8192), (8192, 72));
        assert_eq!(
            surface_size(PhysicalSize::new(20000, 30000), 16384),
            (16384, 16384)
        );
    }
}
