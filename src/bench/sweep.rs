//! The sweep of `fuzzy-vpl bench`: option lists, modes, and the configurations they expand to.

use std::fmt;
use std::str::FromStr;

use crate::gi::kmeans::{AUTO_GAMMA, gamma_name, parse_gamma, valid_plane_gate};
use crate::gi::pipeline::{
    DEFAULT_WEIGHT_EXPONENT, FrameSettings, Weighting, valid_weight_exponent,
};

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

/// `--pairs 461/750,3072/2000`: K_SP/K_VPL pairs.
pub fn parse_pairs(s: &str) -> Result<Vec<(u32, u32)>, String> {
    s.split(',')
        .map(|item| {
            let item = item.trim();
            let (a, b) = item
                .split_once('/')
                .ok_or_else(|| format!("--pairs {s:?}: {item:?} is not K_SP/K_VPL"))?;
            let n = |v: &str| {
                v.trim()
                    .parse::<u32>()
                    .map_err(|_| format!("--pairs {s:?}: {item:?} is not K_SP/K_VPL"))
            };
            Ok((n(a)?, n(b)?))
        })
        .collect()
}

/// Parses a comma-separated list (`"192,768"`), naming `option` in errors. Duplicates are dropped,
/// order is kept; an empty list is an error.
pub fn parse_list<T>(option: &str, s: &str) -> Result<Vec<T>, String>
where
    T: FromStr + PartialEq,
{
    let mut out: Vec<T> = Vec::new();
    for item in s.split(',') {
        let item = item.trim();
        if item.is_empty() {
            return Err(format!("{option} {s:?}: empty item in the list"));
        }
        let v = item
            .parse::<T>()
            .map_err(|_| format!("{option} {s:?}: {item:?} is not a valid value"))?;
        if !out.contains(&v) {
            out.push(v);
        }
    }
    Ok(out)
}

/// One item of `--plane-gate`: `off` (the paper) or an angle in degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneGate(pub Option<f32>);

impl FromStr for PlaneGate {
    type Err = ();
    fn from_str(s: &str) -> Result<Self, ()> {
        if s.eq_ignore_ascii_case("off") {
            return Ok(PlaneGate(None));
        }
        s.parse::<f32>().map(|d| PlaneGate(Some(d))).map_err(|_| ())
    }
}

/// A `--gamma` item: `auto` or a factor of at least 1 (`kmeans::parse_gamma`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gamma(pub u32);

impl FromStr for Gamma {
    type Err = ();
    fn from_str(s: &str) -> Result<Self, ()> {
        parse_gamma(s).map(Gamma).map_err(|_| ())
    }
}

/// Parses `--modes`.
pub fn parse_modes(s: &str) -> Result<Vec<Mode>, String> {
    let mut out = Vec::new();
    for item in s.split(',') {
        if item.trim().is_empty() {
            return Err(format!("--modes {s:?}: empty item in the list"));
        }
        let m: Mode = item.parse().map_err(|e| format!("--modes: {e}"))?;
        if !out.contains(&m) {
            out.push(m);
        }
    }
    Ok(out)
}

/// The lists a sweep multiplies out.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    pub modes: Vec<Mode>,
    pub sp_clusters: Vec<u32>,
    pub vpl_clusters: Vec<u32>,
    pub fuzziness: Vec<u32>,
    pub gamma: Vec<u32>,
    /// p of the fuzzy weights (weighted and sp-only modes).
    pub weight_exponent: Vec<f32>,
    /// Plane gates of the fuzzy modes' F lists (`None`: off, the paper).
    pub plane_gate: Vec<Option<f32>>,
    /// (K_SP, K_VPL) pairs measured instead of every SP K × VPL K (`--pairs`: e.g. the paper's
    /// light / intermediate / high settings without the off-diagonal ones).
    pub pairs: Option<Vec<(u32, u32)>>,
}

/// The sweep options as typed (`None` = not given).
#[derive(Clone, Debug, Default)]
pub struct SweepArgs {
    pub modes: Option<String>,
    pub sp_clusters: Option<String>,
    pub vpl_clusters: Option<String>,
    pub fuzziness: Option<String>,
    pub gamma: Option<String>,
    pub weight_exponent: Option<String>,
    pub plane_gate: Option<String>,
    pub pairs: Option<String>,
}

impl Sweep {
    /// The full default sweep: the three shading modes at the render defaults, three SP cluster counts.
    pub fn full_default() -> Sweep {
        Sweep {
            modes: vec![Mode::Hard, Mode::Uniform, Mode::Weighted],
            sp_clusters: vec![768, 1536, 3072],
            vpl_clusters: vec![1024],
            fuzziness: vec![6],
            gamma: vec![AUTO_GAMMA],
            weight_exponent: vec![DEFAULT_WEIGHT_EXPONENT],
            plane_gate: vec![None],
            pairs: None,
        }
    }

    /// `--quick`: every mode at two SP cluster counts and 128 VPL clusters (9 configurations).
    pub fn quick_default() -> Sweep {
        Sweep {
            modes: Mode::ALL.to_vec(),
            sp_clusters: vec![48, 96],
            vpl_clusters: vec![128],
            fuzziness: vec![6],
            gamma: vec![AUTO_GAMMA],
            weight_exponent: vec![DEFAULT_WEIGHT_EXPONENT],
            plane_gate: vec![None],
            pairs: None,
        }
    }

    /// Parses the given lists over `base` and checks every value.
    pub fn parse(args: &SweepArgs, base: Sweep) -> Result<Sweep, String> {
        let mut s = base;
        if let Some(v) = &args.modes {
            s.modes = parse_modes(v)?;
        }
        if let Some(v) = &args.sp_clusters {
            s.sp_clusters = parse_list("--sp-clusters", v)?;
        }
        if let Some(v) = &args.vpl_clusters {
            s.vpl_clusters = parse_list("--vpl-clusters", v)?;
        }
        if let Some(v) = &args.fuzziness {
            s.fuzziness = parse_list("--fuzziness", v)?;
        }
        if let Some(v) = &args.gamma {
            s.gamma = parse_list::<Gamma>("--gamma", v)?
                .into_iter()
                .map(|g| g.0)
                .collect();
        }
        if let Some(v) = &args.weight_exponent {
            s.weight_exponent = parse_list("--weight-exponent", v)?;
        }
        if let Some(v) = &args.plane_gate {
            s.plane_gate = parse_list::<PlaneGate>("--plane-gate", v)?
                .into_iter()
                .map(|g| g.0)
                .collect();
        }
        if let Some(v) = &args.pairs {
            if args.sp_clusters.is_some() || args.vpl_clusters.is_some() {
                return Err(
                    "--pairs replaces --sp-clusters and --vpl-clusters: give one or the other"
                        .into(),
                );
            }
            s.pairs = Some(parse_pairs(v)?);
        }
        s.validate()?;
        Ok(s)
    }

    pub fn validate(&self) -> Result<(), String> {
        if self.modes.is_empty()
            || self.sp_clusters.is_empty()
            || self.vpl_clusters.is_empty()
            || self.fuzziness.is_empty()
            || self.gamma.is_empty()
            || self.weight_exponent.is_empty()
            || self.plane_gate.is_empty()
        {
            return Err("every sweep list needs at least one value".into());
        }
        if let Some(f) = self.fuzziness.iter().find(|f| !(1..=16).contains(*f)) {
            return Err(format!("--fuzziness {f}: must be 1..16"));
        }
        if let Some(p) = self
            .weight_exponent
            .iter()
            .find(|p| !valid_weight_exponent(**p))
        {
            return Err(format!(
                "--weight-exponent {p}: must be a number in [0, 64]"
            ));
        }
        if let Some(g) = self
            .plane_gate
            .iter()
            .flatten()
            .find(|g| !valid_plane_gate(**g))
        {
            return Err(format!(
                "--plane-gate {g}: must be off or an angle in (0, 90] degrees"
            ));
        }
        let (sps, vpls): (Vec<u32>, Vec<u32>) = match &self.pairs {
            Some(p) if p.is_empty() => return Err("--pairs needs at least one pair".into()),
            Some(p) => p.iter().copied().unzip(),
            None => (self.sp_clusters.clone(), self.vpl_clusters.clone()),
        };
        if self.pairs.is_some() && (sps.contains(&0) || vpls.contains(&0)) {
            return Err(
                "--pairs: a K of 0; use --modes vpl-only or sp-only for no clustering".into(),
            );
        }
        let sp_modes = self.modes.iter().any(|m| m.clusters_sps());
        if sp_modes && sps.contains(&0) {
            return Err("--sp-clusters 0: use --modes vpl-only for no SP clustering".into());
        }
        let vpl_modes = self.modes.iter().any(|m| m.clusters_vpls());
        if vpl_modes && vpls.contains(&0) {
            return Err("--vpl-clusters 0: use --modes sp-only for no VPL clustering".into());
        }
        Ok(())
    }

    /// Every distinct configuration: modes × SP K × VPL K × F × γ, with the values a mode ignores
    /// dropped (hard has F = 1; vpl-only has no SP K, F, γ; sp-only has no VPL K).
    pub fn configs(&self) -> Vec<Config> {
        let ks: Vec<(u32, u32)> = match &self.pairs {
            Some(p) => p.clone(),
            None => self
                .sp_clusters
                .iter()
                .flat_map(|&sp| self.vpl_clusters.iter().map(move |&vpl| (sp, vpl)))
                .collect(),
        };
        let mut out: Vec<Config> = Vec::new();
        for &mode in &self.modes {
            for &(sp, vpl) in &ks {
                for &f in &self.fuzziness {
                    for &g in &self.gamma {
                        for &p in &self.weight_exponent {
                            for &gate in &self.plane_gate {
                                let c = Config {
                                    mode,
                                    sp_clusters: if mode.clusters_sps() { sp } else { 0 },
                                    vpl_clusters: if mode.clusters_vpls() { vpl } else { 0 },
                                    fuzziness: if mode.uses_fuzziness() { f } else { 1 },
                                    gamma: if mode.clusters_sps() { g } else { AUTO_GAMMA },
                                    weight_exponent: if mode.uses_weights() { p } else { 1.0 },
                                    plane_gate_deg: if mode.uses_fuzziness() { gate } else { None },
                                };
                                if !out.contains(&c) {
                                    out.push(c);
                                }
                            }
                        }
                    }
                }
            }
        }
        out
    }
}

/// One point of the sweep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    pub mode: Mode,
    /// 0 = no SP clustering.
    pub sp_clusters: u32,
    /// 0 = no VPL clustering.
    pub vpl_clusters: u32,
    /// F in effect (1 for hard and vpl-only).
    pub fuzziness: u32,
    /// γ (`AUTO_GAMMA`: the auto rule; also where no SP clustering runs).
    pub gamma: u32,
    /// p of the fuzzy weights (1 where the mode has none).
    pub weight_exponent: f32,
    /// The plane gate of the F lists, degrees (`None`: off, and where the mode has no F).
    pub plane_gate_deg: Option<f32>,
}

impl Config {
    /// `weighted 48/128 F6 γ4`: mode, K_sp/K_vpl ("-" = not clustered), F and γ where they apply.
    pub fn label(&self) -> String {
        let k = |v: u32| {
            if v == 0 {
                "-".to_string()
            } else {
                v.to_string()
            }
        };
        let mut s = format!(
            "{} {}/{}",
            self.mode,
            k(self.sp_clusters),
            k(self.vpl_clusters)
        );
        if self.mode.uses_fuzziness() {
            s += &format!(" F{}", self.fuzziness);
        }
        if self.mode.clusters_sps() && self.sp_clusters > 0 {
            s += &format!(" g{}", gamma_name(self.gamma));
        }
        if self.mode.uses_weights() && self.weight_exponent != 1.0 {
            s += &format!(" p{}", self.weight_exponent);
        }
        if let Some(g) = self.plane_gate_deg {
            s += &format!(" gate{g}");
        }
        s
    }

    /// The label of what ran (`label` is of what was asked): a K the renderer turned off (at or
    /// above the pixel or VPL count) shows as "-" with a note, and γ as Alg. 1 used it
    /// (`kmeans::effective_gamma`, at most pixels / K).
    pub fn label_ran(&self, sp_ran: bool, vpl_ran: bool, gamma_used: Option<u32>) -> String {
        let ran = Config {
            sp_clusters: if sp_ran { self.sp_clusters } else { 0 },
            vpl_clusters: if vpl_ran { self.vpl_clusters } else { 0 },
            gamma: gamma_used.unwrap_or(self.gamma),
            ..*self
        };
        let mut s = ran.label();
        let off: Vec<&str> = [
            (self.sp_clusters > 0 && !sp_ran, "K_sp"),
            (self.vpl_clusters > 0 && !vpl_ran, "K_vpl"),
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

    /// The frame settings of this configuration over `base` (size, VPLs, seed, n_t, iterations...).
    pub fn settings(&self, base: &FrameSettings) -> FrameSettings {
        FrameSettings {
            reference: false,
            sp_clusters: self.sp_clusters,
            vpl_clusters: self.vpl_clusters,
            fuzziness: self.fuzziness.max(1),
            gamma: self.gamma,
            weighting: self.mode.weighting(),
            weight_exponent: self.weight_exponent,
            plane_gate_deg: self.plane_gate_deg,
            ..base.clone()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_parse_trim_and_dedup() {
        assert_eq!(
            parse_list::<u32>("--sp-clusters", "192, 768,192").unwrap(),
            vec![192, 768]
        );
        assert_eq!(parse_list::<u32>("--gamma", "4").unwrap(), vec![4]);
        assert_eq!(
            parse_list::<f32>("--x", "0.5,1").unwrap(),
            vec![0.5f32, 1.0]
        );
    }

    #[test]
    fn bad_lists_name_the_option_and_value() {
        let e = parse_list::<u32>("--sp-clusters", "192,abc").unwrap_err();
        assert!(e.contains("--sp-clusters") && e.contains("abc"), "{e}");
        let e = parse_list::<u32>("--sp-clusters", "192,,768").unwrap_err();
        assert!(e.contains("empty"), "{e}");
        let e = parse_list::<u32>("--vpl-clusters", "-5").unwrap_err();
        assert!(e.contains("-5"), "{e}");
        assert!(parse_list::<u32>("--gamma", "").is_err());
    }

    #[test]
    fn plane_gates_expand_for_the_fuzzy_modes_only() {
        let a = SweepArgs {
            modes: Some("hard,uniform,weighted".into()),
            sp_clusters: Some("48".into()),
            plane_gate: Some("off, 20,OFF".into()),
            ..Default::default()
        };
        let s = Sweep::parse(&a, Sweep::quick_default()).unwrap();
        assert_eq!(s.plane_gate, vec![None, Some(20.0)]);
        let labels: Vec<String> = s.configs().iter().map(Config::label).collect();
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
        let c = s.configs()[2];
        assert_eq!(
            c.settings(&FrameSettings::default()).plane_gate_deg,
            Some(20.0)
        );
        for bad in ["0", "90.5", "-3", "nan", "on", "20,"] {
            let a = SweepArgs {
                plane_gate: Some(bad.into()),
                ..Default::default()
            };
            let e = Sweep::parse(&a, Sweep::quick_default()).unwrap_err();
            assert!(e.contains("--plane-gate"), "{bad}: {e}");
        }
    }

    #[test]
    fn modes_parse_with_aliases() {
        assert_eq!(
            parse_modes("hard,uniform,weighted,vpl-only,sp-only").unwrap(),
            Mode::ALL.to_vec()
        );
        assert_eq!(
            parse_modes("Weighted,inverse-distance").unwrap(),
            vec![Mode::Weighted]
        );
        let e = parse_modes("hard,fuzzy").unwrap_err();
        assert!(e.contains("fuzzy") && e.contains("vpl-only"), "{e}");
    }

    #[test]
    fn invalid_values_are_rejected() {
        let args = |f: &str| SweepArgs {
            fuzziness: Some(f.into()),
            ..Default::default()
        };
        assert!(Sweep::parse(&args("6,17"), Sweep::quick_default()).is_err());
        assert!(Sweep::parse(&args("0"), Sweep::quick_default()).is_err());
        assert!(Sweep::parse(&args("1,16"), Sweep::quick_default()).is_ok());
        let g = SweepArgs {
            gamma: Some("0".into()),
            ..Default::default()
        };
        assert!(Sweep::parse(&g, Sweep::quick_default()).is_err());
        // γ: auto (the default) and factors, auto reaching the frame settings as it is.
        let g = SweepArgs {
            gamma: Some("auto,8".into()),
            ..Default::default()
        };
        let sw = Sweep::parse(&g, Sweep::quick_default()).unwrap();
        assert_eq!(sw.gamma, vec![AUTO_GAMMA, 8]);
        assert_eq!(Sweep::quick_default().gamma, vec![AUTO_GAMMA]);
        let c = sw.configs();
        let weighted: Vec<_> = c.iter().filter(|c| c.mode == Mode::Weighted).collect();
        assert_eq!(weighted[0].label(), "weighted 48/128 F6 gauto");
        assert_eq!(
            weighted[0].settings(&FrameSettings::default()).gamma,
            AUTO_GAMMA
        );
        assert_eq!(
            weighted[0].label_ran(true, true, Some(5)),
            "weighted 48/128 F6 g5"
        );
        assert_eq!(weighted[1].settings(&FrameSettings::default()).gamma, 8);
        let k = SweepArgs {
            sp_clusters: Some("0".into()),
            ..Default::default()
        };
        assert!(Sweep::parse(&k, Sweep::quick_default()).is_err());
        // ... but fine where no mode clusters SPs.
        let k = SweepArgs {
            sp_clusters: Some("0".into()),
            modes: Some("vpl-only".into()),
            ..Default::default()
        };
        assert!(Sweep::parse(&k, Sweep::quick_default()).is_ok());
    }

    #[test]
    fn configs_multiply_out_and_drop_what_a_mode_ignores() {
        let s = Sweep {
            modes: Mode::ALL.to_vec(),
            sp_clusters: vec![48, 96],
            vpl_clusters: vec![128, 256],
            fuzziness: vec![4, 6],
            gamma: vec![4],
            weight_exponent: vec![1.0, 2.0],
            plane_gate: vec![None],
            pairs: None,
        };
        let c = s.configs();
        let count = |m: Mode| c.iter().filter(|c| c.mode == m).count();
        assert_eq!(count(Mode::Hard), 4); // F is 1, no p
        assert_eq!(count(Mode::Uniform), 8); // no p
        assert_eq!(count(Mode::Weighted), 16);
        assert_eq!(count(Mode::VplOnly), 2); // one per VPL K
        assert_eq!(count(Mode::SpOnly), 8); // SP K × F × p
        assert!(c.iter().any(|c| c.label() == "weighted 48/128 F6 g4 p2"));
        // --pairs: only the given (K_SP, K_VPL) pairs.
        let paired = Sweep::parse(
            &SweepArgs {
                modes: Some("hard,weighted,vpl-only".into()),
                pairs: Some("48/128, 96/256".into()),
                ..Default::default()
            },
            Sweep::quick_default(),
        )
        .unwrap()
        .configs();
        let labels: Vec<String> = paired.iter().map(|c| c.label()).collect();
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
            let a = SweepArgs {
                pairs: Some(bad.into()),
                ..Default::default()
            };
            assert!(Sweep::parse(&a, Sweep::quick_default()).is_err(), "{bad}");
        }
        let both = SweepArgs {
            pairs: Some("48/128".into()),
            sp_clusters: Some("48".into()),
            ..Default::default()
        };
        assert!(Sweep::parse(&both, Sweep::quick_default()).is_err());
        assert!(
            c.iter()
                .filter(|c| c.mode == Mode::VplOnly)
                .all(|c| c.sp_clusters == 0)
        );
        assert!(
            c.iter()
                .filter(|c| c.mode == Mode::SpOnly)
                .all(|c| c.vpl_clusters == 0)
        );
        assert_eq!(Sweep::quick_default().configs().len(), 9);
        let w = c.iter().find(|c| c.mode == Mode::Weighted).unwrap();
        assert_eq!(w.label(), "weighted 48/128 F4 g4");
        let v = c.iter().find(|c| c.mode == Mode::VplOnly).unwrap();
        assert_eq!(v.label(), "vpl-only -/128");
        let st = w.settings(&FrameSettings::default());
        assert_eq!(st.weighting, Weighting::InverseDistance);
        assert_eq!(
            (st.sp_clusters, st.vpl_clusters, st.fuzziness),
            (48, 128, 4)
        );
        assert!(!st.reference);
    }
}
