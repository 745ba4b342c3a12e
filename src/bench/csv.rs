//! `results.csv`: one row per configuration, written and read with the `csv` crate. A row (`Row`)
//! is a serde struct of its own columns that carries the settings it was made with
//! (`ClusterSettings`, `FrameSettings`) and its method's knobs and report. The columns (`Layout`,
//! the same for `path.csv`): the contract's, in order (`COLUMNS`: the row's own fields and the
//! settings fields the contract placed among them, a reader indexes them by name,
//! docs/design.md), then every other settings field (`settings_columns`, generated from the
//! settings' declarations: a field added to them is a column), every method's knobs
//! (`MethodSettings::columns`) and every method's report columns (`method::report_columns`). A
//! settings cell is serde's value of the field as text (`Cell`), or its contract's older form
//! (`Form`). Fields are quoted only when they hold a comma, quote or newline (RFC 4180). Columns
//! were added over time: a file may stop after any column after `label`, and the missing ones read
//! their defaults; the generated blocks are found by name.

mod cell;
use cell::cells_of;
use std::sync::OnceLock;

use serde::de::{self, DeserializeOwned, Deserializer, Visitor};
use serde::{Deserialize, Serialize, Serializer};

use crate::gi::pass::Pass;
use crate::method::MethodSettings;
use crate::render::FRAME_KEY;
use crate::settings::{ClusterSettings, FrameSettings, Gamma};
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

/// One measured configuration: a row of `results.csv`, a field a column, with the settings it was
/// made with (their fields are columns too: `COLUMNS`, `settings_columns`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Row {
    pub scene: String,
    /// glTF camera index, or `default` (the scene's default view).
    pub camera: String,
    pub mode: String,
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
    /// γ Alg. 1 sampled with (`cluster.gamma` is the one asked; at most pixels / K): empty in the
    /// file when no SP clustering ran; older files without it read empty.
    #[serde(default)]
    pub gamma_used: Option<u32>,
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
    /// For a budget's row (`cluster.target_ms`): the lowest MSE of the sweep's fixed settings
    /// (same camera) at no more frame time than this row's: the Pareto front at its time (empty
    /// when none is as fast).
    #[serde(default, serialize_with = "opt_sci")]
    pub front_mse: Option<f64>,
    /// The method (`method::Method`, its name in the `method` column; docs/methods.md); files
    /// without the column read the default method. Its knobs are the knob columns
    /// (`MethodSettings::columns`: the row's own method's filled, the others' empty); files without
    /// them read the defaults.
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
    /// The clustering the frame ran with (`RenderSettings::cluster` as it ran: under a budget the
    /// K's chosen and `target_ms` the budget, empty for the sweep's rows), its fields columns.
    #[serde(skip)]
    pub cluster: ClusterSettings,
    /// The frame's settings as it ran (`width`, `height` and `vpls` the frame's own: `vpls` the
    /// VPLs traced), its fields columns.
    #[serde(skip)]
    pub frame: FrameSettings,
    /// The method's report (`Frame::report`), in the report columns after the knobs
    /// (`method::report_columns`); files without them read none.
    #[serde(skip)]
    pub report: Option<serde_json::Value>,
}

impl Carried for Row {
    fn carried(&self) -> Parts<'_> {
        (
            &self.cluster,
            &self.frame,
            &self.method,
            self.report.as_ref(),
        )
    }
    fn carried_mut(&mut self) -> PartsMut<'_> {
        (
            &mut self.cluster,
            &mut self.frame,
            &mut self.method,
            &mut self.report,
        )
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

/// A number as Rust prints it (`0`, `0.866`, `1.4118200015218463`): the file's form since its
/// first version.
fn display<T: std::fmt::Display, S: Serializer>(v: &T, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(v)
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

/// The `method` column: the method's name (its knobs are the knob columns).
pub(crate) fn method_cell<S: Serializer>(m: &MethodSettings, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(m.method.name())
}

pub(crate) fn method_of_cell<'de, D: Deserializer<'de>>(d: D) -> Result<MethodSettings, D::Error> {
    Ok(MethodSettings {
        method: crate::method::Method::deserialize(d)?,
        ..Default::default()
    })
}

/// The field names of a struct that derives `Deserialize`, in order: what serde passes to
/// `deserialize_struct` (serde's names: renamed fields by their new name, skipped ones left out).
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

/// Every settings field a row carries, by serde name, in declaration order: `ClusterSettings`'
/// fields, then `FrameSettings`'. Each is a column of `results.csv` and `path.csv`: where the
/// contract placed it (`Layout::columns`), or else after the contract's columns in this order.
pub fn settings_columns() -> impl Iterator<Item = &'static str> {
    let cluster = fields_of::<ClusterSettings>().iter();
    cluster.chain(fields_of::<FrameSettings>()).copied()
}

/// What a row type carries beside its own columns: the settings it was made with, its method's
/// knobs and the method's report (one serde value, `Frame::report`'s), read from and written to
/// the settings, knob and report columns.
pub(crate) trait Carried {
    fn carried(&self) -> Parts<'_>;
    fn carried_mut(&mut self) -> PartsMut<'_>;
}

pub(crate) type Parts<'a> = (
    &'a ClusterSettings,
    &'a FrameSettings,
    &'a MethodSettings,
    Option<&'a serde_json::Value>,
);

pub(crate) type PartsMut<'a> = (
    &'a mut ClusterSettings,
    &'a mut FrameSettings,
    &'a mut MethodSettings,
    &'a mut Option<serde_json::Value>,
);

/// A CSV file's columns: `columns`, the contract's in order (a name is the row's own field or a
/// settings field), then the settings fields not among them (`settings_columns`' order), every
/// method's knobs and every method's report columns.
pub(crate) struct Layout {
    pub columns: &'static [&'static str],
    /// The last column every file has.
    pub required: &'static str,
    /// The settings columns whose cells the contract writes otherwise than serde.
    pub forms: &'static [Form],
}

/// A settings column in a form of its own (the contract's, older than the settings' serde form).
pub(crate) struct Form {
    pub column: &'static str,
    /// The cell from serde's text of the field (`Cell`) and the row's other settings cells (serde's
    /// text, by name).
    pub write: fn(&str, &[(&'static str, String)]) -> String,
    /// serde's text of the field from a non-empty cell, or why it is not one.
    pub read: fn(&str) -> Result<String, String>,
}

/// The columns of `results.csv` the contract names, in its order (docs/design.md, "Bench
/// outputs"): the row's own fields and the settings fields it placed among them.
pub const COLUMNS: &[&str] = &[
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
    "vpl_trace_ms",
    "vpl_cluster_ms",
    "primary_ms",
    "sp_cluster_ms",
    "visibility_ms",
    "shade_ms",
    "gather_ms",
    "direct_ms",
    "frame_ms",
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
    "flip",
    "border",
    "interior",
    "border_ratio",
    "flip_border",
    "target_ms",
    "front_mse",
    "method",
    "indirect_ms",
    "adapter",
    "driver",
];

/// `results.csv`'s layout: `target_ms` in scientific notation (`4e1`), as the error columns; γ read
/// also as a number (`4.0`).
pub(crate) const LAYOUT: Layout = Layout {
    columns: COLUMNS,
    required: "label",
    forms: &[
        Form {
            column: "target_ms",
            write: |text, _| match text.parse::<f64>() {
                Ok(v) => format!("{v:e}"),
                Err(_) => text.to_string(),
            },
            read: |text| Ok(text.to_string()),
        },
        Form {
            column: "gamma",
            write: |text, _| text.to_string(),
            read: gamma_text,
        },
    ],
};

/// γ as written (`auto` or the factor), or a number: serde's text of it.
fn gamma_text(text: &str) -> Result<String, String> {
    match text.parse::<Gamma>() {
        Ok(g) => Ok(g.to_string()),
        Err(e) => match text.trim().parse::<f64>() {
            Ok(g) => Ok((g as u32).to_string()),
            Err(_) => Err(e.to_string()),
        },
    }
}

/// The settings cells of a row, by name: serde's text of every field of `settings_columns` (empty
/// where serde skips it), then the layout's forms.
fn settings_cells(
    layout: &Layout,
    c: &ClusterSettings,
    f: &FrameSettings,
) -> Vec<(&'static str, String)> {
    let serde = [cells_of(c), cells_of(f)].concat();
    let at = |name: &str| serde.iter().find(|(n, _)| *n == name);
    let mut cells: Vec<(&'static str, String)> = settings_columns()
        .map(|name| (name, at(name).map_or(String::new(), |c| c.1.clone())))
        .collect();
    for form in layout.forms {
        if let Some(cell) = cells.iter_mut().find(|(n, _)| *n == form.column) {
            cell.1 = (form.write)(&cell.1, &serde);
        }
    }
    cells
}

/// The settings from a row's settings cells (name, text): an empty or missing cell reads the
/// default, a non-empty one its value (the layout's form read first; as JSON where the field takes
/// that, else as a string: `4` a number, `point` a string). An error names the column and the
/// text.
fn settings_of_cells<'a>(
    layout: &Layout,
    cells: impl Iterator<Item = (&'a str, &'a str)> + Clone,
) -> Result<(ClusterSettings, FrameSettings), String> {
    fn one<'a, T: DeserializeOwned>(
        layout: &Layout,
        cells: impl Iterator<Item = (&'a str, &'a str)>,
    ) -> Result<T, String> {
        use serde_json::Value;
        let fields = fields_of::<T>();
        let mut map = serde_json::Map::new();
        for (name, cell) in cells.filter(|(n, t)| !t.is_empty() && fields.contains(n)) {
            let text = match layout.forms.iter().find(|f| f.column == name) {
                Some(f) => (f.read)(cell).map_err(|e| format!("{name} {cell:?}: {e}"))?,
                None => cell.to_string(),
            };
            // The field alone: its value as JSON, else as a string.
            let alone = |v: &Value| {
                let object = Value::Object([(name.to_string(), v.clone())].into_iter().collect());
                serde_json::from_value::<T>(object).map(|_| ())
            };
            let json = serde_json::from_str::<Value>(&text).ok();
            let mut refused = None;
            let value = json
                .into_iter()
                .chain([Value::String(text.clone())])
                .find(|v| alone(v).map_err(|e| refused.get_or_insert(e)).is_ok());
            match value {
                Some(v) => map.insert(name.to_string(), v),
                None => {
                    let e = refused.map_or(String::new(), |e| e.to_string());
                    return Err(format!("{name} {cell:?}: {e}"));
                }
            };
        }
        serde_json::from_value(Value::Object(map)).map_err(|e| e.to_string())
    }
    Ok((one(layout, cells.clone())?, one(layout, cells)?))
}

/// A layout's header: its columns, the settings fields not among them, then every method's knobs
/// and every method's report columns (`method::report_columns`).
pub(crate) fn header_of(layout: &Layout) -> Vec<String> {
    let settings = settings_columns().filter(|c| !layout.columns.contains(c));
    let columns = layout.columns.iter().copied().chain(settings);
    columns
        .chain(MethodSettings::columns())
        .chain(crate::method::report_columns())
        .map(String::from)
        .collect()
}

/// The header, in order.
pub fn header() -> Vec<String> {
    static HEADER: OnceLock<Vec<String>> = OnceLock::new();
    HEADER.get_or_init(|| header_of(&LAYOUT)).clone()
}

/// The device's columns, after the method's: files written before them have neither.
pub const ADAPTER_COLUMNS: [&str; 2] = ["adapter", "driver"];

/// The method's columns, after the error columns: `method` (the `method::Method`'s name) and
/// `indirect_ms`. Files written before them have neither.
pub const METHOD_COLUMNS: [&str; 2] = ["method", "indirect_ms"];

/// A row's own columns (its serde fields) as the `csv` crate writes them, by name.
fn own_cells<T: Serialize + DeserializeOwned>(r: &T) -> Vec<(&'static str, String)> {
    let mut w = ::csv::WriterBuilder::new()
        .has_headers(false)
        .from_writer(Vec::new());
    w.serialize(r).expect("writing to memory");
    let bytes = w.into_inner().expect("writing to memory");
    let record = ::csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(bytes.as_slice())
        .records()
        .next()
        .expect("one record")
        .expect("the csv crate reads what it wrote");
    let names = fields_of::<T>().iter().copied();
    names.zip(record.iter().map(String::from)).collect()
}

/// `rows` under `layout`'s header as CSV text, `\n` line ends: each row's own fields and settings
/// in the layout's columns, then its knobs and report.
pub(crate) fn write_rows<T: Serialize + DeserializeOwned + Carried>(
    layout: &Layout,
    rows: &[T],
) -> String {
    let header = header_of(layout);
    let knobs_at = header.len() - MethodSettings::columns().len();
    let knobs_at = knobs_at - crate::method::report_columns().len();
    let mut w = ::csv::WriterBuilder::new()
        .has_headers(false)
        .terminator(::csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    w.write_record(&header).expect("writing to memory");
    for r in rows {
        let own = own_cells(r);
        let (c, f, m, report) = r.carried();
        let settings = settings_cells(layout, c, f);
        let cell = |name: &str| {
            let mut all = own.iter().chain(&settings);
            all.find(|(n, _)| *n == name).map_or("", |c| c.1.as_str())
        };
        let mut record: Vec<String> = header[..knobs_at]
            .iter()
            .map(|h| cell(h).to_string())
            .collect();
        record.extend(m.column_values());
        record.extend(crate::method::report_values(m.method, report));
        w.write_record(&record).expect("writing to memory");
    }
    String::from_utf8(w.into_inner().expect("writing to memory")).expect("UTF-8 fields")
}

/// The whole file: header and rows, `\n` line ends.
pub fn to_csv(rows: &[Row]) -> String {
    write_rows(&LAYOUT, rows)
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

/// A file's rows as `T` (a row type written by `write_rows` under `layout`, or by an older
/// version). The header, less the report columns (found by name wherever they stand: older files
/// have some of them among the others), is a prefix of the layout's columns through at least
/// `required`, then any of the generated columns (settings fields not among the layout's, knobs),
/// each once, by name: files written before a block have none of it. A missing column reads its
/// default; `fix` completes a row from what the header lacks.
pub(crate) fn read_rows<T: DeserializeOwned + Carried>(
    text: &str,
    layout: &Layout,
    fix: impl Fn(&mut T, &::csv::StringRecord),
) -> Result<Vec<T>> {
    let mut reader = ::csv::ReaderBuilder::new()
        .flexible(true)
        .from_reader(text.as_bytes());
    let head = reader.headers().context("reading the header")?.clone();
    let h: Vec<&str> = head.iter().collect();
    let report = crate::method::report_columns();
    let knobs = MethodSettings::columns();
    let cols: Vec<&str> = h.iter().copied().filter(|c| !report.contains(c)).collect();
    let listed = (cols.iter().zip(layout.columns))
        .take_while(|(a, b)| a == b)
        .count();
    let required = layout.columns.iter().position(|c| *c == layout.required);
    let generated = |c: &&str| {
        !layout.columns.contains(c) && (settings_columns().any(|s| s == *c) || knobs.contains(c))
    };
    let mut seen = cols.clone();
    seen.sort();
    seen.dedup();
    if required.is_none_or(|r| listed <= r)
        || !cols[listed..].iter().all(generated)
        || seen.len() != cols.len()
    {
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
        let cells = h.iter().copied().zip(record.iter());
        let (c, f, m, row_report) = row.carried_mut();
        (*c, *f) = settings_of_cells(layout, cells.clone())
            .map_err(|e| anyhow::anyhow!("line {line}: {e}"))?;
        for (name, text) in cells.clone() {
            if let Some(Err(e)) = m.set_column(name, text).filter(|_| !text.is_empty()) {
                bail!("line {line}: {name} {text:?}: {e}");
            }
        }
        *row_report = crate::method::report_of_cells(m.method, cells);
        fix(&mut row, &head);
        rows.push(row);
    }
    Ok(rows)
}

/// Reads a file written by `to_csv` back, or by an older version (for tests and tools).
pub fn from_csv(text: &str) -> Result<Vec<Row>> {
    read_rows(text, &LAYOUT, |r: &mut Row, head| {
        if !head.iter().any(|h| h == "indirect_ms") {
            r.indirect_ms = r.indirect_of_stages();
        }
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::method::Method;
    use crate::settings::{ClusterLight, Gamma};

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
            mode: mode.into(),
            reference_ms: 50.0,
            mse: bias * 1e-2 / k.sqrt(),
            rel_mse: bias * 1e-1 / k.sqrt(),
            sp_clusters_used: sp.saturating_sub(1),
            vpl_clusters_used: vpl,
            shadow_rays: 123_456_789_012,
            repeat: 3,
            label: format!("{mode} {sp}/{vpl}"),
            gamma_used: Some(4),
            flip: Some(bias * 0.05),
            border: Some(bias * 1e-4),
            interior: Some(1e-4),
            border_ratio: Some(bias),
            flip_border: Some(bias * 0.06),
            front_mse: None,
            method: MethodSettings::default(),
            indirect_ms: 0.0,
            adapter: "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, Mesa 22.3.6 (LLVM 15.0.6))".into(),
            driver: "llvmpipe Mesa 22.3.6 (LLVM 15.0.6)".into(),
            cluster: ClusterSettings {
                sp_clusters: sp,
                vpl_clusters: vpl,
                fuzziness: 6,
                gamma: Gamma::Fixed(4),
                normal_threshold: 0.866,
                iterations: 10,
                weight_exponent: 1.0,
                plane_gate: None,
                target_ms: None,
                ..Default::default()
            },
            frame: FrameSettings {
                width: 96,
                height: 72,
                vpls: 1024,
                ..Default::default()
            },
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

    /// The cell of column `c` in line `n` (1: the first row) of `text`.
    pub fn cell(text: &str, n: usize, c: &str) -> String {
        let head = split_line(text.lines().next().unwrap());
        let at = head
            .iter()
            .position(|h| h == c)
            .unwrap_or_else(|| panic!("no {c}"));
        split_line(text.lines().nth(n).unwrap())[at].clone()
    }

    /// `text` without the columns `drop` names.
    pub fn without(text: &str, drop: impl Fn(&str) -> bool) -> String {
        let head = split_line(text.lines().next().unwrap());
        let keep: Vec<usize> = (0..head.len()).filter(|&i| !drop(&head[i])).collect();
        write_records(text.lines().map(|l| {
            let f = split_line(l);
            keep.iter().map(|&i| f[i].clone()).collect()
        }))
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
        r.cluster.gamma = Gamma::Auto;
        let csv = to_csv(std::slice::from_ref(&r));
        assert!(csv.contains(",auto,"), "{csv}");
        assert_eq!(from_csv(&csv).unwrap(), vec![r]);
    }

    /// Settings without a column of the contract's are columns too (generated from their
    /// declarations), each as serde writes it, and read back.
    #[test]
    fn settings_round_trip_in_their_columns() {
        let mut r = synthetic("weighted", 48, 128);
        let c = &mut r.cluster;
        (c.temporal, c.temporal_alpha, c.visibility_facing) = (true, 0.25, true);
        (c.cluster_light, c.reseed) = (ClusterLight::Point, false);
        (r.frame.seed, r.frame.clamp, r.frame.indirect_scale) = (7, 0.05, 0.5);
        let text = to_csv(std::slice::from_ref(&r));
        let text_of = |c: &str| cell(&text, 1, c);
        let cell = |a: &str, b: &str| (text_of(a), text_of(b));
        assert_eq!(
            cell("temporal", "temporal_alpha"),
            ("true".into(), "0.25".into())
        );
        assert_eq!(text_of("visibility_facing"), "true");
        assert_eq!(
            cell("cluster_light", "reseed"),
            ("point".into(), "false".into())
        );
        assert_eq!(cell("seed", "clamp"), ("7".into(), "0.05".into()));
        assert_eq!(
            cell("indirect_scale", "weighting"),
            ("0.5".into(), "inverse-distance".into())
        );
        assert_eq!(from_csv(&text).unwrap(), vec![r.clone()]);
        // Without those columns (a file of an older version), the settings read their defaults.
        let extra: Vec<&str> = settings_columns()
            .filter(|c| !COLUMNS.contains(c))
            .collect();
        let old = from_csv(&without(&text, |c| extra.contains(&c))).unwrap();
        let d = ClusterSettings::default();
        assert_eq!(
            (old[0].cluster.temporal, old[0].cluster.temporal_alpha),
            (d.temporal, d.temporal_alpha)
        );
        assert_eq!(old[0].frame.seed, FrameSettings::default().seed);
        assert_eq!(old[0].cluster.sp_clusters, 48);
        // A cell a setting refuses is an error naming its line and column.
        let bad = text.replacen(",point,", ",pointy,", 1);
        let e = from_csv(&bad).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("cluster_light"), "{e}");
        let head = split_line(text.lines().next().unwrap());
        let mut line = split_line(text.lines().nth(1).unwrap());
        line[head.iter().position(|h| h == "seed").unwrap()] = "-1".into();
        let e = from_csv(&write_records([head, line]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 2") && e.contains("seed \"-1\""), "{e}");
    }

    /// Every settings field (`ClusterSettings`, `FrameSettings`) is a column of both files, once,
    /// named as serde names it: the contract's where it placed it, the others after the contract's
    /// columns in declaration order, before the knobs.
    #[test]
    fn every_settings_field_is_a_column_of_both_files() {
        let fields: Vec<&str> = fields_of::<ClusterSettings>()
            .iter()
            .chain(fields_of::<FrameSettings>())
            .copied()
            .collect();
        assert!(fields.contains(&"plane_gate_deg") && fields.contains(&"seed"));
        let path = crate::bench::path::COLUMNS;
        for (h, listed) in [(header(), COLUMNS), (crate::bench::path::header(), path)] {
            for f in &fields {
                assert_eq!(h.iter().filter(|c| c == f).count(), 1, "{f} in {h:?}");
            }
            let rest: Vec<&str> = fields
                .iter()
                .copied()
                .filter(|f| !listed.contains(f))
                .collect();
            let at = listed.len();
            assert_eq!(h[..at], listed[..]);
            assert_eq!(h[at..at + rest.len()], rest[..]);
            assert_eq!(h[at + rest.len()], MethodSettings::columns()[0]);
        }
    }

    #[test]
    fn a_method_row_keeps_its_knobs_in_their_columns() {
        // A method whose knobs are the paper's has no knob columns of its own.
        for entry in crate::method::REGISTRY.iter().filter(|r| r.own_settings) {
            let mut r = synthetic(entry.method.name(), 0, 0);
            r.method.method = entry.method;
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
            assert!(!own.is_empty(), "{}", entry.method);
            let knobs = head.len()
                - MethodSettings::columns().len()
                - crate::method::report_columns().len();
            for (i, v) in line.iter().enumerate().skip(knobs) {
                assert_eq!(
                    v.is_empty(),
                    !own.contains(&i),
                    "{} column {}",
                    entry.method,
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
        // Drop the report columns, the knob columns and the generated settings columns: files of
        // the versions before them.
        let report = crate::method::report_columns();
        let csv = without(&csv, |c| report.contains(&c));
        assert_eq!(from_csv(&csv).unwrap(), vec![r.clone()]);
        let csv = without(&csv, |c| MethodSettings::columns().contains(&c));
        assert_eq!(from_csv(&csv).unwrap(), vec![r.clone()]);
        let csv = without(&csv, |c| !COLUMNS.contains(&c));
        assert_eq!(from_csv(&csv).unwrap(), vec![r.clone()]);
        let cut_n = |text: &str, n: usize| {
            write_records(text.lines().map(|l| {
                let f = split_line(l);
                f[..f.len() - n].to_vec()
            }))
        };
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
            (Method::default(), r.flip)
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
        assert_eq!(back[0].cluster.weight_exponent, 1.0);
        assert_eq!(back[0].gamma_used, None);
        assert_eq!(back[0].cluster.plane_gate, None);
        assert_eq!(back[0].method.method, Method::default());
        let want = r.frame_ms() - r.stage("primary") - r.stage("direct");
        assert!((back[0].indirect_ms - want).abs() < 1e-9);
        assert_eq!(back[0].indirect_ms, r.indirect_of_stages());
        assert_eq!(back[0].label, r.label);
        // Not a prefix of the contract's columns, or short of `label`: refused.
        assert!(from_csv(&old.replacen("scene,camera", "camera,scene", 1)).is_err());
        let short = cut(&old);
        assert!(from_csv(&short).is_err());
    }

    /// A file as the version before the generated settings columns wrote it (commit d05e11d:
    /// the contract's columns, then the knobs and the report columns): its rows read, and written
    /// again every one of its columns has the same text.
    #[test]
    fn a_file_before_the_settings_columns_reads_and_keeps_its_text() {
        let old = include_str!("testdata/results-d05e11d.csv");
        let rows = from_csv(old).unwrap();
        let mut want = synthetic("weighted", 48, 128);
        let c = &mut want.cluster;
        (c.plane_gate, c.target_ms, c.weight_exponent) = (Some(20.0), Some(40.0), 2.0);
        want.report = Some(serde_json::json!({
            "sp_iterations": 3, "sp_warm_kept": 40, "visibility_rows_reused": 0
        }));
        assert_eq!(rows, vec![want]);
        let again = to_csv(&rows);
        for c in split_line(old.lines().next().unwrap()) {
            assert_eq!(cell(&again, 1, &c), cell(old, 1, &c), "{c}");
        }
    }

    /// The header is the contract's columns (the stage columns `stages()` after `iterations`),
    /// the other settings, then the knobs, then the report columns; no two columns share a name,
    /// every own field of a row is a column, and `stage` reads each stage's own column.
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
        // The contract's columns are each a row's field or a setting, and every field is one.
        for (own, listed) in [
            (fields_of::<Row>(), COLUMNS),
            (
                fields_of::<crate::bench::path::PathRow>(),
                crate::bench::path::COLUMNS,
            ),
        ] {
            for c in listed {
                assert!(own.contains(c) ^ settings_columns().any(|s| s == *c), "{c}");
            }
            for f in own {
                assert!(listed.contains(f), "{f} has no column");
            }
        }
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
        (r.flip, r.border, r.cluster.target_ms, r.front_mse) =
            (Some(0.125), None, Some(40.0), Some(1e-9));
        (r.cluster.plane_gate, r.gamma_used) = (Some(20.0), None);
        r.cluster.weight_exponent = 2.0;
        // The last entry's method: its knobs (their defaults) filled, the others' empty.
        let entry = crate::method::REGISTRY.last().unwrap();
        r.method.method = entry.method;
        let text = to_csv(std::slice::from_ref(&r));
        let cell = |c: &str| cell(&text, 1, c);
        assert_eq!(
            (cell("vpl_trace_ms"), cell("gather_ms")),
            ("0".into(), "6".into())
        );
        assert_eq!(
            (cell("frame_ms"), cell("normal_threshold")),
            ("8".into(), "0.866".into())
        );
        assert_eq!(
            (cell("mse"), cell("rel_mse")),
            ("1.5e-7".into(), "2.5e-3".into())
        );
        assert_eq!(
            (cell("flip"), cell("border"), cell("target_ms")),
            ("1.25e-1".into(), "".into(), "4e1".into())
        );
        assert_eq!(
            (cell("plane_gate_deg"), cell("gamma_used")),
            ("20".into(), "".into())
        );
        assert_eq!(
            (cell("weight_exponent"), cell("indirect_ms")),
            ("2".into(), "3.75".into())
        );
        assert_eq!(
            (cell("width"), cell("height"), cell("vpls")),
            ("96".into(), "72".into(), "1024".into())
        );
        assert_eq!(cell("method"), entry.method.name());
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
            (r.label.as_str(), r.cluster.gamma, r.sp_clusters_used),
            ("weighted 48/128 F6 g4", Gamma::Fixed(4), 47)
        );
        assert_eq!((r.shade_ms, r.frame_ms(), r.mse), (2.5, 7.75, 1.2e-4));
        assert_eq!(
            (
                r.cluster.weight_exponent,
                r.gamma_used,
                r.cluster.plane_gate
            ),
            (1.0, None, None)
        );
        assert_eq!(
            (r.cluster.sp_clusters, r.cluster.vpl_clusters, r.frame.vpls),
            (48, 128, 1024)
        );
        assert_eq!((r.flip, r.border_ratio, r.front_mse), (None, None, None));
        assert_eq!(r.method, MethodSettings::default());
        assert_eq!((r.adapter.as_str(), r.driver.as_str()), ("", ""));
        // indirect_ms: the frame less primary rays and direct light.
        assert_eq!(r.indirect_ms, 7.75 - 0.5 - 0.75);
        // Written again, it has every column and reads back the same.
        assert_eq!(from_csv(&to_csv(&rows)).unwrap(), rows);
        // γ written as a number reads as the factor.
        let float = old.replacen(",4,0.866,", ",4.0,0.866,", 1);
        assert_eq!(from_csv(&float).unwrap()[0].cluster.gamma, Gamma::Fixed(4));
    }

    #[test]
    fn bad_csv_is_an_error() {
        assert!(from_csv("").is_err());
        assert!(from_csv("a,b\n1,2\n").is_err());
        let mut csv = to_csv(&[synthetic("hard", 48, 128)]);
        csv = csv.replace(",hard,", ",hard,extra,");
        assert!(from_csv(&csv).is_err());
        // A column no version wrote, or one twice: refused.
        let good = to_csv(&[synthetic("hard", 48, 128)]);
        assert!(from_csv(&good.replacen(",seed,", ",seeds,", 1)).is_err());
        assert!(from_csv(&good.replacen(",seed,", ",bounces,", 1)).is_err());
    }
}
