//! A frame, from the scene to the image. `Renderer` (`renderer.rs`) holds what one scene keeps on one
//! device; `Plan` (`plan.rs`) decides which passes a frame runs; `record.rs` records them in order
//! (the shared passes of `gi`, the method's of `method`, the shared ones again) and returns a
//! `GpuFrame` (`frame.rs`), read back only on request. `resident.rs` keeps the VPLs and their
//! clustering between frames, `history.rs` what temporal accumulation carries to the next,
//! `limits.rs` what an adapter holds, `refine.rs` the viewer's refinement at rest, `probe.rs` what
//! tests read; `timed.rs` renders frames for timing and `budget.rs` picks the clustering for a time
//! target.
//!
//! Each name is reached one way: through this module (`render::Renderer`, `render::Frame`, ...).

pub mod budget;
mod frame;
mod history;
mod limits;
mod path_trace;
mod plan;
mod probe;
mod record;
mod refine;
mod renderer;
mod resident;
mod settings;
pub mod timed;

pub use frame::{FRAME_KEY, Frame, FrameBuffers, FramePool, GpuFrame};
pub use history::{History, HistoryKey};
pub use limits::{
    PATH_TRACE_PIXEL_BYTES, PIXEL_BYTES, TooLarge, check_frame_size, check_method_limits,
    check_vpls, max_pixels,
};
pub use plan::Plan;
pub use renderer::Renderer;
pub use settings::{Cancelled, Control, RenderSettings};
