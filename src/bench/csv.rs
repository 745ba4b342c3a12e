//! `results.csv`: one row per configuration. A fixed header (the contract a reader indexes by name);
//! fields are quoted only when they hold a comma, quote or newline (RFC 4180, by the `csv` crate).

use std::collections::BTreeMap;

use crate::method::{Method, MethodSettings};
use crate::render::pipeline::{FRAME_KEY, Pass};
use crate::settings::Gamma;
use anyhow::{Context, Result, bail};

/// The passes with a `<stage>_ms` column, in the order of the CSV columns (`frame` follows them):
/// the first `Pass::STAGES` of `Pass::TIMED` (the unclustered reference has `reference_ms`; the
/// other methods' passes are summed in `indirect_ms`).
pub fn stage_passes() -> impl Iterator<Item = Pass> {
    Pass::TIMED.into_iter().take(Pass::STAGES)
}

/// The stage timings of a row, in the order of the CSV columns (`frame` last).
pub fn stages() -> impl Iterator<Item = &'static str> {
    stage_passes().map(|p| p.name()).chain([FRAME_KEY])
}

/// One measured configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub scene: String,
    /// glTF camera index, or `default` (the scene's default view).
    pub camera: String,
    pub width: u32,
    pub height: u32,
    pub vpls: u32,
    pub mode: String,
    pub vpl_clusters: u32,
    pub sp_clusters: u32,
    pub fuzziness: u32,
    /// γ asked (`auto` or the factor, written so in the file).
    pub gamma: Gamma,
    pub normal_threshold: f32,
    pub iterations: u32,
    /// GPU ms per stage (mean of the 3 best of `repeat`), keyed by `stages()`.
    pub stages_ms: BTreeMap<String, f64>,
    /// The reference's frame time (same camera), ms.
    pub reference_ms: f64,
    /// reference_ms ÷ frame.
    pub speedup: f64,
    pub mse: f64,
    pub rel_mse: f64,
    pub sp_clusters_used: u32,
    pub vpl_clusters_used: u32,
    pub shadow_rays: u64,
    pub repeat: u32,
    /// Short name used in plots and the summary (`weighted 48/128 F6 g4`).
    pub label: String,
    /// p of the fuzzy weights (w'_f = dist^-p; Eq. 10: 1). Older files without it read 1.
    pub weight_exponent: f32,
    /// γ Alg. 1 sampled with (`gamma` is the one asked; at most pixels / K): empty in the file
    /// when no SP clustering ran. Last column; older files without it read empty.
    pub gamma_used: Option<u32>,
    /// The plane gate of the F lists in degrees (`bench --plane-gate`), empty when off; older files
    /// without it read off.
    pub plane_gate_deg: Option<f32>,
    /// The method (`method::Method`, by its command-line name; docs/methods.md), after
    /// `plane_gate_deg`; files without the column read `colom`. Its knobs are the last columns
    /// (`MethodSettings::columns`: the row's own method's filled, the others' empty); files
    /// without them read the defaults.
    pub method: MethodSettings,
    /// The indirect light's ms: `frame` less `primary` and `direct` (every method's own passes, the
    /// measure the methods are compared by); files without it read `frame − primary − direct`.
    pub indirect_ms: f64,
    /// The adapter and its driver the times were taken on (`GpuContext::adapter_name`,
    /// `gpu::driver_name`), the last two columns; files without them read empty.
    pub adapter: String,
    pub driver: String,
    /// Mean FLIP of the tone-mapped image against the reference's (`stats::ErrorStats::flip`).
    /// Older files without it read empty, as do the border columns below.
    pub flip: Option<f64>,
    /// The error of the light's steps across SP-cluster borders, inside clusters, their ratio and
    /// FLIP at border pixels (`metrics::BorderError`): empty without SP clustering.
    pub border: Option<f64>,
    pub interior: Option<f64>,
    pub border_ratio: Option<f64>,
    pub flip_border: Option<f64>,
    /// `bench --target-ms`: the budget this row's K's were chosen for (empty for the sweep's rows).
    pub target_ms: Option<f64>,
    /// For a budget's row: the lowest MSE of the sweep's fixed settings (same camera) at no more
    /// frame time than this row's: the Pareto front at its time (empty when none is as fast).
    pub front_mse: Option<f64>,
}

impl Row {
    pub fn stage(&self, k: &str) -> f64 {
        self.stages_ms.get(k).copied().unwrap_or(0.0)
    }

    pub fn frame_ms(&self) -> f64 {
        self.stage("frame")
    }
}

/// The header, in order.
pub fn header() -> Vec<String> {
    let mut h: Vec<String> = [
        "scene",
        "camera",
        "width",
        "height",
        "vpls",
        "mode",
        "vpl_clusters",
        "sp_clusters",
        "fuzziness",
        "gamma",
        "normal_threshold",
        "iterations",
    ]
    .map(String::from)
    .to_vec();
    h.extend(stages().map(|s| format!("{s}_ms")));
    h.extend(
        [
            "reference_ms",
            "speedup",
            "mse",
            "rel_mse",
            "sp_clusters_used",
            "vpl_clusters_used",
            "shadow_rays",
            "repeat",
            "label",
            "weight_exponent",
            "gamma_used",
            "plane_gate_deg",
        ]
        .map(String::from),
    );
    h.extend(ERROR_COLUMNS.map(String::from));
    h.extend(METHOD_COLUMNS.map(String::from));
    h.extend(ADAPTER_COLUMNS.map(String::from));
    h.extend(MethodSettings::columns().into_iter().map(String::from));
    h
}

/// The device's columns, after the method's: files written before them have neither.
pub const ADAPTER_COLUMNS: [&str; 2] = ["adapter", "driver"];

/// The method's columns, the last ones (after the error columns): `method` (the
/// `method::Method`'s name) and `indirect_ms`. Files written before them have neither.
pub const METHOD_COLUMNS: [&str; 2] = ["method", "indirect_ms"];

/// The error columns added after `plane_gate_deg`, in order.
pub const ERROR_COLUMNS: [&str; 7] = [
    "flip",
    "border",
    "interior",
    "border_ratio",
    "flip_border",
    "target_ms",
    "front_mse",
];

fn record(r: &Row) -> Vec<String> {
    let mut v = vec![
        r.scene.clone(),
        r.camera.clone(),
        r.width.to_string(),
        r.height.to_string(),
        r.vpls.to_string(),
        r.mode.clone(),
        r.vpl_clusters.to_string(),
        r.sp_clusters.to_string(),
        r.fuzziness.to_string(),
        r.gamma.to_string(),
        r.normal_threshold.to_string(),
        r.iterations.to_string(),
    ];
    v.extend(stages().map(|s| format!("{}", r.stage(s))));
    v.extend([
        format!("{}", r.reference_ms),
        format!("{}", r.speedup),
        format!("{:e}", r.mse),
        format!("{:e}", r.rel_mse),
        r.sp_clusters_used.to_string(),
        r.vpl_clusters_used.to_string(),
        r.shadow_rays.to_string(),
        r.repeat.to_string(),
        r.label.clone(),
        r.weight_exponent.to_string(),
        r.gamma_used.map_or(String::new(), |g| g.to_string()),
        r.plane_gate_deg.map_or(String::new(), |g| g.to_string()),
    ]);
    let opt = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:e}"));
    v.extend(
        [
            r.flip,
            r.border,
            r.interior,
            r.border_ratio,
            r.flip_border,
            r.target_ms,
            r.front_mse,
        ]
        .map(opt),
    );
    v.extend([r.method.method.name().into(), format!("{}", r.indirect_ms)]);
    v.extend([r.adapter.clone(), r.driver.clone()]);
    v.extend(r.method.column_values());
    v
}

/// The whole file: header and rows, `\n` line ends.
pub fn to_csv(rows: &[Row]) -> String {
    write_records(std::iter::once(header()).chain(rows.iter().map(record)))
}

/// One CSV line's fields (for tests and tools reading `path.csv`).
pub fn split_line(line: &str) -> Vec<String> {
    ::csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(line.as_bytes())
        .records()
        .next()
        .and_then(|r| r.ok())
        .map_or_else(Vec::new, |r| r.iter().map(String::from).collect())
}

/// Writes `records` (the header first) as CSV text, `\n` line ends.
pub fn write_records(records: impl IntoIterator<Item = Vec<String>>) -> String {
    let mut w = ::csv::WriterBuilder::new()
        .terminator(::csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    for r in records {
        w.write_record(&r).expect("writing to memory");
    }
    String::from_utf8(w.into_inner().expect("writing to memory")).expect("UTF-8 fields")
}

/// Reads a file written by `to_csv` back (for tests and tools).
pub fn from_csv(text: &str) -> Result<Vec<Row>> {
    let mut reader = ::csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(text.as_bytes());
    let mut records = reader.records();
    let head: Vec<String> = records
        .next()
        .context("empty CSV")??
        .iter()
        .map(String::from)
        .collect();
    // The columns through `label` are required; a file from an older version may stop after any of
    // the later ones (they were added at the end).
    let full = header();
    let prefix_of = |h: &[String]| head.len() <= h.len() && head[..] == h[..head.len()];
    let required = full.iter().position(|h| h == "label").unwrap() + 1;
    if head.len() < required || !prefix_of(&full) {
        bail!("unexpected CSV header: {}", head.join(","));
    }
    let col = |name: &str| head.iter().position(|h| h == name).unwrap();
    let mut rows = Vec::new();
    for (i, record) in records.enumerate() {
        let f: Vec<String> = record?.iter().map(String::from).collect();
        if f.len() != head.len() {
            bail!(
                "line {}: {} fields, expected {}",
                i + 2,
                f.len(),
                head.len()
            );
        }
        let get = |name: &str| f[col(name)].as_str();
        let get_or_empty = |name: &str| match head.iter().any(|h| h == name) {
            true => get(name),
            false => "",
        };
        let num = |name: &str| -> Result<f64> {
            get(name)
                .parse::<f64>()
                .with_context(|| format!("line {}: {name} {:?}", i + 2, get(name)))
        };
        let opt_num = |name: &str| -> Result<Option<f64>> {
            match head.iter().any(|h| h == name) {
                true if !get(name).is_empty() => Ok(Some(num(name)?)),
                _ => Ok(None),
            }
        };
        rows.push(Row {
            scene: get("scene").into(),
            camera: get("camera").into(),
            width: num("width")? as u32,
            height: num("height")? as u32,
            vpls: num("vpls")? as u32,
            mode: get("mode").into(),
            vpl_clusters: num("vpl_clusters")? as u32,
            sp_clusters: num("sp_clusters")? as u32,
            fuzziness: num("fuzziness")? as u32,
            gamma: get("gamma")
                .parse()
                .or_else(|_| num("gamma").map(|g| Gamma::Fixed(g as u32)))?,
            normal_threshold: num("normal_threshold")? as f32,
            iterations: num("iterations")? as u32,
            stages_ms: stages()
                .map(|s| Ok((s.to_string(), num(&format!("{s}_ms"))?)))
                .collect::<Result<_>>()?,
            reference_ms: num("reference_ms")?,
            speedup: num("speedup")?,
            mse: num("mse")?,
            rel_mse: num("rel_mse")?,
            sp_clusters_used: num("sp_clusters_used")? as u32,
            vpl_clusters_used: num("vpl_clusters_used")? as u32,
            shadow_rays: get("shadow_rays").parse().context("shadow_rays")?,
            repeat: num("repeat")? as u32,
            label: get("label").into(),
            weight_exponent: if head.iter().any(|h| h == "weight_exponent") {
                num("weight_exponent")? as f32
            } else {
                1.0
            },
            gamma_used: match head.iter().any(|h| h == "gamma_used") {
                true if !get("gamma_used").is_empty() => Some(num("gamma_used")? as u32),
                _ => None,
            },
            plane_gate_deg: match head.iter().any(|h| h == "plane_gate_deg") {
                true if !get("plane_gate_deg").is_empty() => Some(num("plane_gate_deg")? as f32),
                _ => None,
            },
            flip: opt_num("flip")?,
            border: opt_num("border")?,
            interior: opt_num("interior")?,
            border_ratio: opt_num("border_ratio")?,
            flip_border: opt_num("flip_border")?,
            target_ms: opt_num("target_ms")?,
            front_mse: opt_num("front_mse")?,
            method: MethodSettings {
                method: match head.iter().any(|h| h == "method") {
                    true => <Method as clap::ValueEnum>::from_str(get("method"), false)
                        .map_err(|e| anyhow::anyhow!("line {}: method: {e}", i + 2))?,
                    false => Method::Colom,
                },
                ..Default::default()
            },
            indirect_ms: 0.0,
            adapter: get_or_empty("adapter").into(),
            driver: get_or_empty("driver").into(),
        });
        let r = rows.last_mut().unwrap();
        for name in MethodSettings::columns() {
            let text = get_or_empty(name);
            if let Some(Err(e)) = r.method.set_column(name, text).filter(|_| !text.is_empty()) {
                bail!("line {}: {name} {text:?}: {e}", i + 2);
            }
        }
        r.indirect_ms = if head.iter().any(|h| h == "indirect_ms") {
            num("indirect_ms")?
        } else {
            r.frame_ms() - r.stage("primary") - r.stage("direct")
        };
    }
    Ok(rows)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A plausible row for tests (time grows with the K's, error falls).
    pub fn synthetic(mode: &str, sp: u32, vpl: u32) -> Row {
        let mut stages_ms = BTreeMap::new();
        let k = (sp + vpl) as f64;
        for (i, s) in stages().enumerate() {
            stages_ms.insert(s.to_string(), 0.5 + i as f64 * 0.1 + k * 1e-3);
        }
        // The frame: every stage but the resident VPL work.
        let frame: f64 = stage_passes()
            .filter(|p| !p.resident())
            .map(|p| stages_ms[p.name()])
            .sum();
        stages_ms.insert(FRAME_KEY.into(), frame);
        let bias = match mode {
            "hard" => 2.0,
            "uniform" => 1.3,
            _ => 1.0,
        };
        let mut r = Row {
            scene: "builtin:cornell".into(),
            camera: "default".into(),
            width: 96,
            height: 72,
            vpls: 1024,
            mode: mode.into(),
            vpl_clusters: vpl,
            sp_clusters: sp,
            fuzziness: 6,
            gamma: Gamma::Fixed(4),
            normal_threshold: 0.866,
            iterations: 10,
            stages_ms,
            reference_ms: 50.0,
            speedup: 50.0 / frame,
            mse: bias * 1e-2 / k.sqrt(),
            rel_mse: bias * 1e-1 / k.sqrt(),
            sp_clusters_used: sp.saturating_sub(1),
            vpl_clusters_used: vpl,
            shadow_rays: 123_456_789_012,
            repeat: 3,
            label: format!("{mode} {sp}/{vpl}"),
            weight_exponent: 1.0,
            gamma_used: Some(4),
            plane_gate_deg: None,
            flip: Some(bias * 0.05),
            border: Some(bias * 1e-4),
            interior: Some(1e-4),
            border_ratio: Some(bias),
            flip_border: Some(bias * 0.06),
            target_ms: None,
            front_mse: None,
            method: MethodSettings::default(),
            indirect_ms: 0.0,
            adapter: "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, Mesa 22.3.6 (LLVM 15.0.6))".into(),
            driver: "llvmpipe Mesa 22.3.6 (LLVM 15.0.6)".into(),
        };
        r.indirect_ms = r.frame_ms() - r.stage("primary") - r.stage("direct");
        r
    }

    #[test]
    fn a_row_round_trips() {
        let mut r = synthetic("weighted", 48, 128);
        r.scene = "dir, with \"comma\"/scene.glb".into();
        r.mse = 1.234_567_890_123e-7;
        let csv = to_csv(std::slice::from_ref(&r));
        assert_eq!(csv.lines().count(), 2);
        let back = from_csv(&csv).unwrap();
        assert_eq!(back, vec![r.clone()]);
        // γ auto is written as the word and read back.
        r.gamma = Gamma::Auto;
        let csv = to_csv(std::slice::from_ref(&r));
        assert!(csv.contains(",auto,"), "{csv}");
        assert_eq!(from_csv(&csv).unwrap(), vec![r]);
    }

    #[test]
    fn a_method_row_keeps_its_knobs_in_their_columns() {
        for room in crate::method::ROOMS {
            let mut r = synthetic(room.method.name(), 0, 0);
            r.method.method = room.method;
            let text = to_csv(std::slice::from_ref(&r));
            assert_eq!(from_csv(&text).unwrap()[0].method, r.method);
            // Its own knobs filled, the other methods' empty.
            let head = split_line(text.lines().next().unwrap());
            let line = split_line(text.lines().nth(1).unwrap());
            let own: Vec<usize> = MethodSettings::columns()
                .iter()
                .zip(r.method.column_values())
                .filter(|(_, v)| !v.is_empty())
                .map(|(c, _)| head.iter().position(|h| h == c).unwrap())
                .collect();
            assert!(!own.is_empty(), "{}", room.method);
            let knobs = head.len() - MethodSettings::columns().len();
            for (i, v) in line.iter().enumerate().skip(knobs) {
                assert_eq!(
                    v.is_empty(),
                    !own.contains(&i),
                    "{} column {}",
                    room.method,
                    head[i]
                );
            }
            // A knob set in the file reads back; one out of its range is refused with its line
            // and column.
            let mut f = line.clone();
            let mut set = r.method;
            let (col, val) = (&head[own[0]], f[own[0]].clone());
            assert!(set.set_column(col, &val).unwrap().is_ok());
            f[own[0]] = "-3".into();
            let bad = write_records([head.clone(), f]);
            let e = from_csv(&bad).unwrap_err().to_string();
            assert!(e.contains("line 2") && e.contains(col.as_str()), "{e}");
        }
    }

    #[test]
    fn older_files_without_the_last_columns_read() {
        let mut r = synthetic("hard", 48, 128);
        r.gamma_used = None;
        let csv = to_csv(std::slice::from_ref(&r));
        assert_eq!(from_csv(&csv).unwrap(), vec![r.clone()]);
        let cut_n = |text: &str, n: usize| {
            write_records(text.lines().map(|l| {
                let f = split_line(l);
                f[..f.len() - n].to_vec()
            }))
        };
        // Drop the method knob columns: a file of the version before them.
        let csv = cut_n(&csv, MethodSettings::columns().len());
        assert_eq!(from_csv(&csv).unwrap(), vec![r.clone()]);
        // Drop the adapter columns: a file of the version before them.
        let a = ADAPTER_COLUMNS.len();
        let csv = cut_n(&csv, a);
        let back = from_csv(&csv).unwrap();
        assert_eq!(
            (back[0].adapter.as_str(), back[0].driver.as_str()),
            ("", "")
        );
        assert_eq!(back[0].indirect_ms, r.indirect_ms);
        // Drop the method columns: a file of the version before them (with the error columns).
        let m = METHOD_COLUMNS.len();
        let back = from_csv(&cut_n(&csv, m)).unwrap();
        assert_eq!(
            (back[0].method.method, back[0].flip),
            (Method::Colom, r.flip)
        );
        // Drop also the error columns: a file of the version before them.
        let n = ERROR_COLUMNS.len();
        let before = from_csv(&cut_n(&csv, m + n)).unwrap();
        assert_eq!((before[0].flip, before[0].border_ratio), (None, None));
        assert_eq!(before[0].mse, r.mse);
        // Drop also the three columns before them (weight_exponent, gamma_used, plane_gate_deg).
        let cut = |text: &str| cut_n(text, 3);
        let old = cut_n(&csv, m + n + 3);
        let back = from_csv(&old).unwrap();
        assert_eq!(back[0].weight_exponent, 1.0);
        assert_eq!(back[0].gamma_used, None);
        assert_eq!(back[0].plane_gate_deg, None);
        assert_eq!(back[0].method.method, Method::Colom);
        let want = r.frame_ms() - r.stage("primary") - r.stage("direct");
        assert!((back[0].indirect_ms - want).abs() < 1e-9);
        assert_eq!(back[0].label, r.label);
        // Not a prefix of the header, or short of `label`: refused.
        assert!(from_csv(&old.replacen("scene,camera", "camera,scene", 1)).is_err());
        let short = cut(&old);
        assert!(from_csv(&short).is_err());
    }

    #[test]
    fn bad_csv_is_an_error() {
        assert!(from_csv("").is_err());
        assert!(from_csv("a,b\n1,2\n").is_err());
        let mut csv = to_csv(&[synthetic("hard", 48, 128)]);
        csv = csv.replace(",hard,", ",hard,extra,");
        assert!(from_csv(&csv).is_err());
    }
}
