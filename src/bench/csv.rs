//! `results.csv`: one row per configuration, a serde struct (`Row`) written and read with the
//! `csv` crate. Its fields are the columns, in order (the contract a reader indexes by name,
//! docs/design.md), then every method's knobs (`MethodSettings::columns`); fields are quoted only
//! when they hold a comma, quote or newline (RFC 4180). Columns were added at the end over time:
//! a file may stop after any column after `label`, and the missing ones read their defaults.

use std::sync::OnceLock;

use serde::de::{self, Deserializer, Visitor};
use serde::{Deserialize, Serialize, Serializer};

use crate::gi::pass::Pass;
use crate::method::{Method, MethodSettings};
use crate::render::FRAME_KEY;
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

/// One measured configuration: a row of `results.csv`, a field a column.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
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
    #[serde(deserialize_with = "gamma_cell")]
    pub gamma: Gamma,
    #[serde(serialize_with = "display")]
    pub normal_threshold: f32,
    pub iterations: u32,
    /// GPU ms per stage (mean of the 3 best of `repeat`), one column a stage of `stages()`
    /// (`Row::stage` reads them by name).
    #[serde(serialize_with = "display")]
    pub vpl_trace_ms: f64,
    #[serde(serialize_with = "display")]
    pub vpl_cluster_ms: f64,
    #[serde(serialize_with = "display")]
    pub primary_ms: f64,
    #[serde(serialize_with = "display")]
    pub sp_cluster_ms: f64,
    #[serde(serialize_with = "display")]
    pub visibility_ms: f64,
    #[serde(serialize_with = "display")]
    pub shade_ms: f64,
    #[serde(serialize_with = "display")]
    pub gather_ms: f64,
    #[serde(serialize_with = "display")]
    pub direct_ms: f64,
    #[serde(serialize_with = "display")]
    pub frame_ms: f64,
    /// The reference's frame time (same camera), ms.
    #[serde(serialize_with = "display")]
    pub reference_ms: f64,
    /// reference_ms ÷ frame.
    #[serde(serialize_with = "display")]
    pub speedup: f64,
    #[serde(serialize_with = "sci")]
    pub mse: f64,
    #[serde(serialize_with = "sci")]
    pub rel_mse: f64,
    pub sp_clusters_used: u32,
    pub vpl_clusters_used: u32,
    pub shadow_rays: u64,
    pub repeat: u32,
    /// Short name used in plots and the summary (`weighted 48/128 F6 g4`). The last column every
    /// file has; the later ones read their defaults where a file stops before them.
    pub label: String,
    /// p of the fuzzy weights (w'_f = dist^-p; Eq. 10: 1). Older files without it read 1.
    #[serde(default = "one", serialize_with = "display")]
    pub weight_exponent: f32,
    /// γ Alg. 1 sampled with (`gamma` is the one asked; at most pixels / K): empty in the file
    /// when no SP clustering ran; older files without it read empty.
    #[serde(default)]
    pub gamma_used: Option<u32>,
    /// The plane gate of the F lists in degrees (`bench --plane-gate`), empty when off; older files
    /// without it read off.
    #[serde(default, serialize_with = "opt_display")]
    pub plane_gate_deg: Option<f32>,
    /// Mean FLIP of the tone-mapped image against the reference's (`stats::ErrorStats::flip`).
    /// Older files without it read empty, as do the border columns below.
    #[serde(default, serialize_with = "opt_sci")]
    pub flip: Option<f64>,
    /// The error of the light's steps across SP-cluster borders, inside clusters, their ratio and
    /// FLIP at border pixels (`metrics::BorderError`): empty without SP clustering.
    #[serde(default, serialize_with = "opt_sci")]
    pub border: Option<f64>,
    #[serde(default, serialize_with = "opt_sci")]
    pub interior: Option<f64>,
    #[serde(default, serialize_with = "opt_sci")]
    pub border_ratio: Option<f64>,
    #[serde(default, serialize_with = "opt_sci")]
    pub flip_border: Option<f64>,
    /// `bench --target-ms`: the budget this row's K's were chosen for (empty for the sweep's rows).
    #[serde(default, serialize_with = "opt_sci")]
    pub target_ms: Option<f64>,
    /// For a budget's row: the lowest MSE of the sweep's fixed settings (same camera) at no more
    /// frame time than this row's: the Pareto front at its time (empty when none is as fast).
    #[serde(default, serialize_with = "opt_sci")]
    pub front_mse: Option<f64>,
    /// The method (`method::Method`, its name in the `method` column; docs/methods.md); files
    /// without the column read `colom`. Its knobs are the last columns (`MethodSettings::columns`:
    /// the row's own method's filled, the others' empty); files without them read the defaults.
    #[serde(
        default,
        serialize_with = "method_cell",
        deserialize_with = "method_of_cell"
    )]
    pub method: MethodSettings,
    /// The indirect light's ms: `frame` less `primary` and `direct` (every method's own passes, the
    /// measure the methods are compared by); files without it read `frame − primary − direct`.
    #[serde(default, serialize_with = "display")]
    pub indirect_ms: f64,
    /// The adapter and its driver the times were taken on (`GpuContext::adapter_name`,
    /// `gpu::driver_name`); files without them read empty.
    #[serde(default)]
    pub adapter: String,
    #[serde(default)]
    pub driver: String,
    /// The method's report (`Frame::report`), in the report columns after the knobs
    /// (`method::report_columns`); files without them read none.
    #[serde(skip)]
    pub report: Option<serde_json::Value>,
}

impl MethodCells for Row {
    fn knobs(&mut self) -> &mut MethodSettings {
        &mut self.method
    }
    fn report(&mut self) -> &mut Option<serde_json::Value> {
        &mut self.report
    }
}

/// The stage columns by stage name: the one place the fields meet `stages()`' names.
macro_rules! stage_columns {
    ($($stage:ident: $field:ident),+ $(,)?) => {
        impl Row {
            /// The `<k>_ms` column (0 for a name that has none).
            pub fn stage(&self, k: &str) -> f64 {
                match k {
                    $(stringify!($stage) => self.$field,)+
                    _ => 0.0,
                }
            }

            /// Every stage column, by name, in `stages()`' order.
            pub fn stages_mut(&mut self) -> Vec<(&'static str, &mut f64)> {
                vec![$((stringify!($stage), &mut self.$field)),+]
            }
        }
    };
}

stage_columns! {
    vpl_trace: vpl_trace_ms,
    vpl_cluster: vpl_cluster_ms,
    primary: primary_ms,
    sp_cluster: sp_cluster_ms,
    visibility: visibility_ms,
    shade: shade_ms,
    gather: gather_ms,
    direct: direct_ms,
    frame: frame_ms,
}

impl Row {
    pub fn frame_ms(&self) -> f64 {
        self.frame_ms
    }

    /// `frame` less `primary` and `direct`: `indirect_ms` of a file written before the column.
    pub fn indirect_of_stages(&self) -> f64 {
        self.frame_ms - self.primary_ms - self.direct_ms
    }
}

fn one() -> f32 {
    1.0
}

/// A number as Rust prints it (`0`, `0.866`, `1.4118200015218463`): the file's form since its
/// first version.
fn display<T: std::fmt::Display, S: Serializer>(v: &T, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(v)
}

fn opt_display<T: std::fmt::Display, S: Serializer>(
    v: &Option<T>,
    s: S,
) -> Result<S::Ok, S::Error> {
    match v {
        Some(v) => s.collect_str(v),
        None => s.serialize_none(),
    }
}

/// An error (`1.925e-4`), in scientific notation.
fn sci<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(&format_args!("{v:e}"))
}

fn opt_sci<S: Serializer>(v: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
    match v {
        Some(v) => sci(v, s),
        None => s.serialize_none(),
    }
}

/// γ as written (`auto` or the factor), or a number.
fn gamma_cell<'de, D: Deserializer<'de>>(d: D) -> Result<Gamma, D::Error> {
    let text = String::deserialize(d)?;
    text.parse::<Gamma>()
        .or_else(|e| match text.trim().parse::<f64>() {
            Ok(g) => Ok(Gamma::Fixed(g as u32)),
            Err(_) => Err(de::Error::custom(e)),
        })
}

/// The `method` column: the method's name (its knobs are the last columns).
pub(crate) fn method_cell<S: Serializer>(m: &MethodSettings, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(m.method.name())
}

pub(crate) fn method_of_cell<'de, D: Deserializer<'de>>(d: D) -> Result<MethodSettings, D::Error> {
    Ok(MethodSettings {
        method: Method::deserialize(d)?,
        ..Default::default()
    })
}

/// A row's knob columns (`MethodSettings::columns`), after its own: serialised as their values.
pub(crate) struct KnobCells<'a>(pub &'a MethodSettings);

impl Serialize for KnobCells<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.0.column_values())
    }
}

/// The field names of a struct that derives `Deserialize`, in order: what serde passes to
/// `deserialize_struct` (a file's columns are its row type's fields).
pub(crate) fn fields_of<'de, T: Deserialize<'de>>() -> &'static [&'static str] {
    struct Names<'a>(&'a mut &'static [&'static str]);
    impl<'de> Deserializer<'de> for Names<'_> {
        type Error = de::value::Error;
        fn deserialize_any<V: Visitor<'de>>(self, _: V) -> Result<V::Value, Self::Error> {
            Err(de::Error::custom("not a struct"))
        }
        fn deserialize_struct<V: Visitor<'de>>(
            self,
            _: &'static str,
            fields: &'static [&'static str],
            _: V,
        ) -> Result<V::Value, Self::Error> {
            *self.0 = fields;
            Err(de::Error::custom("names only"))
        }
        serde::forward_to_deserialize_any! {
            bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
            option unit unit_struct newtype_struct seq tuple tuple_struct map enum identifier
            ignored_any
        }
    }
    let mut names: &'static [&'static str] = &[];
    let _ = T::deserialize(Names(&mut names));
    names
}

/// A row type's header: its fields, then every method's knobs, then every method's report
/// columns (`method::report_columns`).
pub(crate) fn header_of<'de, T: Deserialize<'de>>() -> Vec<String> {
    let own = fields_of::<T>().iter().copied();
    own.chain(MethodSettings::columns())
        .chain(crate::method::report_columns())
        .map(String::from)
        .collect()
}

/// A row's report columns (`method::report_values`), after its knobs: serialised as their values.
pub(crate) struct ReportCells(pub Vec<String>);

impl Serialize for ReportCells {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(&self.0)
    }
}

/// What a row type holds beside its own columns: its method's knobs and the method's report (one
/// serde value, `Frame::report`'s), read from and written to the knob and report columns.
pub(crate) trait MethodCells {
    fn knobs(&mut self) -> &mut MethodSettings;
    fn report(&mut self) -> &mut Option<serde_json::Value>;
}

/// The header, in order.
pub fn header() -> Vec<String> {
    static HEADER: OnceLock<Vec<String>> = OnceLock::new();
    HEADER.get_or_init(header_of::<Row>).clone()
}

/// The device's columns, after the method's: files written before them have neither.
pub const ADAPTER_COLUMNS: [&str; 2] = ["adapter", "driver"];

/// The method's columns, after the error columns: `method` (the `method::Method`'s name) and
/// `indirect_ms`. Files written before them have neither.
pub const METHOD_COLUMNS: [&str; 2] = ["method", "indirect_ms"];

/// `rows` (each a `T` followed by its knob columns and its report columns) under `header` as CSV
/// text, `\n` line ends.
pub(crate) fn write_rows<'a, T: Serialize + 'a>(
    header: &[String],
    rows: impl IntoIterator<Item = (&'a T, &'a MethodSettings, Option<&'a serde_json::Value>)>,
) -> String {
    let mut w = ::csv::WriterBuilder::new()
        .has_headers(false)
        .terminator(::csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    w.write_record(header).expect("writing to memory");
    for (r, m, report) in rows {
        let cells = ReportCells(crate::method::report_values(m.method, report));
        w.serialize((r, KnobCells(m), cells))
            .expect("writing to memory");
    }
    String::from_utf8(w.into_inner().expect("writing to memory")).expect("UTF-8 fields")
}

/// The whole file: header and rows, `\n` line ends.
pub fn to_csv(rows: &[Row]) -> String {
    write_rows(
        &header(),
        rows.iter().map(|r| (r, &r.method, r.report.as_ref())),
    )
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

/// A file's rows as `T` (a row type written by `write_rows`): its header, less the report columns
/// (`method::report_columns`, found by name wherever they stand: older files have some of them
/// among their own), a prefix of `full`'s that holds at least the columns through
/// `last_required`; every line as many fields as the header; the knob columns it has set into the
/// row's `MethodSettings` and its method's report columns into its report. `fix` completes a row
/// from what the header lacks.
pub(crate) fn read_rows<T: de::DeserializeOwned + MethodCells>(
    text: &str,
    full: &[String],
    last_required: &str,
    fix: impl Fn(&mut T, &::csv::StringRecord),
) -> Result<Vec<T>> {
    let mut reader = ::csv::ReaderBuilder::new()
        .flexible(true)
        .from_reader(text.as_bytes());
    let head = reader.headers().context("reading the header")?.clone();
    let h: Vec<&str> = head.iter().collect();
    let report = crate::method::report_columns();
    let own = |cols: &[&str]| -> Vec<String> {
        let own = cols.iter().filter(|c| !report.contains(c));
        own.map(|c| c.to_string()).collect()
    };
    let (own_h, full) = (
        own(&h),
        own(&full.iter().map(String::as_str).collect::<Vec<_>>()),
    );
    let required = full.iter().position(|c| c == last_required).unwrap() + 1;
    if own_h.len() < required || own_h.len() > full.len() || full[..own_h.len()] != own_h[..] {
        bail!("unexpected CSV header: {}", h.join(","));
    }
    let mut rows = Vec::new();
    for (i, record) in reader.records().enumerate() {
        let (record, line) = (record?, i + 2);
        if record.len() != head.len() {
            bail!(
                "line {line}: {} fields, expected {}",
                record.len(),
                head.len()
            );
        }
        let mut row: T = record
            .deserialize(Some(&head))
            .with_context(|| format!("line {line}"))?;
        let m = row.knobs();
        for (name, text) in h.iter().zip(&record) {
            if let Some(Err(e)) = m.set_column(name, text).filter(|_| !text.is_empty()) {
                bail!("line {line}: {name} {text:?}: {e}");
            }
        }
        let method = m.method;
        *row.report() = crate::method::report_of_cells(method, h.iter().copied().zip(&record));
        fix(&mut row, &head);
        rows.push(row);
    }
    Ok(rows)
}

/// Reads a file written by `to_csv` back, or by an older version (for tests and tools).
pub fn from_csv(text: &str) -> Result<Vec<Row>> {
    read_rows(text, &header(), "label", |r: &mut Row, head| {
        if !head.iter().any(|h| h == "indirect_ms") {
            r.indirect_ms = r.indirect_of_stages();
        }
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A plausible row for tests (time grows with the K's, error falls).
    pub fn synthetic(mode: &str, sp: u32, vpl: u32) -> Row {
        let k = (sp + vpl) as f64;
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
            reference_ms: 50.0,
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
            ..Default::default()
        };
        for (i, (_, v)) in r.stages_mut().into_iter().enumerate() {
            *v = 0.5 + i as f64 * 0.1 + k * 1e-3;
        }
        // The frame: every stage but the resident VPL work.
        r.frame_ms = stage_passes()
            .filter(|p| !p.resident())
            .map(|p| r.stage(p.name()))
            .sum();
        r.speedup = 50.0 / r.frame_ms;
        r.indirect_ms = r.indirect_of_stages();
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
        // colom's knobs are the paper's own columns.
        for room in crate::method::ROOMS.iter().filter(|r| r.own_knobs) {
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
            let knobs = head.len()
                - MethodSettings::columns().len()
                - crate::method::report_columns().len();
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
        // Drop the report columns, then the method knob columns: files of the versions before
        // them.
        let csv = cut_n(&csv, crate::method::report_columns().len());
        assert_eq!(from_csv(&csv).unwrap(), vec![r.clone()]);
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
        // flip, border, interior, border_ratio, flip_border, target_ms and front_mse.
        let n = 7;
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
        assert_eq!(back[0].indirect_ms, r.indirect_of_stages());
        assert_eq!(back[0].label, r.label);
        // Not a prefix of the header, or short of `label`: refused.
        assert!(from_csv(&old.replacen("scene,camera", "camera,scene", 1)).is_err());
        let short = cut(&old);
        assert!(from_csv(&short).is_err());
    }

    /// The header is the row's fields (the stage columns `stages()` after `iterations`), then the
    /// knobs, then the report columns; no two columns share a name, and `stage` reads each stage's
    /// own column.
    #[test]
    fn the_header_is_the_rows_fields_then_the_knobs() {
        let h = header();
        let at = h.iter().position(|c| c == "iterations").unwrap() + 1;
        let stage_cols: Vec<String> = stages().map(|s| format!("{s}_ms")).collect();
        assert_eq!(h[at..at + stage_cols.len()], stage_cols[..]);
        let report = crate::method::report_columns();
        let knobs_at = h.len() - MethodSettings::columns().len() - report.len();
        assert_eq!(
            h[knobs_at..h.len() - report.len()],
            MethodSettings::columns()
        );
        assert_eq!(h[h.len() - report.len()..], report);
        let mut unique = h.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), h.len(), "{h:?}");
        let mut r = synthetic("weighted", 48, 128);
        let names: Vec<&str> = r.stages_mut().into_iter().map(|(n, _)| n).collect();
        assert_eq!(names, stages().collect::<Vec<_>>());
        for (i, (_, v)) in r.stages_mut().into_iter().enumerate() {
            *v = i as f64 + 0.25;
        }
        for (i, s) in stages().enumerate() {
            assert_eq!(r.stage(s), i as f64 + 0.25, "{s}");
        }
        assert_eq!(r.stage("no such stage"), 0.0);
    }

    /// Every column holds its own field: a row whose numbers all differ is written with each value
    /// under its field's name (in the forms the file has always had: `0`, `0.866`, `1.5e-7`, empty
    /// for none), and reads back equal.
    #[test]
    fn every_field_is_written_under_its_name_and_reads_back() {
        let mut r = synthetic("weighted", 48, 128);
        for (i, (_, v)) in r.stages_mut().into_iter().enumerate() {
            *v = i as f64;
        }
        (r.reference_ms, r.speedup, r.indirect_ms) = (10.5, 2.25, 3.75);
        (r.mse, r.rel_mse) = (1.5e-7, 2.5e-3);
        (r.flip, r.border, r.target_ms, r.front_mse) = (Some(0.125), None, Some(40.0), Some(1e-9));
        (r.plane_gate_deg, r.gamma_used, r.weight_exponent) = (Some(20.0), None, 2.0);
        // The last room's method: its knobs (their defaults) filled, the others' empty.
        let room = crate::method::ROOMS.last().unwrap();
        r.method.method = room.method;
        let text = to_csv(std::slice::from_ref(&r));
        let head = split_line(text.lines().next().unwrap());
        let line = split_line(text.lines().nth(1).unwrap());
        let cell = |c: &str| line[head.iter().position(|h| h == c).unwrap()].as_str();
        assert_eq!((cell("vpl_trace_ms"), cell("gather_ms")), ("0", "6"));
        assert_eq!((cell("frame_ms"), cell("normal_threshold")), ("8", "0.866"));
        assert_eq!((cell("mse"), cell("rel_mse")), ("1.5e-7", "2.5e-3"));
        assert_eq!(
            (cell("flip"), cell("border"), cell("target_ms")),
            ("1.25e-1", "", "4e1")
        );
        assert_eq!((cell("plane_gate_deg"), cell("gamma_used")), ("20", ""));
        assert_eq!(
            (cell("weight_exponent"), cell("indirect_ms")),
            ("2", "3.75")
        );
        assert_eq!(cell("method"), room.method.name());
        let knobs = MethodSettings::columns()
            .into_iter()
            .zip(r.method.column_values());
        let mut own = 0;
        for (c, v) in knobs {
            assert_eq!(cell(c), v, "{c}");
            own += !v.is_empty() as usize;
        }
        assert!(own > 0);
        assert_eq!(cell("gamma"), "4");
        assert_eq!(from_csv(&text).unwrap(), vec![r]);
    }

    /// A file of the first version (through `label`, before p, γ used, the plane gate, the error,
    /// method, adapter and knob columns), as written then: its rows read with those columns'
    /// defaults.
    #[test]
    fn a_file_of_the_first_version_reads_with_defaults() {
        let old = "\
scene,camera,width,height,vpls,mode,vpl_clusters,sp_clusters,fuzziness,gamma,normal_threshold,\
iterations,vpl_trace_ms,vpl_cluster_ms,primary_ms,sp_cluster_ms,visibility_ms,shade_ms,gather_ms,\
direct_ms,frame_ms,reference_ms,speedup,mse,rel_mse,sp_clusters_used,vpl_clusters_used,\
shadow_rays,repeat,label
builtin:cornell,default,96,72,1024,weighted,128,48,6,4,0.866,10,1.5,2,0.5,3,1,2.5,0,0.75,7.75,\
100,12.9,1.2e-4,3.4e-3,47,128,40000,3,weighted 48/128 F6 g4
";
        let rows = from_csv(old).unwrap();
        let r = &rows[0];
        assert_eq!(
            (r.label.as_str(), r.gamma, r.sp_clusters_used),
            ("weighted 48/128 F6 g4", Gamma::Fixed(4), 47)
        );
        assert_eq!((r.shade_ms, r.frame_ms(), r.mse), (2.5, 7.75, 1.2e-4));
        assert_eq!(
            (r.weight_exponent, r.gamma_used, r.plane_gate_deg),
            (1.0, None, None)
        );
        assert_eq!((r.flip, r.border_ratio, r.front_mse), (None, None, None));
        assert_eq!(r.method, MethodSettings::default());
        assert_eq!((r.adapter.as_str(), r.driver.as_str()), ("", ""));
        // indirect_ms: the frame less primary rays and direct light.
        assert_eq!(r.indirect_ms, 7.75 - 0.5 - 0.75);
        // Written again, it has every column and reads back the same.
        assert_eq!(from_csv(&to_csv(&rows)).unwrap(), rows);
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
