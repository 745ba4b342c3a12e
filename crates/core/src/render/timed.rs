//! The one frame loop and the one way frames are timed.
//!
//! `FrameLoop` renders frames one after another on one renderer (each frame's past the previous
//! one's): the VPL frame or the path tracer's, after `warmup_ms` of busy GPU work when asked, and,
//! where it steps a time budget (the viewer), with `budget::Controller` choosing the K's frame by
//! frame. `bench --camera-path` renders its path with it, the viewer's worker its frames, and
//! `timed` its repeats.
//!
//! `timed` is how `render` and `bench` time a frame: the GPU warmed up (`--warmup-ms`,
//! `Renderer::warm_up`; the path tracer: the busy kernel alone), then with `--target-ms` the
//! budget controller's frames (`budget::fit`, its last frame counting as the first timed one),
//! then renders up to `repeat`; each pass's time is the mean of its 3 best runs (`best_of_runs`,
//! the paper's method).

use std::collections::BTreeMap;

use anyhow::Result;

use super::budget::{self, Budget, Controller};
use super::frame::Frame;
use super::{RenderSettings, Renderer};
use crate::gi::pass::Pass;
use crate::scene::Camera;

/// What a frame is: the VPL frame (`Renderer::render`) or the diffuse path tracer's with SPP
/// samples a pixel (`Renderer::path_trace`, `render --path-trace`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FrameKind {
    #[default]
    Vpl,
    PathTrace(u32),
}

/// Frames one after another on one renderer (see the module).
#[derive(Default)]
pub struct FrameLoop {
    pub kind: FrameKind,
    /// GPU work in ms before each frame (`bench --camera-path`: a frame is timed once, right after
    /// GPU work that touches no renderer state); 0: none.
    pub warmup_ms: f64,
    /// Whether a frame with a time budget (`--target-ms`) takes its K's from the controller.
    pub steps_budget: bool,
    controller: Option<Controller>,
}

impl FrameLoop {
    /// A loop of `kind` frames, each after `warmup_ms` of busy GPU work.
    pub fn new(kind: FrameKind, warmup_ms: f64) -> FrameLoop {
        FrameLoop {
            kind,
            warmup_ms,
            ..Default::default()
        }
    }

    /// A loop of VPL frames whose time budget `budget::Controller` steps once a frame (made anew
    /// when the budget or the frame's size changes; the viewer's).
    pub fn stepping_budget() -> FrameLoop {
        FrameLoop {
            steps_budget: true,
            ..Default::default()
        }
    }

    /// The next frame of `s` at `camera`, and the settings it ran with (under a stepped budget,
    /// `s` with the controller's K's).
    pub fn next(
        &mut self,
        renderer: &mut Renderer,
        camera: &Camera,
        s: &RenderSettings,
    ) -> Result<(Frame, RenderSettings)> {
        let s = self.settings_for(renderer, s)?;
        let frame = match self.kind {
            FrameKind::Vpl => renderer.render(camera, &s)?,
            FrameKind::PathTrace(spp) => renderer.path_trace(camera, &s, spp)?,
        };
        if let Some(c) = &mut self.controller {
            c.observe(&s, &frame);
        }
        Ok((frame, s))
    }

    /// `next` with the frame left on the GPU (`Renderer::render_gpu`; the viewer's shared display
    /// path).
    pub fn next_gpu(
        &mut self,
        renderer: &mut Renderer,
        camera: &Camera,
        s: &RenderSettings,
    ) -> Result<(crate::render::frame::GpuFrame, RenderSettings)> {
        let s = self.settings_for(renderer, s)?;
        let frame = renderer.render_gpu(camera, &s)?;
        if let Some(c) = &mut self.controller {
            c.observe(&s, &frame.meta);
        }
        Ok((frame, s))
    }

    /// The settings the next frame runs with (a budget's K's), after the warm-up.
    fn settings_for(
        &mut self,
        renderer: &mut Renderer,
        s: &RenderSettings,
    ) -> Result<RenderSettings> {
        if self.warmup_ms > 0.0 {
            renderer.ctx.warm_up(self.warmup_ms)?;
        }
        let mut s = s.clone();
        match s.cluster.target_ms {
            Some(_) if self.steps_budget => {
                let c = match self.controller.take() {
                    Some(c) if c.fits(&s) => c,
                    _ => Controller::new(&s).expect("a budget"),
                };
                c.apply(&mut s);
                self.controller = Some(c);
            }
            _ => self.controller = None,
        }
        Ok(s)
    }

    /// The K_SP and K_VPL the next frame under the stepped budget will take (`None`: no budget).
    pub fn next_ks(&self) -> Option<(u32, u32)> {
        self.controller.as_ref().map(Controller::ks)
    }
}

/// How many frames are timed, what they are and how long the GPU is warmed up before them.
#[derive(Clone, Copy, Debug)]
pub struct Timing {
    /// Frames rendered (at least 1; with a time budget its controller's frames count from the last).
    pub repeat: u32,
    /// GPU work in ms before the first timed frame (`settings::TimingSettings::warmup_ms`).
    pub warmup_ms: f64,
    pub kind: FrameKind,
}

/// A timed frame: the last one rendered, the settings it ran with (the controller's choice under a
/// time budget), its per-pass times, the warm-up done, and the controller's steps.
pub struct Timed {
    pub frame: Frame,
    pub settings: RenderSettings,
    pub timings_ms: BTreeMap<String, f64>,
    pub warmup_ms: f64,
    pub budget: Option<Budget>,
}

/// Renders `s` at `camera` as the module says; `tick` is called after each rendered frame (a
/// progress bar).
pub fn timed(
    renderer: &mut Renderer,
    camera: &Camera,
    s: &RenderSettings,
    timing: Timing,
    tick: &mut dyn FnMut(),
) -> Result<Timed> {
    let warmup_ms = match timing.kind {
        FrameKind::Vpl => renderer.warm_up(camera, s, timing.warmup_ms)?,
        // The path tracer builds its pipeline each frame and keeps nothing: the busy kernel alone.
        FrameKind::PathTrace(_) => renderer.ctx.warm_up(timing.warmup_ms)?,
    };
    let mut settings = s.clone();
    let mut runs = Vec::new();
    let mut last = None;
    let mut controller = None;
    if let (FrameKind::Vpl, Some(t)) = (timing.kind, s.cluster.target_ms) {
        let (chosen, b, f) = budget::fit(renderer, camera, s, t)?;
        settings = chosen;
        runs.push(f.timings_ms.clone());
        last = Some(f);
        controller = Some(b);
        tick();
    }
    let mut frames = FrameLoop::new(timing.kind, 0.0);
    for _ in runs.len() as u32..timing.repeat.max(1) {
        let (f, _) = frames.next(renderer, camera, &settings)?;
        runs.push(f.timings_ms.clone());
        last = Some(f);
        tick();
    }
    Ok(Timed {
        frame: last.expect("at least one frame"),
        settings,
        timings_ms: best_of_runs(&runs),
        warmup_ms,
        budget: controller,
    })
}

/// Every timing key of the contract (the shared passes of `Pass::TIMED`, every method's passes and
/// `frame`), so readers can index them; passes that did not run read 0.
pub fn timing_keys() -> impl Iterator<Item = &'static str> {
    let own = crate::method::REGISTRY.iter().flat_map(|r| r.passes);
    (Pass::TIMED.iter().chain(own))
        .map(|p| p.name())
        .chain([super::frame::FRAME_KEY])
}

/// Mean of the `k` smallest values (all of them if fewer): the paper's "3-best" timing.
pub fn mean_of_best(values: &[f64], k: usize) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let k = k.clamp(1, v.len());
    v[..k].iter().sum::<f64>() / k as f64
}

/// Per-key mean of the 3 best over several runs' timings, with every contract key present.
pub fn best_of_runs(runs: &[BTreeMap<String, f64>]) -> BTreeMap<String, f64> {
    let mut keys: Vec<String> = timing_keys().map(String::from).collect();
    for r in runs {
        for k in r.keys() {
            if !keys.contains(k) {
                keys.push(k.clone());
            }
        }
    }
    keys.into_iter()
        .map(|k| {
            let vals: Vec<f64> = runs
                .iter()
                .map(|r| r.get(&k).copied().unwrap_or(0.0))
                .collect();
            (k, mean_of_best(&vals, 3))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn best_three_of_ten() {
        let v = [9.0, 1.0, 8.0, 2.0, 7.0, 3.0, 6.0, 4.0, 5.0, 10.0];
        assert_eq!(mean_of_best(&v, 3), 2.0);
        assert_eq!(mean_of_best(&[5.0], 3), 5.0);
        assert_eq!(mean_of_best(&[], 3), 0.0);
    }

    #[test]
    fn every_contract_key_present() {
        let mut r = BTreeMap::new();
        r.insert("primary".to_string(), 2.0);
        let b = best_of_runs(&[r]);
        for k in timing_keys() {
            assert!(b.contains_key(k), "{k}");
        }
        // The contract's ten (the shared passes and `frame`), and every method's passes.
        let own: usize = crate::method::REGISTRY.iter().map(|r| r.passes.len()).sum();
        assert_eq!(timing_keys().count(), 10 + own);
        for r in crate::method::REGISTRY {
            assert!(
                r.passes.iter().all(|p| b.contains_key(p.name())),
                "{}",
                r.method
            );
        }
        assert_eq!(b["primary"], 2.0);
        assert_eq!(b["vpl_trace"], 0.0);
    }
}
