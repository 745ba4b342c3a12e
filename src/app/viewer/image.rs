//! What the image area shows: the current view composed on the CPU or drawn by the display pass,
//! reprojected while a newer frame renders, and when it must be redrawn.

use crate::app::views::{self, View};
use crate::app::worker::Rendered;
use crate::app::{Viewer, reproject};
use std::time::Instant;

impl Viewer {
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
    pub fn gpu_view(&self) -> Option<crate::app::display::GpuView<'_>> {
        use crate::app::display::Source;
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
        Some(crate::app::display::GpuView {
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
}
