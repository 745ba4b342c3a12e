//! K for a time budget (`--target-ms`): a controller that moves K_VPL, with K_SP on one line of
//! settings, until the frame's GPU time meets the budget.
//!
//! The line passes through the paper's intermediate setting (1% of the pixels as SP clusters with
//! 2000 of 8192 VPLs as VPL clusters) with K_SP growing as the square root of K_VPL
//! (`k_sp_on_line`): on lavapipe the shading (pixels × K_VPL) costs most and SP clusters are cheap,
//! while the error grows fast as K_SP falls (conference, 320×240: 8 SP clusters have 18× the MSE of
//! 115), so the line keeps K_SP high where the paper's own light setting (0.15%, 750) drops it
//! (docs/results.md, "K for a time budget"). Along it the frame's time is `fixed + V(x)`, where `fixed`
//! is the passes that do not depend on K (primary rays, direct light) and V the others, modelled
//! locally as c · x^e in the controlled K, x. The first exponent comes from the measured split of
//! the frame (visibility grows as K_SP × K_VPL, x^1.5 on the line; shading as K_VPL, x^1); from the
//! second frame on it is the secant of the last two frames. Each step solves fixed + c · x^e =
//! budget for x.
//!
//! Where the fewest clusters still miss the budget, the direct light is what is left to cut: the
//! controller then lowers its samples a pixel (its time is linear in them) until the frame meets the
//! budget, down to 1; under the budget it gives them back, up to the user's count, before it raises K.

use anyhow::Result;

use super::frame::Frame;
use super::{RenderSettings, Renderer};
use crate::gi::pass::Pass;
use crate::scene::Camera;
use crate::settings::ClusterSettings;

/// Frames the controller renders at most.
pub const MAX_FRAMES: u32 = 8;

/// It stops early when a frame is within this fraction of the budget.
pub const SETTLED: f64 = 0.1;

/// The fewest SP and VPL clusters it goes down to.
pub const MIN_SP_CLUSTERS: u32 = 8;
pub const MIN_VPL_CLUSTERS: u32 = 16;

/// K_SP on the line for K_VPL VPL clusters of `vpls` VPLs and `pixels` pixels:
/// 0.01 · pixels · sqrt(K_VPL / (0.244 · vpls)) (1% of the pixels at 2000 of 8192 VPLs, 0.35% at 250,
/// 1.4% at 4000), within [8, pixels / 4].
pub fn k_sp_on_line(k_vpl: u32, pixels: u32, vpls: u32) -> u32 {
    let frac = k_vpl as f64 / (2000.0 / 8192.0 * vpls.max(1) as f64);
    let k = 0.01 * pixels as f64 * frac.sqrt();
    (k.round() as u32).clamp(MIN_SP_CLUSTERS.min(pixels).max(1), (pixels / 4).max(1))
}

/// Which K the controller moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Controlled {
    /// Both clusterings: K_VPL, with K_SP on the line.
    Both,
    /// SP clustering only (K_VPL off): K_SP.
    SpOnly,
    /// VPL clustering only (K_SP off): K_VPL.
    VplOnly,
}

/// One frame the controller saw.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Step {
    pub sp_clusters: u32,
    pub vpl_clusters: u32,
    /// The direct light's samples a pixel.
    pub direct_samples: u32,
    /// The frame's GPU time (`frame`).
    pub frame_ms: f64,
}

/// The time split of a frame the controller needs: the K-independent part and the part that grows
/// with the controlled K, with its exponent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Split {
    pub frame_ms: f64,
    /// Primary rays and direct light.
    pub fixed_ms: f64,
    /// The direct light alone.
    pub direct_ms: f64,
    /// The exponent of the rest in the controlled K, from its passes' shares.
    pub exponent: f64,
}

impl Split {
    /// The split of `f` when `c` controls it.
    pub fn of(f: &Frame, c: Controlled) -> Split {
        let fixed = f.ms(Pass::Primary) + f.ms(Pass::Direct);
        let rest = (f.frame_ms() - fixed).max(0.0);
        let (vis, shade, gather) = (
            f.ms(Pass::Visibility),
            f.ms(Pass::Shade),
            f.ms(Pass::Gather),
        );
        let weighted = match c {
            Controlled::Both => 1.5 * vis + shade,
            Controlled::SpOnly => vis,
            Controlled::VplOnly => gather + shade,
        };
        Split {
            frame_ms: f.frame_ms(),
            fixed_ms: fixed,
            direct_ms: f.ms(Pass::Direct),
            exponent: if rest > 0.0 {
                (weighted / rest).clamp(0.2, 3.0)
            } else {
                1.0
            },
        }
    }
}

/// The controller: `start` gives the first K's, `step` the next ones after each frame, until
/// `done`.
#[derive(Clone, Debug)]
pub struct Budget {
    pub target_ms: f64,
    pub controlled: Controlled,
    pixels: u32,
    vpls: u32,
    /// The user's direct-light samples: the most the controller gives.
    max_direct: u32,
    /// Whether it may cut the direct light's samples (`k_only` turns it off).
    cut_direct: bool,
    /// The controlled K of each frame seen, with its split.
    seen: Vec<(u32, Split)>,
    pub steps: Vec<Step>,
}

impl Budget {
    /// A controller for `target_ms` on the frame of `s`, moving what `s` clusters (K = 0 or at least
    /// the point count turns a clustering off, as in `Plan`) and, past the fewest clusters, the direct
    /// light's samples.
    pub fn new(target_ms: f64, s: &RenderSettings) -> Budget {
        let (c, pixels, vpls) = (&s.cluster, s.frame.width * s.frame.height, s.frame.vpls);
        let sp = c.sp_clusters > 0 && c.sp_clusters < pixels;
        let vpl = c.vpl_clusters > 0 && c.vpl_clusters < vpls;
        let controlled = match (sp, vpl) {
            (true, false) => Controlled::SpOnly,
            (false, true) => Controlled::VplOnly,
            _ => Controlled::Both,
        };
        Budget {
            target_ms,
            controlled,
            pixels,
            vpls,
            max_direct: s.frame.direct_samples.max(1),
            cut_direct: true,
            seen: Vec::new(),
            steps: Vec::new(),
        }
    }

    /// The same controller moving the K's only, never the direct light's samples.
    pub fn k_only(self) -> Budget {
        Budget {
            cut_direct: false,
            ..self
        }
    }

    fn range(&self) -> (u32, u32) {
        match self.controlled {
            Controlled::SpOnly => (
                MIN_SP_CLUSTERS.min(self.pixels).max(1),
                (self.pixels / 4).max(1),
            ),
            Controlled::Both | Controlled::VplOnly => (
                MIN_VPL_CLUSTERS.min(self.vpls / 2).max(1),
                (self.vpls / 2).max(1),
            ),
        }
    }

    /// `c` with the controlled K set to `x` (and K_SP on the line when both are controlled).
    pub fn apply(&self, c: &ClusterSettings, x: u32) -> ClusterSettings {
        let mut c = c.clone();
        match self.controlled {
            Controlled::Both => {
                c.vpl_clusters = x;
                c.sp_clusters = k_sp_on_line(x, self.pixels, self.vpls);
            }
            Controlled::SpOnly => c.sp_clusters = x,
            Controlled::VplOnly => c.vpl_clusters = x,
        }
        c
    }

    /// The first frame's settings: the paper's intermediate setting (2000 of 8192 VPLs as VPL
    /// clusters, 1% of the pixels as SP clusters), or the K given for a single clustering; the
    /// user's direct-light samples.
    pub fn start(&self, s: &RenderSettings) -> RenderSettings {
        let (lo, hi) = self.range();
        let c = &s.cluster;
        let x = match self.controlled {
            Controlled::Both => ((2000.0 / 8192.0 * self.vpls as f64) as u32).clamp(lo, hi),
            Controlled::SpOnly => c.sp_clusters.clamp(lo, hi),
            Controlled::VplOnly => c.vpl_clusters.clamp(lo, hi),
        };
        let mut s = s.clone();
        s.cluster = self.apply(c, x);
        s.frame.direct_samples = self.max_direct;
        s
    }

    fn x_of(&self, c: &ClusterSettings) -> u32 {
        match self.controlled {
            Controlled::SpOnly => c.sp_clusters,
            Controlled::Both | Controlled::VplOnly => c.vpl_clusters,
        }
    }

    /// A frame rendered with `s` took `split`: the settings of the next frame (the same when it
    /// cannot move further).
    pub fn step(&mut self, s: &RenderSettings, split: Split) -> RenderSettings {
        let c = &s.cluster;
        let x = self.x_of(c);
        let used = s.frame.direct_samples.max(1);
        self.steps.push(Step {
            sp_clusters: c.sp_clusters,
            vpl_clusters: c.vpl_clusters,
            direct_samples: used,
            frame_ms: split.frame_ms,
        });
        let mut exponent = split.exponent;
        // The secant of the last two frames' variable parts, where they differ enough to tell.
        if let Some(&(x0, s0)) = self.seen.last() {
            let (v0, v1) = (s0.frame_ms - s0.fixed_ms, split.frame_ms - split.fixed_ms);
            if x0 != x && v0 > 0.0 && v1 > 0.0 && (x as f64 / x0 as f64).ln().abs() > 0.05 {
                let e = (v1 / v0).ln() / (x as f64 / x0 as f64).ln();
                if e.is_finite() {
                    exponent = e.clamp(0.2, 3.0);
                }
            }
        }
        self.seen.push((x, split));
        let (lo, hi) = self.range();
        let mut next = s.clone();
        // The direct light: cut where the fewest clusters miss the budget, given back (before K
        // grows) where the frame is under it.
        let off = split.frame_ms / self.target_ms - 1.0;
        let cut = off > SETTLED && x <= lo && used > 1;
        let give = off < -SETTLED && used < self.max_direct;
        if self.cut_direct && split.direct_ms > 0.0 && (cut || give) {
            next.frame.direct_samples = direct_samples_for(
                used,
                split.direct_ms,
                self.target_ms - (split.frame_ms - split.direct_ms),
            )
            .clamp(1, self.max_direct);
            if next.frame.direct_samples != used {
                return next;
            }
        }
        let v = split.frame_ms - split.fixed_ms;
        let want = self.target_ms - split.fixed_ms;
        let k = if v <= 0.0 || want <= 0.0 {
            lo as f64
        } else {
            x as f64 * (want / v).powf(1.0 / exponent)
        };
        // At most a factor 8 a step: one noisy frame does not throw K to its bounds.
        let k = k.clamp(x as f64 / 8.0, x as f64 * 8.0);
        next.cluster = self.apply(c, (k.round() as u32).clamp(lo, hi));
        next
    }

    /// Whether the last frame met the budget within `SETTLED`, or the frames are spent, or K cannot
    /// move (`next` equals the last frame's settings).
    pub fn done(&self, next: &RenderSettings) -> bool {
        let Some(last) = self.steps.last() else {
            return false;
        };
        let c = &next.cluster;
        self.steps.len() as u32 >= MAX_FRAMES
            || (last.frame_ms / self.target_ms - 1.0).abs() <= SETTLED
            || (last.sp_clusters, last.vpl_clusters, last.direct_samples)
                == (
                    c.sp_clusters,
                    c.vpl_clusters,
                    next.frame.direct_samples.max(1),
                )
    }
}

/// The direct-light samples a pixel that take `room_ms`, where `used` samples took `direct_ms` (the
/// pass's time is linear in them); at least 1.
pub fn direct_samples_for(used: u32, direct_ms: f64, room_ms: f64) -> u32 {
    let n = used as f64 * room_ms / direct_ms;
    if n.is_finite() {
        n.floor().max(1.0) as u32
    } else {
        1
    }
}

/// The viewer's controller (`view --target-ms`, the panel's time budget): a `Budget` (K only: the
/// direct light accumulates at rest, and a reference is kept per direct-sample count, which a cut
/// would change) for one target and frame size, stepped once per frame shown. Its K's stay while
/// frames land within `SETTLED` of the target, so a steady view stays steady.
pub struct Controller {
    pub target_ms: f64,
    pub pixels: u32,
    budget: Budget,
    /// K_SP and K_VPL of the next frame.
    ks: (u32, u32),
}

impl Controller {
    /// A controller for `s`'s budget and size (`None` without a budget).
    pub fn new(s: &RenderSettings) -> Option<Controller> {
        let t = s.cluster.target_ms?;
        let budget = Budget::new(t, s).k_only();
        let first = budget.start(s);
        Some(Controller {
            target_ms: t,
            pixels: s.frame.width * s.frame.height,
            budget,
            ks: (first.cluster.sp_clusters, first.cluster.vpl_clusters),
        })
    }

    /// Whether it was made for `s`'s budget and size.
    pub fn fits(&self, s: &RenderSettings) -> bool {
        s.cluster.target_ms == Some(self.target_ms) && s.frame.width * s.frame.height == self.pixels
    }

    /// `s` with the K's it chose.
    pub fn apply(&self, s: &mut RenderSettings) {
        (s.cluster.sp_clusters, s.cluster.vpl_clusters) = self.ks;
    }

    /// K_SP and K_VPL of the next frame.
    pub fn ks(&self) -> (u32, u32) {
        self.ks
    }

    /// A frame rendered with `s` (its K's): the next K's, kept when the frame missed the budget by
    /// more than `SETTLED`.
    pub fn observe(&mut self, s: &RenderSettings, frame: &Frame) {
        if !self.fits(s) {
            return;
        }
        let next = self
            .budget
            .step(s, Split::of(frame, self.budget.controlled));
        if (frame.frame_ms() / self.target_ms - 1.0).abs() > SETTLED {
            self.ks = (next.cluster.sp_clusters, next.cluster.vpl_clusters);
        }
    }
}

/// Renders `camera` with `s` until its frame time meets `target_ms` (at most `MAX_FRAMES` frames):
/// the settings it settled on (`s` with the chosen K's), the controller (its `steps`) and the last
/// frame, rendered with those settings.
pub fn fit(
    renderer: &mut Renderer,
    camera: &Camera,
    s: &RenderSettings,
    target_ms: f64,
) -> Result<(RenderSettings, Budget, Frame)> {
    let mut b = Budget::new(target_ms, s);
    let mut cur = b.start(s);
    loop {
        let frame = renderer.render(camera, &cur)?;
        let next = b.step(&cur, Split::of(&frame, b.controlled));
        if b.done(&next) {
            return Ok((cur, b, frame));
        }
        cur = next;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame whose passes follow a known time model: primary rays 10 ms, direct light 0.625 ms a
    /// sample (10 ms at 16), SP clustering 5 ms, visibility 2e-5 ms a K_SP × K_VPL pair, shading
    /// 0.02 ms a VPL cluster.
    fn frame(s: &RenderSettings) -> Split {
        let c = &s.cluster;
        let direct = 0.625 * s.frame.direct_samples as f64;
        let vis = 2e-5 * c.sp_clusters as f64 * c.vpl_clusters as f64;
        let shade = 0.02 * c.vpl_clusters as f64;
        let rest = 5.0 + vis + shade;
        Split {
            frame_ms: 10.0 + direct + rest,
            fixed_ms: 10.0 + direct,
            direct_ms: direct,
            exponent: ((1.5 * vis + shade) / rest).clamp(0.2, 3.0),
        }
    }

    fn settings(c: &ClusterSettings, pixels: (u32, u32), vpls: u32) -> RenderSettings {
        let mut s = RenderSettings {
            cluster: c.clone(),
            ..Default::default()
        };
        (s.frame.width, s.frame.height) = pixels;
        s.frame.vpls = vpls;
        s.frame.direct_samples = 16;
        s
    }

    fn run(
        target: f64,
        c: &ClusterSettings,
        pixels: (u32, u32),
        vpls: u32,
    ) -> (Budget, RenderSettings) {
        let s = settings(c, pixels, vpls);
        let mut b = Budget::new(target, &s);
        let mut s = b.start(&s);
        loop {
            let next = b.step(&s, frame(&s));
            if b.done(&next) {
                return (b, s);
            }
            s = next;
        }
    }

    /// A frame that took `frame_ms` in all with these passes' times (the others did not run).
    fn timed(frame_ms: f64, passes: &[(Pass, f64)]) -> Frame {
        let mut timings_ms: std::collections::BTreeMap<String, f64> = passes
            .iter()
            .map(|&(p, ms)| (p.name().to_string(), ms))
            .collect();
        timings_ms.insert(crate::render::frame::FRAME_KEY.to_string(), frame_ms);
        Frame {
            passes: passes.iter().map(|&(p, _)| p).collect(),
            timings_ms,
            ..Default::default()
        }
    }

    /// `Split::of` by hand. The fixed part is primary rays + direct light; the rest is the frame
    /// less it; the exponent is the controlled passes' time weighted by their exponent (visibility
    /// 1.5 on the line, shading and gather 1) over the rest, within [0.2, 3].
    #[test]
    fn split_of_a_frame_by_hand() {
        use Controlled::*;
        use Pass::*;
        // Primary 10, direct 20, SP clustering 10, visibility 30, shading 40: frame 110, fixed 30,
        // rest 80.
        let f: &[(Pass, f64)] = &[
            (Primary, 10.0),
            (Direct, 20.0),
            (SpCluster, 10.0),
            (Visibility, 30.0),
            (Shade, 40.0),
        ];
        // VPL clustering alone with the gather (K_SP off): primary 5, direct 15, gather 12,
        // shading 36, frame 80: fixed 20, rest 60.
        let g: &[(Pass, f64)] = &[
            (Primary, 5.0),
            (Direct, 15.0),
            (Gather, 12.0),
            (Shade, 36.0),
        ];
        // Nothing but the fixed part (rest 0), or a frame shorter than its fixed passes (rest
        // negative, read as 0).
        let z: &[(Pass, f64)] = &[(Primary, 10.0), (Direct, 20.0), (Shade, 5.0)];
        // (frame ms, passes, the K moved) → (fixed ms, direct ms, exponent).
        type Passes<'a> = &'a [(Pass, f64)];
        let cases: [(f64, Passes, Controlled, [f64; 3]); 9] = [
            // Both: (1.5 · 30 + 40) / 80 = 85 / 80 = 1.0625.
            (110.0, f, Both, [30.0, 20.0, 1.0625]),
            // SP clustering alone: visibility only, 30 / 80 = 0.375.
            (110.0, f, SpOnly, [30.0, 20.0, 0.375]),
            // VPL clustering alone: gather + shading, here 40 / 80 = 0.5.
            (110.0, f, VplOnly, [30.0, 20.0, 0.5]),
            // (12 + 36) / 60 = 0.8; Both weighs shading only: 36 / 60 = 0.6.
            (80.0, g, VplOnly, [20.0, 15.0, 0.8]),
            (80.0, g, Both, [20.0, 15.0, 0.6]),
            // Clamped: visibility 100 of a rest of 40 (the passes overlap the frame's own
            // timestamps) gives 1.5 · 100 / 40 = 3.75 → 3; visibility 1 of 40 alone 0.025 → 0.2.
            (
                50.0,
                &[(Primary, 10.0), (Visibility, 100.0)],
                Both,
                [10.0, 0.0, 3.0],
            ),
            (
                50.0,
                &[(Primary, 10.0), (Visibility, 1.0)],
                SpOnly,
                [10.0, 0.0, 0.2],
            ),
            // No rest: exponent 1, the fixed part as measured.
            (30.0, z, Both, [30.0, 20.0, 1.0]),
            (25.0, z, Both, [30.0, 20.0, 1.0]),
        ];
        for (frame, passes, c, want) in cases {
            let s = Split::of(&timed(frame, passes), c);
            let got = [s.fixed_ms, s.direct_ms, s.exponent];
            assert_eq!(got, want, "{passes:?} in {frame} ms, {c:?}");
        }
        assert_eq!(Split::of(&timed(110.0, f), Both).frame_ms, 110.0);
        // A frame with no direct light (no emitter, no punctual light): direct 0.
        let d = timed(60.0, &[(Primary, 12.0), (Shade, 48.0)]);
        let s = Split::of(&d, Both);
        assert_eq!((s.fixed_ms, s.direct_ms, s.exponent), (12.0, 0.0, 1.0));
    }

    /// One step of the controller from a split worked by hand: frame 110 ms, fixed 30, exponent
    /// 1.0625 (above), budget 70 ms: K_VPL 1000 · ((70 − 30) / 80)^(1 / 1.0625) = 1000 · 0.5^0.941
    /// = 520.8 → 521; the next step's exponent is the secant of the two frames.
    #[test]
    fn a_step_solves_the_fitted_model() {
        use Pass::*;
        let f = timed(
            110.0,
            &[
                (Primary, 10.0),
                (Direct, 20.0),
                (SpCluster, 10.0),
                (Visibility, 30.0),
                (Shade, 40.0),
            ],
        );
        let c = ClusterSettings {
            vpl_clusters: 1000,
            ..ClusterSettings::default()
        };
        let s = settings(&c, (320, 240), 8192);
        let mut b = Budget::new(70.0, &s);
        let s = RenderSettings {
            cluster: b.apply(&s.cluster, 1000),
            ..s
        };
        let next = b.step(&s, Split::of(&f, b.controlled));
        assert_eq!(next.cluster.vpl_clusters, 521);
        assert_eq!(next.cluster.sp_clusters, k_sp_on_line(521, 320 * 240, 8192));
        assert_eq!(next.frame.direct_samples, 16);
        assert!(!b.done(&next));
        // The second frame at K 521 took 30 + 50 ms (80): the secant exponent
        // ln(50 / 80) / ln(521 / 1000) = 0.7209 (not the split's own 1), and K = 521 · (40 /
        // 50)^(1 / 0.7209) = 382.3 → 382.
        let g = timed(80.0, &[(Primary, 10.0), (Direct, 20.0), (Shade, 50.0)]);
        let after = b.step(&next, Split::of(&g, b.controlled));
        assert_eq!(after.cluster.vpl_clusters, 382);
        assert_eq!(b.steps.len(), 2);
        assert_eq!((b.steps[1].vpl_clusters, b.steps[1].frame_ms), (521, 80.0));
    }

    #[test]
    fn the_line_passes_through_the_papers_intermediate_setting() {
        // 640×480, 8192 VPLs: 2000 → 1% (3072); 250 → 0.35%; 4000 → 1.41%.
        assert_eq!(k_sp_on_line(2000, 640 * 480, 8192), 3072);
        assert_eq!(k_sp_on_line(250, 640 * 480, 8192), 1086);
        assert_eq!(k_sp_on_line(4000, 640 * 480, 8192), 4344);
        // Bounded by 8 and a quarter of the pixels.
        assert_eq!(k_sp_on_line(1, 64 * 48, 8192), 8);
        assert_eq!(k_sp_on_line(1 << 30, 64 * 48, 8192), 64 * 48 / 4);
    }

    #[test]
    fn meets_a_budget_of_a_known_time_model_within_a_few_frames() {
        let c = ClusterSettings::default();
        for target in [40.0, 60.0, 100.0, 150.0] {
            let (b, s) = run(target, &c, (320, 240), 8192);
            let last = b.steps.last().unwrap();
            assert!(
                (last.frame_ms / target - 1.0).abs() <= SETTLED,
                "{target}: {:?}",
                b.steps
            );
            assert!(b.steps.len() <= 4, "{target}: {:?}", b.steps);
            let c = &s.cluster;
            assert_eq!(
                (last.sp_clusters, last.vpl_clusters),
                (c.sp_clusters, c.vpl_clusters)
            );
            assert_eq!(c.sp_clusters, k_sp_on_line(c.vpl_clusters, 320 * 240, 8192));
            // K alone meets these: the direct light keeps the user's samples.
            assert!(
                b.steps.iter().all(|st| st.direct_samples == 16),
                "{:?}",
                b.steps
            );
        }
    }

    #[test]
    fn past_the_fewest_clusters_the_direct_light_is_cut_to_meet_the_budget() {
        let c = ClusterSettings::default();
        // At the fewest clusters (16 / 8 on 320×240) the model takes 10 + 10 + 5.3 ms: 22 ms needs
        // the direct light at 10.7 ms → 6.8 ms, 10 or 11 samples (11: 23.0 ms, within 10%).
        let (b, s) = run(22.0, &c, (320, 240), 8192);
        let last = b.steps.last().unwrap();
        assert_eq!(s.cluster.vpl_clusters, MIN_VPL_CLUSTERS, "{:?}", b.steps);
        assert!(
            (last.frame_ms / 22.0 - 1.0).abs() <= SETTLED,
            "{:?}",
            b.steps
        );
        assert!((9..=12).contains(&s.frame.direct_samples), "{:?}", b.steps);
        assert_eq!(last.direct_samples, s.frame.direct_samples);
        // Below even primary rays and SP clustering: the fewest of both, within MAX_FRAMES.
        let (b, s) = run(10.0, &c, (320, 240), 8192);
        assert_eq!(s.cluster.vpl_clusters, MIN_VPL_CLUSTERS);
        assert_eq!(s.frame.direct_samples, 1, "{:?}", b.steps);
        assert!(b.steps.len() as u32 <= MAX_FRAMES);
        // Moving K only (the viewer), the direct light keeps its samples.
        let st = settings(&c, (320, 240), 8192);
        let mut b = Budget::new(22.0, &st).k_only();
        let mut s = b.start(&st);
        while !b.done(&s) {
            s = b.step(&s, frame(&s));
        }
        assert!(
            b.steps.iter().all(|st| st.direct_samples == 16),
            "{:?}",
            b.steps
        );
        // A huge budget ends at the most clusters (half the VPLs) with every sample.
        let (_, s) = run(1e9, &c, (160, 120), 8192);
        assert_eq!((s.cluster.vpl_clusters, s.frame.direct_samples), (4096, 16));
    }

    /// One knob a step: under the budget at the fewest clusters with 4 of 16 direct samples
    /// (10 + 2.5 + 5.3 ms of 40), the step gives the direct light its samples back (4 · 24.7 / 2.5
    /// → 39, clamped to 16) and leaves K; the next step, with every sample and still under the
    /// budget (25.3 ms), grows K and keeps the samples (cargo-mutants: the direct light's early
    /// return taken when the samples did not change survived).
    #[test]
    fn a_step_moves_the_direct_light_or_k_not_both() {
        let (mut b, s) = at_k(40.0, MIN_VPL_CLUSTERS, 4);
        let next = b.step(&s, frame(&s));
        assert_eq!(next.frame.direct_samples, 16);
        assert_eq!(next.cluster, s.cluster);
        let after = b.step(&next, frame(&next));
        assert_eq!(after.frame.direct_samples, 16);
        assert!(
            after.cluster.vpl_clusters > MIN_VPL_CLUSTERS,
            "{:?}",
            b.steps
        );
    }

    #[test]
    fn direct_samples_are_linear_in_the_room_left() {
        // 16 samples took 40 ms: 10 ms of room is 4 samples, 2 ms rounds down to 0 and is 1.
        assert_eq!(direct_samples_for(16, 40.0, 10.0), 4);
        assert_eq!(direct_samples_for(16, 40.0, 2.0), 1);
        assert_eq!(direct_samples_for(16, 40.0, -5.0), 1);
        assert_eq!(direct_samples_for(4, 10.0, 40.0), 16);
    }

    /// The first frame is the paper's intermediate setting: 2000 of 8192 VPLs as VPL clusters (the
    /// same share of 4096: 1000) with 1% of the pixels as SP clusters, the user's direct samples
    /// (cargo-mutants: the share as 2000 % 8192, clamped to K_VPL = VPLs / 2, survived).
    #[test]
    fn the_first_frame_is_the_intermediate_setting() {
        let c = ClusterSettings::default();
        for (vpls, k_vpl) in [(8192, 2000), (4096, 1000)] {
            let s = settings(&c, (640, 480), vpls);
            let first = Budget::new(100.0, &s).start(&s);
            assert_eq!(first.cluster.vpl_clusters, k_vpl);
            assert_eq!(
                first.cluster.sp_clusters,
                k_sp_on_line(k_vpl, 640 * 480, vpls)
            );
            assert_eq!(first.frame.direct_samples, 16);
        }
        assert_eq!(k_sp_on_line(2000, 640 * 480, 8192), 3072);
    }

    /// Where the model has no answer, K falls toward the fewest clusters, at most 8× a step: a frame
    /// whose time is all primary rays and direct light (V = 0), and one whose fixed part alone is
    /// over the budget (cargo-mutants: the two conditions joined by `&&` survived; K then rose 8×
    /// in the first case and fell to the fewest at once, a NaN power, in the second).
    #[test]
    fn k_falls_where_the_model_has_no_answer() {
        let s = settings(&ClusterSettings::default(), (640, 480), 8192);
        let first = Budget::new(100.0, &s).start(&s);
        assert_eq!(first.cluster.vpl_clusters, 2000);
        for (frame_ms, fixed_ms) in [(50.0, 50.0), (150.0, 120.0)] {
            let split = Split {
                frame_ms,
                fixed_ms,
                direct_ms: 20.0,
                exponent: 1.5,
            };
            let next = Budget::new(100.0, &s).step(&first, split);
            assert_eq!(next.cluster.vpl_clusters, 2000 / 8, "{split:?}");
            assert_eq!(next.frame.direct_samples, 16);
        }
    }

    #[test]
    fn a_single_clustering_moves_only_its_own_k() {
        let c = ClusterSettings {
            vpl_clusters: 0,
            sp_clusters: 500,
            ..ClusterSettings::default()
        };
        let b = Budget::new(100.0, &settings(&c, (320, 240), 8192));
        assert_eq!(b.controlled, Controlled::SpOnly);
        let s = b.apply(&c, 900);
        assert_eq!((s.sp_clusters, s.vpl_clusters), (900, 0));
        let c = ClusterSettings {
            sp_clusters: 0,
            ..ClusterSettings::default()
        };
        let b = Budget::new(100.0, &settings(&c, (320, 240), 8192));
        assert_eq!(b.controlled, Controlled::VplOnly);
        assert_eq!(b.apply(&c, 300).sp_clusters, 0);
    }

    fn split(frame_ms: f64, fixed_ms: f64, direct_ms: f64) -> Split {
        Split {
            frame_ms,
            fixed_ms,
            direct_ms,
            exponent: 1.0,
        }
    }

    /// A controller for `target` ms on 320×240 with 8192 VPLs, and its start's settings with K_VPL
    /// `k` (K_SP on the line) and `samples` direct samples.
    fn at_k(target: f64, k: u32, samples: u32) -> (Budget, RenderSettings) {
        let st = settings(&ClusterSettings::default(), (320, 240), 8192);
        let b = Budget::new(target, &st);
        let mut s = b.start(&st);
        s.cluster = b.apply(&s.cluster, k);
        s.frame.direct_samples = samples;
        (b, s)
    }

    /// Within `SETTLED` of the budget the direct light keeps its samples, even at the fewest
    /// clusters with samples to give back: 38 of 40 ms at 4 of 16 samples leaves 4 and grows K (a
    /// cut or give-back there would ask 4 · 4.5 / 2.5 → 7). Without a direct light (0 ms) a frame
    /// over the budget at the fewest clusters leaves the samples as they are. (cargo-mutants:
    /// `off`'s `/` as `*` or `%` and `−` as `+` or `/`, the give-back's `−SETTLED` as `SETTLED` and
    /// its `&&` as `||`, and `direct_ms > 0` as `>= 0` survived.)
    #[test]
    fn the_direct_light_stays_within_the_band_and_without_a_direct_pass() {
        let (mut b, s) = at_k(40.0, MIN_VPL_CLUSTERS, 4);
        let next = b.step(&s, split(38.0, 12.5, 2.5));
        assert_eq!(next.frame.direct_samples, 4);
        assert!(
            next.cluster.vpl_clusters > MIN_VPL_CLUSTERS,
            "{:?}",
            next.cluster
        );
        let (mut b, s) = at_k(40.0, MIN_VPL_CLUSTERS, 16);
        let next = b.step(&s, split(60.0, 10.0, 0.0));
        assert_eq!(next.frame.direct_samples, 16);
        assert_eq!(next.cluster.vpl_clusters, MIN_VPL_CLUSTERS);
    }

    /// The secant needs K to have moved by more than 5% (ln ratio 0.05): K 1000 → 1020 with the
    /// variable part doubling (timing noise) keeps the split's exponent 1, so K = 1020 · 30 / 80 =
    /// 382.5 → 383; the secant there would be ln 2 / ln 1.02 = 35, clamped to 3 (K 736).
    /// (cargo-mutants: the ratio's `/` as `*` or `%`, and each of the guard's three `&&` as `||`,
    /// survived.)
    #[test]
    fn the_secant_waits_for_k_to_move_five_percent() {
        let (mut b, mut s) = at_k(40.0, 1000, 16);
        b.step(&s, split(50.0, 10.0, 5.0));
        s.cluster = b.apply(&s.cluster, 1020);
        let next = b.step(&s, split(90.0, 10.0, 5.0));
        assert_eq!(next.cluster.vpl_clusters, 383, "{:?}", b.steps);
    }

    /// The range of the controlled K: K_SP alone goes up to a quarter of the pixels (16×16: 64),
    /// K_VPL down to half the VPLs where that is below `MIN_VPL_CLUSTERS` (20 VPLs: 10).
    /// (cargo-mutants: `pixels / 4` as `* 4` or `% 4`, `vpls / 2` as `* 2` survived.)
    #[test]
    fn k_stays_within_a_quarter_of_the_pixels_and_half_the_vpls() {
        let c = ClusterSettings {
            sp_clusters: 32,
            vpl_clusters: 0,
            ..Default::default()
        };
        let (b, s) = run(1e9, &c, (16, 16), 8192);
        assert_eq!(b.controlled, Controlled::SpOnly);
        assert_eq!(s.cluster.sp_clusters, 64, "{:?}", b.steps);
        let c = ClusterSettings {
            vpl_clusters: 12,
            ..Default::default()
        };
        let (b, s) = run(1e-3, &c, (32, 32), 20);
        assert_eq!(b.controlled, Controlled::VplOnly);
        assert_eq!(s.cluster.vpl_clusters, 10, "{:?}", b.steps);
    }

    /// The viewer's controller: made for one budget and size (`fits`), it keeps its K's while a
    /// frame lands within `SETTLED` (29.5 of 30 ms) and moves them past it (60 ms: K falls); a
    /// frame of another size is ignored. (cargo-mutants: `fits` as `true` and its `&&` as `||`,
    /// `observe`'s band test with `/` as `*` or `%` and `−` as `+` or `/` survived.)
    #[test]
    fn the_viewers_controller_moves_k_only_outside_the_band() {
        let mut st = settings(&ClusterSettings::default(), (320, 240), 8192);
        st.cluster.target_ms = Some(30.0);
        let mut c = Controller::new(&st).unwrap();
        assert!(c.fits(&st));
        let mut other = st.clone();
        other.cluster.target_ms = Some(31.0);
        assert!(!c.fits(&other));
        let mut other = st.clone();
        other.frame.width = 321;
        assert!(!c.fits(&other));
        let ks = c.ks();
        let mut s = st.clone();
        c.apply(&mut s);
        let f = |ms: f64| {
            timed(
                ms,
                &[
                    (Pass::Primary, 10.0),
                    (Pass::Direct, 5.0),
                    (Pass::Shade, ms - 15.0),
                ],
            )
        };
        c.observe(&s, &f(29.5));
        assert_eq!(c.ks(), ks);
        c.observe(&other, &f(90.0));
        assert_eq!(c.ks(), ks);
        c.observe(&s, &f(60.0));
        assert!(c.ks().1 < ks.1, "{:?} from {ks:?}", c.ks());
    }
}
