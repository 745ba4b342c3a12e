//! What temporal accumulation (`gi::accumulate`) carries from one frame to the next: the frame's
//! accumulated indirect light, its G-buffer and camera, and the settings they were rendered with.

use crate::gi::accumulate::AccumulateParams;
use crate::gi::primary::CameraParams;
use crate::method::MethodSettings;
use crate::render::settings::RenderSettings;
use crate::settings::{ClusterSettings, FrameSettings};

/// Everything but the camera that a frame's indirect light depends on: a history rendered with
/// another key is not used (`Renderer::set_lights` and `forget_past` drop it too).
#[derive(Clone, Debug, PartialEq)]
pub struct HistoryKey {
    frame: FrameSettings,
    cluster: ClusterSettings,
    method: MethodSettings,
}

impl HistoryKey {
    pub fn of(s: &RenderSettings) -> Self {
        HistoryKey {
            frame: s.frame,
            cluster: s.cluster.clone(),
            method: s.method,
        }
    }
}

/// A frame's accumulated indirect light (a vec4 a pixel, w = the frames it averages), on its
/// G-buffer, seen from `cam` (all at the image's size).
pub struct History {
    /// The frame's buffers: its image G-buffer and accumulated indirect light
    /// (`FrameBuffers::image_gbuffer`, `image_indirect`), held so that no later frame reuses them.
    pub buffers: std::sync::Arc<super::frame::FrameBuffers>,
    pub cam: CameraParams,
    pub key: HistoryKey,
}

impl History {
    /// The kernel's uniform for a frame of `s` seen from `cam`, onto `history` where it was rendered
    /// with the same key and size (else the frame starts a history).
    pub fn params<'h>(
        history: Option<&'h History>,
        s: &RenderSettings,
        cam: &CameraParams,
    ) -> (AccumulateParams, Option<&'h History>) {
        let key = HistoryKey::of(s);
        let h = history.filter(|h| h.key == key && h.cam.size[..2] == cam.size[..2]);
        let p = AccumulateParams::new(cam, h.map(|h| &h.cam), s.cluster.temporal_alpha);
        (p, h)
    }
}
