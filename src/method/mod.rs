//! The methods that compute a frame's indirect light besides colom's own passes (docs/methods.md).
//! Each lives in its own folder: its passes (a Rust module driving the WGSL file of its name), its
//! resident and per-frame state, and its production CPU stages. All reuse the shared passes of `gi`
//! (VPLs, primary rays, direct light, the gather of Eq. 5) and reach the frame through one trait,
//! `IndirectMethod`; `ROOMS` is the registry `render::pipeline` picks a method's passes and its
//! state from. A new method is a folder and a line in `ROOMS`.

pub mod cvrtgi;
pub mod lightcluster;
pub mod wang;

use std::any::Any;
use std::collections::BTreeMap;

use anyhow::Result;

use crate::gi::dispatch::Gpu;
use crate::gi::pass::Pass;
use crate::gi::primary::CameraParams;
use crate::gi::reference::Reference;
use crate::gi::render_settings::RenderSettings;
use crate::gi::scene_gpu::SceneGpu;
use crate::gi::vpl_cluster::ResidentLights;
use crate::gi::vpl_trace::ResidentVpls;
use crate::gpu::GpuContext;
use crate::scene::Scene;
use crate::settings::Method;

/// What a method's passes read from the frame: the scene and settings, the resident VPLs (and the
/// VPL clustering when the plan asks for one), the shared gather pass, the G-buffer of primary hits
/// and the buffer the indirect light goes to (vec4 a pixel, linear, render units).
pub struct FrameInputs<'a> {
    pub scene: &'a Scene,
    pub settings: &'a RenderSettings,
    pub vpls: &'a ResidentVpls,
    pub lights: Option<&'a ResidentLights>,
    /// The gather of every light with its own shadow ray (`reference.wgsl`, Eq. 5).
    pub reference: &'a Reference,
    pub gbuffer: &'a wgpu::Buffer,
    pub pixels: u32,
    pub cam: CameraParams,
    pub indirect: &'a wgpu::Buffer,
}

/// What a frame's indirect passes report for the stats (`Frame`): the shadow rays they traced, the
/// SP and VPL clusters they used, and the CPU milliseconds of a pass's steps (added to its GPU time).
#[derive(Clone, Debug, Default)]
pub struct MethodCounts {
    pub indirect_rays: u64,
    pub sp_used: u32,
    pub vpl_clusters_used: u32,
    pub cpu_ms: Vec<(Pass, f64)>,
}

/// A method's resident state and the recording of its passes.
pub trait IndirectMethod: Any {
    /// Records `pass` (one of its room's `passes`, in their order within a frame).
    fn record(
        &mut self,
        pass: Pass,
        gpu: &mut Gpu,
        frame: &FrameInputs,
        counts: &mut MethodCounts,
    ) -> Result<()>;

    /// The timings of resident stages (re)built during this frame, taken out of the frame's
    /// `timings` (they are not the frame's, as the VPLs' are not); none by default.
    fn take_resident_timings(
        &mut self,
        _timings: &mut BTreeMap<String, f64>,
    ) -> BTreeMap<String, f64> {
        BTreeMap::new()
    }

    /// The state itself, for tests and views (`Renderer::method_state`).
    fn as_any(&self) -> &dyn Any;
}

/// A method in the registry: its name, its passes in order, and how its state is built (the first
/// time a frame uses it on a scene's GPU data).
pub struct Room {
    pub method: Method,
    pub passes: &'static [Pass],
    pub build: fn(&GpuContext, &SceneGpu) -> Box<dyn IndirectMethod>,
}

/// The registry. colom (the paper) is not here: its passes are the renderer's own, since every
/// method's reference is colom's unclustered gather.
pub const ROOMS: &[Room] = &[wang::ROOM, lightcluster::ROOM, cvrtgi::ROOM];

/// `method`'s room, `None` for colom.
pub fn room(method: Method) -> Option<&'static Room> {
    ROOMS.iter().find(|r| r.method == method)
}
