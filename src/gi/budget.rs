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

use anyhow::Result;

use super::frame::Frame;
use super::pipeline::{Pass, RenderSettings, Renderer};
use crate::scene::Camera;
use crate::settings::ClusterSettings;

/// Frames the controller renders at most.
pub const MAX_FRAMES: u32 = 6;

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
    /// The controlled K of each frame seen, with its split.
    seen: Vec<(u32, Split)>,
    pub steps: Vec<Step>,
}

impl Budget {
    /// A controller for `target_ms` on `pixels` pixels and `vpls` VPLs, moving what `c` clusters
    /// (K = 0 or at least the point count turns a clustering off, as in `Plan`).
    pub fn new(target_ms: f64, c: &ClusterSettings, pixels: u32, vpls: u32) -> Budget {
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
            seen: Vec::new(),
            steps: Vec::new(),
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
    /// clusters, 1% of the pixels as SP clusters), or the K given for a single clustering.
    pub fn start(&self, c: &ClusterSettings) -> ClusterSettings {
        let (lo, hi) = self.range();
        let x = match self.controlled {
            Controlled::Both => ((2000.0 / 8192.0 * self.vpls as f64) as u32).clamp(lo, hi),
            Controlled::SpOnly => c.sp_clusters.clamp(lo, hi),
            Controlled::VplOnly => c.vpl_clusters.clamp(lo, hi),
        };
        self.apply(c, x)
    }

    fn x_of(&self, c: &ClusterSettings) -> u32 {
        match self.controlled {
            Controlled::SpOnly => c.sp_clusters,
            Controlled::Both | Controlled::VplOnly => c.vpl_clusters,
        }
    }

    /// A frame rendered with `c` took `split`: the settings of the next frame (the same when it
    /// cannot move further).
    pub fn step(&mut self, c: &ClusterSettings, split: Split) -> ClusterSettings {
        let x = self.x_of(c);
        self.steps.push(Step {
            sp_clusters: c.sp_clusters,
            vpl_clusters: c.vpl_clusters,
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
        let v = split.frame_ms - split.fixed_ms;
        let want = self.target_ms - split.fixed_ms;
        let next = if v <= 0.0 || want <= 0.0 {
            lo as f64
        } else {
            x as f64 * (want / v).powf(1.0 / exponent)
        };
        // At most a factor 8 a step: one noisy frame does not throw K to its bounds.
        let next = next.clamp(x as f64 / 8.0, x as f64 * 8.0);
        self.apply(c, (next.round() as u32).clamp(lo, hi))
    }

    /// Whether the last frame met the budget within `SETTLED`, or the frames are spent, or K cannot
    /// move (`next` equals the last frame's settings).
    pub fn done(&self, next: &ClusterSettings) -> bool {
        let Some(last) = self.steps.last() else {
            return false;
        };
        self.steps.len() as u32 >= MAX_FRAMES
            || (last.frame_ms / self.target_ms - 1.0).abs() <= SETTLED
            || (last.sp_clusters, last.vpl_clusters) == (next.sp_clusters, next.vpl_clusters)
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
    let f = &s.frame;
    let mut b = Budget::new(target_ms, &s.cluster, f.width * f.height, f.vpls);
    let mut cur = RenderSettings {
        cluster: b.start(&s.cluster),
        ..s.clone()
    };
    loop {
        let frame = renderer.render(camera, &cur)?;
        let next = b.step(&cur.cluster, Split::of(&frame, b.controlled));
        if b.done(&next) {
            return Ok((cur, b, frame));
        }
        cur.cluster = next;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame whose passes follow a known time model: primary + direct 20 ms, SP clustering 5 ms,
    /// visibility 2e-5 ms a K_SP × K_VPL pair, shading 0.02 ms a VPL cluster.
    fn frame(c: &ClusterSettings) -> Split {
        let vis = 2e-5 * c.sp_clusters as f64 * c.vpl_clusters as f64;
        let shade = 0.02 * c.vpl_clusters as f64;
        let rest = 5.0 + vis + shade;
        Split {
            frame_ms: 20.0 + rest,
            fixed_ms: 20.0,
            exponent: ((1.5 * vis + shade) / rest).clamp(0.2, 3.0),
        }
    }

    fn run(target: f64, c: &ClusterSettings, pixels: u32, vpls: u32) -> (Budget, ClusterSettings) {
        let mut b = Budget::new(target, c, pixels, vpls);
        let mut s = b.start(c);
        loop {
            let next = b.step(&s, frame(&s));
            if b.done(&next) {
                return (b, s);
            }
            s = next;
        }
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
            let (b, s) = run(target, &c, 320 * 240, 8192);
            let last = b.steps.last().unwrap();
            assert!(
                (last.frame_ms / target - 1.0).abs() <= SETTLED,
                "{target}: {:?}",
                b.steps
            );
            assert!(b.steps.len() <= 4, "{target}: {:?}", b.steps);
            assert_eq!(
                (last.sp_clusters, last.vpl_clusters),
                (s.sp_clusters, s.vpl_clusters)
            );
            assert_eq!(s.sp_clusters, k_sp_on_line(s.vpl_clusters, 320 * 240, 8192));
        }
    }

    #[test]
    fn a_budget_below_the_fixed_part_ends_at_the_fewest_clusters() {
        let c = ClusterSettings::default();
        let (b, s) = run(10.0, &c, 320 * 240, 8192);
        assert_eq!(s.vpl_clusters, MIN_VPL_CLUSTERS);
        assert!(b.steps.len() as u32 <= MAX_FRAMES);
        // A huge budget ends at the most: half the VPLs.
        let (_, s) = run(1e9, &c, 160 * 120, 8192);
        assert_eq!(s.vpl_clusters, 4096);
    }

    #[test]
    fn a_single_clustering_moves_only_its_own_k() {
        let c = ClusterSettings {
            vpl_clusters: 0,
            sp_clusters: 500,
            ..ClusterSettings::default()
        };
        let b = Budget::new(100.0, &c, 320 * 240, 8192);
        assert_eq!(b.controlled, Controlled::SpOnly);
        let s = b.apply(&c, 900);
        assert_eq!((s.sp_clusters, s.vpl_clusters), (900, 0));
        let c = ClusterSettings {
            sp_clusters: 0,
            ..ClusterSettings::default()
        };
        let b = Budget::new(100.0, &c, 320 * 240, 8192);
        assert_eq!(b.controlled, Controlled::VplOnly);
        assert_eq!(b.apply(&c, 300).sp_clusters, 0);
    }
}
