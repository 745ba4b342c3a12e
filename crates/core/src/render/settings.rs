//! What a frame is rendered with (the user's settings as they are, and how the indirect light is
//! computed), and the `Control` another thread follows and stops a frame with.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use crate::method::MethodSettings;
use crate::settings::{ClusterSettings, FrameSettings};

/// What a frame is rendered with: the user's settings (`crate::settings`) as they are, and how the
/// indirect light is computed.
#[derive(Clone, Debug, Default)]
pub struct RenderSettings {
    pub frame: FrameSettings,
    pub cluster: ClusterSettings,
    /// The method and its knobs (the paper's are `cluster`).
    pub method: MethodSettings,
    /// No clustering at all (Eq. 5 per pixel and VPL).
    pub reference: bool,
    /// Print progress of long passes on stderr.
    pub progress: bool,
    /// Shared with another thread (the viewer): progress of the long gather passes and a cancel flag
    /// checked between their dispatches.
    pub control: Option<Arc<Control>>,
}

/// Progress of a frame's long pass (`reference` / `gather`) and a request to stop it, shared between
/// the rendering thread and another one. A cancelled frame returns the error `Cancelled`.
#[derive(Debug, Default)]
pub struct Control {
    pub cancel: AtomicBool,
    /// Dispatches of the long pass done and in all (0 / 0 until it starts).
    pub done: AtomicU64,
    pub total: AtomicU64,
}

impl Control {
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
    pub fn is_cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }
    /// Fraction of the long pass done, 0..1.
    pub fn fraction(&self) -> f32 {
        let all = self.total.load(Ordering::Relaxed);
        if all == 0 {
            0.0
        } else {
            self.done.load(Ordering::Relaxed) as f32 / all as f32
        }
    }
}

/// The error of a frame stopped through `Control::cancel`.
#[derive(Debug, thiserror::Error)]
#[error("frame cancelled")]
pub struct Cancelled;
