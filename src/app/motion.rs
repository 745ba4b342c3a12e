//! What the viewer measures of itself while the camera moves (`view --animate --frames N --stats`):
//! the time from a camera change (its input event, or the animation's step) to the first presented
//! window frame that shows the new camera, and the GPU time of the GI frames rendered while moving
//! against one at rest.

use std::time::Instant;

use serde::Serialize;

#[derive(Debug, Default)]
pub struct Motion {
    /// The earliest input event the next window frame handles.
    pub input_at: Option<Instant>,
    /// When the camera first changed since the last presented frame that showed it.
    pub change_at: Option<Instant>,
    /// Camera change → presented image, ms, one per shown change.
    pub latencies_ms: Vec<f64>,
    /// GPU ms (timestamps) of the GI frames that finished while the camera moved.
    pub moving_gi_ms: Vec<f64>,
    /// The worker's wall ms for the same frames (job received → frame done).
    pub moving_gi_wall_ms: Vec<f64>,
    /// The fraction of those frames' pixels whose primary ray hit a surface (`lit_fraction`).
    pub lit_fractions: Vec<f64>,
    /// (GPU ms, wall ms, width, height) of the last GI frame at rest.
    pub rest: Option<(f64, f64, u32, u32)>,
}

/// `motion` and `rest` of the viewer's stats JSON (docs/design.md, "Additive contracts").
#[derive(Debug, Serialize, PartialEq)]
pub struct MotionStats {
    pub image_latency_ms_p95: f64,
    pub image_latency_ms_mean: f64,
    pub image_latency_ms_max: f64,
    /// Camera changes measured.
    pub changes: usize,
    /// `None` when no GI frame finished while moving.
    pub gi_frame_ms_mean: Option<f64>,
    /// The worker's wall time for them: on a software adapter the GPU is the CPU and this is the
    /// figure to read on the shared display path, whose timestamps lavapipe gets wrong
    /// (docs/viewer.md, "Display paths").
    pub gi_frame_wall_ms_mean: Option<f64>,
    pub gi_frames: usize,
    /// The smallest fraction of image pixels with a surface hit over the GI frames rendered while
    /// moving (`None` when none finished): a motion that leaves the scene shows black.
    pub lit_fraction_min: Option<f64>,
}

/// The fraction of a frame's pixels whose primary ray hit a surface (`Frame::positions`' w > 0).
pub fn lit_fraction(positions: &[[f32; 4]]) -> f64 {
    let hit = positions.iter().filter(|p| p[3] > 0.0).count();
    hit as f64 / positions.len().max(1) as f64
}

#[derive(Debug, Serialize, PartialEq)]
pub struct RestStats {
    pub gi_frame_ms: f64,
    pub gi_frame_wall_ms: f64,
    pub width: u32,
    pub height: u32,
}

/// The q-quantile (0..1) of `v` by the nearest-rank method; `None` when empty.
pub fn quantile(v: &[f64], q: f64) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let rank = ((q * s.len() as f64).ceil() as usize).clamp(1, s.len());
    Some(s[rank - 1])
}

impl Motion {
    /// The camera changed now (after the input at `input_at`, if any).
    pub fn camera_changed(&mut self, now: Instant) {
        if self.change_at.is_none() {
            self.change_at = Some(self.input_at.unwrap_or(now).min(now));
        }
    }

    /// A window frame showing the current camera was presented at `now`.
    pub fn shown(&mut self, now: Instant) {
        if let Some(t) = self.change_at.take() {
            self.latencies_ms
                .push(now.duration_since(t).as_secs_f64() * 1e3);
        }
    }

    pub fn stats(&self) -> Option<MotionStats> {
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
        Some(MotionStats {
            image_latency_ms_p95: quantile(&self.latencies_ms, 0.95)?,
            image_latency_ms_mean: mean(&self.latencies_ms),
            image_latency_ms_max: quantile(&self.latencies_ms, 1.0)?,
            changes: self.latencies_ms.len(),
            gi_frame_ms_mean: (!self.moving_gi_ms.is_empty()).then(|| mean(&self.moving_gi_ms)),
            gi_frame_wall_ms_mean: (!self.moving_gi_wall_ms.is_empty())
                .then(|| mean(&self.moving_gi_wall_ms)),
            gi_frames: self.moving_gi_ms.len(),
            lit_fraction_min: self.lit_fractions.iter().copied().reduce(f64::min),
        })
    }

    pub fn rest_stats(&self) -> Option<RestStats> {
        self.rest
            .map(|(gi_frame_ms, gi_frame_wall_ms, width, height)| RestStats {
                gi_frame_ms,
                gi_frame_wall_ms,
                width,
                height,
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn quantile_by_nearest_rank() {
        let v: Vec<f64> = (1..=20).map(f64::from).collect();
        assert_eq!(quantile(&v, 0.95), Some(19.0));
        assert_eq!(quantile(&v, 1.0), Some(20.0));
        assert_eq!(quantile(&v, 0.0), Some(1.0));
        assert_eq!(quantile(&[3.0], 0.95), Some(3.0));
        assert_eq!(quantile(&[], 0.95), None);
    }

    #[test]
    fn latency_runs_from_the_first_input_to_the_frame_that_shows_it() {
        let t0 = Instant::now();
        let mut m = Motion {
            input_at: Some(t0),
            ..Default::default()
        };
        m.camera_changed(t0 + Duration::from_millis(10));
        // A second change before the frame is shown does not restart the clock.
        m.camera_changed(t0 + Duration::from_millis(20));
        m.shown(t0 + Duration::from_millis(50));
        // Shown again with no change: nothing recorded.
        m.shown(t0 + Duration::from_millis(60));
        assert_eq!(m.latencies_ms.len(), 1);
        assert!((m.latencies_ms[0] - 50.0).abs() < 1e-6);
        // Without an input event (the animation) the clock starts at the change.
        m.input_at = None;
        m.camera_changed(t0 + Duration::from_millis(100));
        m.shown(t0 + Duration::from_millis(130));
        assert!((m.latencies_ms[1] - 30.0).abs() < 1e-6);
        m.moving_gi_ms = vec![10.0, 30.0];
        m.moving_gi_wall_ms = vec![12.0, 40.0];
        m.lit_fractions = vec![1.0, 0.75];
        let s = m.stats().unwrap();
        assert_eq!(s.lit_fraction_min, Some(0.75));
        assert_eq!(
            lit_fraction(&[
                [0.0, 0.0, 0.0, 1.0],
                [0.0; 4],
                [1.0, 2.0, 3.0, 1.0],
                [0.0; 4]
            ]),
            0.5
        );
        assert_eq!((s.changes, s.gi_frames), (2, 2));
        assert_eq!(s.gi_frame_ms_mean, Some(20.0));
        assert_eq!(s.gi_frame_wall_ms_mean, Some(26.0));
        assert!((s.image_latency_ms_p95 - 50.0).abs() < 1e-6);
        assert!(Motion::default().stats().is_none());
    }
}

/// The calling thread's CPU time (Linux: `CLOCK_THREAD_CPUTIME_ID`; `None` elsewhere). Unlike a
/// clock on the wall it does not count the time the thread waits or is preempted (on a 2-core
/// machine, by the GI worker's and the software driver's threads).
pub fn thread_cpu_time() -> Option<std::time::Duration> {
    #[cfg(target_os = "linux")]
    {
        let mut t = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: clock_gettime writes the timespec it is given.
        let r = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
        (r == 0).then(|| std::time::Duration::new(t.tv_sec as u64, t.tv_nsec as u32))
    }
    #[cfg(not(target_os = "linux"))]
    {
        None
    }
}

/// A window frame's app code measured both ways: the UI thread's CPU time (`thread_cpu_time`; the
/// wall time where a platform has no thread clock) and the wall time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AppTime {
    pub cpu_ms: f64,
    pub wall_ms: f64,
}

impl AppTime {
    /// A clock started now (`stop` reads it).
    pub fn start() -> (Instant, Option<std::time::Duration>) {
        (Instant::now(), thread_cpu_time())
    }

    pub fn stop(started: (Instant, Option<std::time::Duration>)) -> AppTime {
        let wall_ms = started.0.elapsed().as_secs_f64() * 1e3;
        let cpu_ms = match (started.1, thread_cpu_time()) {
            (Some(a), Some(b)) => b.saturating_sub(a).as_secs_f64() * 1e3,
            _ => wall_ms,
        };
        AppTime { cpu_ms, wall_ms }
    }
}

/// What the viewer's own window frames cost (`view --stats`, "ui"): the UI thread's time in app code
/// a window frame (polling the worker, egui, the display, not waiting for the surface or present) as
/// CPU time and on the wall,
/// and the bytes each window frame moved between the CPU and the GPU (`gpu::traffic`, every device
/// of the process: the split path's GI device included), apart for frames while the camera moves
/// and at rest.
#[derive(Default)]
pub struct UiCost {
    /// (moving, app time, bytes read back, bytes uploaded) a window frame.
    pub frames: Vec<(bool, AppTime, u64, u64)>,
    /// The first and last window frame's time.
    pub span: Option<(Instant, Instant)>,
}

#[derive(serde::Serialize, Debug, PartialEq)]
pub struct UiCostStats {
    /// The UI thread's CPU time in app code a window frame (`AppTime::cpu_ms`).
    pub cpu_ms_p50: f64,
    pub cpu_ms_p95: f64,
    /// The same on the wall (with the time the thread waited or was preempted).
    pub wall_ms_p50: f64,
    pub wall_ms_p95: f64,
    /// Window frames a second over the measured span.
    pub fps: f64,
    pub frames: usize,
    /// Mean bytes a window frame (`gpu::traffic`: images, G-buffers, counters; timestamps apart).
    pub bytes_read_back: f64,
    pub bytes_uploaded: f64,
}

impl UiCost {
    pub fn frame(
        &mut self,
        moving: bool,
        ms: AppTime,
        traffic: crate::gpu::traffic::Traffic,
        at: Instant,
    ) {
        self.frames
            .push((moving, ms, traffic.read_back, traffic.uploaded));
        let first = self.span.map_or(at, |s| s.0);
        self.span = Some((first, at));
    }

    /// The stats of the frames moving (`true`) or at rest; `None` without any.
    pub fn stats(&self, moving: bool) -> Option<UiCostStats> {
        let f: Vec<_> = self.frames.iter().filter(|f| f.0 == moving).collect();
        if f.is_empty() {
            return None;
        }
        let ms: Vec<f64> = f.iter().map(|f| f.1.cpu_ms).collect();
        let wall: Vec<f64> = f.iter().map(|f| f.1.wall_ms).collect();
        let n = f.len() as f64;
        let secs = self
            .span
            .map_or(0.0, |(a, b)| b.duration_since(a).as_secs_f64());
        Some(UiCostStats {
            cpu_ms_p50: quantile(&ms, 0.5).unwrap_or(0.0),
            cpu_ms_p95: quantile(&ms, 0.95).unwrap_or(0.0),
            wall_ms_p50: quantile(&wall, 0.5).unwrap_or(0.0),
            wall_ms_p95: quantile(&wall, 0.95).unwrap_or(0.0),
            fps: if secs > 0.0 {
                (self.frames.len() as f64 - 1.0) / secs
            } else {
                0.0
            },
            frames: f.len(),
            bytes_read_back: f.iter().map(|f| f.2 as f64).sum::<f64>() / n,
            bytes_uploaded: f.iter().map(|f| f.3 as f64).sum::<f64>() / n,
        })
    }
}
