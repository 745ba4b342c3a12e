//! The interactive viewer (`fuzzy-vpl view`): winit + egui on the window's own wgpu device, with the
//! GI renderer on a worker thread (see docs/viewer.md).
//!
//! - `window.rs`: event loop, surface, egui rendering, PNG read-back.
//! - `worker.rs`: the GI thread (own `GpuContext` + `Scene` + `Renderer`), newest-job-wins.
//! - `panel.rs`: the side panel (settings, stats, reference, plot, screenshots) and the image area.
//! - `views.rs`: what the image area shows, composed from the last frame.
//! - `camera.rs`: fly / orbit camera. `bookmarks.rs`: the bookmarks file. `screenshot.rs`: file output.

pub mod bookmarks;
pub mod camera;
pub mod display;
pub mod flip;
pub mod lights;
pub mod motion;
pub mod offscreen;
pub mod painter;
pub mod panel;
pub mod reproject;
pub mod reproject_gpu;
pub mod screenshot;
pub mod twin;
pub mod views;
pub mod window;
pub mod worker;

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::Result;

use crate::exposure::Exposure;
use crate::method::{MethodEntry, MethodSettings};
use crate::render::{Control, RenderSettings};
use crate::scene::Scene;
use crate::settings::{ClusterSettings, FrameSettings, Weighting};
use bookmarks::BookmarksFile;
use camera::ViewCamera;
use views::View;
use worker::{FrameJob, Loader, Rendered, SceneInfo, Worker};

/// The viewer cannot start here (no display, no adapter): exit code 2, one line.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct Unavailable(pub String);

/// How the viewer starts.
pub struct ViewOptions {
    pub spec: String,
    pub scene: Scene,
    pub loader: Loader,
    /// Initial image area in logical pixels (the window adds the panel's width).
    pub width: u32,
    pub height: u32,
    pub camera: Option<usize>,
    pub settings: UiSettings,
    /// Scripted run: after this many window frames showing a full-scale GI frame, save the window
    /// to `screenshot` and exit.
    pub frames: Option<u32>,
    pub screenshot: Option<PathBuf>,
    /// The view to start in; a scripted run in `reference` or `error` computes the reference first.
    pub view: View,
    /// Keep moving the camera (`ViewCamera::animated`, for measuring frame rates while moving).
    pub animate: bool,
    /// Scripted run: write the motion stats JSON here once done.
    pub stats: Option<PathBuf>,
    /// Where panel screenshots go.
    pub shot_dir: PathBuf,
    /// The split view's B settings, pinned at start (`view --b-...`).
    pub b: Option<UiSettings>,
    /// Keep references on disk too (`view --keep-references`).
    pub refs_on_disk: bool,
    /// One device for the GI and the window, or a device each (`view --display-path`).
    pub display_path: DisplayPath,
    /// No window: paint into an offscreen texture of the window's size (`view --offscreen`).
    pub offscreen: bool,
}

/// How a GI frame reaches the window (`view --display-path`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DisplayPath {
    /// `shared` on a hardware adapter, `split` on a software one (lavapipe), where the GI device's
    /// threads running at a lower priority keep the window responsive.
    Auto,
    /// One device: the GI worker renders on the window's device and the window displays the frames'
    /// buffers where they are (nothing read back, nothing uploaded).
    Shared,
    /// The GI worker on a device of its own: each frame is read back and uploaded to the window's.
    Split,
}

impl DisplayPath {
    /// The path taken on an adapter that is (`software`) or is not a CPU.
    pub fn resolve(self, software: bool) -> DisplayPath {
        match self {
            DisplayPath::Auto if software => DisplayPath::Split,
            DisplayPath::Auto => DisplayPath::Shared,
            p => p,
        }
    }
}

pub fn run(opts: ViewOptions) -> Result<()> {
    if opts.offscreen {
        offscreen::run(opts)
    } else {
        window::run(opts)
    }
}

/// The panel's state: the settings types as the renderer takes them (their controls drawn from
/// their declarations), and what only a panel has (the exposure, the render scale, the direct
/// light switched off).
#[derive(Clone, Debug, PartialEq)]
pub struct UiSettings {
    /// The frame (its size is the viewer's GI size, set per frame).
    pub frame: FrameSettings,
    pub cluster: ClusterSettings,
    /// The method and its knobs (each method's declared controls).
    pub method: MethodSettings,
    /// The display exposure; with `exposure_auto` the panel keeps it at `exposure::auto_exposure` of
    /// the latest frame.
    pub exposure: f32,
    pub exposure_auto: bool,
    pub render_scale: f32,
    pub direct_on: bool,
}

impl UiSettings {
    /// The panel's state for `s`.
    pub fn new(s: &RenderSettings) -> Self {
        UiSettings {
            frame: s.frame,
            cluster: s.cluster.clone(),
            method: s.method,
            exposure: match s.frame.exposure {
                Exposure::Fixed(e) => e,
                Exposure::Auto => 1.0,
            },
            exposure_auto: s.frame.exposure.is_auto(),
            render_scale: 1.0,
            direct_on: true,
        }
    }

    /// The panel's "the paper" toggle (`--paper`): on, every setting at the paper's choice
    /// (`settings::paper::apply`, for a frame of `width` × `height`); off, the adaptations and the
    /// clamp back at their defaults (the clusters' K, F, n_t stay as they are).
    pub fn set_paper(&mut self, on: bool, width: u32, height: u32) {
        if on {
            let mut frame = FrameSettings {
                width,
                height,
                ..self.frame
            };
            crate::settings::paper::apply(&mut frame, &mut self.cluster, &|_| false);
            self.frame.clamp = frame.clamp;
            self.render_scale = 1.0;
        } else {
            let d = ClusterSettings::default();
            let c = &mut self.cluster;
            c.paper = false;
            c.cluster_light = d.cluster_light;
            c.reseed = d.reseed;
            c.ring_fallback = d.ring_fallback;
            c.position_fallback = d.position_fallback;
            c.centroid_normal = d.centroid_normal;
            self.frame.clamp = FrameSettings::default().clamp;
        }
    }

    /// The gate's angle when it is on and applies (fuzzy modes).
    pub fn plane_gate(&self) -> Option<f32> {
        (self.cluster.weighting != Weighting::Hard)
            .then_some(self.cluster.plane_gate)
            .flatten()
    }

    /// Whether the SP and the VPL clusterings run (a K of 0: off).
    pub fn clusterings_on(&self) -> (bool, bool) {
        (self.cluster.sp_clusters > 0, self.cluster.vpl_clusters > 0)
    }

    /// The settings a frame of `width` × `height` is rendered with.
    pub fn frame_settings(&self, width: u32, height: u32) -> RenderSettings {
        let c = &self.cluster;
        RenderSettings {
            frame: FrameSettings {
                width,
                height,
                // The image at its own size, the indirect light at the render scale.
                indirect_scale: self.render_scale.clamp(0.05, 1.0),
                ..self.frame
            },
            cluster: ClusterSettings {
                fuzziness: c.f(),
                plane_gate: self.plane_gate(),
                ..c.clone()
            },
            method: self.method,
            ..Default::default()
        }
    }

    /// The scatter plot's series: how the indirect light is computed.
    pub fn mode_label(&self) -> String {
        let p = self.cluster.weight_exponent;
        let entry = self.method.entry_with_own_settings();
        let series = |r: &MethodEntry| format!("{} {}", r.method, (r.series)(&self.method));
        let (sp_on, vpl_on) = self.clusterings_on();
        match (sp_on, vpl_on) {
            _ if entry.is_some_and(|r| !r.clusters_sps) => series(entry.unwrap()),
            (false, false) => "no clustering".into(),
            (false, true) => "VPL clusters only".into(),
            (true, _) if let Some(r) = entry => {
                let m = series(r);
                if vpl_on || !(r.vpl_clusters)(&self.method) {
                    m
                } else {
                    format!("{m}, all VPLs")
                }
            }
            (true, _) => {
                let m = match self.cluster.weighting {
                    Weighting::Hard => "hard".to_string(),
                    Weighting::Uniform => "fuzzy uniform".to_string(),
                    Weighting::InverseDistance if p == 1.0 => "fuzzy weighted".to_string(),
                    Weighting::InverseDistance => format!("fuzzy weighted p{p}"),
                };
                let m = match self.plane_gate() {
                    Some(g) => format!("{m}, gate {g:.0}°"),
                    None => m,
                };
                if vpl_on { m } else { format!("{m}, all VPLs") }
            }
        }
    }

    /// The settings in short, for file names and plot tooltips.
    pub fn short(&self) -> String {
        let c = &self.cluster;
        let mode = match c.weighting {
            _ if let Some(r) = self.method.entry_with_own_settings() => {
                format!("{}-{}", r.method, (r.short)(&self.method))
            }
            Weighting::InverseDistance if c.weight_exponent == 1.0 => "weighted".to_string(),
            Weighting::InverseDistance => format!("weighted-p{}", c.weight_exponent),
            Weighting::Hard => "hard".to_string(),
            Weighting::Uniform => "uniform".to_string(),
        };
        let (sp, vpl) = (c.sp_clusters, c.vpl_clusters);
        let gate = self
            .plane_gate()
            .map_or(String::new(), |g| format!("_gate{g:.0}"));
        format!(
            "{mode}_K{sp}_Kv{vpl}_N{}_F{}_g{}_nt{:.0}_it{}{gate}",
            self.frame.vpls,
            c.fuzziness,
            c.gamma,
            c.normal_threshold.clamp(-1.0, 1.0).acos().to_degrees(),
            c.iterations
        )
    }
}

/// The GI image size for an image area of `area` px at render scale `scale`, and `Some(lower
/// scale)` when that many pixels exceed `max_pixels` (a frame's per-pixel buffers are one storage
/// binding each: 2,097,152 pixels on lavapipe) and the scale had to be lowered to fit.
pub fn gi_size(area: [u32; 2], scale: f32, max_pixels: u64) -> ((u32, u32), Option<f32>) {
    let size = |s: f32| {
        (
            ((area[0] as f32 * s) as u32).max(8),
            ((area[1] as f32 * s) as u32).max(8),
        )
    };
    let pixels = |(w, h): (u32, u32)| w as u64 * h as u64;
    let s = scale.clamp(0.05, 1.0);
    let full = size(s);
    if pixels(full) <= max_pixels {
        return (full, None);
    }
    let mut lower = s * (max_pixels as f64 / pixels(full) as f64).sqrt() as f32;
    loop {
        let wh = size(lower);
        if pixels(wh) <= max_pixels || lower < 1e-6 {
            return (wh, Some(lower));
        }
        lower *= 0.995;
    }
}

/// The exposure slider's range: its usual one, extended to take the value the viewer started with
/// (egui clamps a slider's value into its range). The settings' sliders widen theirs the same way
/// (`panel::controls`).
#[derive(Clone, Debug, PartialEq)]
pub struct SliderRanges {
    pub exposure: (f32, f32),
}

impl SliderRanges {
    pub fn new(s: &UiSettings) -> Self {
        SliderRanges {
            exposure: (s.exposure.min(0.01), s.exposure.max(64.0)),
        }
    }
}

/// The unclustered reference of one view.
pub struct RefState {
    pub job: FrameJob,
    pub control: Arc<Control>,
    pub started: Instant,
    /// Linear radiance once done, with its wall-clock time.
    pub image: Option<Vec<[f32; 3]>>,
    pub secs: f64,
}

/// A finished reference kept for its view (`Viewer::refs`): returning to that camera with the same
/// reference settings shows it again at no cost.
pub struct CachedRef {
    /// `ref_key` of the view it was rendered for.
    pub key: String,
    pub image: Arc<Vec<[f32; 3]>>,
    pub secs: f64,
}

/// The most references kept in memory (a 640×480 one is 3.7 MB).
pub const MAX_CACHED_REFS: usize = 32;

/// What a reference depends on: the camera, the image size, and the settings that change the
/// unclustered image (VPLs, seed, bounces, clamp, direct samples) and the lights; never the clustering.
pub fn ref_key(
    camera: &crate::scene::Camera,
    s: &RenderSettings,
    lights: &lights::LightSet,
) -> String {
    let f = &s.frame;
    format!(
        "{camera:?} {}x{} vpls {} seed {} bounces {} clamp {} direct {} lights {lights:?}",
        f.width,
        f.height,
        f.vpls,
        f.seed,
        f.bounces,
        f.clamp.to_bits(),
        f.direct_samples
    )
}

/// A stable 64-bit FNV-1a hash of `key`, the file name of a reference kept on disk.
pub fn key_hash(key: &str) -> u64 {
    key.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// A scripted run (`view --frames N`).
#[derive(Clone, Debug)]
pub struct Script {
    /// Window frames left to draw.
    pub left: u32,
    pub screenshot: Option<PathBuf>,
    pub stats: Option<PathBuf>,
    /// The animation has stopped; waiting for the frame at rest.
    pub settling: bool,
}

/// One (time, error) point of the scatter plot.
pub struct PlotPoint {
    pub series: String,
    pub key: String,
    pub ms: f64,
    pub mse: f64,
    pub flip: f64,
}

/// The latest frame's error against its view's reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiveError {
    pub mse: f64,
    pub rel_mse: f64,
    /// Mean FLIP of the two images as displayed (the panel's exposure).
    pub flip: f64,
}

/// Everything the viewer holds apart from the window and its GPU objects.
pub struct Viewer {
    pub spec: String,
    pub info: Option<SceneInfo>,
    pub loader: Loader,
    pub worker: Worker,
    pub wake: Arc<dyn Fn() + Send + Sync>,
    pub status: String,
    pub cam: ViewCamera,
    pub cam_mode: camera::Mode,
    pub speed: f32,
    pub home: ViewCamera,
    pub start_camera: Option<usize>,
    pub s: UiSettings,
    /// The sliders' ranges (which include the start settings).
    pub ranges: SliderRanges,
    pub view: View,
    pub latest: Option<Box<Rendered>>,
    pub texture: Option<egui::TextureHandle>,
    /// This window frame the image area shows the window's display pass (`display::Display`, on the
    /// GPU): its texture and size; `None`: `texture`, composed on the CPU (the CPU reprojection).
    pub gpu_texture: Option<(egui::TextureId, (u32, u32))>,
    pub image_dirty: bool,
    /// What the displayed image depends on besides the frame (view, exposure, …).
    display_key: String,
    /// Why the view shows something else (e.g. no reference yet).
    pub note: Option<&'static str>,
    last_sent: Option<String>,
    next_id: u64,
    pub pending: u64,
    pub last_motion: Instant,
    pub last_tick: Instant,
    /// The image area in physical pixels.
    pub area_px: [u32; 2],
    pub reference: Option<RefState>,
    /// Finished references by view (`ref_key`), newest last.
    pub refs: Vec<CachedRef>,
    /// Also keep references as EXR in `refs_dir` (beside the scene's bookmarks file), and read them
    /// from there.
    pub refs_on_disk: bool,
    /// Keys looked for on disk and not found (not looked for again).
    pub refs_missing: std::collections::HashSet<String>,
    pub points: Vec<PlotPoint>,
    pub live_error: Option<LiveError>,
    /// The split view's pinned B settings (`None`: nothing pinned).
    pub b: Option<UiSettings>,
    /// The split view's divider, a fraction of the image width from its left.
    pub split: f32,
    /// The plot's y axis: FLIP instead of MSE.
    pub plot_flip: bool,
    /// The panel's counts section is open: each frame's counts the GPU keeps (`GpuFrame::counts`)
    /// are read back for it (`FrameJob::want_counts`).
    pub show_counts: bool,
    /// The plot takes the wheel and drags (zoom, pan); off, it always fits its points.
    pub plot_zoom: bool,
    /// Points the plot last fitted to (it re-fits when this changes).
    pub plot_fitted: usize,
    pub bookmarks: BookmarksFile,
    /// The scene's bookmarks file exists but failed to load: never save over it.
    pub bookmarks_unreadable: bool,
    pub bookmark_name: String,
    pub path_field: String,
    pub dialog: Option<std::sync::mpsc::Receiver<Option<PathBuf>>>,
    pub shot_dir: PathBuf,
    pub last_shot: String,
    pub png_request: Option<PathBuf>,
    pub ui_dt: f32,
    pub gi_frames: u64,
    pub gi_ms_sum: f64,
    pub ui_frames: u64,
    /// Window frames since the scripted run's first full GI frame.
    pub script_frames: u64,
    pub animate: bool,
    /// When the animation started and from which camera (`ViewCamera::animated`).
    pub anim_origin: Option<(std::time::Instant, camera::ViewCamera)>,
    /// Scripted run: window frames left, where to save the window (PNG) and the stats (JSON).
    pub script: Option<Script>,
    /// Latency and GI frame times while moving (`motion.rs`).
    pub motion: motion::Motion,
    /// The window frames' own cost: app time and bytes moved (`motion::UiCost`).
    pub ui_cost: motion::UiCost,
    /// `gpu::traffic` at the end of the last window frame.
    pub traffic_mark: crate::gpu::traffic::Traffic,
    /// The window's device when the GI worker renders on it (`--display-path shared`).
    pub shared: Option<worker::SharedDevice>,
    /// Lit-pixel counts of the frames while moving, on the GPU (shared path), and their pixels.
    pub lit_slots: Vec<(crate::gi::sum::PendingSum, u32)>,
    /// The composed view of the latest frame (frame id, display key, RGBA, note): reprojected to
    /// every new camera while the next frame renders.
    composed: Option<(u64, String, Vec<u8>, Option<&'static str>)>,
    /// `composed` thinned to the render scale for reprojection (frame id, display key, image).
    thinned: Option<(u64, String, reproject::Thinned)>,
    /// The camera the image area shows.
    pub shown_camera: Option<crate::scene::Camera>,
    /// The lights as the panel edits them (the scene's until changed).
    pub lights: lights::LightSet,
    /// GPU ms of the last VPL trace (a light change) and clustering.
    pub last_relight: Option<(f64, f64)>,
    pub script_started: Option<Instant>,
    /// Set when the viewer should close (scripted run done, or failed).
    pub exit: Option<Result<(), String>>,
    /// The worker has ended (its load failed, or it stopped): no reply will come.
    pub worker_gone: bool,
    /// A scene being opened, with its worker: it replaces the open one only once it has loaded.
    pub loading: Option<(String, Worker)>,
}

/// The preview a moving camera renders: the image at its full size for the primary rays and the
/// direct light, so edges stay as sharp as at rest, with one direct-light sample a pixel; its indirect
/// light at half the render scale (a quarter of the pixels, at least 8 a side), upsampled as at rest
/// (docs/temporal.md measures what it saves).
pub fn preview_settings(s: RenderSettings) -> RenderSettings {
    let f = &s.frame;
    let fewest = 8.0 / f.width.min(f.height).max(1) as f32;
    RenderSettings {
        frame: FrameSettings {
            indirect_scale: (f.indirect_scale / 2.0).max(fewest).min(1.0),
            direct_samples: 1,
            ..s.frame
        },
        ..s
    }
}

mod plot;
mod references;
#[cfg(test)]
mod tests;
mod viewer;
