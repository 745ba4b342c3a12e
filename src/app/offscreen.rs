//! `view --offscreen`: the same viewer (app, panel, display passes) without a window or a display,
//! each window frame painted into an offscreen texture of the window's size instead of a surface, so
//! the viewer can be measured on a machine with a GPU and no X server. Input is none but the
//! scripted run's (`--animate`, `--frames`, `--view`); frames are paced as the window paces them.

use std::time::{Duration, Instant};

use anyhow::{Result, anyhow};

use super::painter::Painter;
use super::panel::{PANEL_WIDTH, STATS_HEIGHT};
use super::{Unavailable, ViewOptions, Viewer};

/// The target's format (a window's surface is usually BGRA or RGBA 8-bit, not sRGB).
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

pub fn run(opts: ViewOptions) -> Result<()> {
    let instance = crate::gpu::instance();
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        force_fallback_adapter: false,
        compatible_surface: None,
        apply_limit_buckets: false,
    }))
    .map_err(|e| {
        Unavailable(format!(
            "no GPU adapter ({e}); install mesa-vulkan-drivers for the software one"
        ))
    })?;
    // The window `view` would open: the image area plus the panel and the stats strip.
    let size = (
        opts.width + PANEL_WIDTH as u32,
        opts.height + STATS_HEIGHT as u32,
    );
    let max_side = adapter.limits().max_texture_dimension_2d;
    if size.0 > max_side || size.1 > max_side {
        return Err(Unavailable(format!(
            "--width/--height {}x{}: the offscreen window would be {}x{} px, more than the {max_side} px a side this adapter draws",
            opts.width, opts.height, size.0, size.1
        ))
        .into());
    }
    let software = adapter.get_info().device_type == wgpu::DeviceType::Cpu;
    let path = opts.display_path.resolve(software);
    let (device, queue, shared) = super::window::device_for(&instance, &adapter, path)?;
    let target = crate::gpu::texture_2d(
        &device,
        "offscreen window",
        size,
        FORMAT,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let view = target.create_view(&Default::default());
    let mut painter = Painter::new(device, queue, FORMAT);
    // No event loop to wake: the loop below polls the worker every window frame.
    let mut viewer = Viewer::new(opts, std::sync::Arc::new(|| {}), shared);
    let started = Instant::now();
    let result = loop {
        let frame_start = Instant::now();
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(
                egui::Pos2::ZERO,
                egui::vec2(size.0 as f32, size.1 as f32),
            )),
            time: Some(started.elapsed().as_secs_f64()),
            ..Default::default()
        };
        let f = painter.frame(&mut viewer, input);
        let shot = painter.paint(
            &view,
            size,
            &f.jobs,
            f.pixels_per_point,
            viewer.png_request.take(),
        );
        if let Some(done) = painter.finish(&mut viewer, &f, shot) {
            break done.map_err(|e| anyhow!(e));
        }
        // Paced as the window: at once while moving or scripted, at most every min_frame; else
        // when egui asks, but polling the worker at least every 50 ms (no event wakes this loop).
        let delay = super::window::redraw_delay(&viewer, f.repaint)
            .max(viewer.min_frame())
            .min(Duration::from_millis(50));
        let spent = frame_start.elapsed();
        if delay > spent {
            std::thread::sleep(delay - spent);
        }
    };
    super::window::summary(&viewer);
    // The worker may be inside a long frame: leave without waiting for it.
    std::mem::forget(viewer);
    result
}
