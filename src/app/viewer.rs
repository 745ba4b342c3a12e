//! The viewer's state machine: camera and panel input, jobs to the GI worker, what each window
//! frame shows, screenshots and the scripted run (references: `references.rs`).

use super::camera::ViewCamera;
use super::settings::SceneSettings;
use super::views::View;
use super::worker::{FrameJob, Job, Rendered, Reply, SceneInfo, Source, Worker};
use super::{Script, SliderRanges, ViewOptions, Viewer, gi_size, preview_settings};
use super::{camera, lights, motion, reproject, settings, views};
use anyhow::Result;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

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

    /// The RGBA8 image of the current view, its size, and a note when it cannot be shown.
    pub fn compose(&self) -> Option<(u32, u32, Vec<u8>, Option<&'static str>)> {
        let r = self.latest.as_ref()?;
        // On the shared display path the views composed here (FLIP) read the frame back.
        let frame = self.cpu_frame(r);
        let (w, h) = (frame.width, frame.height);
        let e = self.s.exposure;
        let fin = || views::final_image(&frame.direct, &frame.indirect, self.s.direct_on);
        let reference = self.reference_for(r);
        let (img, note) = match self.view {
            View::Final => (views::tonemap(&fin(), e), None),
            View::Direct => (views::tonemap(&frame.direct, e), None),
            View::Indirect => (views::tonemap(&frame.indirect, e), None),
            View::SpClusters => match &r.sp_ids {
                Some(ids) => (views::sp_clusters(ids, &frame.radiance, e), None),
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
            View::Split | View::Diff => match &r.b_frame {
                Some(b) if b.radiance.len() == frame.radiance.len() => {
                    let bf = views::final_image(&b.direct, &b.indirect, self.s.direct_on);
                    if self.view == View::Split {
                        let a = views::tonemap(&fin(), e);
                        (
                            views::split(&a, &views::tonemap(&bf, e), w, h, self.split),
                            None,
                        )
                    } else {
                        (views::error(&fin(), &bf), None)
                    }
                }
                _ => (
                    views::tonemap(&fin(), e),
                    Some(if self.b.is_none() {
                        "nothing pinned as B: press \"pin as B\""
                    } else {
                        "B is rendering…"
                    }),
                ),
            },
            View::Flip => match reference {
                Some(img) => (views::flip(&frame.radiance, img, w, h, e), None),
                None => (
                    views::tonemap(&fin(), e),
                    Some("no reference for this view yet: press \"compute reference\""),
                ),
            },
            View::Error => match reference {
                Some(img) => (views::error(&frame.radiance, img), None),
                None => (
                    views::tonemap(&fin(), e),
                    Some("no reference for this view yet: press \"compute reference\""),
                ),
            },
        };
        Some((w, h, img, note))
    }

    /// The animation's step (`--animate`), at the start of a window frame so the frame shows it.
    pub fn animate_step(&mut self) {
        let Some(info) = self.info.as_ref().filter(|_| self.animate) else {
            return;
        };
        let diagonal = (info.bounds.1 - info.bounds.0).length();
        let (t0, start) = *self.anim_origin.get_or_insert((Instant::now(), self.cam));
        self.set_camera(start.animated(diagonal, t0.elapsed().as_secs_f32()));
    }

    /// `r`'s frame with its images on the CPU: as it came, or (shared display path, asked for by a
    /// reference, a screenshot) read back from the GPU now. An empty frame where that fails.
    pub fn cpu_frame<'a>(&self, r: &'a Rendered) -> std::borrow::Cow<'a, crate::render::Frame> {
        match (&r.gpu, &self.shared) {
            (Some(g), Some(d)) if r.frame.radiance.is_empty() => {
                std::borrow::Cow::Owned(g.read_with(&d.device, &d.queue).unwrap_or_default())
            }
            _ => std::borrow::Cow::Borrowed(&r.frame),
        }
    }

    /// Whether the latest frame is shown reprojected to a camera it was not rendered for (temporal
    /// reuse on, the camera moved since): the CPU warp of `current_image` then draws it.
    pub fn reprojecting(&self) -> bool {
        self.latest.as_ref().is_some_and(|r| {
            let f = &r.frame;
            self.s.cluster.temporal
                && r.job.camera != self.cam.to_camera()
                && f.positions.len() == (f.width * f.height) as usize
        })
    }

    /// What the window's display pass (`display::Display`, on the GPU) draws this window frame: the
    /// latest frame's view (FLIP too, `app::flip`) when it is not reprojected on the CPU; `None`
    /// otherwise (`current_image` composes it on the CPU).
    pub fn gpu_view(&self) -> Option<super::display::GpuView<'_>> {
        use super::display::Source;
        if self.reprojecting() {
            return None;
        }
        let r = self.latest.as_ref()?;
        let f = &r.frame;
        let n = (f.width * f.height) as usize;
        let id = r.job.id;
        let refined = r.refined.map_or(0, |x| x.0);
        let key = format!("{id}/{refined}");
        let a = match &r.gpu {
            Some(g) => Source::Gpu(key, g),
            None => Source::Cpu((key, &f.direct[..], &f.indirect[..])),
        };
        let no_ref = "no reference for this view yet: press \"compute reference\"";
        let mut note = None;
        let mut view = self.view;
        let reference = match self.reference_for(r) {
            Some(img) if img.len() == n => Some((format!("{:p}", img.as_ptr()), img)),
            _ => None,
        };
        if matches!(view, View::Reference | View::Error | View::Flip) && reference.is_none() {
            (view, note) = (View::Final, Some(no_ref));
        }
        let b = match (&r.b_frame, &r.b_gpu) {
            (_, Some(g)) if g.buffers.size == (f.width, f.height) => {
                Some(Source::Gpu(format!("{id}"), g))
            }
            (Some(b), _) if b.radiance.len() == n => Some(Source::Cpu((
                format!("{id}"),
                &b.direct[..],
                &b.indirect[..],
            ))),
            _ => None,
        };
        if matches!(view, View::Split | View::Diff) && b.is_none() {
            note = Some(if self.b.is_none() {
                "nothing pinned as B: press \"pin as B\""
            } else {
                "B is rendering…"
            });
            view = View::Final;
        }
        let labels = r.sp_ids.as_deref().map(|l| (format!("{id}"), l));
        if view == View::SpClusters && labels.is_none() {
            (view, note) = (View::Final, Some("no SP clustering in this frame"));
        }
        // Shared path: a frame of another camera is reprojected on the GPU (temporal reuse on).
        let now = self.cam.to_camera();
        let reproject = match &r.gpu {
            Some(g) if self.s.cluster.temporal && r.job.camera != now => {
                let at = |c: &crate::scene::Camera| {
                    let c = c.with_eye_scaled(g.geometry_scale);
                    crate::gi::primary::CameraParams::new(&c, f.width, f.height)
                };
                Some((at(&r.job.camera), at(&now), g.buffers.image_gbuffer()))
            }
            _ => None,
        };
        Some(super::display::GpuView {
            note,
            camera: if reproject.is_some() {
                now
            } else {
                r.job.camera.clone()
            },
            reproject,
            size: (f.width, f.height),
            view,
            a,
            b,
            reference,
            labels,
            // The auto exposure of a frame on the GPU is reduced there; one on the CPU has it.
            exposure: match (&r.gpu, self.s.exposure_auto) {
                (Some(_), true) => crate::exposure::Exposure::Auto,
                _ => crate::exposure::Exposure::Fixed(self.s.exposure),
            },
            direct_on: self.s.direct_on,
            split: self.split,
        })
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
        let (mut w, mut h) = (r.frame.width, r.frame.height);
        let (id, dkey, rgba, note) = self.composed.as_ref()?;
        self.note = *note;
        let now = self.cam.to_camera();
        let from = &r.job.camera;
        let reprojected;
        let img: &[u8] = if self.s.cluster.temporal
            && *from != now
            && r.frame.positions.len() == (w * h) as usize
        {
            // A frame at rest has the image area's pixels: reprojected every window frame on the
            // CPU, it is thinned once to the render scale's (what the previews have at most).
            let step = (1.0 / self.s.render_scale.clamp(0.05, 1.0)).floor() as usize;
            let f = &r.frame;
            let stale = |t: &(u64, String, reproject::Thinned)| {
                (t.0, &t.1) != (*id, dkey) || t.2.step != step
            };
            if self.thinned.as_ref().is_none_or(stale) {
                let cam = crate::gi::primary::CameraParams::new(from, w, h);
                let t = reproject::Thinned::new(rgba, &f.positions, &f.normals, (w, h), step, &cam);
                self.thinned = Some((*id, dkey.clone(), t));
            }
            let t = &self.thinned.as_ref().expect("set").2;
            (w, h) = t.size;
            reprojected = reproject::reproject(
                &t.rgba,
                &t.positions,
                &t.normals,
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
            "{:?} {} {} {} {} {}",
            self.view,
            self.split,
            self.s.exposure,
            self.s.direct_on,
            self.latest
                .as_ref()
                .is_some_and(|r| self.reference_for(r).is_some()),
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
        // Moving, every window frame once there is a GI frame counts (the worker may deliver a new
        // preview every window frame, leaving the image "dirty" at each tick); at rest, a frame
        // whose image has been drawn.
        let mut shown = self
            .latest
            .as_ref()
            .is_some_and(|r| self.animate || at_rest(r))
            && (self.animate || !self.image_dirty);
        if self.script.is_some() && self.view.needs_reference() && shown {
            let has = self
                .latest
                .as_ref()
                .is_some_and(|r| self.reference_for(r).is_some());
            if self.reference.is_none() && !has {
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
            Some(p) if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) => {
                self.exit = Some(self.write_displayed_exr(&p).map_err(|e| format!("{e:#}")));
            }
            Some(p) => {
                if self.png_request.is_none() {
                    self.png_request = Some(p);
                }
            }
            None => self.exit = Some(Ok(())),
        }
    }

    /// The lit fractions counted on the GPU (`FrameJob::count_lit`), read back once into `motion`.
    fn read_lit_counts(&mut self) -> Result<()> {
        let Some(d) = &self.shared else {
            return Ok(());
        };
        if let Some((ring, _, _)) = self.lit_slots.first() {
            let counts: Vec<u32> = crate::gpu::read_buffer(
                &d.device,
                &d.queue,
                ring,
                crate::gi::count_lit::SLOTS as usize,
            )?;
            for (_, slot, pixels) in self.lit_slots.drain(..) {
                let lit = counts[slot as usize] as f64 / pixels.max(1) as f64;
                self.motion.lit_fractions.push(lit);
            }
        }
        Ok(())
    }

    /// The window frames' cost over the scripted run (`motion::UiCost`): all of them, and apart
    /// while moving and at rest.
    fn ui_stats(&self) -> serde_json::Value {
        let c = &self.ui_cost;
        let ms: Vec<f64> = c.frames.iter().map(|f| f.1.cpu_ms).collect();
        let wall: Vec<f64> = c.frames.iter().map(|f| f.1.wall_ms).collect();
        let q = |p| motion::quantile(&ms, p);
        let qw = |p| motion::quantile(&wall, p);
        let all = c
            .stats(true)
            .map(|m| m.fps)
            .or(c.stats(false).map(|r| r.fps));
        serde_json::json!({
            "cpu_ms": { "p50": q(0.5), "p95": q(0.95) },
            "wall_ms": { "p50": qw(0.5), "p95": qw(0.95) },
            "fps": all,
            "frames": c.frames.len(),
            "moving": c.stats(true),
            "rest": c.stats(false),
        })
    }

    /// The scripted run's stats JSON: the scene, the settings, and what `motion` measured.
    fn write_stats(&mut self, path: &std::path::Path) -> Result<()> {
        self.read_lit_counts()?;
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
            "display_path": if self.shared.is_some() { "shared" } else { "split" },
            "ui": self.ui_stats(),
        });
        crate::export::write_json(path, &json)
    }
}
