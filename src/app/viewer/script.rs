//! The scripted run (`--script`): each window frame's step, and the stats JSON it writes.

use crate::app::worker::Rendered;
use crate::app::{Viewer, motion};
use anyhow::Result;
use std::time::Instant;

impl Viewer {
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
        let (pending, pixels): (Vec<_>, Vec<_>) = self.lit_slots.drain(..).unzip();
        let counts = crate::gi::sum::read_all(&d.device, &d.queue, &pending)?;
        for (lit, pixels) in counts.into_iter().zip(pixels) {
            let lit = lit as f64 / pixels.max(1) as f64;
            self.motion.lit_fractions.push(lit);
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
