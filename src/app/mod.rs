//! The interactive viewer (`fuzzy-vpl view`): winit + egui on the window's own wgpu device, with the
//! GI renderer on a worker thread (see docs/viewer.md).
//!
//! - `window.rs`: event loop, surface, egui rendering, PNG read-back.
//! - `worker.rs`: the GI thread (own `GpuContext` + `Scene` + `Renderer`), newest-job-wins.
//! - `panel.rs`: the side panel (settings, stats, reference, plot, screenshots) and the image area.
//! - `views.rs`: what the image area shows, composed from the last frame.
//! - `camera.rs`: fly / orbit camera. `settings.rs`: the bookmarks file. `screenshot.rs`: file output.

pub mod camera;
pub mod lights;
pub mod motion;
pub mod panel;
pub mod reproject;
pub mod screenshot;
pub mod settings;
pub mod views;
pub mod window;
pub mod worker;

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Result;

use crate::exposure::Exposure;
use crate::gi::pipeline::{Control, RenderSettings};
use crate::metrics;
use crate::scene::Scene;
use crate::settings::{
    AUTO_GAMMA_MIN, ClusterSettings, DEFAULT_PLANE_GATE_DEG, FrameSettings, Gamma, Weighting,
};
use camera::ViewCamera;
use settings::SceneSettings;
use views::View;
use worker::{FrameJob, Job, Loader, Rendered, Reply, SceneInfo, Source, Worker};

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
    /// Keep orbiting the camera (for measuring frame rates while moving).
    pub animate: bool,
    /// Scripted run: write the motion stats JSON here once done.
    pub stats: Option<PathBuf>,
    /// Where panel screenshots go.
    pub shot_dir: PathBuf,
}

pub fn run(opts: ViewOptions) -> Result<()> {
    window::run(opts)
}

/// The panel's state: the settings types as the renderer takes them, and what only a panel has
/// (clusterings switched off keep their K, γ's slider keeps its value while `auto` is ticked, the
/// plane gate keeps its angle while off, n_t is shown in degrees).
#[derive(Clone, Debug, PartialEq)]
pub struct UiSettings {
    /// The frame (its size is the viewer's GI size, set per frame).
    pub frame: FrameSettings,
    pub cluster: ClusterSettings,
    /// γ of the slider, used when `gamma_auto` is off.
    pub gamma: u32,
    /// γ by `Gamma::auto` (the default).
    pub gamma_auto: bool,
    /// n_t as the largest normal angle within a cluster, degrees.
    pub nt_degrees: f32,
    /// The display exposure; with `exposure_auto` the panel keeps it at `exposure::auto_exposure` of
    /// the latest frame.
    pub exposure: f32,
    pub exposure_auto: bool,
    pub render_scale: f32,
    /// The plane gate of the fuzzy F lists (off: the paper) and its angle, degrees.
    pub plane_gate_on: bool,
    pub plane_gate_deg: f32,
    pub sp_on: bool,
    pub vpl_on: bool,
    pub direct_on: bool,
}

impl UiSettings {
    /// The panel's state for `s` (its K's at least 1 so that switching a clustering on has one).
    pub fn new(s: &RenderSettings) -> Self {
        let c = &s.cluster;
        UiSettings {
            frame: s.frame,
            cluster: ClusterSettings {
                sp_clusters: c.sp_clusters.max(1),
                vpl_clusters: c.vpl_clusters.max(1),
                ..c.clone()
            },
            gamma: match c.gamma {
                Gamma::Auto => AUTO_GAMMA_MIN,
                Gamma::Fixed(g) => g,
            },
            gamma_auto: c.gamma.is_auto(),
            nt_degrees: c.normal_threshold.clamp(-1.0, 1.0).acos().to_degrees(),
            exposure: match s.frame.exposure {
                Exposure::Fixed(e) => e,
                Exposure::Auto => 1.0,
            },
            exposure_auto: s.frame.exposure.is_auto(),
            render_scale: 1.0,
            plane_gate_on: c.plane_gate.is_some(),
            plane_gate_deg: c.plane_gate.unwrap_or(DEFAULT_PLANE_GATE_DEG),
            sp_on: c.sp_clusters > 0,
            vpl_on: c.vpl_clusters > 0,
            direct_on: true,
        }
    }

    /// The gate's angle when it is on and applies (fuzzy modes).
    pub fn plane_gate(&self) -> Option<f32> {
        (self.plane_gate_on && self.cluster.weighting != Weighting::Hard)
            .then_some(self.plane_gate_deg)
    }

    /// γ as the frame settings take it: `Auto` when auto is ticked, else the slider's.
    pub fn gamma_setting(&self) -> Gamma {
        if self.gamma_auto {
            Gamma::Auto
        } else {
            Gamma::Fixed(self.gamma)
        }
    }

    /// The settings a frame of `width` × `height` is rendered with.
    pub fn frame_settings(&self, width: u32, height: u32) -> RenderSettings {
        let c = &self.cluster;
        RenderSettings {
            frame: FrameSettings {
                width,
                height,
                ..self.frame
            },
            cluster: ClusterSettings {
                vpl_clusters: if self.vpl_on { c.vpl_clusters } else { 0 },
                sp_clusters: if self.sp_on { c.sp_clusters } else { 0 },
                fuzziness: c.f(),
                gamma: self.gamma_setting(),
                normal_threshold: self.nt_degrees.to_radians().cos(),
                plane_gate: self.plane_gate(),
                weights_to_reps: false,
                ..c.clone()
            },
            ..Default::default()
        }
    }

    /// The scatter plot's series: how the indirect light is computed.
    pub fn mode_label(&self) -> String {
        let p = self.cluster.weight_exponent;
        match (self.sp_on, self.vpl_on) {
            (false, false) => "no clustering".into(),
            (false, true) => "VPL clusters only".into(),
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
                if self.vpl_on {
                    m
                } else {
                    format!("{m}, all VPLs")
                }
            }
        }
    }

    /// The settings in short, for file names and plot tooltips.
    pub fn short(&self) -> String {
        let c = &self.cluster;
        let mode = match c.weighting {
            Weighting::InverseDistance if c.weight_exponent == 1.0 => "weighted".to_string(),
            Weighting::InverseDistance => format!("weighted-p{}", c.weight_exponent),
            Weighting::Hard => "hard".to_string(),
            Weighting::Uniform => "uniform".to_string(),
        };
        let sp = if self.sp_on {
            format!("K{}", c.sp_clusters)
        } else {
            "K0".into()
        };
        let vpl = if self.vpl_on {
            format!("Kv{}", c.vpl_clusters)
        } else {
            "Kv0".into()
        };
        let gate = self
            .plane_gate()
            .map_or(String::new(), |g| format!("_gate{g:.0}"));
        format!(
            "{mode}_{sp}_{vpl}_N{}_F{}_g{}_nt{:.0}_it{}{gate}",
            self.frame.vpls,
            c.fuzziness,
            self.gamma_setting(),
            self.nt_degrees,
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

/// The panel sliders' ranges: their usual ones, extended to take the values the viewer started
/// with (egui clamps a slider's value into its range, which silently changed command-line values
/// such as `--vpls 100000` to 65536).
#[derive(Clone, Debug, PartialEq)]
pub struct SliderRanges {
    pub sp_clusters: u32,
    pub vpl_clusters: u32,
    pub vpls: u32,
    pub gamma: u32,
    pub iterations: u32,
    pub weight_exponent: f32,
    pub exposure: (f32, f32),
    pub plane_gate_min: f32,
}

impl SliderRanges {
    pub fn new(s: &UiSettings) -> Self {
        SliderRanges {
            sp_clusters: s.cluster.sp_clusters.max(16384),
            vpl_clusters: s.cluster.vpl_clusters.max(16384),
            vpls: s.frame.vpls.max(65536),
            gamma: s.gamma.max(16),
            iterations: s.cluster.iterations.max(50),
            weight_exponent: s.cluster.weight_exponent.max(8.0),
            exposure: (s.exposure.min(0.01), s.exposure.max(64.0)),
            plane_gate_min: s.plane_gate_deg.min(1.0),
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
    pub points: Vec<PlotPoint>,
    pub live_error: Option<(f64, f64)>,
    pub bookmarks: SceneSettings,
    /// The scene's settings file exists but failed to load: never save over it.
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
    /// Scripted run: window frames left, where to save the window (PNG) and the stats (JSON).
    pub script: Option<Script>,
    /// Latency and GI frame times while moving (`motion.rs`).
    pub motion: motion::Motion,
    /// The composed view of the latest frame (frame id, display key, RGBA, note): reprojected to
    /// every new camera while the next frame renders.
    composed: Option<(u64, String, Vec<u8>, Option<&'static str>)>,
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

impl Viewer {
    pub fn new(opts: ViewOptions, wake: Arc<dyn Fn() + Send + Sync>) -> Viewer {
        let w = wake.clone();
        let worker = Worker::spawn(
            Source::Loaded(Box::new(opts.scene), opts.spec.clone()),
            opts.loader.clone(),
            Box::new(move || w()),
        );
        let placeholder = ViewCamera {
            eye: glam::Vec3::ZERO,
            yaw: 0.0,
            pitch: 0.0,
            yfov: 1.0,
            distance: 1.0,
        };
        Viewer {
            spec: opts.spec.clone(),
            info: None,
            loader: opts.loader,
            worker,
            wake,
            status: String::new(),
            cam: placeholder,
            cam_mode: camera::Mode::Fly,
            speed: 1.0,
            home: placeholder,
            start_camera: opts.camera,
            ranges: SliderRanges::new(&opts.settings),
            s: opts.settings,
            view: opts.view,
            latest: None,
            texture: None,
            image_dirty: false,
            display_key: String::new(),
            note: None,
            last_sent: None,
            next_id: 1,
            pending: 0,
            last_motion: Instant::now() - Duration::from_secs(10),
            last_tick: Instant::now(),
            area_px: [opts.width, opts.height],
            reference: None,
            points: Vec::new(),
            live_error: None,
            bookmarks: SceneSettings::default(),
            bookmarks_unreadable: false,
            bookmark_name: String::new(),
            path_field: opts.spec,
            dialog: None,
            shot_dir: opts.shot_dir,
            last_shot: String::new(),
            png_request: None,
            ui_dt: 0.0,
            gi_frames: 0,
            gi_ms_sum: 0.0,
            ui_frames: 0,
            script_frames: 0,
            animate: opts.animate,
            script: opts.frames.map(|n| Script {
                left: n.max(1),
                screenshot: opts.screenshot.clone(),
                stats: opts.stats.clone(),
                settling: false,
            }),
            motion: motion::Motion::default(),
            composed: None,
            shown_camera: None,
            lights: lights::LightSet {
                lights: Vec::new(),
                emitter_scale: 1.0,
            },
            last_relight: None,
            script_started: None,
            exit: None,
            worker_gone: false,
            loading: None,
        }
    }

    /// Opens another scene: a new worker loads it while the open scene stays on screen, and
    /// replaces it once loaded (`poll`); when loading fails the open scene and its worker stay.
    pub fn open(&mut self, spec: String) {
        let w = self.wake.clone();
        let worker = Worker::spawn(
            Source::Spec(spec.clone()),
            self.loader.clone(),
            Box::new(move || w()),
        );
        // A load still running is dropped (its worker ends after loading).
        self.loading = Some((spec.clone(), worker));
        self.path_field = spec;
    }

    /// The loading worker's first reply: swap it in when its scene loaded, else keep the open one.
    fn poll_loading(&mut self) -> bool {
        let Some((spec, w)) = &self.loading else {
            return false;
        };
        let failed = match w.rx.try_recv() {
            Err(std::sync::mpsc::TryRecvError::Empty) => return false,
            Ok(Reply::Loaded(info)) => {
                let (spec, worker) = self.loading.take().expect("loading");
                if let Some(r) = self.reference.take() {
                    r.control.cancel();
                }
                // The old worker ends after its current job.
                self.worker = worker;
                self.worker_gone = false;
                self.spec = spec;
                self.latest = None;
                self.texture = None;
                self.points.clear();
                self.live_error = None;
                self.start_camera = None;
                self.status.clear();
                self.loaded(*info);
                return true;
            }
            Ok(Reply::LoadFailed(msg)) => msg,
            Ok(_) => format!("{spec}: the loading worker sent no scene"),
            Err(std::sync::mpsc::TryRecvError::Disconnected) => {
                format!("{spec}: loading stopped (see stderr)")
            }
        };
        self.loading = None;
        self.status = format!("{failed} (kept {})", self.spec);
        true
    }

    /// The worker's scene is ready: start camera, bookmarks, status.
    fn loaded(&mut self, info: SceneInfo) {
        let radius = 0.5 * (info.bounds.1 - info.bounds.0).length();
        let cam = self
            .start_camera
            .and_then(|i| info.cameras.get(i).cloned())
            .unwrap_or_else(|| info.default_camera.clone());
        let centre = 0.5 * (info.bounds.0 + info.bounds.1);
        let dist = (centre - cam.eye()).dot(cam.forward()).max(radius * 0.5);
        self.home = ViewCamera::from_camera(&cam, dist);
        self.cam = self.home;
        self.speed = (radius * 0.5).max(1e-6);
        self.bookmarks_unreadable = false;
        self.bookmarks = match self.settings_path() {
            Some(p) => SceneSettings::load(&p).unwrap_or_else(|e| {
                self.status = format!("{e:#} (kept; moved aside on the next save)");
                self.bookmarks_unreadable = true;
                SceneSettings::default()
            }),
            None => SceneSettings::default(),
        };
        if self.status.starts_with("loading") {
            self.status.clear();
        }
        self.lights = lights::LightSet {
            lights: info.lights.clone(),
            emitter_scale: 1.0,
        };
        self.last_relight = None;
        if !info.has_light {
            let dark = lights::NO_LIGHT;
            self.status = if self.status.is_empty() {
                dark.into()
            } else {
                format!("{} · {dark}", self.status)
            };
        }
        self.info = Some(info);
        self.last_sent = None;
    }

    pub fn settings_path(&self) -> Option<PathBuf> {
        settings::settings_path(&self.spec)
    }

    /// Saves the bookmarks; a settings file that failed to load is moved aside first, never
    /// overwritten.
    pub fn save_bookmarks(&mut self) {
        if let Some(p) = self.settings_path() {
            match self.bookmarks.save_keeping(&p, self.bookmarks_unreadable) {
                Ok(moved) => {
                    self.bookmarks_unreadable = false;
                    self.status = match moved {
                        Some(m) => format!(
                            "{} could not be read: moved to {}; bookmarks saved to {}",
                            p.display(),
                            m.display(),
                            p.display()
                        ),
                        None => format!("bookmarks saved to {}", p.display()),
                    }
                }
                Err(e) => self.status = format!("{e:#}"),
            }
        }
    }

    pub fn reset_camera(&mut self) {
        self.set_camera(self.home);
    }

    pub fn set_camera(&mut self, c: ViewCamera) {
        if c != self.cam {
            self.cam = c;
            // Measured from the first image on (before it there is nothing to move).
            if self.latest.is_some() {
                self.motion.camera_changed(Instant::now());
            }
            self.camera_moved();
        }
    }

    /// A moving camera renders at a reduced scale and invalidates the reference.
    pub fn camera_moved(&mut self) {
        self.last_motion = Instant::now();
        if let Some(r) = self.reference.take() {
            r.control.cancel();
            if r.image.is_none() {
                self.status = "reference cancelled: the camera moved".into();
            }
        }
        self.points.clear();
        self.live_error = None;
    }

    pub fn moving(&self) -> bool {
        self.last_motion.elapsed() < Duration::from_millis(300)
    }

    /// The GI image size at full render scale (lowered to what the worker's device holds).
    pub fn full_size(&self) -> (u32, u32) {
        self.gi_size().0
    }

    /// The GI size at full render scale and, when the device cannot hold that many pixels, the
    /// lower render scale used instead.
    pub fn gi_size(&self) -> ((u32, u32), Option<f32>) {
        let most = self.info.as_ref().map_or(u64::MAX, |i| i.max_pixels);
        gi_size(self.area_px, self.s.render_scale, most)
    }

    /// Sends a frame job when the camera, settings or size changed (progressive: a preview while
    /// moving, `preview_settings`, the full frame once the camera rests).
    pub fn schedule(&mut self) {
        if self.info.is_none() {
            return;
        }
        let (w, h) = self.full_size();
        let preview = self.moving();
        let settings = if preview {
            preview_settings(self.s.frame_settings(w, h))
        } else {
            self.s.frame_settings(w, h)
        };
        let job = FrameJob {
            id: self.next_id,
            camera: self.cam.to_camera(),
            settings,
            want_sp_ids: self.view == View::SpClusters,
            preview,
        };
        let key = format!("{:?} {:?} {}", job.camera, job.settings, job.want_sp_ids);
        if self.last_sent.as_deref() != Some(key.as_str()) {
            self.last_sent = Some(key);
            self.pending = job.id;
            self.next_id += 1;
            self.worker.send(Job::Frame(job));
        }
    }

    /// Starts the reference of the current view at full scale.
    pub fn start_reference(&mut self) {
        if let Some(r) = self.reference.take() {
            r.control.cancel();
        }
        let (w, h) = self.full_size();
        let control = worker::control();
        let mut settings = self.s.frame_settings(w, h);
        settings.reference = true;
        settings.control = Some(control.clone());
        let job = FrameJob {
            id: self.next_id,
            camera: self.cam.to_camera(),
            settings,
            want_sp_ids: false,
            preview: false,
        };
        self.next_id += 1;
        self.worker.send(Job::Reference(job.clone()));
        self.reference = Some(RefState {
            job,
            control,
            started: Instant::now(),
            image: None,
            secs: 0.0,
        });
        self.points.clear();
        self.status.clear();
    }

    pub fn cancel_reference(&mut self) {
        if let Some(r) = self.reference.take() {
            r.control.cancel();
        }
    }

    /// Whether a frame is comparable with the finished reference (same view, size and VPLs).
    fn reference_for(&self, r: &Rendered) -> Option<&[[f32; 3]]> {
        let rs = self.reference.as_ref()?;
        let img = rs.image.as_ref()?;
        let (a, b) = (&rs.job.settings, &r.job.settings);
        (rs.job.camera == r.job.camera
            && (
                a.frame.width,
                a.frame.height,
                a.frame.vpls,
                a.frame.seed,
                a.frame.clamp.to_bits(),
                a.frame.direct_samples,
            ) == (
                b.frame.width,
                b.frame.height,
                b.frame.vpls,
                b.frame.seed,
                b.frame.clamp.to_bits(),
                b.frame.direct_samples,
            ))
            .then_some(img.as_slice())
    }

    fn record_error(&mut self) {
        let Some(r) = &self.latest else { return };
        let Some(reference) = self.reference_for(r) else {
            self.live_error = None;
            return;
        };
        let img = r.frame.radiance.as_slice();
        let (mse, rel) = (
            metrics::mse(img, reference),
            metrics::rel_mse(img, reference),
        );
        let ms = r.frame.timings_ms.get("frame").copied().unwrap_or(0.0);
        self.live_error = Some((mse, rel));
        let key = self.s.short();
        let series = self.s.mode_label();
        self.points.retain(|p| p.key != key);
        self.points.push(PlotPoint {
            series,
            key,
            ms,
            mse,
        });
    }

    /// Handles the worker's replies; returns whether anything changed.
    pub fn poll(&mut self) -> bool {
        let mut changed = self.poll_loading();
        loop {
            let reply = match self.worker.rx.try_recv() {
                Ok(r) => r,
                Err(std::sync::mpsc::TryRecvError::Empty) => break,
                Err(std::sync::mpsc::TryRecvError::Disconnected) => {
                    // Ended without saying why (it panicked outside a frame): no reply will come.
                    if !self.worker_gone {
                        self.worker_gone = true;
                        changed = true;
                        let msg =
                            "the GI worker stopped (see stderr); load the scene again".to_string();
                        self.status = msg.clone();
                        if self.script.is_some() {
                            self.exit = Some(Err(msg));
                        }
                    }
                    break;
                }
            };
            changed = true;
            match reply {
                Reply::Loaded(info) => self.loaded(*info),
                Reply::LoadFailed(msg) => {
                    self.worker_gone = true;
                    self.status = msg.clone();
                    if self.script.is_some() {
                        self.exit = Some(Err(msg));
                    }
                }
                Reply::Frame(r) => {
                    if r.relit.is_some() {
                        self.last_relight = r.relit;
                    }
                    self.gi_frames += 1;
                    self.gi_ms_sum += r.wall_ms;
                    let gpu_ms = r.frame.timings_ms.get("frame").copied().unwrap_or(0.0);
                    if r.job.preview {
                        self.motion.moving_gi_ms.push(gpu_ms);
                    } else {
                        self.motion.rest = Some((gpu_ms, r.frame.width, r.frame.height));
                    }
                    self.latest = Some(r);
                    self.image_dirty = true;
                    self.record_error();
                }
                Reply::Reference(r) => {
                    if let Some(rs) = &mut self.reference
                        && rs.job.id == r.job.id
                    {
                        rs.image = Some(r.frame.radiance.clone());
                        rs.secs = rs.started.elapsed().as_secs_f64();
                        self.image_dirty = true;
                        self.record_error();
                    }
                }
                Reply::Refined {
                    id,
                    direct,
                    estimates,
                    samples,
                    gpu_ms,
                } => {
                    if let Some(r) = self.latest.as_mut().filter(|r| r.job.id == id) {
                        r.frame.radiance = direct
                            .iter()
                            .zip(&r.frame.indirect)
                            .map(|(a, b)| [0, 1, 2].map(|c| a[c] + b[c]))
                            .collect();
                        r.frame.direct = direct;
                        r.refined = Some((estimates, samples, gpu_ms));
                        self.image_dirty = true;
                    }
                }
                Reply::ReferenceCancelled => {}
                Reply::Failed(msg) => {
                    self.status = msg.clone();
                    if self.script.is_some() {
                        self.exit = Some(Err(msg));
                    }
                }
            }
        }
        if let Some(rx) = &self.dialog
            && let Ok(picked) = rx.try_recv()
        {
            self.dialog = None;
            if let Some(p) = picked {
                self.open(p.to_string_lossy().into_owned());
            }
        }
        changed
    }

    /// The RGBA8 image of the current view, its size, and a note when it cannot be shown.
    pub fn compose(&self) -> Option<(u32, u32, Vec<u8>, Option<&'static str>)> {
        let r = self.latest.as_ref()?;
        let (w, h) = (r.frame.width, r.frame.height);
        let e = self.s.exposure;
        let fin = || views::final_image(&r.frame.direct, &r.frame.indirect, self.s.direct_on);
        let reference = self.reference_for(r);
        let (img, note) = match self.view {
            View::Final => (views::tonemap(&fin(), e), None),
            View::Direct => (views::tonemap(&r.frame.direct, e), None),
            View::Indirect => (views::tonemap(&r.frame.indirect, e), None),
            View::SpClusters => match &r.sp_ids {
                Some(ids) => (views::sp_clusters(ids, &r.frame.radiance, e), None),
                None => (
                    views::tonemap(&fin(), e),
                    Some("no SP clustering in this frame"),
                ),
            },
            View::VplPoints => {
                let base = views::tonemap(&fin(), e);
                (
                    views::vpl_points(
                        &base,
                        &r.job.camera,
                        w,
                        h,
                        &r.vpls,
                        &r.lights,
                        r.lights_clustered,
                    ),
                    None,
                )
            }
            View::Reference => match reference {
                Some(img) => (views::tonemap(img, e), None),
                None => (
                    views::tonemap(&fin(), e),
                    Some("no reference for this view yet: press \"compute reference\""),
                ),
            },
            View::Error => match reference {
                Some(img) => (views::error(&r.frame.radiance, img), None),
                None => (
                    views::tonemap(&fin(), e),
                    Some("no reference for this view yet: press \"compute reference\""),
                ),
            },
        };
        Some((w, h, img, note))
    }

    /// Writes the current view's linear radiance (as displayed: direct toggle applied) as EXR.
    pub fn save_exr(&mut self) {
        let Some(r) = &self.latest else {
            self.last_shot = "no frame yet".into();
            return;
        };
        let img = match self.view {
            View::Direct => r.frame.direct.clone(),
            View::Indirect => r.frame.indirect.clone(),
            // Without a reference these views show the clustered frame: saving that under a
            // `_reference_` / `_error_` name would mislabel it.
            View::Reference | View::Error if self.reference_for(r).is_none() => {
                self.last_shot =
                    "no reference for this view yet: nothing saved (press \"compute reference\")"
                        .into();
                return;
            }
            View::Reference => self.reference_for(r).expect("checked").to_vec(),
            _ => views::final_image(&r.frame.direct, &r.frame.indirect, self.s.direct_on),
        };
        let path = screenshot::unique_path(
            &self.shot_dir,
            &screenshot::scene_stem(&self.spec),
            &format!("{}_{}", self.s.short(), self.view.slug()),
            "exr",
        );
        self.last_shot = match crate::export::write_exr(&path, r.frame.width, r.frame.height, &img)
        {
            Ok(()) => format!("saved {}", path.display()),
            Err(e) => format!("{e:#}"),
        };
    }

    pub fn request_png(&mut self) {
        self.png_request = Some(screenshot::unique_path(
            &self.shot_dir,
            &screenshot::scene_stem(&self.spec),
            &format!("{}_{}", self.s.short(), self.view.slug()),
            "png",
        ));
    }

    /// The animation's step (`--animate`), at the start of a window frame so the frame shows it.
    pub fn animate_step(&mut self) {
        if self.animate && self.info.is_some() {
            let dt = self.last_tick.elapsed().as_secs_f32();
            let mut c = self.cam;
            c.orbit(0.6 * dt.min(0.2), 0.0);
            self.set_camera(c);
        }
    }

    /// The image the area shows now, as an egui image: the latest frame's view, reprojected to the
    /// current camera while a newer frame renders (temporal reuse on); `None` when there is none.
    /// Sets `shown_camera` and the view's note.
    pub fn current_image(&mut self) -> Option<egui::ColorImage> {
        let r = self.latest.as_ref()?;
        let key = (r.job.id, self.display_key.clone());
        if self.image_dirty
            || self
                .composed
                .as_ref()
                .is_none_or(|c| (c.0, &c.1) != (key.0, &key.1))
        {
            let (_, _, rgba, note) = self.compose()?;
            self.composed = Some((key.0, key.1, rgba, note));
        }
        self.image_dirty = false;
        let r = self.latest.as_ref()?;
        let (w, h) = (r.frame.width, r.frame.height);
        let (_, _, rgba, note) = self.composed.as_ref()?;
        self.note = *note;
        let now = self.cam.to_camera();
        let from = &r.job.camera;
        let reprojected;
        let img: &[u8] = if self.s.cluster.temporal
            && *from != now
            && r.frame.positions.len() == (w * h) as usize
        {
            reprojected = reproject::reproject(
                rgba,
                &r.frame.positions,
                &crate::gi::primary::CameraParams::new(from, w, h),
                &crate::gi::primary::CameraParams::new(&now, w, h),
            );
            self.shown_camera = Some(now);
            &reprojected
        } else {
            self.shown_camera = Some(from.clone());
            rgba
        };
        Some(egui::ColorImage::from_rgba_unmultiplied(
            [w as usize, h as usize],
            img,
        ))
    }

    /// Whether the image area must be redrawn: a new frame or view, or (reprojecting) a camera the
    /// shown image was not made for.
    pub fn image_stale(&self) -> bool {
        self.image_dirty
            || (self.s.cluster.temporal
                && self.latest.is_some()
                && self.shown_camera.as_ref() != Some(&self.cam.to_camera()))
    }

    /// The shortest time between window frames: while the worker renders on the same CPU cores
    /// (a software adapter), window frames are paced to 25 a second so that they leave it most of
    /// the cores; otherwise 60.
    pub fn min_frame(&self) -> Duration {
        let busy = self
            .latest
            .as_ref()
            .is_none_or(|r| r.job.id != self.pending);
        if busy && self.info.as_ref().is_some_and(|i| i.software) {
            Duration::from_millis(40)
        } else {
            Duration::from_millis(16)
        }
    }

    /// A window frame was presented at `now`: the camera change it shows is measured.
    pub fn presented(&mut self, now: Instant) {
        if self.shown_camera.as_ref() == Some(&self.cam.to_camera()) {
            self.motion.shown(now);
        }
    }

    /// Per window frame: camera input has been applied; schedules work and drives a scripted run.
    pub fn tick(&mut self) {
        let now = Instant::now();
        self.ui_dt = now.duration_since(self.last_tick).as_secs_f32();
        self.last_tick = now;
        self.ui_frames += 1;
        self.schedule();
        let dk = format!(
            "{:?} {} {} {} {}",
            self.view,
            self.s.exposure,
            self.s.direct_on,
            self.reference.as_ref().is_some_and(|r| r.image.is_some()),
            self.live_error.is_some()
        );
        if dk != self.display_key {
            self.display_key = dk;
            self.image_dirty = true;
        }
        let full = self.full_size();
        let pending = self.pending;
        let at_rest = move |r: &Rendered| {
            !r.job.preview && (r.frame.width, r.frame.height) == full && r.job.id == pending
        };
        let mut shown = self
            .latest
            .as_ref()
            .is_some_and(|r| self.animate || at_rest(r))
            && !self.image_dirty;
        if self.script.is_some() && self.view.needs_reference() && shown {
            if self.reference.is_none() {
                self.start_reference();
            }
            shown = self.live_error.is_some();
        }
        let rest_ready = self.latest.as_ref().is_some_and(|r| at_rest(r)) && !self.moving();
        let Some(sc) = &mut self.script else { return };
        if !shown && !sc.settling {
            return;
        }
        self.script_started.get_or_insert(now);
        if sc.left > 0 {
            sc.left -= 1;
            return;
        }
        if self.animate && sc.stats.is_some() {
            // Stop moving, then measure the frame at rest.
            self.animate = false;
            sc.settling = true;
            return;
        }
        if sc.settling && !rest_ready {
            return;
        }
        sc.settling = false;
        let (shot, stats) = (sc.screenshot.clone(), sc.stats.take());
        if let Some(p) = stats
            && let Err(e) = self.write_stats(&p)
        {
            self.exit = Some(Err(format!("{e:#}")));
            return;
        }
        match shot {
            Some(p) => {
                if self.png_request.is_none() {
                    self.png_request = Some(p);
                }
            }
            None => self.exit = Some(Ok(())),
        }
    }

    /// The scripted run's stats JSON: the scene, the settings, and what `motion` measured.
    fn write_stats(&self, path: &std::path::Path) -> Result<()> {
        let (w, h) = self.full_size();
        // The settings types as they are, with the display exposure (a number) and the render scale.
        let rs = self.s.frame_settings(w, h);
        let mut settings = serde_json::to_value(rs.cluster)?;
        let frame = serde_json::to_value(rs.frame)?;
        if let (Some(m), serde_json::Value::Object(f)) = (settings.as_object_mut(), frame) {
            m.extend(f);
            m.insert("exposure".into(), self.s.exposure.into());
            m.insert("render_scale".into(), self.s.render_scale.into());
        }
        let json = serde_json::json!({
            "scene": self.spec,
            "width": w,
            "height": h,
            "adapter": self.info.as_ref().map(|i| i.adapter.clone()),
            "settings": settings,
            "ui_frames": self.ui_frames,
            "motion": self.motion.stats(),
            "rest": self.motion.rest_stats(),
        });
        crate::export::write_json(path, &json)
    }
}

/// The preview a moving camera renders: a quarter of the pixels (half scale), one direct-light
/// sample a pixel (docs/temporal.md measures what it saves).
pub fn preview_settings(s: RenderSettings) -> RenderSettings {
    RenderSettings {
        frame: FrameSettings {
            width: (s.frame.width / 2).max(8),
            height: (s.frame.height / 2).max(8),
            direct_samples: 1,
            ..s.frame
        },
        ..s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A viewer on builtin:cornell with `s`, without a window (its worker starts on lavapipe).
    fn viewer(s: UiSettings) -> Viewer {
        let loader: Loader = Arc::new(|spec: &str| Ok(crate::scene::load(spec)?));
        let opts = ViewOptions {
            spec: "builtin:cornell".into(),
            scene: crate::scene::load("builtin:cornell").unwrap(),
            loader,
            width: 64,
            height: 48,
            camera: None,
            settings: s,
            frames: None,
            screenshot: None,
            view: View::Final,
            animate: false,
            stats: None,
            shot_dir: std::env::temp_dir(),
        };
        Viewer::new(opts, Arc::new(|| {}))
    }

    /// One egui frame of the whole window's UI.
    fn draw(v: &mut Viewer) {
        let ctx = egui::Context::default();
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(
                egui::Pos2::ZERO,
                egui::vec2(1200.0, 2000.0),
            )),
            ..Default::default()
        };
        let _ = ctx.run_ui(input, |ui| v.ui(ui));
    }

    /// Polls until `done` holds (the worker replies on lavapipe within seconds).
    fn poll_until(v: &mut Viewer, done: impl Fn(&Viewer) -> bool) {
        let t = Instant::now();
        while !done(v) {
            assert!(t.elapsed() < Duration::from_secs(120), "timed out");
            v.poll();
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("fuzzy-vpl-app-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_scene_that_fails_to_load_keeps_the_open_one() {
        let d = scratch("trunc");
        // A GLB header that promises more bytes than the file has.
        let glb = d.join("trunc.glb");
        let mut bytes = b"glTF".to_vec();
        bytes.extend(2u32.to_le_bytes());
        bytes.extend(1000u32.to_le_bytes());
        bytes.extend(b"{\"asset\"");
        std::fs::write(&glb, &bytes).unwrap();
        let mut v = viewer(UiSettings::new(&RenderSettings::default()));
        poll_until(&mut v, |v| v.info.is_some());
        let cam = v.cam;
        v.open(glb.display().to_string());
        assert!(v.loading.is_some());
        poll_until(&mut v, |v| v.loading.is_none());
        assert_eq!(v.spec, "builtin:cornell");
        assert_eq!(
            v.info.as_ref().map(|i| i.spec.as_str()),
            Some("builtin:cornell")
        );
        assert_eq!(v.cam, cam);
        assert!(!v.worker_gone);
        assert!(v.status.contains("trunc.glb"), "{}", v.status);
        // The open scene's worker still renders.
        v.schedule();
        poll_until(&mut v, |v| v.latest.is_some());
        // A scene that loads replaces it.
        v.open("builtin:conference".into());
        poll_until(&mut v, |v| v.loading.is_none());
        assert_eq!(v.spec, "builtin:conference");
        assert!(v.info.is_some() && v.latest.is_none());
        assert!(v.status.is_empty(), "{}", v.status);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_bookmarks_file_that_fails_to_load_is_moved_aside_not_overwritten() {
        let d = scratch("bookmarks");
        // One triangle, lit by nothing: it only has to load.
        let pos: [f32; 9] = [-1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 0.0, 1.0, 0.0];
        let bytes: Vec<u8> = pos.iter().flat_map(|f| f.to_le_bytes()).collect();
        std::fs::write(d.join("t.bin"), &bytes).unwrap();
        let gltf = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
          "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
          "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[-1,-1,0],"max":[1,1,0]}],
          "bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"uri":"t.bin","byteLength":36}]}"#;
        let scene = d.join("t.gltf");
        std::fs::write(&scene, gltf).unwrap();
        let settings = d.join("t.gltf.fuzzy-vpl.json");
        std::fs::write(&settings, "{ \"bookmarks\": [ truncated").unwrap();
        let mut v = viewer(UiSettings::new(&RenderSettings::default()));
        poll_until(&mut v, |v| v.info.is_some());
        v.open(scene.display().to_string());
        poll_until(&mut v, |v| v.loading.is_none());
        assert_eq!(v.spec, scene.display().to_string());
        assert!(
            v.status.contains("not a fuzzy-vpl settings file"),
            "{}",
            v.status
        );
        v.bookmarks
            .bookmarks
            .push(settings::Bookmark::new("door".into(), &v.cam));
        v.save_bookmarks();
        let aside = d.join("t.gltf.fuzzy-vpl.json.bad-1");
        assert_eq!(
            std::fs::read_to_string(&aside).unwrap(),
            "{ \"bookmarks\": [ truncated"
        );
        assert!(v.status.contains("moved to"), "{}", v.status);
        assert_eq!(SceneSettings::load(&settings).unwrap(), v.bookmarks);
        // Later saves write the (now readable) file in place.
        v.save_bookmarks();
        assert!(!d.join("t.gltf.fuzzy-vpl.json.bad-2").exists());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn exr_of_the_reference_view_without_a_reference_is_refused() {
        let d = scratch("refshot");
        let mut s = UiSettings::new(&RenderSettings::default());
        s.frame.vpls = 256;
        s.cluster.vpl_clusters = 32;
        s.cluster.sp_clusters = 64;
        let mut v = viewer(s);
        v.shot_dir = d.clone();
        v.view = View::Reference;
        poll_until(&mut v, |v| v.info.is_some());
        v.schedule();
        poll_until(&mut v, |v| v.latest.is_some());
        v.save_exr();
        assert!(v.last_shot.contains("no reference"), "{}", v.last_shot);
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0);
        // The final view saves under its own name.
        v.view = View::Final;
        v.save_exr();
        assert!(v.last_shot.contains("_final_"), "{}", v.last_shot);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn the_direct_light_accumulates_at_rest() {
        let mut s = UiSettings::new(&RenderSettings::default());
        (
            s.frame.vpls,
            s.cluster.vpl_clusters,
            s.cluster.sp_clusters,
            s.cluster.temporal,
        ) = (256, 32, 64, true);
        s.frame.direct_samples = 2;
        let mut v = viewer(s);
        poll_until(&mut v, |v| v.info.is_some());
        v.schedule();
        poll_until(&mut v, |v| {
            v.latest
                .as_ref()
                .and_then(|r| r.refined)
                .is_some_and(|(n, ..)| n >= 3)
        });
        let r = v.latest.as_ref().unwrap();
        let (n, spp, ms) = r.refined.unwrap();
        assert_eq!(spp, n as u64 * 2);
        assert!(ms > 0.0);
        // The image shown is the running mean plus the frame's indirect light.
        for ((p, d), i) in r
            .frame
            .radiance
            .iter()
            .zip(&r.frame.direct)
            .zip(&r.frame.indirect)
        {
            assert_eq!(*p, [d[0] + i[0], d[1] + i[1], d[2] + i[2]]);
        }
        // A change starts a new frame, which accumulates from its own first estimate.
        v.s.frame.seed += 1;
        v.schedule();
        let id = v.pending;
        poll_until(&mut v, |v| {
            v.latest
                .as_ref()
                .is_some_and(|r| r.job.id == id && r.refined.is_some())
        });
    }

    #[test]
    fn lights_move_without_a_restart() {
        let mut s = UiSettings::new(&RenderSettings::default());
        (
            s.frame.vpls,
            s.cluster.vpl_clusters,
            s.cluster.sp_clusters,
            s.cluster.temporal,
        ) = (256, 32, 64, true);
        let mut v = viewer(s);
        poll_until(&mut v, |v| v.info.is_some());
        v.schedule();
        poll_until(&mut v, |v| v.latest.is_some());
        let lum = |v: &Viewer| metrics::mean_luminance(&v.latest.as_ref().unwrap().frame.radiance);
        let before = lum(&v);
        assert!(v.last_relight.is_some(), "the first frame traced the VPLs");
        v.last_relight = None;
        // The ceiling light off, a point light in the middle of the box.
        let bounds = v.info.as_ref().unwrap().bounds;
        let mut set = v.lights.clone();
        set.emitter_scale = 0.0;
        set.lights.push(lights::new_point(bounds));
        v.set_lights(set);
        assert!(v.status.is_empty(), "{}", v.status);
        v.schedule();
        poll_until(&mut v, |v| v.last_relight.is_some());
        let r = v.latest.as_ref().unwrap();
        assert!(r.frame.radiance.iter().flatten().all(|c| c.is_finite()));
        assert!(r.frame.vpls > 0);
        let (trace, cluster) = v.last_relight.unwrap();
        assert!(trace > 0.0 && cluster > 0.0, "{trace} {cluster}");
        assert!(
            (lum(&v) - before).abs() > 1e-3 * before,
            "{} vs {before}",
            lum(&v)
        );
        // Nothing left that emits: the panel says so.
        v.set_lights(lights::LightSet {
            lights: vec![],
            emitter_scale: 0.0,
        });
        assert!(v.status.contains("no light"), "{}", v.status);
    }

    #[test]
    fn auto_gamma_reaches_the_frame_and_the_file_names() {
        let s = UiSettings::new(&RenderSettings::default());
        assert!(s.gamma_auto);
        assert_eq!(s.frame_settings(64, 48).cluster.gamma, Gamma::Auto);
        assert!(s.short().contains("_gauto_"), "{}", s.short());
        // Unticked, the slider's γ is used (a γ from the command line arrives unticked).
        let mut fixed = RenderSettings::default();
        fixed.cluster.gamma = Gamma::Fixed(8);
        let mut s = UiSettings::new(&fixed);
        assert!(!s.gamma_auto);
        assert_eq!(s.frame_settings(64, 48).cluster.gamma, Gamma::Fixed(8));
        assert!(s.short().contains("_g8_"), "{}", s.short());
        s.gamma_auto = true;
        assert_eq!(s.frame_settings(64, 48).cluster.gamma, Gamma::Auto);
    }

    #[test]
    fn command_line_values_beyond_the_sliders_survive_the_panel() {
        let fs = RenderSettings {
            frame: FrameSettings {
                vpls: 100_000,
                exposure: Exposure::Fixed(100.0),
                ..Default::default()
            },
            cluster: ClusterSettings {
                sp_clusters: 20_000,
                vpl_clusters: 20_000,
                gamma: Gamma::Fixed(100),
                iterations: 1000,
                weight_exponent: 20.0,
                plane_gate: Some(0.5),
                weighting: Weighting::InverseDistance,
                ..Default::default()
            },
            ..Default::default()
        };
        let s = UiSettings::new(&fs);
        let mut v = viewer(s.clone());
        draw(&mut v);
        draw(&mut v);
        assert_eq!(v.s, s);
    }

    #[test]
    fn gi_size_lowers_the_render_scale_to_what_the_device_holds() {
        assert_eq!(gi_size([640, 480], 0.5, 2_097_152), ((320, 240), None));
        assert_eq!(gi_size([10, 10], 0.1, 2_097_152), ((8, 8), None));
        // 2048x1100 at scale 1 is 2,252,800 pixels: more than lavapipe's binding holds.
        let ((w, h), lower) = gi_size([2048, 1100], 1.0, 2_097_152);
        let lower = lower.expect("lowered");
        assert!(w as u64 * h as u64 <= 2_097_152, "{w}x{h}");
        assert!(lower < 1.0 && lower > 0.95, "{lower}");
        assert!(w > 1900 && h > 1000, "{w}x{h}");
        let ((w, h), lower) = gi_size([16384, 16384], 1.0, 2_097_152);
        assert!(
            w as u64 * h as u64 <= 2_097_152 && lower.is_some(),
            "{w}x{h}"
        );
    }
}
