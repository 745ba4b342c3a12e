//! What a frame produces and what bounds it: the `Frame` a render returns, the checks that its
//! buffers fit the adapter's storage bindings, and the `Control` another thread stops it with.

use std::collections::BTreeMap;

use super::pipeline::{Pass, Plan, RenderSettings};
use crate::gi::primary::SP_BYTES;
use crate::gpu::GpuContext;
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

/// Bytes of the visibility bit matrix a frame records (0 when it clusters no SPs): one row per SP
/// cluster, one bit per light, the lights being the VPL clusters or, unclustered, every VPL (an
/// upper bound: fewer may be traced or used). It is one storage binding.
pub fn visibility_bytes(plan: &Plan, s: &RenderSettings) -> u64 {
    if !plan.sp_clustering {
        return 0;
    }
    s.cluster.sp_clusters as u64 * visibility_lights(plan, s).div_ceil(32).max(1) as u64 * 4
}

fn visibility_lights(plan: &Plan, s: &RenderSettings) -> u32 {
    if plan.vpl_clustering {
        s.cluster.vpl_clusters
    } else {
        s.frame.vpls
    }
}

/// Refuses a frame whose visibility bit matrix does not fit in one storage binding of `ctx` (K_sp ×
/// lights / 8 bytes: 200,000 SP clusters × 8192 VPLs is 205 MB, lavapipe binds 128 MiB): the message
/// names the options.
pub fn check_visibility_size(
    ctx: &GpuContext,
    plan: &Plan,
    s: &RenderSettings,
) -> Result<(), String> {
    let bytes = visibility_bytes(plan, s);
    let binding = ctx.max_binding();
    if bytes > binding {
        let lights = visibility_lights(plan, s);
        let what = if plan.vpl_clustering {
            "VPL clusters"
        } else {
            "VPLs"
        };
        return Err(format!(
            "--sp-clusters {} with {lights} {what}: the visibility bit matrix (a bit per SP cluster and light) takes {bytes} bytes, more than the {binding} bytes of one storage binding on this adapter; use fewer SP clusters or cluster the VPLs",
            s.cluster.sp_clusters
        ));
    }
    Ok(())
}

/// A rendered frame: linear radiance per pixel, row-major from the top-left.
#[derive(Clone, Debug, Default)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// emission + direct + indirect.
    pub radiance: Vec<[f32; 3]>,
    /// emission + direct.
    pub direct: Vec<[f32; 3]>,
    /// Indirect light from the VPLs (zero when none ran).
    pub indirect: Vec<[f32; 3]>,
    pub vpls: u32,
    /// Passes that ran, in order.
    pub passes: Vec<Pass>,
    /// GPU milliseconds per pass (summed over its dispatches); `frame` excludes resident VPL work.
    pub timings_ms: BTreeMap<String, f64>,
    pub shading_points: u32,
    pub shadow_rays: u64,
    pub sp_clusters_used: u32,
    pub vpl_clusters_used: u32,
    /// γ Alg. 1 sampled with (`kmeans::effective_gamma`); `None` when no SP clustering ran.
    pub gamma_used: Option<u32>,
    /// The shading point of each pixel: world position, w = 1 where the primary ray hit (0: sky).
    /// What the viewer reprojects a frame with.
    pub positions: Vec<[f32; 4]>,
    /// The shading normal of each pixel's shading point (xyz; zero where the ray missed): with
    /// `positions`, what tells two frames' pixels show the same surface (`metrics::instability_world`).
    pub normals: Vec<[f32; 4]>,
    /// Alg. 1 iterations the SP clustering ran (0 when none ran).
    pub sp_iterations: u32,
    /// SP centroids a temporal warm start kept from the previous frame (`None`: a cold start).
    pub sp_warm_kept: Option<u32>,
    /// Rows of the visibility matrix copied from the previous frame instead of traced (kept
    /// representatives, same lights).
    pub visibility_rows_reused: u32,
    /// With `--method cvrtgi`: its voxels, clusters, faces and lit clusters and voxels, and the
    /// rays and CPU time of the resident stages this frame (re)built.
    pub cvrtgi: Option<crate::method::cvrtgi::CvrtgiReport>,
}

impl Frame {
    /// GPU milliseconds of `pass` (0 when it did not run).
    pub fn ms(&self, pass: Pass) -> f64 {
        self.timings_ms.get(pass.name()).copied().unwrap_or(0.0)
    }

    /// GPU milliseconds of the whole frame (`FRAME_KEY`: every pass but the resident VPL work).
    pub fn frame_ms(&self) -> f64 {
        self.timings_ms.get(FRAME_KEY).copied().unwrap_or(0.0)
    }

    pub fn ran(&self, pass: Pass) -> bool {
        self.passes.contains(&pass)
    }
}

/// The timing key of the whole frame (docs/design.md, "Stats JSON").
pub const FRAME_KEY: &str = "frame";
