//! The methods that compute a frame's indirect light (docs/methods.md), each in its own folder: its
//! passes (a Rust module driving the WGSL file of its name, or the shared passes of `gi` it drives),
//! its resident and per-frame state, its production CPU stages and its knobs. All reuse the shared
//! passes of `gi` (VPLs, primary rays, direct light, the gather of Eq. 5) and reach the frame
//! through one trait, `IndirectMethod`. colom (the paper) is the default and every method's
//! reference; `registry!` below is the registry of the others (`REGISTRY`, `Method`, `MethodSettings`,
//! `MethodLists`), from which `render::Plan` picks a method's passes and state. A new method
//! is its folder and one line of the registry (docs/architecture.md, "Adding a method").

pub mod colom;

use std::any::Any;
use std::collections::BTreeMap;
use std::fmt;

use anyhow::Result;
#[cfg(feature = "cli")]
use clap::builder::PossibleValue;
use serde::{Deserialize, Serialize};

use crate::gi::dispatch::Gpu;
use crate::gi::pass::Pass;
use crate::gi::primary::CameraParams;
use crate::gi::reference::Reference;
use crate::gi::scene_gpu::SceneGpu;
use crate::gi::vpl_cluster::ResidentLights;
use crate::gi::vpl_trace::ResidentVpls;
use crate::gpu::GpuContext;
use crate::scene::Scene;
use crate::settings::{ClusterSettings, FrameSettings, Invalid, KnobWidget};

/// What a method's passes read from the frame: the scene and settings, the resident VPLs (and the
/// VPL clustering when the plan asks for one), the shared gather pass, the G-buffer of primary hits
/// and the buffer the indirect light goes to (vec4 a pixel, linear, render units).
pub struct FrameInputs<'a> {
    pub scene: &'a Scene,
    pub frame: &'a FrameSettings,
    pub cluster: &'a ClusterSettings,
    pub method: &'a MethodSettings,
    pub vpls: &'a ResidentVpls,
    pub lights: Option<&'a ResidentLights>,
    /// The gather of every light with its own shadow ray (`reference.wgsl`, Eq. 5).
    pub reference: &'a Reference,
    pub gbuffer: &'a wgpu::Buffer,
    /// The size the method's passes work at: the render scale's (`--indirect-scale`), else the
    /// image's (`pixels()` is its product).
    pub size: (u32, u32),
    /// The G-term clamp's distance in render units (`FrameSettings::d_min` of the scene's extent).
    pub d_min: f32,
    pub cam: CameraParams,
    pub indirect: &'a wgpu::Buffer,
}

impl FrameInputs<'_> {
    /// The pixels the method's passes work on (`size`'s product).
    pub fn pixels(&self) -> u32 {
        self.size.0 * self.size.1
    }
}

/// What a method's largest buffers are checked against before a frame (`MethodEntry::limits`): one
/// storage binding's bytes, the clustering settings and the lights its passes see.
pub struct Limits<'a> {
    pub max_binding: u64,
    pub cluster: &'a ClusterSettings,
    /// The VPL clusters asked (`lights_clustered`), or every VPL.
    pub lights: u32,
    pub lights_clustered: bool,
}

/// An entry's `limits` with no buffer beyond the frame's.
pub fn no_limits(_: &Limits) -> Result<(), String> {
    Ok(())
}

/// What a frame's indirect passes report for the stats (`Frame`): the shadow rays they traced, the
/// SP and VPL clusters they used, the CPU milliseconds of a pass's steps (added to its GPU time),
/// γ as the SP clustering sampled with (a setting as resolved, not a count), the method's own
/// report and the counts left on the GPU. A method's own counts are its report's, never fields here.
#[derive(Clone, Debug, Default)]
pub struct Tally {
    pub indirect_rays: u64,
    pub sp_used: u32,
    pub vpl_clusters_used: u32,
    pub cpu_ms: Vec<(Pass, f64)>,
    /// γ Alg. 1 sampled with (`kmeans::effective_gamma`): the stats' `settings.gamma_used`, the
    /// CSV's `gamma_used`; `None` when no SP clustering ran.
    pub gamma_used: Option<u32>,
    /// The method's own report (e.g. cvrtgi's sizes), one serde value: `Frame::report`, the stats'
    /// `counts.<method>`.
    pub report: Option<serde_json::Value>,
    /// Counts the GPU keeps: read back only when asked (`PendingReport::read`).
    pub pending: Option<std::sync::Arc<dyn PendingReport>>,
}

/// A method's counts left on the GPU (its clustering's counters, its pixels' rays summed there):
/// the frame's recording never waits for them, and they are read back only on request
/// (`GpuFrame::read`, `GpuFrame::counts`: the stats, the viewer's counts, the bench).
pub trait PendingReport: fmt::Debug + Send + Sync {
    /// Reads them back (a wait for the frame's passes and a few bytes).
    fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Resolved>;
}

/// A `PendingReport` read back: shadow rays to add to the frame's, the SP clusters used where the
/// GPU counted them, and the method's report (its keys join `Tally::report`'s).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Resolved {
    pub indirect_rays: u64,
    pub sp_used: Option<u32>,
    pub report: Option<serde_json::Value>,
}

/// A method's shadow rays summed on the GPU (`gi::sum`): its per-pixel counts never leave it.
#[derive(Debug)]
pub struct PendingRays(pub crate::gi::sum::PendingSum);

impl PendingReport for PendingRays {
    fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Resolved> {
        Ok(Resolved {
            indirect_rays: self.0.read(device, queue)?,
            ..Default::default()
        })
    }
}

/// `report` with `more`'s keys added (both objects), else whichever there is (`more` first).
pub fn join_reports(
    report: Option<serde_json::Value>,
    more: Option<serde_json::Value>,
) -> Option<serde_json::Value> {
    match (report, more) {
        (Some(serde_json::Value::Object(mut a)), Some(serde_json::Value::Object(b))) => {
            a.extend(b);
            Some(serde_json::Value::Object(a))
        }
        (a, b) => b.or(a),
    }
}

/// A method's resident state and the recording of its passes.
pub trait IndirectMethod: Any {
    /// Records `pass` (one of its entry's `passes`, in their order within a frame).
    /// `g`: the device, the scene's bind group and the profiler; `n`: what the frame counts.
    fn record(&mut self, pass: Pass, g: &mut Gpu, f: &FrameInputs, n: &mut Tally) -> Result<()>;

    /// The timings of resident stages (re)built during this frame, taken out of the frame's
    /// `timings` (they are not the frame's, as the VPLs' are not); none by default.
    fn take_resident_timings(
        &mut self,
        _timings: &mut BTreeMap<String, f64>,
    ) -> BTreeMap<String, f64> {
        BTreeMap::new()
    }

    /// Called after every frame, whether or not this method ran in it: a frame's state becomes
    /// the last frame's (what temporal reuse starts from); none by default.
    fn end_frame(&mut self) {}

    /// Takes the state the next frame would start from (`Renderer::warm_up` renders an untimed
    /// frame in between and puts it back); nothing by default.
    fn take_past(&mut self) -> Box<dyn Any> {
        Box::new(())
    }

    /// Puts back what `take_past` took.
    fn put_past(&mut self, _past: Box<dyn Any>) {}

    /// The last frame's SP clustering, where the method keeps one (tests, the views' cluster
    /// labels, `Renderer::sp_clustering`); none by default.
    fn sp_clustering(&self) -> Option<&crate::gi::kmeans::Clustering> {
        None
    }
}

/// A method in the registry: its name, its passes in order, how its state is built (the first time
/// a frame uses it on a scene's GPU data), what of colom's clustering it uses, and how its knobs are
/// shown and swept.
pub struct MethodEntry {
    pub method: Method,
    /// What `--method`'s help says of it (its possible value's line).
    pub doc: &'static str,
    pub passes: &'static [Pass],
    pub build: fn(&GpuContext, &SceneGpu) -> Box<dyn IndirectMethod>,
    /// It clusters the shading points with `--sp-clusters` as K (and needs 0 < K < pixels).
    pub clusters_sps: bool,
    /// Its lights are the resident VPL clusters (step 2, `--vpl-clusters`) with these knobs
    /// (else the VPLs).
    pub vpl_clusters: fn(&MethodSettings) -> bool,
    /// Refuses a frame whose largest buffer of its own exceeds a storage binding (the message
    /// names the options); `no_limits` where it has none.
    pub limits: fn(&Limits) -> Result<(), String>,
    /// Its knobs are its own (`MethodSettings`' field of its name); colom's are the paper's
    /// `ClusterSettings`, shown and swept on their own.
    pub own_settings: bool,
    /// One line for the viewer's method selector.
    pub about: &'static str,
    /// Its colour in the bench's plots (sRGB).
    pub colour: [u8; 3],
    /// Its knobs in a label: the bench's (`a0.3`), the viewer's series (`α 0.3`), file names
    /// (`a0.3`).
    pub label: fn(&MethodSettings) -> String,
    pub series: fn(&MethodSettings) -> String,
    pub short: fn(&MethodSettings) -> String,
    /// The keys of its report (`Tally::report`, what its pending counts read back) that the
    /// bench's `results.csv` and `path.csv` carry as columns (`report_columns`), in order.
    pub report_columns: &'static [&'static str],
}

/// Every method's report columns in registry order (the CSVs' last columns, after the knobs').
pub fn report_columns() -> Vec<&'static str> {
    REGISTRY
        .iter()
        .flat_map(|r| r.report_columns.iter().copied())
        .collect()
}

/// A row's values of `report_columns()`: its method's report's (numbers and text as they are,
/// empty where the key is absent or null), empty for the other methods'.
pub fn report_values(method: Method, report: Option<&serde_json::Value>) -> Vec<String> {
    REGISTRY
        .iter()
        .flat_map(|r| {
            r.report_columns.iter().map(move |key| {
                let v = report
                    .filter(|_| r.method == method)
                    .and_then(|v| v.get(key));
                match v {
                    None | Some(serde_json::Value::Null) => String::new(),
                    Some(serde_json::Value::String(s)) => s.clone(),
                    Some(v) => v.to_string(),
                }
            })
        })
        .collect()
}

/// `method`'s report from a row's cells of its report columns (`(column, text)`, any order, the
/// others' ignored): numbers as numbers, `true`/`false` as booleans, other text as text, empty
/// cells absent; `None` when no cell of its is filled.
pub fn report_of_cells<'a>(
    method: Method,
    cells: impl IntoIterator<Item = (&'a str, &'a str)>,
) -> Option<serde_json::Value> {
    let own = entry(method).report_columns;
    let map: serde_json::Map<String, serde_json::Value> = cells
        .into_iter()
        .filter(|(c, t)| own.contains(c) && !t.is_empty())
        .map(|(c, t)| {
            let v = serde_json::from_str::<serde_json::Value>(t)
                .ok()
                .filter(|v| v.is_number() || v.is_boolean())
                .unwrap_or_else(|| serde_json::Value::String(t.to_string()));
            (c.to_string(), v)
        })
        .collect();
    (!map.is_empty()).then_some(serde_json::Value::Object(map))
}

/// Declares the registry from one line a method (`module: Variant`), the method's folder (declared
/// beside it, `pub mod module;`, and holding its `ENTRY`, its knobs as `Settings` and their bench lists
/// as `Lists`, both made by `knobs!`): its `Method` variant (named `module` on the command line,
/// in JSON and in the CSV), its line of `REGISTRY`, its field `module` of `MethodSettings` (its knobs,
/// flattened into the CLI, the stats JSON and the CSV's last columns) and of `MethodLists`.
macro_rules! registry {
    ($($module:ident: $Variant:ident),+ $(,)?) => {

        /// The registry: colom (the paper, the default) and the others.
        pub const REGISTRY: &[MethodEntry] = &[colom::ENTRY, $($module::ENTRY),+];

        /// Which system computes the indirect light (docs/methods.md). Every method reuses the
        /// VPLs, the BVH, the primary rays, the direct light, the reference and the metrics, and
        /// adds only what its paper adds. colom is the default; the others are the registry's
        /// (`registry!`). (`Ord`: the renderer keeps the methods' state in a map by method.)
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub enum Method {
            /// Colom, Marques, Santos 2022, the paper this tool rebuilds (its entry's `doc`).
            #[default]
            Colom,
            $(
                #[doc = concat!("`", stringify!($module), "` (its entry's `doc`).")]
                $Variant,
            )+
        }

        impl Method {
            pub const ALL: [Method; 1 + [$(stringify!($module)),+].len()] =
                [Method::Colom, $(Method::$Variant),+];

            /// Its name on the command line, in JSON and in the CSV.
            pub fn name(self) -> &'static str {
                match self {
                    Method::Colom => "colom",
                    $(Method::$Variant => stringify!($module),)+
                }
            }
        }

        /// The method and every method's knobs (each declared in its module with `knobs!`),
        /// flattened into `render`, `view` and the stats JSON beside the paper's
        /// `ClusterSettings`.
        #[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
        #[cfg_attr(feature = "cli", derive(clap::Args))]
        #[serde(default)]
        pub struct MethodSettings {
            /// The method that computes the indirect light: colom (the paper this tool
            /// rebuilds), wang (Wang et al. 2009: irradiance at SP-cluster centres,
            /// interpolated), lightcluster (LightCluster: VPLs clustered by distance, a disc's
            /// visibility per cluster), cvrtgi (clustered voxel GI: irradiance per voxel face
            /// from voxel clusters), restir (ReSTIR DI over the VPLs: resampled candidates,
            /// temporal and spatial reuse). docs/methods.md.
            #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = Method::Colom, help_heading = METHOD_HEADING))]
            pub method: Method,
            $(
                #[cfg_attr(feature = "cli", command(flatten))]
                #[serde(flatten)]
                pub $module: $module::Settings,
            )+
        }

        impl MethodSettings {
            /// Every method's knobs as columns of the bench's `results.csv` and `path.csv`, in
            /// order (their last columns).
            pub fn columns() -> Vec<&'static str> {
                [$($module::Settings::NAMES),+].concat()
            }

            /// A row's values of `columns()`: its own method's knobs, empty for the other
            /// methods'.
            pub fn column_values(&self) -> Vec<String> {
                let own = |m: Method, v: Vec<String>| match self.method == m {
                    true => v,
                    false => vec![String::new(); v.len()],
                };
                [$(own(Method::$Variant, self.$module.values())),+].concat()
            }

            /// The asked method's knob `name` as text; `None` when it has no such knob.
            pub fn knob(&self, name: &str) -> Option<String> {
                match self.method {
                    Method::Colom => None,
                    $(Method::$Variant => self.$module.get(name),)+
                }
            }

            /// Sets the knob of column `name` from its text; `None` when no method has that
            /// knob.
            pub fn set_column(&mut self, name: &str, text: &str) -> Option<Result<(), Invalid>> {
                None$(.or_else(|| self.$module.set(name, text)))+
            }
        }

        /// The asked method's knobs as the viewer shows them (`knobs!`'s controls; none for colom,
        /// whose knobs are the paper's `ClusterSettings`).
        impl $crate::settings::Controlled for MethodSettings {
            fn controls(&self) -> &'static [KnobWidget] {
                match self.method {
                    Method::Colom => &[],
                    $(Method::$Variant => $module::Settings::CONTROLS,)+
                }
            }

            fn control(&self, name: &str) -> Option<serde_json::Value> {
                match self.method {
                    Method::Colom => None,
                    $(Method::$Variant => self.$module.control(name),)+
                }
            }

            fn set_control(&mut self, name: &str, v: serde_json::Value) -> bool {
                match self.method {
                    Method::Colom => false,
                    $(Method::$Variant => self.$module.set_control(name, v),)+
                }
            }
        }

        /// `bench`'s lists: the methods to compare and each method's knob lists.
        #[derive(Clone, Debug, Default, PartialEq)]
        #[cfg_attr(feature = "cli", derive(clap::Args))]
        pub struct MethodLists {
            /// Methods to compare: colom,wang,lightcluster,cvrtgi,restir (default colom;
            /// docs/methods.md). `--modes` and the fuzzy knobs apply to colom; a method that
            /// clusters the SPs (wang) also takes the K's and --iterations; each method's own
            /// knob lists follow.
            #[cfg_attr(feature = "cli", arg(long, value_name = "LIST", value_delimiter = ',', value_parser = parse_method))]
            pub methods: Vec<Method>,
            $(
                #[cfg_attr(feature = "cli", command(flatten))]
                pub $module: $module::Lists,
            )+
        }

        impl MethodLists {
            /// `method`'s knob combinations (`knobs!`'s `configs`) as `MethodSettings`; colom has
            /// none of its own (its lists are `bench::sweep::Sweep`'s): its defaults.
            pub fn configs_of(&self, method: Method) -> Vec<MethodSettings> {
                let with = |set: &dyn Fn(&mut MethodSettings)| {
                    let mut m = MethodSettings {
                        method,
                        ..Default::default()
                    };
                    set(&mut m);
                    m
                };
                match method {
                    Method::Colom => vec![with(&|_| {})],
                    $(Method::$Variant => self
                        .$module
                        .configs()
                        .into_iter()
                        .map(|k| with(&|m| m.$module = k))
                        .collect(),)+
                }
            }
        }
    };
}

// The registry: a method other than colom is its folder, its `mod` line and its line in `registry!`.
// The folders are declared outside the macro so that tools that walk `mod` declarations
// (cargo-mutants: docs/testing.md) see them.
pub mod cvrtgi;
pub mod lightcluster;
pub mod restir;
pub mod wang;

registry! {
    wang: Wang,
    lightcluster: LightCluster,
    cvrtgi: Cvrtgi,
    restir: Restir,
}

/// `method`'s registry entry.
pub fn entry(method: Method) -> &'static MethodEntry {
    REGISTRY
        .iter()
        .find(|r| r.method == method)
        .expect("every method has an entry")
}

/// How `method`'s state is built: its entry's `build`.
pub fn build(method: Method) -> fn(&GpuContext, &SceneGpu) -> Box<dyn IndirectMethod> {
    entry(method).build
}

/// The `--help` group of the method and its knobs.
pub const METHOD_HEADING: &str = "Method (docs/methods.md)";

/// A developer variable (`FVPL_*`) a method's passes read: an integer in `lo..=hi`. The
/// application checks its value before any work (a value out of range is one line, exit code 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EnvInteger {
    pub name: &'static str,
    pub lo: u32,
    pub hi: u32,
}

/// Every method's developer variables (each declared in its room).
pub const ENV_INTEGERS: &[EnvInteger] = &[colom::shade::PATTERNS_ENV, colom::shade::TILE_CULL_ENV];

impl Method {
    /// Its line in `--method`'s help.
    pub fn doc(self) -> &'static str {
        entry(self).doc
    }
}

/// The command line's names (`registry!`), each with its entry's `doc` in `--help`.
#[cfg(feature = "cli")]
impl clap::ValueEnum for Method {
    fn value_variants<'a>() -> &'a [Self] {
        &Method::ALL
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.name()).help(self.doc()))
    }
}

/// Serialised by its name (`"lightcluster"`).
impl Serialize for Method {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> Deserialize<'de> for Method {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Method, D::Error> {
        let name = String::deserialize(d)?;
        Method::ALL
            .into_iter()
            .find(|m| m.name() == name)
            .ok_or_else(|| serde::de::Error::custom(parse_method(&name).unwrap_err()))
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl MethodSettings {
    /// The asked method's registry entry.
    pub fn entry(&self) -> &'static MethodEntry {
        entry(self.method)
    }

    /// The asked method's registry entry where its knobs are its own (`MethodEntry::own_settings`; `None`: colom,
    /// whose knobs are the paper's `ClusterSettings`).
    pub fn entry_with_own_settings(&self) -> Option<&'static MethodEntry> {
        Some(self.entry()).filter(|r| r.own_settings)
    }
}

impl MethodLists {
    /// The methods asked, repeats dropped (default: colom).
    pub fn methods(&self) -> Vec<Method> {
        let mut out = Vec::new();
        for &m in &self.methods {
            if !out.contains(&m) {
                out.push(m);
            }
        }
        if out.is_empty() {
            out.push(Method::Colom);
        }
        out
    }
}

/// A method by its name (any case).
pub fn parse_method(item: &str) -> Result<Method, Invalid> {
    let item = item.trim();
    let mut known = Method::ALL.into_iter();
    known
        .find(|m| m.name().eq_ignore_ascii_case(item))
        .ok_or_else(|| {
            Invalid(format!(
                "unknown method (expected one of: {})",
                Method::ALL.map(|m| m.name()).join(", ")
            ))
        })
}

#[cfg(test)]
mod tests {
    /// Each struct a method declares for its shader with `gpu_struct!` is the text `build.rs` read
    /// from the declaration (`gpu::shader::rust_struct`, what `#import rust/NAME` inlines).
    #[test]
    fn every_gpu_struct_is_the_text_build_rs_read() {
        for (name, wgsl) in [
            ("CvParams", cvrtgi::CvParams::WGSL),
            ("VisParams", colom::visibility::VisParams::WGSL),
        ] {
            assert_eq!(crate::gpu::shader::rust_struct(name), Some(wgsl), "{name}");
        }
        let declared = crate::gpu::shader::FILES
            .iter()
            .filter(|(p, _)| p.starts_with("rust/"));
        assert_eq!(
            declared.count(),
            2,
            "a gpu_struct! this test does not check"
        );
    }

    use super::*;

    #[cfg(feature = "cli")]
    #[test]
    fn method_names_are_the_command_line_and_json_names() {
        use clap::ValueEnum;
        assert_eq!(Method::value_variants(), Method::ALL);
        for m in Method::ALL {
            assert_eq!(Method::from_str(m.name(), false), Ok(m));
            let j = serde_json::to_string(&m).unwrap();
            assert_eq!(j, format!("\"{}\"", m.name()));
            assert_eq!(serde_json::from_str::<Method>(&j).unwrap(), m);
        }
    }

    #[test]
    fn every_method_has_one_entry() {
        for m in Method::ALL {
            assert_eq!(entry(m).method, m);
            assert_eq!(REGISTRY.iter().filter(|r| r.method == m).count(), 1, "{m}");
            assert_eq!(entry(m).own_settings, m != Method::Colom, "{m}");
        }
        assert_eq!(REGISTRY.len(), Method::ALL.len());
    }

    /// `--method`'s possible values carry each method's line (colom's, its entry's `doc`), and an
    /// unknown name in JSON is refused with the names it may be.
    #[cfg(feature = "cli")]
    #[test]
    fn the_help_lines_are_the_entries_docs() {
        use clap::ValueEnum;
        for m in Method::ALL {
            let v = m.to_possible_value().unwrap();
            assert_eq!(v.get_name(), m.name());
            assert_eq!(v.get_help().unwrap().to_string(), m.doc());
        }
        assert!(
            Method::Colom
                .doc()
                .starts_with("Colom, Marques, Santos 2022")
        );
        assert!(Method::Wang.doc().starts_with("Wang et al. 2009"));
        let e = serde_json::from_str::<Method>("\"fuzzy\"")
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown method") && e.contains("cvrtgi"), "{e}");
    }

    /// A method's passes are named once: no two passes (the shared ones, every method's) share a
    /// name, which keys their timings, the stats and the CSV.
    #[test]
    fn pass_names_are_unique() {
        let mut names: Vec<&str> = Pass::TIMED.iter().map(|p| p.name()).collect();
        names.extend([Pass::PathTrace, Pass::Upsample].map(|p| p.name()));
        // colom's passes are among the contract's timed ones (`Pass::TIMED`).
        for r in REGISTRY.iter().filter(|r| r.own_settings) {
            assert!(!r.passes.is_empty(), "{}", r.method);
            names.extend(r.passes.iter().map(|p| p.name()));
        }
        let mut sorted = names.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), names.len(), "{names:?}");
    }

    /// The methods' developer variables are `FVPL_*`, named once, each with a range.
    #[test]
    fn env_integers_are_named_once() {
        for (i, v) in ENV_INTEGERS.iter().enumerate() {
            assert!(v.name.starts_with("FVPL_") && v.lo <= v.hi, "{v:?}");
            assert!(ENV_INTEGERS[..i].iter().all(|w| w.name != v.name), "{v:?}");
        }
    }

    /// Reports join key by key; one alone is kept.
    #[test]
    fn reports_join() {
        let a = serde_json::json!({"a": 1, "b": 2});
        let b = serde_json::json!({"b": 3, "c": 4});
        assert_eq!(
            join_reports(Some(a.clone()), Some(b.clone())),
            Some(serde_json::json!({"a": 1, "b": 3, "c": 4}))
        );
        assert_eq!(join_reports(Some(a.clone()), None), Some(a));
        assert_eq!(join_reports(None, Some(b.clone())), Some(b));
        assert_eq!(join_reports(None, None), None);
    }

    /// The knobs' columns follow the registry's order, a method's own filled and the others' empty.
    #[test]
    fn knob_columns_follow_the_registry() {
        let want: Vec<&str> = REGISTRY
            .iter()
            .filter(|r| r.own_settings)
            .flat_map(|r| {
                let m = MethodSettings {
                    method: r.method,
                    ..Default::default()
                };
                MethodSettings::columns()
                    .into_iter()
                    .zip(m.column_values())
                    .filter(|(_, v)| !v.is_empty())
                    .map(|(c, _)| c)
                    .collect::<Vec<_>>()
            })
            .collect();
        assert_eq!(want, MethodSettings::columns());
        assert!(
            MethodSettings::default()
                .column_values()
                .iter()
                .all(String::is_empty)
        );
    }
}
