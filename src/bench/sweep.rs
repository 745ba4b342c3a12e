//! The sweep of `fuzzy-vpl bench`: option lists, modes, and the configurations they expand to.

use std::fmt;
use std::str::FromStr;

use crate::method::{Method, MethodLists, MethodSettings};
use crate::settings::{ClusterLists, ClusterSettings, Gamma, Invalid, Weighting};

/// One configuration of a sweep: the paper's knobs (`Deref`, so `c.sp_clusters` reads them) and
/// the method with its knobs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Config {
    pub cluster: ClusterSettings,
    pub method: MethodSettings,
}

impl std::ops::Deref for Config {
    type Target = ClusterSettings;
    fn deref(&self) -> &ClusterSettings {
        &self.cluster
    }
}

impl From<ClusterSettings> for Config {
    /// The default method (whose knobs are the paper's `ClusterSettings`) with `cluster`.
    fn from(cluster: ClusterSettings) -> Config {
        Config {
            cluster,
            method: MethodSettings::default(),
        }
    }
}

/// What is clustered, and how a pixel combines its SP clusters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Mode {
    /// Both clusterings, F = 1 (the nearest SP cluster only).
    Hard,
    /// Both clusterings, Eq. (8): the mean over the F nearest SP clusters.
    Uniform,
    /// Both clusterings, Eq. (9): inverse-distance weights over the F nearest SP clusters.
    Weighted,
    /// VPL clustering only: every pixel gathers every VPL cluster with its own shadow ray.
    VplOnly,
    /// SP clustering only (inverse-distance weights): cluster representatives see every VPL.
    SpOnly,
}

impl Mode {
    pub const ALL: [Mode; 5] = [
        Mode::Hard,
        Mode::Uniform,
        Mode::Weighted,
        Mode::VplOnly,
        Mode::SpOnly,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Mode::Hard => "hard",
            Mode::Uniform => "uniform",
            Mode::Weighted => "weighted",
            Mode::VplOnly => "vpl-only",
            Mode::SpOnly => "sp-only",
        }
    }

    pub fn weighting(self) -> Weighting {
        match self {
            Mode::Hard => Weighting::Hard,
            Mode::Uniform => Weighting::Uniform,
            Mode::Weighted | Mode::SpOnly => Weighting::InverseDistance,
            // No SP clusters: the weighting is not used.
            Mode::VplOnly => Weighting::Hard,
        }
    }

    pub fn clusters_sps(self) -> bool {
        self != Mode::VplOnly
    }

    pub fn clusters_vpls(self) -> bool {
        self != Mode::SpOnly
    }

    /// Whether the mode weights its F clusters by distance (Eq. 9 / 10, exponent p).
    pub fn uses_weights(self) -> bool {
        matches!(self, Mode::Weighted | Mode::SpOnly)
    }

    /// Whether F (and so the fuzzy weights) matters.
    pub fn uses_fuzziness(self) -> bool {
        matches!(self, Mode::Uniform | Mode::Weighted | Mode::SpOnly)
    }

    /// `c` in this mode: its weighting, and what the mode ignores at its neutral value (no SP K
    /// and γ auto without SP clustering, no VPL K without VPL clustering, F = 1 and no plane gate
    /// without fuzzy weights, p = 1 without inverse-distance weights, no reuse).
    pub fn applied(self, c: ClusterSettings) -> ClusterSettings {
        let fuzzy = self.uses_fuzziness();
        ClusterSettings {
            sp_clusters: if self.clusters_sps() {
                c.sp_clusters
            } else {
                0
            },
            vpl_clusters: if self.clusters_vpls() {
                c.vpl_clusters
            } else {
                0
            },
            fuzziness: if fuzzy { c.fuzziness } else { 1 },
            gamma: if self.clusters_sps() {
                c.gamma
            } else {
                Gamma::Auto
            },
            weighting: self.weighting(),
            weight_exponent: if self.uses_weights() {
                c.weight_exponent
            } else {
                1.0
            },
            plane_gate: if fuzzy { c.plane_gate } else { None },
            weights_to_reps: false,
            temporal: false,
            ..c
        }
    }
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Mode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim().to_ascii_lowercase();
        match t.as_str() {
            "inverse-distance" => return Ok(Mode::Weighted),
            "vpl" | "vpls-only" => return Ok(Mode::VplOnly),
            "sp" | "sps-only" => return Ok(Mode::SpOnly),
            _ => {}
        }
        Mode::ALL
            .into_iter()
            .find(|m| m.name() == t)
            .ok_or_else(|| {
                format!(
                    "unknown mode {s:?} (expected one of: {})",
                    Mode::ALL.map(|m| m.name()).join(", ")
                )
            })
    }
}

/// A `--pairs` item: K_SP/K_VPL.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pair(pub u32, pub u32);

pub fn parse_pair(item: &str) -> Result<Pair, Invalid> {
    let bad = || Invalid("not K_SP/K_VPL".into());
    let (a, b) = item.trim().split_once('/').ok_or_else(bad)?;
    let n = |v: &str| v.trim().parse::<u32>().map_err(|_| bad());
    Ok(Pair(n(a)?, n(b)?))
}

pub fn parse_mode(item: &str) -> Result<Mode, Invalid> {
    item.parse().map_err(Invalid)
}

/// The lists a sweep multiplies out: the modes, every swept `ClusterSettings` field as a
/// comma-separated list (`ClusterLists`, declared with the field: an empty list takes the
/// default; `--quick` has its own defaults for the K's, and for the modes), the K pairs, the time
/// budgets and the methods with their knobs' lists.
#[derive(clap::Args, Clone, Debug, Default, PartialEq)]
#[command(next_help_heading = "Sweep (comma-separated lists)")]
pub struct Sweep {
    /// Modes to compare: hard,uniform,weighted,vpl-only,sp-only (default hard,uniform,weighted;
    /// quick: all five).
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = parse_mode)]
    pub modes: Vec<Mode>,
    /// The swept fields of `ClusterSettings`, each a list.
    #[command(flatten)]
    pub cluster: ClusterLists,
    /// K_SP/K_VPL pairs to measure instead of every --sp-clusters × --vpl-clusters, e.g. the paper's
    /// light, intermediate and high settings at 640x480: 461/750,3072/2000,12288/4000.
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = parse_pair)]
    pub pairs: Vec<Pair>,
    /// GPU-time budgets in ms: after the sweep, each mode's K's are chosen for each budget (as
    /// `render --target-ms`) and its error compared with the sweep's best fixed setting at no more
    /// time (the `front_mse` column).
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = crate::settings::parse_target_ms)]
    pub target_ms: Vec<f64>,
    /// `--paper` (on), or a list of off / on: the configurations with it start from the paper's
    /// settings (`render --paper`: point cluster lights, no re-seeding or fallbacks, mean
    /// centroid normals, n_t = √3/2; every method's frame without a G-term clamp unless --clamp is
    /// given, against a reference without it too); with no K lists, every configuration takes the
    /// paper's K ratios for the frame. The lists given still sweep over them (`--paper --cluster-light
    /// point,spread`); `--paper off,on` puts the defaults and the paper side by side (label word
    /// `paper`).
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = crate::settings::parse_on_off,
          num_args = 0..=1, default_missing_value = "on")]
    pub paper: Vec<bool>,
    /// The methods (`--methods`, default the paper's) and each one's knob lists (docs/methods.md),
    /// after the other lists: their headings follow.
    #[command(flatten)]
    pub method: MethodLists,
}

/// `v` without repeats, in order; `default` when empty.
fn or_default<T: PartialEq + Clone>(v: &[T], default: &[T]) -> Vec<T> {
    let src = if v.is_empty() { default } else { v };
    let mut out: Vec<T> = Vec::new();
    for x in src {
        if !out.contains(x) {
            out.push(x.clone());
        }
    }
    out
}

impl Sweep {
    /// The lists with every empty one at its default (`quick`: the small sweep's), repeats dropped,
    /// checked.
    pub fn resolve(&self, quick: bool) -> Result<Sweep, String> {
        let c = &self.cluster;
        if !self.pairs.is_empty() && (!c.sp_clusters.is_empty() || !c.vpl_clusters.is_empty()) {
            return Err(
                "--pairs replaces --sp-clusters and --vpl-clusters: give one or the other".into(),
            );
        }
        let s = Sweep {
            method: MethodLists {
                methods: self.method.methods(),
                ..self.method.clone()
            },
            modes: or_default(
                &self.modes,
                if quick {
                    &Mode::ALL
                } else {
                    &[Mode::Hard, Mode::Uniform, Mode::Weighted]
                },
            ),
            cluster: self.resolve_cluster(quick),
            pairs: or_default(&self.pairs, &[]),
            target_ms: or_default(&self.target_ms, &[]),
            paper: or_default(&self.paper, &[false]),
        };
        s.validate()?;
        Ok(s)
    }

    /// The cluster lists resolved (`ClusterLists::resolve`); with `--paper` the empty lists of the
    /// settings `--paper` changes stay empty, so that each configuration keeps its start's value
    /// (the paper's with `--paper`, the default without).
    fn resolve_cluster(&self, quick: bool) -> ClusterLists {
        let (c, mut r) = (&self.cluster, self.cluster.resolve(quick));
        if self.paper.contains(&true) {
            macro_rules! paper {
                ($($field:ident),+) => {
                    $(if c.$field.is_empty() {
                        r.$field = Vec::new();
                    })+
                };
            }
            paper!(
                normal_threshold,
                fuzziness,
                weight_exponent,
                plane_gate,
                cluster_light,
                reseed,
                ring_fallback,
                position_fallback,
                centroid_normal
            );
        }
        r
    }

    /// The (K_SP, K_VPL) pairs: `--pairs`, or every `--sp-clusters` × `--vpl-clusters`.
    fn ks(&self) -> Vec<(u32, u32)> {
        let c = &self.cluster;
        if self.pairs.is_empty() {
            c.sp_clusters
                .iter()
                .flat_map(|&sp| c.vpl_clusters.iter().map(move |&vpl| (sp, vpl)))
                .collect()
        } else {
            self.pairs.iter().map(|p| (p.0, p.1)).collect()
        }
    }

    fn validate(&self) -> Result<(), String> {
        let (sps, vpls): (Vec<u32>, Vec<u32>) = self.ks().into_iter().unzip();
        if !self.pairs.is_empty() && (sps.contains(&0) || vpls.contains(&0)) {
            return Err(
                "--pairs: a K of 0; use --modes vpl-only or sp-only for no clustering".into(),
            );
        }
        let methods = &self.method.methods;
        // A method whose knobs are the paper's `ClusterSettings` runs the modes.
        let modes = methods
            .iter()
            .any(|&m| !crate::method::entry(m).own_settings);
        let sp_entry = methods
            .iter()
            .map(|&m| crate::method::entry(m))
            .find(|r| r.own_settings && r.clusters_sps);
        if let Some(r) = sp_entry
            && sps.contains(&0)
        {
            return Err(format!(
                "--sp-clusters 0: {} needs SP clusters (it clusters the shading points)",
                r.method
            ));
        }
        let sp_modes = modes && self.modes.iter().any(|m| m.clusters_sps());
        if sp_modes && sps.contains(&0) {
            return Err("--sp-clusters 0: use --modes vpl-only for no SP clustering".into());
        }
        let vpl_modes = modes && self.modes.iter().any(|m| m.clusters_vpls());
        if vpl_modes && vpls.contains(&0) {
            return Err("--vpl-clusters 0: use --modes sp-only for no VPL clustering".into());
        }
        Ok(())
    }

    /// Every configuration of a resolved sweep, without repeats: the values a mode ignores are
    /// dropped (hard has F = 1, vpl-only no SP K, sp-only no VPL K); another method takes its own
    /// knobs' combinations, with the K's (and iterations) when it uses the paper's clusterings.
    pub fn configs(&self) -> Vec<Config> {
        let ks = self.ks();
        let mut out: Vec<Config> = Vec::new();
        let mut push = |c: Config| {
            if !out.contains(&c) {
                out.push(c);
            }
        };
        for method in self.method.methods() {
            let entry = crate::method::entry(method);
            if !entry.own_settings {
                self.cluster_configs(method, &ks)
                    .into_iter()
                    .for_each(&mut push);
                continue;
            }
            let own = self.method.configs_of(method);
            let uses_k = entry.clusters_sps || own.iter().any(entry.vpl_clusters);
            let ks = if uses_k { ks.clone() } else { vec![(0, 0)] };
            let iterations = if entry.clusters_sps {
                self.cluster.iterations.clone()
            } else {
                vec![ClusterSettings::default().iterations]
            };
            for &paper in &self.paper {
                for &(sp, vpl) in &ks {
                    for &iterations in &iterations {
                        for &m in &own {
                            push(Config {
                                cluster: ClusterSettings {
                                    sp_clusters: if entry.clusters_sps { sp } else { 0 },
                                    vpl_clusters: if (entry.vpl_clusters)(&m) { vpl } else { 0 },
                                    fuzziness: 1,
                                    weighting: Weighting::Hard,
                                    iterations,
                                    paper,
                                    ..Default::default()
                                },
                                method: m,
                            });
                        }
                    }
                }
            }
        }
        out
    }

    /// The configurations of `method`, whose knobs are the paper's `ClusterSettings`: each
    /// `--paper` value × mode × K pair × every combination of the other lists
    /// (`ClusterLists::configs`, in the order of their fields), with what the mode ignores set to
    /// its neutral value.
    fn cluster_configs(&self, method: Method, ks: &[(u32, u32)]) -> Vec<Config> {
        // The K's come from the pairs, one (K_SP, K_VPL) at a time.
        let lists = ClusterLists {
            sp_clusters: Vec::new(),
            vpl_clusters: Vec::new(),
            ..self.cluster.clone()
        };
        let mut out = Vec::new();
        for &paper in &self.paper {
            let start = if paper {
                crate::settings::paper::paper_defaults().1
            } else {
                ClusterSettings::default()
            };
            for &mode in &self.modes {
                for &(sp, vpl) in ks {
                    let base = ClusterSettings {
                        sp_clusters: sp,
                        vpl_clusters: vpl,
                        weighting: mode.weighting(),
                        ..start.clone()
                    };
                    out.extend(lists.configs(&base).into_iter().map(|c| mode.applied(c)));
                }
            }
        }
        let method = MethodSettings {
            method,
            ..Default::default()
        };
        let config = |cluster| Config { cluster, method };
        out.into_iter().map(config).collect()
    }
}

/// The mode a configuration of the sweep is in.
pub fn mode(c: &ClusterSettings) -> Mode {
    match (c.sp_clusters, c.vpl_clusters, c.weighting) {
        (0, _, _) => Mode::VplOnly,
        (_, 0, _) => Mode::SpOnly,
        (_, _, Weighting::Hard) => Mode::Hard,
        (_, _, Weighting::Uniform) => Mode::Uniform,
        (_, _, Weighting::InverseDistance) => Mode::Weighted,
    }
}

/// The `mode` column of a configuration: the mode of a method whose knobs are the paper's
/// `ClusterSettings`, or the method's name for the other methods (each is its own series in the
/// plots).
pub fn mode_name(c: &Config) -> &'static str {
    match c.method.entry_with_own_settings() {
        None => mode(c).name(),
        Some(entry) => entry.method.name(),
    }
}

/// Short name of a configuration for plots and the summary (`weighted 48/128 F6 gauto`,
/// another method's name, K's where it uses them, and its knobs).
pub fn label(c: &Config) -> String {
    label_in(mode(c), c, &c.method)
}

/// The settings a configuration starts from: the paper's with `--paper`, else the defaults; its
/// label names what departs from them.
fn start_of(c: &ClusterSettings) -> ClusterSettings {
    if c.paper {
        crate::settings::paper::paper_defaults().1
    } else {
        ClusterSettings::default()
    }
}

/// `label_of` with the word `paper` for a configuration with `--paper`.
fn label_in(mode: Mode, c: &ClusterSettings, m: &MethodSettings) -> String {
    let s = label_of(mode, c, m);
    if c.paper { s + " paper" } else { s }
}

fn label_of(mode: Mode, c: &ClusterSettings, m: &MethodSettings) -> String {
    let k = |v: u32| {
        if v == 0 {
            "-".to_string()
        } else {
            v.to_string()
        }
    };
    if let Some(entry) = m.entry_with_own_settings() {
        let own = (entry.label)(m);
        if !(entry.clusters_sps || (entry.vpl_clusters)(m)) {
            return format!("{} {own}", entry.method);
        }
        let mut s = format!(
            "{} {}/{} {own}",
            entry.method,
            k(c.sp_clusters),
            k(c.vpl_clusters)
        );
        if entry.clusters_sps && c.iterations != ClusterSettings::default().iterations {
            s += &format!(" i{}", c.iterations);
        }
        return s;
    }
    let mut s = format!("{} {}/{}", mode, k(c.sp_clusters), k(c.vpl_clusters));
    if mode.uses_fuzziness() {
        s += &format!(" F{}", c.fuzziness);
    }
    if mode.clusters_sps() && c.sp_clusters > 0 {
        s += &format!(" g{}", c.gamma);
    }
    if c.normal_threshold != start_of(c).normal_threshold {
        s += &format!(" nt{}", c.normal_threshold);
    }
    if c.iterations != ClusterSettings::default().iterations {
        s += &format!(" i{}", c.iterations);
    }
    if mode.uses_weights() && c.weight_exponent != 1.0 {
        s += &format!(" p{}", c.weight_exponent);
    }
    if let Some(g) = c.plane_gate {
        s += &format!(" gate{g}");
    }
    s + &adaptations_label(c)
}

/// The adaptations a configuration departs from its start in (`point`, `-reseed`, `-rings`,
/// `-position`, `mean-normal`; with `--paper` the reverse: `spread`, `+reseed`, ...), each a word
/// of its label.
fn adaptations_label(c: &ClusterSettings) -> String {
    let d = start_of(c);
    let mut s = String::new();
    if c.cluster_light != d.cluster_light {
        s += &format!(" {}", c.cluster_light);
    }
    for (on, default, word) in [
        (c.reseed, d.reseed, "reseed"),
        (c.ring_fallback, d.ring_fallback, "rings"),
        (c.position_fallback, d.position_fallback, "position"),
    ] {
        if on != default {
            s += &format!(" {}{word}", if on { "+" } else { "-" });
        }
    }
    if c.centroid_normal != d.centroid_normal {
        s += &format!(" {}-normal", c.centroid_normal);
    }
    s
}

/// The label of what ran: clusterings the frame skipped (K ≥ the points) shown as off, γ as used.
pub fn label_ran(c: &Config, sp_ran: bool, vpl_ran: bool, gamma_used: Option<u32>) -> String {
    let ran = ClusterSettings {
        sp_clusters: if sp_ran { c.sp_clusters } else { 0 },
        vpl_clusters: if vpl_ran { c.vpl_clusters } else { 0 },
        gamma: gamma_used.map_or(c.gamma, Gamma::Fixed),
        ..c.cluster.clone()
    };
    let mut s = label_in(mode(c), &ran, &c.method);
    let off: Vec<&str> = [
        (c.sp_clusters > 0 && !sp_ran, "K_sp"),
        (c.vpl_clusters > 0 && !vpl_ran, "K_vpl"),
    ]
    .iter()
    .filter(|x| x.0)
    .map(|x| x.1)
    .collect();
    if !off.is_empty() {
        s += &format!(" ({} off)", off.join(", "));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Wrap {
        #[command(flatten)]
        s: Sweep,
    }

    /// The sweep of `bench ARGS` (`quick` defaults or the full ones).
    fn parse(args: &[&str], quick: bool) -> Result<Sweep, String> {
        let w = Wrap::try_parse_from(std::iter::once("bench").chain(args.iter().copied()))
            .map_err(|e| e.to_string())?;
        w.s.resolve(quick)
    }

    #[test]
    fn lists_parse_trim_and_dedup() {
        let s = parse(&["--sp-clusters", "192,768,192", "--gamma", "4"], true).unwrap();
        assert_eq!(s.cluster.sp_clusters, vec![192, 768]);
        assert_eq!(s.cluster.gamma, vec![Gamma::Fixed(4)]);
        let s = parse(&["--weight-exponent", "0.5,1"], true).unwrap();
        assert_eq!(s.cluster.weight_exponent, vec![0.5f32, 1.0]);
    }

    /// The lists are `ClusterSettings`' own (`listed!`): empty, each is its field's default, but
    /// for the K's' sweep lists (the full sweep's and `--quick`'s); a list item is checked by its
    /// field's parser.
    #[test]
    fn empty_lists_take_the_settings_defaults() {
        let d = ClusterSettings::default();
        for quick in [false, true] {
            let c = parse(&[], quick).unwrap().cluster;
            let (sp, vpl): (&[u32], &[u32]) = match quick {
                false => (&[768, 1536, 3072], &[d.vpl_clusters]),
                true => (&[48, 96], &[128]),
            };
            assert_eq!(
                (c.sp_clusters.as_slice(), c.vpl_clusters.as_slice()),
                (sp, vpl)
            );
            assert_eq!(c.fuzziness, [d.fuzziness]);
            assert_eq!(c.gamma, [d.gamma]);
            assert_eq!(c.normal_threshold, [d.normal_threshold]);
            assert_eq!(c.iterations, [d.iterations]);
            assert_eq!(c.weight_exponent, [d.weight_exponent]);
            assert_eq!(c.plane_gate, [d.plane_gate]);
        }
        let e = parse(&["--iterations", "5,1001"], true).unwrap_err();
        let want = crate::settings::parse_iterations("1001").unwrap_err().0;
        assert!(e.contains("--iterations") && e.contains(&want), "{e}");
    }

    #[test]
    fn bad_lists_name_the_option_and_value() {
        let e = parse(&["--sp-clusters", "192,abc"], true).unwrap_err();
        assert!(e.contains("--sp-clusters") && e.contains("abc"), "{e}");
        let e = parse(&["--sp-clusters", "192,,768"], true).unwrap_err();
        assert!(e.contains("--sp-clusters"), "{e}");
        let e = parse(&["--vpl-clusters", "-5"], true).unwrap_err();
        assert!(e.contains("-5"), "{e}");
        assert!(parse(&["--gamma", ""], true).is_err());
    }

    #[test]
    fn paper_starts_from_the_papers_settings_and_lists_sweep_the_switches() {
        let s = parse(
            &[
                "--paper",
                "--modes",
                "weighted",
                "--pairs",
                "48/128",
                "--cluster-light",
                "point,spread",
            ],
            true,
        )
        .unwrap();
        let c = s.configs();
        assert_eq!(c.len(), 2);
        assert!(c.iter().all(|c| c.paper && !c.reseed && !c.ring_fallback));
        let labels: Vec<String> = c.iter().map(label).collect();
        // A label names what departs from the paper's settings, and the word paper.
        assert_eq!(
            labels,
            [
                "weighted 48/128 F6 gauto paper",
                "weighted 48/128 F6 gauto spread paper",
            ]
        );
        // Without --paper the switches' lists sweep from the defaults.
        let s = parse(
            &["--modes", "hard", "--pairs", "48/128", "--reseed", "on,off"],
            true,
        );
        let labels: Vec<String> = s.unwrap().configs().iter().map(label).collect();
        assert_eq!(labels, ["hard 48/128 gauto", "hard 48/128 gauto -reseed"]);
    }

    /// `--paper off,on`: every configuration once with the defaults and once with the paper's
    /// settings (each method's), the defaults first; a bare `--paper` is on, none is off.
    #[test]
    fn paper_off_on_sweeps_the_defaults_and_the_paper() {
        // The default method and one with knobs of its own, each of them pinned to one value.
        let entry = crate::method::REGISTRY
            .iter()
            .find(|r| r.own_settings)
            .unwrap();
        let methods = format!("{},{}", Method::default().name(), entry.method.name());
        let mut args: Vec<String> = ["--paper", "off,on", "--modes", "hard", "--pairs", "48/128"]
            .map(String::from)
            .to_vec();
        args.extend(["--methods".to_string(), methods]);
        let own = MethodSettings {
            method: entry.method,
            ..Default::default()
        };
        let knobs = MethodSettings::columns()
            .into_iter()
            .zip(own.column_values());
        for (knob, value) in knobs.filter(|(_, v)| !v.is_empty()) {
            args.extend([format!("--{}", knob.replace('_', "-")), value]);
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let s = parse(&args, true).unwrap();
        assert_eq!(s.paper, [false, true]);
        let c = s.configs();
        let labels: Vec<String> = c.iter().map(label).collect();
        let d = ClusterSettings::default();
        let p = crate::settings::paper::paper_defaults().1;
        assert_eq!(
            labels[..2],
            ["hard 48/128 gauto", "hard 48/128 gauto paper"]
        );
        assert_eq!(c.len(), 4, "{labels:?}");
        assert!(!c[0].paper && c[0].reseed == d.reseed && c[0].cluster_light == d.cluster_light);
        assert!(c[1].paper && c[1].reseed == p.reseed && c[1].cluster_light == p.cluster_light);
        assert!(!c[1].ring_fallback && !c[1].position_fallback);
        let other: Vec<&Config> = c
            .iter()
            .filter(|c| c.method.method == entry.method)
            .collect();
        assert_eq!(other.len(), 2);
        assert!(!other[0].paper && other[1].paper);
        assert!(label(other[1]).ends_with(" paper") && !label(other[0]).contains("paper"));
        assert_eq!(parse(&["--paper"], true).unwrap().paper, [true]);
        assert_eq!(parse(&[], true).unwrap().paper, [false]);
        assert_eq!(parse(&["--paper", "on,on"], true).unwrap().paper, [true]);
        assert!(parse(&["--paper", "yes"], true).is_err());
    }

    #[test]
    fn plane_gates_expand_for_the_fuzzy_modes_only() {
        let s = parse(
            &[
                "--modes",
                "hard,uniform,weighted",
                "--sp-clusters",
                "48",
                "--plane-gate",
                "off,20,OFF",
            ],
            true,
        )
        .unwrap();
        assert_eq!(s.cluster.plane_gate, vec![None, Some(20.0)]);
        let labels: Vec<String> = s.configs().iter().map(label).collect();
        assert_eq!(
            labels,
            [
                "hard 48/128 gauto",
                "uniform 48/128 F6 gauto",
                "uniform 48/128 F6 gauto gate20",
                "weighted 48/128 F6 gauto",
                "weighted 48/128 F6 gauto gate20",
            ]
        );
        assert_eq!(s.configs()[2].plane_gate, Some(20.0));
        for bad in ["0", "90.5", "-3", "nan", "on", "20,"] {
            let e = parse(&[&format!("--plane-gate={bad}")], true).unwrap_err();
            assert!(e.contains("--plane-gate"), "{bad}: {e}");
        }
    }

    #[test]
    fn modes_parse_with_aliases() {
        let s = parse(
            &["--modes", "hard,uniform,weighted,vpl-only,sp-only"],
            false,
        )
        .unwrap();
        assert_eq!(s.modes, Mode::ALL.to_vec());
        let s = parse(&["--modes", "Weighted,inverse-distance"], false).unwrap();
        assert_eq!(s.modes, vec![Mode::Weighted]);
        let e = parse(&["--modes", "hard,fuzzy"], false).unwrap_err();
        assert!(e.contains("fuzzy") && e.contains("vpl-only"), "{e}");
    }

    #[test]
    fn invalid_values_are_rejected() {
        assert!(parse(&["--fuzziness", "6,17"], true).is_err());
        assert!(parse(&["--fuzziness", "0"], true).is_err());
        assert!(parse(&["--fuzziness", "1,16"], true).is_ok());
        assert!(parse(&["--gamma", "0"], true).is_err());
        // γ: auto (the default) and factors, auto reaching the frame settings as it is.
        let sw = parse(&["--gamma", "auto,8"], true).unwrap();
        assert_eq!(sw.cluster.gamma, vec![Gamma::Auto, Gamma::Fixed(8)]);
        assert_eq!(parse(&[], true).unwrap().cluster.gamma, vec![Gamma::Auto]);
        let c = sw.configs();
        let weighted: Vec<_> = c.iter().filter(|c| mode(c) == Mode::Weighted).collect();
        assert_eq!(label(weighted[0]), "weighted 48/128 F6 gauto");
        assert_eq!(weighted[0].gamma, Gamma::Auto);
        assert_eq!(
            label_ran(weighted[0], true, true, Some(5)),
            "weighted 48/128 F6 g5"
        );
        assert_eq!(
            label_ran(weighted[0], false, true, None),
            "weighted -/128 F6 (K_sp off)"
        );
        assert_eq!(weighted[1].gamma, Gamma::Fixed(8));
        assert!(parse(&["--sp-clusters", "0"], true).is_err());
        // ... but fine where no mode clusters SPs.
        assert!(parse(&["--sp-clusters", "0", "--modes", "vpl-only"], true).is_ok());
        assert!(parse(&["--normal-threshold", "1.5"], true).is_err());
        assert!(parse(&["--iterations", "1001"], true).is_err());
    }

    #[test]
    fn configs_multiply_out_and_drop_what_a_mode_ignores() {
        let s = Sweep {
            modes: Mode::ALL.to_vec(),
            cluster: ClusterLists {
                sp_clusters: vec![48, 96],
                vpl_clusters: vec![128, 256],
                fuzziness: vec![4, 6],
                gamma: vec![Gamma::Fixed(4)],
                weight_exponent: vec![1.0, 2.0],
                ..Default::default()
            },
            ..Default::default()
        }
        .resolve(true)
        .unwrap();
        let c = s.configs();
        let count = |m: Mode| c.iter().filter(|c| mode(c) == m).count();
        assert_eq!(count(Mode::Hard), 4); // F is 1, no p
        assert_eq!(count(Mode::Uniform), 8); // no p
        assert_eq!(count(Mode::Weighted), 16);
        assert_eq!(count(Mode::VplOnly), 2); // one per VPL K
        assert_eq!(count(Mode::SpOnly), 8); // SP K × F × p
        assert!(c.iter().any(|c| label(c) == "weighted 48/128 F6 g4 p2"));
        // --pairs: only the given (K_SP, K_VPL) pairs.
        let paired = parse(
            &[
                "--modes",
                "hard,weighted,vpl-only",
                "--pairs",
                "48/128, 96/256",
            ],
            true,
        )
        .unwrap()
        .configs();
        let labels: Vec<String> = paired.iter().map(label).collect();
        assert_eq!(
            labels,
            [
                "hard 48/128 gauto",
                "hard 96/256 gauto",
                "weighted 48/128 F6 gauto",
                "weighted 96/256 F6 gauto",
                "vpl-only -/128",
                "vpl-only -/256"
            ]
        );
        for bad in ["48", "48/x", "48/128,", "-1/2"] {
            assert!(parse(&["--pairs", bad], true).is_err(), "{bad}");
        }
        assert!(parse(&["--pairs", "48/128", "--sp-clusters", "48"], true).is_err());
        assert!(
            c.iter()
                .filter(|c| mode(c) == Mode::VplOnly)
                .all(|c| c.sp_clusters == 0)
        );
        assert!(
            c.iter()
                .filter(|c| mode(c) == Mode::SpOnly)
                .all(|c| c.vpl_clusters == 0)
        );
        assert_eq!(parse(&[], true).unwrap().configs().len(), 9);
        let w = c.iter().find(|c| mode(c) == Mode::Weighted).unwrap();
        assert_eq!(label(w), "weighted 48/128 F4 g4");
        let v = c.iter().find(|c| mode(c) == Mode::VplOnly).unwrap();
        assert_eq!(label(v), "vpl-only -/128");
        assert_eq!(w.weighting, Weighting::InverseDistance);
        assert_eq!((w.sp_clusters, w.vpl_clusters, w.fuzziness), (48, 128, 4));
        // Lists of n_t and iterations multiply out too, and show in the labels.
        let s = parse(
            &[
                "--modes",
                "hard",
                "--normal-threshold",
                "0.9,0.5",
                "--iterations",
                "5",
            ],
            true,
        )
        .unwrap();
        let labels: Vec<String> = s.configs().iter().map(label).collect();
        assert!(
            labels.contains(&"hard 96/128 gauto nt0.5 i5".to_string()),
            "{labels:?}"
        );
        assert_eq!(labels.len(), 4);
    }
}
