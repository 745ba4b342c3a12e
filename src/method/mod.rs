//! The methods that compute a frame's indirect light (docs/methods.md), each in its own folder: its
//! passes (a Rust module driving the WGSL file of its name, or the shared passes of `gi` it drives),
//! its resident and per-frame state, its production CPU stages and its knobs. All reuse the shared
//! passes of `gi` (VPLs, primary rays, direct light, the gather of Eq. 5) and reach the frame
//! through one trait, `IndirectMethod`. colom (the paper) is the default and every method's
//! reference; `ROOMS` is the registry of the others, from which `render::pipeline` picks a
//! method's passes and state.

pub mod colom;
pub mod cvrtgi;
pub mod lightcluster;
pub mod wang;

use std::any::Any;
use std::collections::BTreeMap;
use std::fmt;

use anyhow::Result;
use clap::Args;
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
use crate::settings::{ClusterSettings, FrameSettings, Invalid};

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
    pub pixels: u32,
    pub cam: CameraParams,
    pub indirect: &'a wgpu::Buffer,
}

/// What a frame's indirect passes report for the stats (`Frame`): the shadow rays they traced, the
/// SP and VPL clusters they used, and the CPU milliseconds of a pass's steps (added to its GPU time).
#[derive(Clone, Debug, Default)]
pub struct Counts {
    pub indirect_rays: u64,
    pub sp_used: u32,
    pub vpl_clusters_used: u32,
    pub cpu_ms: Vec<(Pass, f64)>,
    /// colom's SP k-means: iterations run, centroids the warm start kept, γ used; visibility rows
    /// copied instead of traced (`Frame`'s fields of the same names).
    pub sp_iterations: u32,
    pub sp_warm_kept: Option<u32>,
    pub gamma_used: Option<u32>,
    pub rows_reused: u32,
}

/// A method's resident state and the recording of its passes.
pub trait IndirectMethod: Any {
    /// Records `pass` (one of its room's `passes`, in their order within a frame).
    /// `g`: the device, the scene's bind group and the profiler; `n`: what the frame counts.
    fn record(&mut self, pass: Pass, g: &mut Gpu, f: &FrameInputs, n: &mut Counts) -> Result<()>;

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
}

/// A method in the registry: its name, its passes in order, how its state is built (the first time
/// a frame uses it on a scene's GPU data), what of colom's clustering it uses, and how its knobs are
/// shown and swept.
pub struct Room {
    pub method: Method,
    pub passes: &'static [Pass],
    pub build: fn(&GpuContext, &SceneGpu) -> Box<dyn IndirectMethod>,
    /// It clusters the shading points with `--sp-clusters` as K (and needs 0 < K < pixels).
    pub clusters_sps: bool,
    /// Its lights are colom's resident VPL clusters (step 2, `--vpl-clusters`).
    pub vpl_clusters: bool,
    /// One line for the viewer's method selector.
    pub about: &'static str,
    /// Its colour in the bench's plots (sRGB).
    pub colour: [u8; 3],
    /// Its knobs in a label: the bench's (`a0.3`), the viewer's series (`α 0.3`), file names
    /// (`a0.3`).
    pub label: fn(&MethodSettings) -> String,
    pub series: fn(&MethodSettings) -> String,
    pub short: fn(&MethodSettings) -> String,
    /// Its knobs in the viewer's panel.
    pub ui: fn(&mut egui::Ui, &mut MethodSettings),
    /// Its knobs' combinations in a bench sweep (`knobs!`'s `configs`).
    pub sweep: fn(&MethodLists) -> Vec<MethodSettings>,
}

/// The registry. colom (the paper) is not here: its passes are the renderer's own, since every
/// method's reference is colom's unclustered gather.
pub const ROOMS: &[Room] = &[wang::ROOM, lightcluster::ROOM, cvrtgi::ROOM];

/// `method`'s room, `None` for colom.
pub fn room(method: Method) -> Option<&'static Room> {
    ROOMS.iter().find(|r| r.method == method)
}

/// How `method`'s state is built: its room's `build`, or colom's.
pub fn build(method: Method) -> fn(&GpuContext, &SceneGpu) -> Box<dyn IndirectMethod> {
    room(method).map_or(colom::build, |r| r.build)
}

/// The `--help` group of the method and its knobs.
pub const METHOD_HEADING: &str = "Method (docs/methods.md)";

/// Which system computes the indirect light (docs/methods.md). Every method reuses the VPLs, the
/// BVH, the primary rays, the direct light, the reference and the metrics, and adds only what its
/// paper adds. A method other than colom is a variant here, a field of `MethodSettings` (its
/// knobs), a line of `ROOMS`, its passes in `gi::pass::Pass`, and its folder.
/// (`Ord`: the renderer keeps the methods' state in a map by method.)
#[derive(
    clap::ValueEnum,
    Serialize,
    Deserialize,
    Default,
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    PartialOrd,
    Ord,
)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Colom, Marques, Santos 2022 (seed 000): fuzzy k-means of SPs and VPLs, visibility between
    /// cluster representatives, Eq. (6) shading per pixel × VPL cluster.
    #[default]
    Colom,
    /// Wang et al. 2009 (seed 001): adaptively seeded k-means of the SPs (§3.2, Eq. 2), irradiance
    /// gathered only at the cluster centres, interpolated per pixel with the §3.4 weight.
    Wang,
    /// LightCluster (seed 002): the VPLs clustered by the minimum-distance (leader) algorithm
    /// (§3.1, d_min = d_init (1 − |C_pos| / z_far)), each cluster a disc light of radius d_min
    /// whose visibility a few shadow rays over the disc estimate (§3.2), every VPL shaded with its
    /// cluster's visibility.
    #[value(name = "lightcluster")]
    #[serde(rename = "lightcluster")]
    LightCluster,
    /// CVRTGI (Cosin Ayerbe & Patow 2022, seed 003): the scene voxelised, voxels clustered by SLIC
    /// with the 35° normal rule (Eq. 1, Alg. 1), per-voxel-face irradiance from the lit clusters a
    /// face's rays find, filtered, read by every pixel; cached while the lights stay.
    Cvrtgi,
}

impl Method {
    pub const ALL: [Method; 4] = [
        Method::Colom,
        Method::Wang,
        Method::LightCluster,
        Method::Cvrtgi,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Method::Colom => "colom",
            Method::Wang => "wang",
            Method::LightCluster => "lightcluster",
            Method::Cvrtgi => "cvrtgi",
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The method and every method's knobs (each declared in its room with `knobs!`), flattened into
/// `render`, `view` and the stats JSON beside the paper's `ClusterSettings`.
#[derive(Args, Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MethodSettings {
    /// The method that computes the indirect light: colom (the paper this tool rebuilds), wang
    /// (Wang et al. 2009: irradiance at SP-cluster centres, interpolated), lightcluster
    /// (LightCluster: VPLs clustered by distance, a disc's visibility per cluster), cvrtgi (clustered
    /// voxel GI: irradiance per voxel face from voxel clusters). docs/methods.md.
    #[arg(long, value_enum, default_value_t = Method::Colom, help_heading = METHOD_HEADING)]
    pub method: Method,
    #[command(flatten)]
    #[serde(flatten)]
    pub wang: wang::settings::WangSettings,
    #[command(flatten)]
    #[serde(flatten)]
    pub lightcluster: lightcluster::settings::LightClusterSettings,
    #[command(flatten)]
    #[serde(flatten)]
    pub cvrtgi: cvrtgi::settings::CvrtgiSettings,
}

impl MethodSettings {
    /// The asked method's room (`None`: colom).
    pub fn room(&self) -> Option<&'static Room> {
        room(self.method)
    }

    /// Every method's knobs as columns of the bench's `results.csv`, in order (its last columns).
    pub fn columns() -> Vec<&'static str> {
        [
            wang::settings::WangSettings::NAMES,
            lightcluster::settings::LightClusterSettings::NAMES,
            cvrtgi::settings::CvrtgiSettings::NAMES,
        ]
        .concat()
    }

    /// A row's values of `columns()`: its own method's knobs, empty for the other methods'.
    pub fn column_values(&self) -> Vec<String> {
        let own = |m: Method, v: Vec<String>| match self.method == m {
            true => v,
            false => vec![String::new(); v.len()],
        };
        [
            own(Method::Wang, self.wang.values()),
            own(Method::LightCluster, self.lightcluster.values()),
            own(Method::Cvrtgi, self.cvrtgi.values()),
        ]
        .concat()
    }

    /// Sets the knob of column `name` from its text; `None` when no method has that knob.
    pub fn set_column(&mut self, name: &str, text: &str) -> Option<Result<(), Invalid>> {
        self.wang
            .set(name, text)
            .or_else(|| self.lightcluster.set(name, text))
            .or_else(|| self.cvrtgi.set(name, text))
    }
}

/// `bench`'s lists: the methods to compare and each method's knob lists.
#[derive(Args, Clone, Debug, Default, PartialEq)]
pub struct MethodLists {
    /// Methods to compare: colom,wang,lightcluster,cvrtgi (default colom; docs/methods.md).
    /// `--modes` and the fuzzy knobs apply to colom; a method that clusters the SPs (wang) also
    /// takes the K's and --iterations; each method's own knob lists follow.
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = parse_method)]
    pub methods: Vec<Method>,
    #[command(flatten)]
    pub wang: wang::settings::WangLists,
    #[command(flatten)]
    pub lightcluster: lightcluster::settings::LightClusterLists,
    #[command(flatten)]
    pub cvrtgi: cvrtgi::settings::CvrtgiLists,
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

/// A room's knob combinations (`knobs!`'s `configs`) as `MethodSettings` of `method`, each set into
/// its field by `set` (`Room::sweep`).
pub fn sweep_of<T>(
    method: Method,
    configs: Vec<T>,
    set: fn(&mut MethodSettings, T),
) -> Vec<MethodSettings> {
    configs
        .into_iter()
        .map(|k| {
            let mut m = MethodSettings {
                method,
                ..Default::default()
            };
            set(&mut m, k);
            m
        })
        .collect()
}

/// A knob's logarithmic slider in a room's panel section.
pub fn log_slider(
    ui: &mut egui::Ui,
    v: &mut f32,
    range: std::ops::RangeInclusive<f32>,
    text: &str,
) {
    ui.add(egui::Slider::new(v, range).logarithmic(true).text(text));
}

pub fn parse_method(item: &str) -> Result<Method, Invalid> {
    <Method as clap::ValueEnum>::from_str(item.trim(), true).map_err(|_| {
        Invalid(format!(
            "unknown method (expected one of: {})",
            Method::ALL.map(|m| m.name()).join(", ")
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn every_method_but_colom_has_a_room() {
        for m in Method::ALL {
            assert_eq!(room(m).is_some(), m != Method::Colom, "{m}");
        }
    }
}
