//! What bounds a frame on an adapter: each per-pixel buffer, the VPL buffer and a method's own
//! largest buffer is one storage binding (`max_storage_buffer_binding_size`; lavapipe: 128 MiB).
//! Checked before any work, so that creating a bind group never panics.

use crate::gi::primary::SP_BYTES;
use crate::gpu::GpuContext;
use crate::render::plan::Plan;
use crate::render::settings::RenderSettings;
use crate::settings::MAX_F;

/// Bytes a pixel takes in a frame's largest per-pixel storage binding: the G-buffer (`SP_BYTES`);
/// the k-means' per-pixel assign and weight lists (F ≤ `MAX_F` words) are no larger. One binding
/// holds at most `max_storage_buffer_binding_size` bytes (lavapipe: 128 MiB, 2,097,152 pixels).
pub const PIXEL_BYTES: u64 = if SP_BYTES > MAX_F as u64 * 4 {
    SP_BYTES
} else {
    MAX_F as u64 * 4
};

/// The path tracer's: its accumulation buffer, 16 bytes a pixel.
pub const PATH_TRACE_PIXEL_BYTES: u64 = 16;

/// The most pixels a frame may have on `ctx` when each takes `bytes_per_pixel` in one binding.
pub fn max_pixels(ctx: &GpuContext, bytes_per_pixel: u64) -> u64 {
    ctx.max_binding() / bytes_per_pixel
}

/// A frame too large for one storage binding of this adapter (creating its bind groups would be a
/// wgpu panic).
#[derive(Debug, thiserror::Error)]
#[error(
    "a {width}x{height} frame has {} pixels; this adapter holds at most {most} ({bytes} bytes a pixel in one {binding}-byte storage binding)",
    *width as u64 * *height as u64
)]
pub struct TooLarge {
    pub width: u32,
    pub height: u32,
    pub most: u64,
    pub bytes: u64,
    pub binding: u64,
}

/// Refuses a frame whose per-pixel buffers do not fit in one storage binding of `ctx`.
pub fn check_frame_size(
    ctx: &GpuContext,
    width: u32,
    height: u32,
    bytes_per_pixel: u64,
) -> Result<(), TooLarge> {
    let most = max_pixels(ctx, bytes_per_pixel);
    if width as u64 * height as u64 > most {
        return Err(TooLarge {
            width,
            height,
            most,
            bytes: bytes_per_pixel,
            binding: ctx.max_binding(),
        });
    }
    Ok(())
}

/// Refuses `--vpls` beyond what one storage binding of `ctx` holds (the VPL buffer); the message
/// names the option.
pub fn check_vpls(ctx: &GpuContext, vpls: u32) -> Result<(), String> {
    use crate::gi::vpl_trace::VPL_BYTES;
    let binding = ctx.max_binding();
    let most = binding / VPL_BYTES;
    if vpls as u64 > most {
        return Err(format!(
            "--vpls {vpls}: at most {most} on this adapter ({VPL_BYTES} bytes a VPL in one {binding}-byte storage binding)"
        ));
    }
    Ok(())
}

/// Refuses a frame whose method's own largest buffer does not fit one storage binding of `ctx`
/// (its entry's `limits`, e.g. a visibility bit matrix of K_SP × lights bits); the message names the
/// options. The shared gather has none.
pub fn check_method_limits(
    ctx: &GpuContext,
    plan: &Plan,
    s: &RenderSettings,
) -> Result<(), String> {
    let Some(method) = plan.method else {
        return Ok(());
    };
    (crate::method::entry(method).limits)(&crate::method::Limits {
        max_binding: ctx.max_binding(),
        cluster: &s.cluster,
        lights: plan.lights(s),
        lights_clustered: plan.vpl_clustering,
    })
}
