//! The settings model: one type per idea, each declared once with its command-line form (clap
//! `Args`) and its serialised form (serde), flattened into `render`, `view` and `bench` and used as
//! they are by the renderer (`render::RenderSettings`), the viewer's state, the stats JSON
//! and the bench CSV.
//!
//! - `ClusterSettings`: the paper's knobs (K_SP, K_VPL, F, γ, n_t, iterations, weighting, p, the
//!   plane gate, temporal reuse, the time target); the other methods' knobs are declared in their
//!   modules with `knobs!` and gathered in `method::MethodSettings`;
//! - `FrameSettings`: what a frame is (size, seed, VPLs, bounces, direct samples, exposure, clamp);
//! - `LightSettings`: the lights added to or scaled in a scene.
//!
//! Ranges are checked by the value parsers below; a value out of range is refused by clap with one
//! line naming the option and the value, exit 2 (`cli::parse`).

mod control;
mod knobs;
pub mod paper;
mod parse;
pub use control::*;
pub(crate) use knobs::{controls, knobs};
use knobs::{declared, listed};
pub use parse::*;
use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::exposure::Exposure;

/// A value a parser refused: the message (`cli::parse` prints it as `--option VALUE: message`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Invalid(pub String);

impl fmt::Display for Invalid {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Invalid {}

pub fn invalid<T>(msg: impl Into<String>) -> Result<T, Invalid> {
    Err(Invalid(msg.into()))
}

/// How a pixel's F SP clusters combine their visibility.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Weighting {
    /// F = 1: the nearest cluster only.
    Hard,
    /// Eq. (8): the mean over the F nearest clusters.
    Uniform,
    /// Eq. (9) with Eq. (10): inverse-distance weights.
    #[default]
    InverseDistance,
}

impl Weighting {
    pub const ALL: [Weighting; 3] = [
        Weighting::Hard,
        Weighting::Uniform,
        Weighting::InverseDistance,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Weighting::Hard => "hard",
            Weighting::Uniform => "uniform",
            Weighting::InverseDistance => "inverse-distance",
        }
    }
}

/// How a VPL cluster's light reaches a shading point (`--cluster-light`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum ClusterLight {
    /// The paper (Eq. 6): the representative VPL as a point light with the members' summed flux.
    Point,
    /// Not in the paper: the other members' share of the flux no closer than their RMS distance.
    #[default]
    Spread,
}

impl fmt::Display for ClusterLight {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ClusterLight::Point => "point",
            ClusterLight::Spread => "spread",
        })
    }
}

/// A centroid's normal after Alg. 1's update (`--centroid-normal`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum CentroidNormal {
    /// Not in the paper: the members' mean normal scaled to unit length.
    #[default]
    Normalised,
    /// The paper (Alg. 1 line 18, value / counter): the members' plain mean normal.
    Mean,
}

impl fmt::Display for CentroidNormal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            CentroidNormal::Normalised => "normalised",
            CentroidNormal::Mean => "mean",
        })
    }
}

/// An on/off option's default as its text (`default_value = on_off(DEFAULT.field)`).
pub const fn on_off(b: bool) -> &'static str {
    if b { "on" } else { "off" }
}

/// The default for the most VPLs one light path leaves (its bounce count); Russian roulette usually
/// ends a path earlier.
pub const MAX_DEPTH: u32 = 8;

/// γ, the SP downsampling factor of Alg. 1's iterations: `auto` (the default) lets
/// `Gamma::resolve` choose it from the pixels and K, or a fixed factor of at least 1.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Gamma {
    #[default]
    Auto,
    Fixed(u32),
}

/// The auto rule's bounds on γ: 4 is the fixed default it replaced (kept wherever the rule has no
/// room), 16 the largest factor measured at equal error (docs/clustering.md, "γ by rule").
pub const AUTO_GAMMA_MIN: u32 = 4;
pub const AUTO_GAMMA_MAX: u32 = 16;
/// The auto rule keeps at least this many sampled points a cluster (Alg. 1's means need members)...
pub const AUTO_SAMPLES_PER_CLUSTER: u32 = 40;
/// ...and at least this many sampled points in all: a full 160×120 picture of the view, so that the
/// sampled set never resolves the image more coarsely than that (γ 20 at 160×120 lost thin surfaces'
/// clusters: docs/clustering.md).
pub const AUTO_MIN_SAMPLED: u32 = 19_200;

impl Gamma {
    /// The auto rule: the largest γ in [4, 16] that keeps `AUTO_SAMPLES_PER_CLUSTER` sampled points
    /// a cluster and `AUTO_MIN_SAMPLED` in all. 640×480: K 461 → 16, K 1000 → 7, K ≥ 1920 → 4;
    /// 1024×720: K 1000 → 16, K 8000 → 4; 160×120 and 320×240: 4 at any K.
    pub fn auto(num_points: u32, k: u32) -> u32 {
        let per_cluster = num_points / (AUTO_SAMPLES_PER_CLUSTER.saturating_mul(k.max(1)));
        let in_all = num_points / AUTO_MIN_SAMPLED;
        per_cluster
            .min(in_all)
            .clamp(AUTO_GAMMA_MIN, AUTO_GAMMA_MAX)
    }

    /// γ as asked: the fixed factor, or the auto rule's choice for `num_points` and `k`.
    pub fn resolve(self, num_points: u32, k: u32) -> u32 {
        match self {
            Gamma::Auto => Gamma::auto(num_points, k),
            Gamma::Fixed(g) => g,
        }
    }

    /// γ as Alg. 1 uses it (`resolve`): at least 1, and at most M / K, so that the sampled set holds
    /// at least K points (a γ near the point count would leave a single sampled point, often in the
    /// sky, and no cluster).
    pub fn effective(self, num_points: u32, k: u32) -> u32 {
        self.resolve(num_points, k)
            .clamp(1, (num_points / k.max(1)).max(1))
    }

    pub fn is_auto(self) -> bool {
        self == Gamma::Auto
    }
}

impl FromStr for Gamma {
    type Err = Invalid;
    fn from_str(v: &str) -> Result<Gamma, Invalid> {
        match v.trim() {
            "auto" => Ok(Gamma::Auto),
            t => match t.parse::<u32>() {
                Ok(g) if g >= 1 => Ok(Gamma::Fixed(g)),
                _ => invalid("γ is `auto` or a whole number of at least 1"),
            },
        }
    }
}

/// `auto` or the number (labels, file names, CSV).
impl fmt::Display for Gamma {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Gamma::Auto => f.write_str("auto"),
            Gamma::Fixed(g) => write!(f, "{g}"),
        }
    }
}

/// Serialised as the command line writes it: `"auto"` or the number.
impl Serialize for Gamma {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Gamma::Auto => s.serialize_str("auto"),
            Gamma::Fixed(g) => s.serialize_u32(*g),
        }
    }
}

impl<'de> Deserialize<'de> for Gamma {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Gamma, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            N(u32),
            S(String),
        }
        match Raw::deserialize(d)? {
            Raw::N(0) => Ok(Gamma::Auto),
            Raw::N(g) => Ok(Gamma::Fixed(g)),
            Raw::S(s) => s.parse().map_err(serde::de::Error::custom),
        }
    }
}

/// The most SP clusters a pixel keeps (F); the slot loops are compiled for F as an override.
pub const MAX_F: u32 = 16;

/// The largest n_t Eq. (7) can use: its test n1 · n2 > n_t is strict, so n_t = 1 would accept no
/// pair at all (not even a point and a centroid with the same normal), every cluster would empty in
/// the first iteration and no point would get one. n_t = 1 is read as the tightest threshold an f32
/// cosine resolves (about 0.08°).
pub const MAX_NORMAL_THRESHOLD: f32 = 1.0 - 1.0 / (1 << 20) as f32;

/// The plane gate's angle the viewer starts from when it is switched on (the held-out study in
/// docs/clustering.md measured 10°, 20° and 30°; 20° was best on average).
pub const DEFAULT_PLANE_GATE_DEG: f32 = 20.0;

/// The default G-term clamp as a fraction of the scene diagonal.
pub const DEFAULT_CLAMP: f32 = 0.02;

/// The most area-light samples a pixel (the default is 16): far beyond any useful count, while
/// without a bound --direct-samples 4294967295 blocked for hours.
pub const MAX_DIRECT_SAMPLES: u32 = 65536;

/// The most diffuse reflections a light path deposits VPLs at.
pub const MAX_BOUNCES: u32 = 64;

/// The largest image side.
pub const MAX_SIDE: u32 = 16384;

listed! {
/// The clustering of shading points and VPLs: the paper's knobs. The fields `bench` sweeps have
/// their lists in `ClusterLists` (`listed!`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
#[cfg_attr(feature = "cli", command(next_help_heading = "Clustering (the paper's knobs)"))]
#[serde(default)]
pub struct ClusterSettings {
    /// K of the shading-point clustering (0 = no SP clustering; off when ≥ the pixel count).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = ClusterSettings::DEFAULT.sp_clusters))]
    pub sp_clusters: u32 = 3072,
        ui "K (SP clusters)" Widget::or("off", Off::Zero, Widget::int_log(1, 16384), 3072.0)
        => list "SP cluster counts (default 768,1536,3072; quick 48,96)." ()
        default [768, 1536, 3072] quick [48, 96],
    /// K of the VPL clustering (0 = no VPL clustering; off when ≥ --vpls).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = ClusterSettings::DEFAULT.vpl_clusters))]
    pub vpl_clusters: u32 = 1024,
        ui "K_VPL" Widget::or("off", Off::Zero, Widget::int_log(1, 16384), 1024.0)
        => list "VPL cluster counts (default 1024; quick 128)." () quick [128],
    /// F: SP clusters per pixel (fuzziness), 1..16 (hard weighting uses 1).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = ClusterSettings::DEFAULT.fuzziness, value_parser = parse_fuzziness))]
    pub fuzziness: u32 = 6,
        ui "F (fuzziness)" Widget::int(1, 16), if |c| c.weighting != Weighting::Hard, paper_only = true
        => list "F values, 1..16 (default 6)." (value_parser = parse_fuzziness),
    /// γ: SP downsampling factor for the k-means iterations, or `auto`: the largest γ in 4..16 that
    /// keeps 40 sampled points a cluster and 19,200 in all. Either way at most pixels / K, so that at
    /// least K points are sampled.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = ClusterSettings::DEFAULT.gamma, value_parser = parse_gamma))]
    pub gamma: Gamma = Gamma::Auto,
        ui "γ (downsampling)" Widget::or("auto", Off::Name("auto"), Widget::int(1, 16), 4.0)
        => list "γ values: `auto` (the default: the largest γ in 4..16 that keeps 40 \
        sampled points a cluster and 19,200 in all) or factors of at least 1, e.g. auto,4,16."
        (value_parser = parse_gamma),
    /// n_t of Eq. (7): cosine of the largest normal angle within a cluster, in [-1, 1] (Eq. 7's test
    /// is strict, so 1 is read as 1 - 2^-20: the same normal only).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = ClusterSettings::DEFAULT.normal_threshold, value_parser = parse_normal_threshold))]
    pub normal_threshold: f32 = 0.866, ui "n_t" Widget::Cosine
        => list "n_t values of Eq. (7), cosines in [-1, 1] (default 0.866)."
        (value_parser = parse_normal_threshold, allow_hyphen_values = true),
    /// k-means iterations (Alg. 1), 0..=1000.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = ClusterSettings::DEFAULT.iterations, value_parser = parse_iterations))]
    pub iterations: u32 = 10, ui "k-means iterations" Widget::int(0, 50)
        => list "k-means iterations (default 10)." (value_parser = parse_iterations),
    /// How a pixel's F clusters combine visibility: hard (F = 1), uniform (Eq. 8), inverse-distance
    /// (Eq. 9).
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = ClusterSettings::DEFAULT.weighting))]
    pub weighting: Weighting = Weighting::InverseDistance,
        ui "weighting" Widget::Choice(&[("hard", "hard"), ("uniform", "fuzzy (uniform)"),
            ("inverse-distance", "weighted")]), paper_only = true,
    /// p of the inverse-distance weights, w'_f = dist^-p: 1 is Eq. (10); larger p falls off faster
    /// (the paper's §6 suggestion), 0 is Eq. (8)'s plain mean (but a point on a centroid still takes
    /// it alone), 64 is nearly hard clustering. [0, 64].
    #[cfg_attr(feature = "cli", arg(long, default_value_t = ClusterSettings::DEFAULT.weight_exponent, value_parser = parse_weight_exponent))]
    pub weight_exponent: f32 = 1.0,
        ui "p (weights = dist^-p; Eq. 10: 1)" Widget::linear(0.0, 8.0), if |c| c.weighting == Weighting::InverseDistance,
        paper_only = true
        => list "p values of the inverse-distance weights w'_f = dist^-p, for \
        weighted and sp-only (default 1, Eq. 10)." (value_parser = parse_weight_exponent),
    /// Not in the paper (off by default): the fuzzy modes' slots 2..F keep only SP clusters whose
    /// centroid lies within DEG degrees of the pixel's tangent plane, seen from the pixel. Eq. (7)
    /// gates on normals alone, so without it a floor pixel's F clusters include a chair seat above
    /// it (docs/clustering.md, "The plane gate"). (0, 90].
    #[cfg_attr(feature = "cli", arg(long = "plane-gate", value_name = "DEG", value_parser = parse_plane_gate))]
    #[serde(rename = "plane_gate_deg", skip_serializing_if = "Option::is_none")]
    pub plane_gate: Option<f32> = None,
        ui "plane gate (°)" Widget::or("off", Off::Null, Widget::linear(1.0, 90.0), DEFAULT_PLANE_GATE_DEG as f64),
        if |c| c.weighting != Weighting::Hard, paper_only = true
        => list "Plane gates of the fuzzy modes' F lists: `off` (the paper, \
        default) or angles in degrees, e.g. off,20 (see render --plane-gate)."
        (value_parser = parse_plane_gate_or_off),
    /// Eq. (10) weights from the distances to the SP clusters' representatives (the paper's text)
    /// instead of their centroids (Alg. 2).
    #[cfg_attr(feature = "cli", arg(long))]
    pub weights_to_reps: bool = false,
        ui "weights to representatives" Widget::Toggle, if |c| c.weighting == Weighting::InverseDistance, paper_only = true,
    /// Temporal reuse (on|off): each frame's SP clustering starts from the previous one's centroids
    /// where the view still sees them, the VPL clustering from its last centroids when the lights
    /// change (docs/temporal.md). A single `render` has no past: only --repeat's later renders reuse.
    #[cfg_attr(feature = "cli", arg(long, default_value = on_off(ClusterSettings::DEFAULT.temporal), value_name = "on|off", value_parser = parse_on_off, action = clap::ArgAction::Set))]
    pub temporal: bool = false, ui "temporal reuse" Widget::Toggle,
    /// With temporal reuse on: the weight of a new frame's indirect light once a surface point's
    /// history is long (it is the plain mean over the point's first frames). Each pixel's surface
    /// point is found in the previous frame and the indirect light blended there, an exponential
    /// moving average over about 1/α frames (docs/temporal.md, "Accumulation"). 1: no
    /// accumulation. (0, 1].
    #[cfg_attr(feature = "cli", arg(long, default_value_t = ClusterSettings::DEFAULT.temporal_alpha, value_name = "ALPHA", value_parser = parse_temporal_alpha))]
    pub temporal_alpha: f32 = 0.7,
        ui "α (indirect history)" Widget::linear(0.05, 1.0), if |c| c.temporal,
    /// Not in the paper (off by default): step 5 traces only representative pairs that face each
    /// other (both cosines positive) and leaves the others' V at 0. The paper's V is pure
    /// visibility; Eq. (6) applies each pixel's own cosines (docs/clustering.md, "V and the facing
    /// test").
    #[cfg_attr(feature = "cli", arg(long, default_value = on_off(ClusterSettings::DEFAULT.visibility_facing), value_name = "on|off", value_parser = parse_on_off, action = clap::ArgAction::Set))]
    pub visibility_facing: bool = false, ui "facing test" Widget::Toggle, paper_only = true,
    /// How a VPL cluster lights a point: `point` (the paper's Eq. 6: its representative VPL with
    /// the members' summed flux) or `spread` (not in the paper, the default: the other members'
    /// share of the flux is evaluated no closer than their RMS distance from the representative;
    /// docs/clustering.md, "VPL clusters as lights").
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = ClusterSettings::DEFAULT.cluster_light))]
    pub cluster_light: ClusterLight = ClusterLight::Spread,
        ui "cluster lights" Widget::Choice(&[("point", "point (paper)"), ("spread", "spread")])
        => list "VPL-cluster lights: point (the paper), spread (default), \
        e.g. point,spread." (value_enum),
    /// Not in the paper (on by default): Alg. 1 re-seeds an empty cluster at a sampled point no
    /// centroid within reach accepts (an orphan), or else at a drawn sampled point
    /// (docs/clustering.md, "Surfaces without a cluster"). off: an empty cluster stays empty.
    #[cfg_attr(feature = "cli", arg(long, default_value = on_off(ClusterSettings::DEFAULT.reseed), value_name = "on|off", value_parser = parse_on_off, action = clap::ArgAction::Set))]
    pub reseed: bool = true, ui "re-seed" Widget::Toggle, paper_only = true
        => list "Re-seeding of empty clusters: on (default), off (the paper)."
        (value_parser = parse_on_off),
    /// Not in the paper (on by default): a point with no centroid passing n_t in the 27 cells
    /// around it searches rings of cells further out (3 while iterating, 4 in the final
    /// assignment). off: the 27 cells only, as Alg. 1 and 2 (docs/clustering.md, "Fallbacks").
    #[cfg_attr(feature = "cli", arg(long, default_value = on_off(ClusterSettings::DEFAULT.ring_fallback), value_name = "on|off", value_parser = parse_on_off, action = clap::ArgAction::Set))]
    pub ring_fallback: bool = true, ui "rings" Widget::Toggle, paper_only = true
        => list "Ring fallback of the search: on (default), off (the paper)."
        (value_parser = parse_on_off),
    /// Not in the paper (on by default): a point the final assignment finds no centroid passing
    /// n_t for takes the nearest centroid by position alone. off: it stays without a cluster (to
    /// Eq. 7 it is at distance ∞ from every centroid) and gets no indirect light from SP clusters.
    #[cfg_attr(feature = "cli", arg(long, default_value = on_off(ClusterSettings::DEFAULT.position_fallback), value_name = "on|off", value_parser = parse_on_off, action = clap::ArgAction::Set))]
    pub position_fallback: bool = true,
        ui "by position" Widget::Toggle, paper_only = true
        => list "Position-only fallback of the final assignment: on \
        (default), off (the paper)." (value_parser = parse_on_off),
    /// A centroid's normal (Alg. 1 line 18): `normalised` (the default: the members' mean normal
    /// scaled to unit length) or `mean` (the paper's value / counter: the plain mean, shorter than 1
    /// where the members' normals differ, which Eq. 7's test n · n_c > n_t then reads as is).
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = ClusterSettings::DEFAULT.centroid_normal))]
    pub centroid_normal: CentroidNormal = CentroidNormal::Normalised,
        ui "centroid normals" Widget::Choice(&[("normalised", "unit"), ("mean", "mean (paper)")]),
        paper_only = true
        => list "Centroid normals: normalised (default), mean (the \
        paper)." (value_enum),
    /// Every setting at the paper's choice (docs/clustering.md, "The paper exactly"): point cluster
    /// lights, no re-seeding, no fallbacks, mean centroid normals, n_t = √3/2, F 6, inverse-distance
    /// weights (Eq. 10, p 1, to the centroids), K_SP and K_VPL in the ratios of the paper's
    /// intermediate setting (8k of 1024×720 pixels, 2k of 8000 VPLs), no G-term clamp, no plane
    /// gate, facing test or temporal reuse. An option given on the command line wins over it.
    #[cfg_attr(feature = "cli", arg(long))]
    pub paper: bool = false,
    /// A GPU-time budget for the frame in ms (> 0): K_SP and K_VPL are chosen to meet it (`render`:
    /// a few frames adjusting them, K_SP following K_VPL on a line through the paper's intermediate
    /// setting; `view`: adjusted while
    /// the view changes). --sp-clusters and --vpl-clusters then only say which clusterings run.
    #[cfg_attr(feature = "cli", arg(long, value_name = "MS", value_parser = parse_target_ms))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_ms: Option<f64> = None,
        ui "time budget (ms)" Widget::or("off", Off::Null, Widget::log(1.0, 100000.0), 500.0),
}
/// `bench`'s lists of the `ClusterSettings` it sweeps: a configuration takes one value of each
/// (`resolve` fills the empty ones, `configs` multiplies them out).
pub struct ClusterLists, heading "Sweep (comma-separated lists)";
}

impl ClusterSettings {
    /// F in effect: 1 for hard clustering.
    pub fn f(&self) -> u32 {
        if self.weighting == Weighting::Hard {
            1
        } else {
            self.fuzziness
        }
    }

    /// The k-means adaptations these settings switch on (`--reseed`, `--ring-fallback`,
    /// `--position-fallback`, `--centroid-normal`).
    pub fn adaptations(&self) -> Adaptations {
        Adaptations {
            reseed: self.reseed,
            ring_fallback: self.ring_fallback,
            position_fallback: self.position_fallback,
            normalised_normal: self.centroid_normal == CentroidNormal::Normalised,
        }
    }

    /// n_t as Eq. (7) uses it: at most `MAX_NORMAL_THRESHOLD`.
    pub fn normal_threshold_used(&self) -> f32 {
        self.normal_threshold.min(MAX_NORMAL_THRESHOLD)
    }
}

/// The k-means's departures from Alg. 1 and 2, each on by default (docs/clustering.md, "The
/// paper exactly"); the shaders take them as pipeline constants (kmeans.wgsl `RESEED`,
/// `RING_FALLBACK`, `POSITION_FALLBACK`, `NORMALISED_NORMAL`), the CPU twin from `KmParams::adapt`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Adaptations {
    pub reseed: bool,
    pub ring_fallback: bool,
    pub position_fallback: bool,
    pub normalised_normal: bool,
}

impl Default for Adaptations {
    fn default() -> Self {
        Adaptations::from_bits(Adaptations::ALL)
    }
}

impl Adaptations {
    /// Every adaptation on (the default).
    pub const ALL: u32 = 0b1111;

    /// As bits: 1 re-seeding, 2 ring fallback, 4 position fallback, 8 normalised normal.
    pub fn bits(self) -> u32 {
        self.reseed as u32
            | (self.ring_fallback as u32) << 1
            | (self.position_fallback as u32) << 2
            | (self.normalised_normal as u32) << 3
    }

    pub fn from_bits(b: u32) -> Adaptations {
        Adaptations {
            reseed: b & 1 != 0,
            ring_fallback: b & 2 != 0,
            position_fallback: b & 4 != 0,
            normalised_normal: b & 8 != 0,
        }
    }

    /// None of them: Alg. 1 and 2 as the paper writes them.
    pub fn none() -> Adaptations {
        Adaptations::from_bits(0)
    }

    /// The shader's pipeline constants.
    pub fn constants(self) -> [(&'static str, f64); 4] {
        [
            ("RESEED", self.reseed as u32 as f64),
            ("RING_FALLBACK", self.ring_fallback as u32 as f64),
            ("POSITION_FALLBACK", self.position_fallback as u32 as f64),
            ("NORMALISED_NORMAL", self.normalised_normal as u32 as f64),
        ]
    }
}

/// The plane gate as the shader tests it: slot j ≥ 2 is kept when |n · (c − p)| ≤ s |c − p|, s =
/// sin θ; 2 (above any ratio) when off. Eq. (7) gates on normals alone, so a pixel's F nearest
/// clusters include parallel surfaces above or below it (a chair seat over the floor) whose
/// visibility differs; this drops them (docs/clustering.md, "The plane gate").
pub fn plane_gate_sine(deg: Option<f32>) -> f32 {
    deg.map_or(2.0, |d| d.clamp(0.0, 90.0).to_radians().sin())
}

declared! {
/// What a frame is: its size, random seed, VPLs, bounce budget, direct-light samples, exposure and
/// G-term clamp.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
#[cfg_attr(feature = "cli", command(next_help_heading = "Frame"))]
#[serde(default)]
pub struct FrameSettings {
    /// Image width, 1..16384.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = FrameSettings::DEFAULT.width, value_parser = parse_side))]
    pub width: u32 = 640,
    /// Image height, 1..16384.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = FrameSettings::DEFAULT.height, value_parser = parse_side))]
    pub height: u32 = 480,
    #[cfg_attr(feature = "cli", arg(long, default_value_t = FrameSettings::DEFAULT.seed))]
    pub seed: u32 = 1,
    /// Number of VPLs (traced once, resident).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = FrameSettings::DEFAULT.vpls))]
    pub vpls: u32 = 8192, ui "VPLs" Widget::int_log(0, 65536),
    /// Indirect bounce budget: the most VPLs a light path deposits (the path tracer gets the same),
    /// 1..64.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = FrameSettings::DEFAULT.bounces, value_parser = parse_bounces))]
    pub bounces: u32 = MAX_DEPTH,
    /// Area-light samples (shadow rays) per pixel for direct light, 1..=65536.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = FrameSettings::DEFAULT.direct_samples, value_parser = parse_direct_samples))]
    pub direct_samples: u32 = 16,
    /// Exposure of PNG images and the viewer: `auto` (the default: the image's log-average
    /// luminance is shown as middle grey 0.18, Reinhard et al. 2002) or a factor >= 0. EXR stays
    /// linear, unscaled radiance.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = FrameSettings::DEFAULT.exposure, value_parser = parse_exposure))]
    pub exposure: Exposure = Exposure::Auto,
    /// G-term clamp: the VPL distance in 1/d² is at least CLAMP × scene diagonal (scale-free),
    /// [0, 1).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = FrameSettings::DEFAULT.clamp, value_parser = parse_clamp))]
    pub clamp: f32 = DEFAULT_CLAMP, ui "G-term clamp" Widget::log(0.0, 0.2),
    /// The indirect light's resolution as a fraction of the image's, (0, 1]: below 1 the
    /// primary rays and the direct light stay at the image's size and the indirect light is
    /// computed on a G-buffer of this scale, then upsampled with depth- and normal-aware weights
    /// (`gi::upsample`). The unclustered reference ignores it. In `view` it is the
    /// render scale (`--render-scale`, the same setting; give one).
    /// Written to the stats only when not 1.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = FrameSettings::DEFAULT.indirect_scale, value_parser = parse_indirect_scale))]
    #[serde(skip_serializing_if = "is_one")]
    pub indirect_scale: f32 = 1.0,
}
}

fn is_one(x: &f32) -> bool {
    *x == 1.0
}

impl FrameSettings {
    pub fn pixels(&self) -> u32 {
        self.width * self.height
    }

    /// The G-term clamp's distance in a scene `extent` across (its diagonal): the VPL distance
    /// in 1/d² is at least this (`--clamp` × extent).
    pub fn d_min(&self, extent: f32) -> f32 {
        self.clamp * extent
    }
}

/// Lights added to a scene (for scenes that ship without any) and the scale of its emitters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
#[cfg_attr(feature = "cli", command(next_help_heading = "Added lights"))]
pub struct LightSettings {
    /// Add a directional light: DX,DY,DZ,E\[,R,G,B\] (direction towards the sun).
    #[cfg_attr(
        feature = "cli",
        arg(
            long,
            value_name = "DX,DY,DZ,E[,R,G,B]",
            allow_hyphen_values = true,
            help = "Add a directional light: DX,DY,DZ,E[,R,G,B] (direction towards the sun)"
        )
    )]
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sun: Vec<String>,
    /// Add a point light: X,Y,Z,I\[,R,G,B\].
    #[cfg_attr(
        feature = "cli",
        arg(
            long,
            value_name = "X,Y,Z,I[,R,G,B]",
            allow_hyphen_values = true,
            help = "Add a point light: X,Y,Z,I[,R,G,B]"
        )
    )]
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub point: Vec<String>,
    /// Multiply every emitter's power by this factor (>= 0).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = LightSettings::DEFAULT.light_scale, value_parser = parse_light_scale))]
    pub light_scale: f32,
}

impl LightSettings {
    /// The defaults, declared once (the options' and `Default`): no added light, scale 1.
    pub const DEFAULT: LightSettings = LightSettings {
        sun: Vec::new(),
        point: Vec::new(),
        light_scale: 1.0,
    };
}

impl Default for LightSettings {
    fn default() -> Self {
        LightSettings::DEFAULT
    }
}

/// The default warm-up before timing, in ms of GPU work (`TimingSettings::warmup_ms`).
pub const WARMUP_MS: f64 = 200.0;

declared! {
/// How GPU times are taken (`render`, `bench`, `bench --camera-path`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
#[cfg_attr(feature = "cli", command(next_help_heading = "Timing"))]
#[serde(default)]
pub struct TimingSettings {
    /// Milliseconds of GPU work before the timed renders (a busy kernel, crates/core/src/gpu/warmup.rs), so
    /// the GPU runs at its working clock; before each camera-path frame too. 0: none.
    #[cfg_attr(feature = "cli", arg(long, value_name = "MS", default_value_t = TimingSettings::DEFAULT.warmup_ms, value_parser = parse_warmup_ms))]
    pub warmup_ms: f64 = WARMUP_MS,
}
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The defaults of a group of options as clap gives them.
    #[cfg(feature = "cli")]
    fn clap_defaults<T: clap::Args + clap::FromArgMatches>() -> T {
        let cmd = T::augment_args(clap::Command::new("defaults"));
        let m = cmd
            .try_get_matches_from(["defaults"])
            .expect("every option of a settings group has a default or is optional");
        T::from_arg_matches(&m).expect("the defaults are valid values")
    }

    /// The options' defaults are the types' `DEFAULT` (declared once; the options name it), also
    /// for the on/off options and flags, whose defaults clap takes as text or as absent.
    #[cfg(feature = "cli")]
    #[test]
    fn the_options_defaults_are_the_declared_defaults() {
        assert_eq!(clap_defaults::<ClusterSettings>(), ClusterSettings::DEFAULT);
        assert_eq!(clap_defaults::<FrameSettings>(), FrameSettings::DEFAULT);
        assert_eq!(clap_defaults::<LightSettings>(), LightSettings::DEFAULT);
        assert_eq!(clap_defaults::<TimingSettings>(), TimingSettings::DEFAULT);
        let m = clap_defaults::<crate::method::MethodSettings>();
        assert_eq!(m, crate::method::MethodSettings::default());
    }

    /// n_t = 1 is read as the tightest threshold Eq. (7)'s strict test can pass: equal normals
    /// (cosine 1 in f32) pass it, and the threshold is 2⁻²⁰ below 1; other values are kept
    /// (cargo-mutants: the bound as 1 + 2⁻²⁰, which no pair passes, survived).
    #[test]
    fn normal_threshold_one_still_admits_equal_normals() {
        let at = |n_t: f32| ClusterSettings {
            normal_threshold: n_t,
            ..Default::default()
        };
        let used = at(1.0).normal_threshold_used();
        assert_eq!(used, 1.0 - 1.0 / (1 << 20) as f32);
        let n = glam::Vec3::new(0.3, -0.5, 0.8).normalize();
        assert!(n.dot(n) > used, "{} against {used}", n.dot(n));
        assert_eq!(at(0.5).normal_threshold_used(), 0.5);
    }

    #[test]
    fn gamma_reads_writes_and_resolves() {
        assert_eq!("auto".parse::<Gamma>(), Ok(Gamma::Auto));
        assert_eq!("8".parse::<Gamma>(), Ok(Gamma::Fixed(8)));
        assert!("0".parse::<Gamma>().is_err());
        assert!("x".parse::<Gamma>().is_err());
        assert_eq!(Gamma::Auto.to_string(), "auto");
        assert_eq!(Gamma::Fixed(3).to_string(), "3");
        assert_eq!(serde_json::to_string(&Gamma::Auto).unwrap(), "\"auto\"");
        assert_eq!(serde_json::to_string(&Gamma::Fixed(5)).unwrap(), "5");
        let back: Gamma = serde_json::from_str("5").unwrap();
        assert_eq!(back, Gamma::Fixed(5));
        // The rule's worked cases (docs/clustering.md): 640×480 at K 461 → 16, K 1000 → 7, K ≥ 1920
        // → 4; never above pixels / K.
        assert_eq!(Gamma::Fixed(9).effective(100, 50), 2);
        assert_eq!(Gamma::Fixed(9).resolve(640 * 480, 461), 9);
        for bad in ["0", "-1", "4.5", "", "Auto2"] {
            assert!(bad.parse::<Gamma>().is_err(), "{bad:?}");
        }
    }

    #[test]
    fn auto_gamma_keeps_samples_per_cluster_and_in_all() {
        // (pixels, K, γ): the paper's settings at 640×480 and 1024×720, the held-out 160×120.
        for (m, k, g) in [
            (640 * 480, 461, 16),
            (640 * 480, 1000, 7),
            (640 * 480, 1920, 4),
            (640 * 480, 3072, 4),
            (640 * 480, 12288, 4),
            (1024 * 720, 1000, 16),
            (1024 * 720, 2000, 9),
            (1024 * 720, 8000, 4),
            (160 * 120, 29, 4),
            (160 * 120, 192, 4),
            (320 * 240, 115, 4),
            (1280 * 960, 100, 16),
            (0, 0, 4),
        ] {
            assert_eq!(Gamma::auto(m, k), g, "{m} points, K {k}");
            let ran = Gamma::Auto.effective(m, k);
            let s = m.div_ceil(ran);
            // Above the floor of 4, the rule's two bounds hold for the points it samples.
            if ran > AUTO_GAMMA_MIN {
                assert!(s >= AUTO_MIN_SAMPLED, "{m}, {k}: {s} sampled");
                assert!(s >= AUTO_SAMPLES_PER_CLUSTER * k, "{m}, {k}: {s} sampled");
            }
        }
        // The cap of every γ (at most M / K) still applies to the rule's choice.
        assert_eq!(Gamma::Auto.effective(1000, 500), 2);
        // A γ asked is kept as it is.
        assert_eq!(Gamma::Fixed(4).effective(640 * 480, 461), 4);
        assert_eq!(Gamma::Auto.resolve(640 * 480, 461), 16);
    }

    #[test]
    fn parsers_refuse_out_of_range() {
        assert!(parse_fuzziness("0").is_err() && parse_fuzziness("17").is_err());
        assert_eq!(parse_fuzziness("16"), Ok(16));
        assert!(parse_normal_threshold("NaN").is_err());
        assert!(parse_normal_threshold("1.01").is_err());
        assert_eq!(parse_normal_threshold("-1"), Ok(-1.0));
        assert!(parse_clamp("1").is_err() && parse_clamp("-0.5").is_err());
        assert!(parse_plane_gate("0").is_err() && parse_plane_gate("91").is_err());
        assert!(parse_plane_gate("NaN").is_err());
        assert!(parse_weight_exponent("65").is_err());
        assert!(parse_direct_samples("0").is_err() && parse_direct_samples("65537").is_err());
        assert!(parse_side("0").is_err() && parse_side("16385").is_err());
        assert!(parse_light_scale("inf").is_err() && parse_light_scale("-1").is_err());
        for bad in ["0", "-0.5", "1.01", "NaN", "inf", "x"] {
            assert!(parse_indirect_scale(bad).is_err(), "{bad}");
        }
        assert_eq!(parse_indirect_scale("0.5"), Ok(0.5));
        assert_eq!(parse_indirect_scale("1"), Ok(1.0));
        assert_eq!(parse_on_off("on"), Ok(true));
        assert!(parse_on_off("yes").is_err());
    }

    /// Every parser at the edges of its range: the last value in and the first out on each side
    /// (cargo-mutants: `<=` turned `<` in a range check survived the tests of the out side only).
    #[test]
    fn parsers_accept_their_edges() {
        assert_eq!(parse_fuzziness("1"), Ok(1));
        assert_eq!(parse_normal_threshold("1"), Ok(1.0));
        assert!(parse_normal_threshold("-1.01").is_err());
        assert_eq!(parse_iterations("0"), Ok(0));
        assert_eq!(parse_iterations("1000"), Ok(1000));
        assert!(parse_iterations("1001").is_err());
        assert_eq!(parse_weight_exponent("0"), Ok(0.0));
        assert_eq!(parse_weight_exponent("64"), Ok(64.0));
        assert!(parse_weight_exponent("-0.01").is_err());
        assert_eq!(parse_plane_gate("90"), Ok(90.0));
        assert_eq!(parse_plane_gate("0.01"), Ok(0.01));
        assert_eq!(parse_target_ms("1e7"), Ok(1e7));
        assert_eq!(parse_target_ms("0.001"), Ok(0.001));
        assert!(parse_target_ms("0").is_err() && parse_target_ms("1.0001e7").is_err());
        assert!(parse_target_ms("inf").is_err() && parse_target_ms("NaN").is_err());
        assert_eq!(parse_on_off(" off "), Ok(false));
        assert_eq!(parse_side("1"), Ok(1));
        assert_eq!(parse_side("16384"), Ok(16384));
        assert_eq!(parse_bounces("1"), Ok(1));
        assert_eq!(parse_bounces("64"), Ok(64));
        assert!(parse_bounces("0").is_err() && parse_bounces("65").is_err());
        assert_eq!(parse_direct_samples("1"), Ok(1));
        assert_eq!(parse_direct_samples("65536"), Ok(65536));
        assert_eq!(parse_clamp("0"), Ok(0.0));
        assert_eq!(parse_clamp("0.99"), Ok(0.99));
        assert_eq!(parse_light_scale("0"), Ok(0.0));
        assert_eq!(parse_light_scale("1e30"), Ok(1e30));
        assert_eq!(parse_exposure("0"), Ok(Exposure::Fixed(0.0)));
        assert_eq!(parse_gamma("1"), Ok(Gamma::Fixed(1)));
        assert!(parse_gamma("0").is_err() && parse_gamma("-1").is_err());
        assert_eq!(parse_warmup_ms("0"), Ok(0.0));
        assert_eq!(parse_warmup_ms("60000"), Ok(60000.0));
        assert!(parse_warmup_ms("-1").is_err() && parse_warmup_ms("60001").is_err());
    }

    /// `Default` is the options' defaults (docs/design.md's CLI table), declared once.
    #[test]
    fn defaults_are_the_options_defaults() {
        let c = ClusterSettings::default();
        let want = (
            3072,
            1024,
            6,
            Gamma::Auto,
            10,
            Weighting::InverseDistance,
            None,
        );
        let got = (
            c.sp_clusters,
            c.vpl_clusters,
            c.fuzziness,
            c.gamma,
            c.iterations,
        );
        assert_eq!(
            (got.0, got.1, got.2, got.3, got.4, c.weighting, c.target_ms),
            want
        );
        assert_eq!((c.normal_threshold, c.weight_exponent), (0.866, 1.0));
        let f = FrameSettings::default();
        assert_eq!(
            (f.width, f.height, f.seed, f.vpls, f.bounces),
            (640, 480, 1, 8192, MAX_DEPTH)
        );
        assert_eq!(
            (f.direct_samples, f.exposure, f.clamp),
            (16, Exposure::Auto, DEFAULT_CLAMP)
        );
        assert_eq!(TimingSettings::default().warmup_ms, WARMUP_MS);
    }

    /// The paper's V is pure visibility: the facing test is an option, off unless asked.
    #[cfg(feature = "cli")]
    #[test]
    fn visibility_is_pure_by_default() {
        use clap::Parser;
        #[derive(Parser)]
        struct Cli {
            #[command(flatten)]
            c: ClusterSettings,
        }
        assert!(!ClusterSettings::default().visibility_facing);
        assert!(!Cli::parse_from(["x"]).c.visibility_facing);
        assert!(
            Cli::parse_from(["x", "--visibility-facing", "on"])
                .c
                .visibility_facing
        );
    }

    #[cfg(feature = "cli")]
    #[test]
    fn settings_round_trip_through_json() {
        let c = ClusterSettings {
            gamma: Gamma::Fixed(7),
            plane_gate: Some(20.0),
            weighting: Weighting::Uniform,
            ..Default::default()
        };
        let j = serde_json::to_string(&c).unwrap();
        assert!(j.contains("\"plane_gate_deg\":20.0"), "{j}");
        assert_eq!(serde_json::from_str::<ClusterSettings>(&j).unwrap(), c);
        let f = FrameSettings::default();
        let j = serde_json::to_string(&f).unwrap();
        assert_eq!(serde_json::from_str::<FrameSettings>(&j).unwrap(), f);
        // At 1 (the default) the stats stay as they were; below 1 the scale is written.
        assert!(!j.contains("indirect_scale"), "{j}");
        let half = FrameSettings {
            indirect_scale: 0.5,
            ..f
        };
        let j = serde_json::to_string(&half).unwrap();
        assert!(j.contains("\"indirect_scale\":0.5"), "{j}");
        assert_eq!(serde_json::from_str::<FrameSettings>(&j).unwrap(), half);
    }

    /// Every control the settings declare reads its field and takes back each value its widget
    /// can give: its value as read, each choice, the word of an `Or`, and the slider's ends.
    #[test]
    fn every_declared_control_takes_what_its_widget_gives() {
        fn check<T: Clone + PartialEq + fmt::Debug>(
            s: &T,
            controls: &[KnobWidget],
            get: impl Fn(&T, &str) -> Option<serde_json::Value>,
            set: impl Fn(&mut T, &str, serde_json::Value) -> bool,
        ) {
            for c in controls {
                let v = get(s, c.name).unwrap_or_else(|| panic!("{}: no value", c.name));
                let mut t = s.clone();
                assert!(set(&mut t, c.name, v.clone()), "{}: {v}", c.name);
                assert_eq!(&t, s, "{}: its own value changes nothing", c.name);
                let mut gives = vec![];
                match c.widget {
                    Widget::Choice(values) => gives.extend(values.iter().map(|v| v.0.into())),
                    Widget::Toggle => gives.extend([true.into(), false.into()]),
                    Widget::Slider(r) => gives.extend(r.ends()),
                    Widget::Or { off, slider, .. } => {
                        gives.push(off.value());
                        gives.extend(slider.ends())
                    }
                    Widget::Cosine => gives.extend([1.0.into(), (-1.0).into(), 0.5.into()]),
                }
                for g in gives {
                    let mut t = s.clone();
                    assert!(set(&mut t, c.name, g.clone()), "{}: {g}", c.name);
                    assert_eq!(
                        get(&t, c.name).as_ref().map(|v| v.is_null()),
                        Some(g.is_null())
                    );
                }
            }
        }
        let c = ClusterSettings::default();
        assert!(ClusterSettings::CONTROLS.len() >= 19);
        check(
            &c,
            ClusterSettings::CONTROLS,
            |s, n| s.control(n),
            |s, n, v| s.set_control(n, v),
        );
        let f = FrameSettings::default();
        check(
            &f,
            FrameSettings::CONTROLS,
            |s, n| s.control(n),
            |s, n, v| s.set_control(n, v),
        );
        // The γ control's word is `auto`, a number a fixed γ.
        let mut g = c.clone();
        assert!(g.set_control("gamma", 8.into()));
        assert_eq!(g.gamma, Gamma::Fixed(8));
        assert!(g.set_control("gamma", "auto".into()));
        assert_eq!(g.gamma, Gamma::Auto);
        // F applies with fuzzy weightings only.
        g.weighting = Weighting::Hard;
        assert!(!g.control_enabled("fuzziness") && g.control_enabled("sp_clusters"));
    }
}
