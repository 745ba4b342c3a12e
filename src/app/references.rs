//! References in the viewer: started for the current view at full scale, kept per view and per
//! reference setting (in memory, optionally as EXR beside the scene), and the error of each
//! finished frame against them.

use super::worker::{FrameJob, Job, Rendered};
use super::{PlotPoint, RefState, Viewer, worker};
use crate::metrics;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

impl Viewer {
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
            want_counts: false,
            preview: false,
            b_settings: None,
            count_lit: false,
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

    /// The reference of the view `r` was rendered for: the one just finished or one kept from an
    /// earlier visit of this view (same camera, size, VPLs, seed, bounces, clamp, direct samples and
    /// lights).
    pub(super) fn reference_for(&self, r: &Rendered) -> Option<&[[f32; 3]]> {
        self.kept_reference(&super::ref_key(
            &r.job.camera,
            &r.job.settings,
            &self.lights,
        ))
    }

    /// The reference kept under `key` (`ref_key`), if any.
    pub(super) fn kept_reference(&self, key: &str) -> Option<&[[f32; 3]]> {
        self.refs
            .iter()
            .rev()
            .find(|c| c.key == key)
            .map(|c| c.image.as_slice())
    }

    /// Whether `r`'s view has a reference (kept or just finished).
    pub fn reference_for_view(&self, r: &Rendered) -> bool {
        self.reference_for(r).is_some()
    }

    /// The folder references are kept in on disk: beside the scene's bookmarks file.
    pub fn refs_dir(&self) -> Option<PathBuf> {
        self.bookmarks_path().map(|p| {
            let mut name = p.file_name().unwrap_or_default().to_os_string();
            name.push(".refs");
            p.with_file_name(name)
        })
    }

    /// Keeps a finished reference (in memory; on disk too when asked).
    pub(super) fn keep_reference(
        &mut self,
        key: String,
        image: Vec<[f32; 3]>,
        secs: f64,
        w: u32,
        h: u32,
    ) {
        if self.refs_on_disk
            && let Some(dir) = self.refs_dir()
        {
            let path = dir.join(format!("{:016x}.exr", super::key_hash(&key)));
            let res = std::fs::create_dir_all(&dir)
                .map_err(anyhow::Error::from)
                .and_then(|_| crate::export::write_exr(&path, w, h, &image));
            if let Err(e) = res {
                self.status = format!("reference not kept on disk: {e:#}");
            }
        }
        self.refs.retain(|c| c.key != key);
        self.refs.push(super::CachedRef {
            key,
            image: Arc::new(image),
            secs,
        });
        if self.refs.len() > super::MAX_CACHED_REFS {
            self.refs.remove(0);
        }
    }

    /// Looks for the latest frame's reference on disk (when references are kept there); returns
    /// whether one was found.
    pub(super) fn load_reference_from_disk(&mut self) -> bool {
        let Some(r) = &self.latest else { return false };
        let key = super::ref_key(&r.job.camera, &r.job.settings, &self.lights);
        let size = (r.frame.width, r.frame.height);
        self.load_kept_reference(key, size)
    }

    /// Reads the reference of `key` and `size` from disk into memory (when references are kept
    /// there and it is not in memory yet); returns whether one was read. A missing, unreadable or
    /// mismatched file is remembered and not looked for again.
    pub(super) fn load_kept_reference(&mut self, key: String, (w, h): (u32, u32)) -> bool {
        if !self.refs_on_disk
            || self.refs.iter().any(|c| c.key == key)
            || self.refs_missing.contains(&key)
        {
            return false;
        }
        let Some(dir) = self.refs_dir() else {
            return false;
        };
        let path = dir.join(format!("{:016x}.exr", super::key_hash(&key)));
        match crate::export::read_exr(&path) {
            Ok((rw, rh, px))
                if (rw, rh) == (w, h) && px.iter().flatten().all(|c| c.is_finite()) =>
            {
                self.refs.push(super::CachedRef {
                    key,
                    image: Arc::new(px),
                    secs: 0.0,
                });
                true
            }
            _ => {
                self.refs_missing.insert(key);
                false
            }
        }
    }

    pub(super) fn record_error(&mut self) {
        let Some(r) = &self.latest else { return };
        let Some(reference) = self.reference_for(r) else {
            self.live_error = None;
            return;
        };
        // On the shared display path the frame is read back for this (a reference asks for it).
        let frame = self.cpu_frame(r);
        let img = frame.radiance.as_slice();
        if img.len() != reference.len() {
            self.live_error = None;
            return;
        }
        let (w, h) = (r.frame.width, r.frame.height);
        let err = super::LiveError {
            mse: metrics::mse(img, reference),
            rel_mse: metrics::rel_mse(img, reference),
            flip: metrics::flip(img, reference, w, h, self.s.exposure),
        };
        let ms = r.frame.timings_ms.get("frame").copied().unwrap_or(0.0);
        self.live_error = Some(err);
        let key = self.s.short();
        let series = self.s.mode_label();
        self.points.retain(|p| p.key != key);
        self.points.push(PlotPoint {
            series,
            key,
            ms,
            mse: err.mse,
            flip: err.flip,
        });
    }
}
