//! The viewer's state machine: camera and panel input, jobs to the GI worker, what each window
//! frame shows, screenshots and the scripted run (references: `references.rs`).

use super::bookmarks::BookmarksFile;
use super::camera::ViewCamera;
use super::views::View;
use super::worker::{FrameJob, Job, Rendered, Reply, SceneInfo, Source, Worker};
use super::{Script, SliderRanges, ViewOptions, Viewer, gi_size, preview_settings};
use super::{bookmarks, camera, lights, motion};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

mod image;
mod script;

impl Viewer {
    /// The viewer of `opts`; with `shared` (the window's device) its GI worker renders on that device
    /// and the window displays the frames where they are (`--display-path shared`).
    pub fn new(
        opts: ViewOptions,
        wake: Arc<dyn Fn() + Send + Sync>,
        shared: Option<super::worker::SharedDevice>,
    ) -> Viewer {
        let w = wake.clone();
        let worker = Worker::spawn(
            Source::Loaded(Box::new(opts.scene), opts.spec.clone()),
            opts.loader.clone(),
            Box::new(move || w()),
            shared.clone(),
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
            gpu_texture: None,
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
            refs: Vec::new(),
            refs_on_disk: opts.refs_on_disk,
            refs_missing: Default::default(),
            points: Vec::new(),
            live_error: None,
            b: opts.b,
            split: 0.5,
            plot_flip: false,
            show_counts: false,
            plot_zoom: false,
            plot_fitted: 0,
            bookmarks: BookmarksFile::default(),
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
            anim_origin: None,
            script: opts.frames.map(|n| Script {
                left: n.max(1),
                screenshot: opts.screenshot.clone(),
                stats: opts.stats.clone(),
                settling: false,
            }),
            motion: motion::Motion::default(),
            ui_cost: Default::default(),
            shared,
            lit_slots: Vec::new(),
            traffic_mark: crate::gpu::traffic::Traffic::now(),
            composed: None,
            thinned: None,
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
            self.shared.clone(),
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
        self.bookmarks = match self.bookmarks_path() {
            Some(p) => BookmarksFile::load(&p).unwrap_or_else(|e| {
                self.status = format!("{e:#} (kept; moved aside on the next save)");
                self.bookmarks_unreadable = true;
                BookmarksFile::default()
            }),
            None => BookmarksFile::default(),
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

    pub fn bookmarks_path(&self) -> Option<PathBuf> {
        bookmarks::bookmarks_path(&self.spec)
    }

    /// Saves the bookmarks; a bookmarks file that failed to load is moved aside first, never
    /// overwritten.
    pub fn save_bookmarks(&mut self) {
        if let Some(p) = self.bookmarks_path() {
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
        // Points are of one view; finished references stay in `refs` for when the view returns.
        self.points.clear();
        self.live_error = None;
    }

    pub fn moving(&self) -> bool {
        self.last_motion.elapsed() < Duration::from_millis(300)
    }

    /// The size of a GI frame at rest: the image area's (lowered to what the worker's device
    /// holds); its indirect light is at the render scale (`FrameSettings::indirect_scale`).
    pub fn full_size(&self) -> (u32, u32) {
        self.gi_size().0
    }

    /// The GI frame's size at rest and, when the device cannot hold the image area's pixels, the
    /// scale of the area it was lowered to.
    pub fn gi_size(&self) -> ((u32, u32), Option<f32>) {
        let most = self.info.as_ref().map_or(u64::MAX, |i| i.max_pixels);
        gi_size(self.area_px, 1.0, most)
    }

    /// Sends a frame job when the camera, settings or size changed (progressive: a preview while
    /// moving, `preview_settings`, the full frame once the camera rests).
    pub fn schedule(&mut self) {
        if self.info.is_none() {
            return;
        }
        let (w, h) = self.full_size();
        let preview = self.moving();
        let mut settings = if preview {
            preview_settings(self.s.frame_settings(w, h))
        } else {
            self.s.frame_settings(w, h)
        };
        // The split and difference views render B for the same camera, both without temporal reuse
        // (one renderer's warm starts would alternate between A's and B's clusterings).
        let b_settings = match (&self.b, self.view) {
            (Some(b), View::Split | View::Diff) => {
                settings.cluster.temporal = false;
                let mut bs = b.frame_settings(w, h);
                bs.cluster.temporal = false;
                bs.cluster.target_ms = None;
                Some(if preview { preview_settings(bs) } else { bs })
            }
            _ => None,
        };
        let job = FrameJob {
            id: self.next_id,
            camera: self.cam.to_camera(),
            settings,
            want_sp_ids: self.view == View::SpClusters,
            want_counts: self.show_counts,
            preview,
            b_settings,
            count_lit: preview && self.script.as_ref().is_some_and(|s| s.stats.is_some()),
        };
        let key = format!(
            "{:?} {:?} {} {:?}",
            job.camera, job.settings, job.want_sp_ids, job.b_settings
        );
        if self.last_sent.as_deref() != Some(key.as_str()) {
            self.last_sent = Some(key);
            self.pending = job.id;
            self.next_id += 1;
            self.worker.send(Job::Frame(job));
        }
    }

    /// A frame rendered under a time budget: where its controller (`budget::Controller`, in the
    /// worker's frame loop for this kind of frame) moved the K's, the same job is sent again so
    /// that the view settles on them.
    fn budget_step(&mut self, r: &Rendered) {
        let c = &r.job.settings.cluster;
        if r.budget_next
            .is_some_and(|k| k != (c.sp_clusters, c.vpl_clusters))
        {
            self.last_sent = None;
        }
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
                        self.motion.moving_gi_wall_ms.push(r.wall_ms);
                        match &r.lit {
                            // Counted on the GPU: read once, with the stats.
                            Some(l) => self.lit_slots.push(l.clone()),
                            None => self
                                .motion
                                .lit_fractions
                                .push(motion::lit_fraction(&r.frame.positions)),
                        }
                    } else {
                        self.motion.rest = Some((gpu_ms, r.wall_ms, r.frame.width, r.frame.height));
                    }
                    self.budget_step(&r);
                    self.latest = Some(r);
                    self.image_dirty = true;
                    self.load_reference_from_disk();
                    self.record_error();
                }
                Reply::Reference(r) => {
                    if let Some(rs) = &mut self.reference
                        && rs.job.id == r.job.id
                    {
                        rs.image = Some(r.frame.radiance.clone());
                        rs.secs = rs.started.elapsed().as_secs_f64();
                        let key = super::ref_key(&rs.job.camera, &rs.job.settings, &self.lights);
                        let secs = rs.secs;
                        self.keep_reference(
                            key,
                            r.frame.radiance.clone(),
                            secs,
                            r.frame.width,
                            r.frame.height,
                        );
                        self.image_dirty = true;
                        self.record_error();
                    }
                }
                Reply::Refined {
                    id,
                    direct,
                    auto_exposure,
                    estimates,
                    samples,
                    gpu_ms,
                } => {
                    if let Some(r) = self.latest.as_mut().filter(|r| r.job.id == id) {
                        if let Some(direct) = direct {
                            r.frame.radiance = direct
                                .iter()
                                .zip(&r.frame.indirect)
                                .map(|(a, b)| [0, 1, 2].map(|c| a[c] + b[c]))
                                .collect();
                            r.frame.direct = direct;
                        }
                        r.auto_exposure = auto_exposure;
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
}
