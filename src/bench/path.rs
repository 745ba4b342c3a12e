//! `bench --camera-path orbit:N:DEG [--temporal off,on]`: the clustered frame along a camera path,
//! each frame against its own unclustered reference (same VPLs, direct-light samples and seed), so
//! that what temporal reuse buys (SP clustering time) and costs (error) is measured frame by frame,
//! with `instability` (`metrics::instability`): how much the clustering error changes between
//! consecutive frames. Writes `path.csv` (a `PathRow` a frame, its columns laid out as
//! `results.csv`'s: the contract's, then every other settings field, the method knobs and the
//! report columns) and `path.png`.

use std::path::Path;

use anyhow::{Result, anyhow};
use glam::{Mat4, Vec3, Vec3A};
use plotters::prelude::*;
use serde::{Deserialize, Serialize};

use super::BenchPlan;
use super::sweep::{self, Config};
use crate::bvh::SceneBvh;
use crate::gi::pass::Pass;
use crate::gi::primary::CameraParams;
use crate::gpu::GpuContext;
use crate::method::MethodSettings;
use crate::render::timed::{FrameKind, FrameLoop, Timing, timed};
use crate::render::{FRAME_KEY, Frame, RenderSettings, Renderer};
use crate::scene::{Camera, Scene};
use crate::settings::{ClusterSettings, FrameSettings};
use crate::{export, metrics};

/// An orbit of `degrees` in all, in `frames` frames, about the vertical axis through the point the
/// start camera looks at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPath {
    pub frames: u32,
    pub degrees: f32,
}

/// `orbit:N:DEG` (N ≥ 1 frames, a finite angle in degrees).
pub fn parse_camera_path(v: &str) -> Result<CameraPath, String> {
    let bad =
        || format!("'{v}': expected orbit:N:DEG (N frames, DEG degrees in all), e.g. orbit:6:3");
    let parts: Vec<&str> = v.trim().split(':').collect();
    match parts.as_slice() {
        ["orbit", n, deg] => {
            let frames: u32 = n.parse().map_err(|_| bad())?;
            let degrees: f32 = deg.parse().map_err(|_| bad())?;
            if frames == 0 || frames > 100_000 || !degrees.is_finite() {
                return Err(bad());
            }
            Ok(CameraPath { frames, degrees })
        }
        _ => Err(bad()),
    }
}

impl CameraPath {
    /// The cameras of the path: `start` turned by DEG · i / (N − 1) about the vertical (+Y, glTF's
    /// up) axis through `target`; the first is `start` itself.
    pub fn cameras(&self, start: &Camera, target: Vec3) -> Vec<Camera> {
        (0..self.frames)
            .map(|i| {
                let t = if self.frames > 1 {
                    i as f32 / (self.frames - 1) as f32
                } else {
                    0.0
                };
                let turn = Mat4::from_translation(target)
                    * Mat4::from_rotation_y((self.degrees * t).to_radians())
                    * Mat4::from_translation(-target);
                Camera {
                    name: format!("{} orbit {i}", start.name),
                    transform: turn * start.transform,
                    yfov: start.yfov,
                }
            })
            .collect()
    }
}

/// The point `cam` looks at: where its central ray first hits the scene, or (looking at nothing) the
/// point along that ray nearest the centre of the scene's bounds.
pub fn orbit_target(scene: &Scene, bvh: &SceneBvh, cam: &Camera) -> Vec3 {
    let (eye, dir) = (cam.eye(), cam.forward());
    match bvh.closest(Vec3A::from(eye), Vec3A::from(dir), 0.0, f32::INFINITY) {
        Some(hit) if hit.t.is_finite() => eye + dir * hit.t,
        _ => {
            let (lo, hi) = scene.bounds();
            let c = 0.5 * (lo + hi);
            eye + dir * (c - eye).dot(dir).max(0.0)
        }
    }
}

/// The point `cam` (in the scene's own units) looks at, in the scene's own units: `orbit_target` on
/// the scene as the renderer holds it, whose geometry is scaled by `geometry_scale` when the scene
/// lies outside 2^±10 (so the camera is cast in those units and the hit brought back).
pub fn orbit_target_of(renderer: &Renderer, cam: &Camera) -> Vec3 {
    let t = orbit_target(
        &renderer.scene,
        &renderer.bvh,
        &renderer.to_render_units(cam),
    );
    (t.as_dvec3() / renderer.geometry_scale).as_vec3()
}

/// One frame of a path: a row of `path.csv`, a field a column, with the settings it was made with
/// (their fields are columns too: `COLUMNS`, `csv::settings_columns`), then every method's knobs
/// (`MethodSettings::columns`). The columns after `reference_ms` were added over time: a file may
/// stop after any of them, and the missing ones read their defaults.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PathRow {
    pub label: String,
    pub frame: u32,
    /// GPU ms of the frame (resident VPL work excluded) and of its SP clustering.
    pub frame_ms: f64,
    pub sp_cluster_ms: f64,
    pub mse: f64,
    pub rel_mse: f64,
    /// `None` for the first frame (no previous one).
    pub instability: Option<f64>,
    pub sp_clusters_used: u32,
    /// GPU ms of this frame's reference. The last column every file has.
    pub reference_ms: f64,
    /// GPU ms of the visibility pass.
    #[serde(default)]
    pub visibility_ms: f64,
    /// The adapter and its driver, and the scene.
    #[serde(default)]
    pub adapter: String,
    #[serde(default)]
    pub driver: String,
    #[serde(default)]
    pub scene: String,
    /// Flicker at the same surface point: frame t's error against frame t−1's where the same
    /// surface was (`metrics::instability_world`); empty at frame 0 or when no pixel matched.
    #[serde(default)]
    pub instability_world: Option<f64>,
    /// The method (its name; files without the column read the default one); its knobs are the last
    /// columns, as in `results.csv`.
    #[serde(
        default,
        serialize_with = "super::csv::method_cell",
        deserialize_with = "super::csv::method_of_cell"
    )]
    pub method: MethodSettings,
    /// The indirect light's ms: `frame` less `primary` and `direct` (every method's own passes);
    /// files without it read empty.
    #[serde(default)]
    pub indirect_ms: Option<f64>,
    /// `instability_world` of the frame's direct light alone against the same references: what
    /// an image without indirect light would score, i.e. how much the references' own indirect
    /// light changes when read between the previous frame's pixels (docs/temporal.md).
    #[serde(default)]
    pub instability_world_direct_only: Option<f64>,
    /// The clustering the frame ran with: `temporal` (written `on`/`off`) and `temporal_alpha` (the
    /// accumulation's, `--temporal-alpha`; empty with temporal off) among the contract's columns.
    #[serde(skip)]
    pub cluster: ClusterSettings,
    /// The frame's settings as it ran (`width`, `height` and `vpls` the frame's own: `vpls` the
    /// VPLs traced); files without `width`, `height` or `vpls` read them 0 (unknown).
    #[serde(skip)]
    pub frame_settings: FrameSettings,
    /// The method's report (`Frame::report`), in the report columns after the knobs
    /// (`method::report_columns`; files of versions that had some among their own columns read
    /// them there, by name).
    #[serde(skip)]
    pub report: Option<serde_json::Value>,
}

impl super::csv::Carried for PathRow {
    fn carried(&self) -> super::csv::Parts<'_> {
        let r = self;
        (&r.cluster, &r.frame_settings, &r.method, r.report.as_ref())
    }
    fn carried_mut(&mut self) -> super::csv::PartsMut<'_> {
        let r = self;
        (
            &mut r.cluster,
            &mut r.frame_settings,
            &mut r.method,
            &mut r.report,
        )
    }
}

impl PathRow {
    /// Whether the frame reused the past (`cluster.temporal`).
    pub fn temporal(&self) -> bool {
        self.cluster.temporal
    }
}

/// The columns of `path.csv` the contract names, in its order (docs/design.md, "Additive
/// contracts" and "path.csv"): the row's own fields and the settings fields placed among them.
pub const COLUMNS: &[&str] = &[
    "label",
    "temporal",
    "frame",
    "frame_ms",
    "sp_cluster_ms",
    "mse",
    "rel_mse",
    "instability",
    "sp_clusters_used",
    "reference_ms",
    "visibility_ms",
    "adapter",
    "driver",
    "scene",
    "width",
    "height",
    "vpls",
    "instability_world",
    "method",
    "indirect_ms",
    "temporal_alpha",
    "instability_world_direct_only",
];

/// `path.csv`'s layout: `temporal` as `on`/`off`, `temporal_alpha` as the `csv` crate writes an
/// `f32` (`0.7`, `1.0`) and empty with temporal off.
const LAYOUT: super::csv::Layout = super::csv::Layout {
    columns: COLUMNS,
    required: "reference_ms",
    forms: &[
        super::csv::Form {
            column: "temporal",
            write: |text, _| crate::settings::on_off(text == "true").into(),
            read: |text| match crate::settings::parse_on_off(text) {
                Ok(on) => Ok(on.to_string()),
                Err(e) => Err(e.to_string()),
            },
        },
        super::csv::Form {
            column: "temporal_alpha",
            write: |text, cells| {
                let on = cells.iter().any(|(n, t)| *n == "temporal" && t == "true");
                match text.parse::<f32>() {
                    Ok(a) if on => csv_text(a),
                    _ => String::new(),
                }
            },
            read: |text| Ok(text.to_string()),
        },
    ],
};

/// `v` as the `csv` crate writes it in a cell.
fn csv_text(v: impl Serialize) -> String {
    let mut w = ::csv::WriterBuilder::new()
        .has_headers(false)
        .from_writer(Vec::new());
    w.serialize([v]).expect("writing to memory");
    let text = String::from_utf8(w.into_inner().expect("writing to memory")).expect("UTF-8");
    text.trim_end().to_string()
}

/// `path.csv`'s header: the contract's columns, the other settings fields, every method's knobs,
/// then their report columns.
pub fn header() -> Vec<String> {
    super::csv::header_of(&LAYOUT)
}

pub fn to_csv(rows: &[PathRow]) -> String {
    super::csv::write_rows(&LAYOUT, rows)
}

/// Reads a file written by `to_csv` back, or by an older version (`bench-table`, tests).
pub fn from_csv(text: &str) -> Result<Vec<PathRow>> {
    super::csv::read_rows(text, &LAYOUT, |r: &mut PathRow, head| {
        let has = |c: &str| head.iter().any(|h| h == c);
        let f = &mut r.frame_settings;
        for (c, v) in [
            ("width", &mut f.width),
            ("height", &mut f.height),
            ("vpls", &mut f.vpls),
        ] {
            if !has(c) {
                *v = 0;
            }
        }
    })
}

/// Means over frames 1.. (the frames that can reuse) of one label and temporal setting: (frame ms,
/// SP clustering ms, MSE, instability).
pub fn means(rows: &[PathRow], label: &str, temporal: bool) -> Option<[f64; 5]> {
    let sel: Vec<&PathRow> = rows
        .iter()
        .filter(|r| r.label == label && r.temporal() == temporal && r.frame >= 1)
        .collect();
    if sel.is_empty() {
        return None;
    }
    let n = sel.len() as f64;
    let mean = |f: &dyn Fn(&PathRow) -> f64| sel.iter().map(|r| f(r)).sum::<f64>() / n;
    Some([
        mean(&|r| r.frame_ms),
        mean(&|r| r.sp_cluster_ms),
        mean(&|r| r.mse),
        mean(&|r| r.instability.unwrap_or(0.0)),
        mean(&|r| r.instability_world.unwrap_or(0.0)),
    ])
}

/// A frame's image `x` (its radiance, or a layer of it) and its reference as
/// `metrics::instability_world` reads them.
fn path_frame<'a>(
    f: &'a Frame,
    x: &'a [[f32; 3]],
    reference: &'a [[f32; 3]],
) -> metrics::PathFrame<'a> {
    metrics::PathFrame {
        x,
        reference,
        positions: &f.positions,
        normals: &f.normals,
        width: f.width as usize,
    }
}

/// Renders every configuration of `plan` along `path` with each of `temporal` (on: with each of
/// `alphas`, `ClusterSettings::temporal_alpha`), against one reference
/// per frame (rendered once, shared by all). Writes `path.csv` and `path.png` into the plan's folder.
pub fn run(
    ctx: &GpuContext,
    scene: &Scene,
    plan: &BenchPlan,
    path: &CameraPath,
    temporal: &[bool],
    alphas: &[f32],
) -> Result<Vec<PathRow>> {
    let mut renderer = Renderer::new(ctx, scene)?;
    let start = &plan.cameras.first().ok_or_else(|| anyhow!("no camera"))?.1;
    let target = orbit_target_of(&renderer, start);
    let cameras = path.cameras(start, target);
    let configs = plan.sweep.configs();
    // One frame along a path (`bench --camera-path` refuses `--paper off,on` without --clamp).
    let frame = plan.frames(&configs).first().copied().unwrap_or(plan.frame);
    let reference_settings = plan.reference_settings(frame);
    let timing = Timing {
        repeat: 1,
        warmup_ms: plan.timing.warmup_ms,
        kind: FrameKind::Vpl,
    };
    let mut references: Vec<(Vec<[f32; 3]>, f64)> = Vec::new();
    for (i, cam) in cameras.iter().enumerate() {
        let t = timed(&mut renderer, cam, &reference_settings, timing, &mut || {})?;
        let ms = t.timings_ms[FRAME_KEY];
        eprintln!(
            "path: reference {}/{} in {ms:.0} ms GPU",
            i + 1,
            cameras.len()
        );
        references.push((t.frame.radiance, ms));
    }
    let mut rows = Vec::new();
    for c in &configs {
        let runs = temporal.iter().flat_map(|&on| {
            let a: Vec<Option<f32>> = match on {
                true => alphas.iter().map(|&a| Some(a)).collect(),
                false => vec![None],
            };
            a.into_iter().map(move |a| (on, a))
        });
        for (on, alpha) in runs {
            let mut s = plan.settings(c);
            s.cluster.temporal = on;
            if let Some(a) = alpha {
                s.cluster.temporal_alpha = a;
            }
            // Pipelines built (one untimed frame on a GPU); each run starts with no past.
            renderer.forget_past();
            renderer.warm_up(&cameras[0], &s, plan.timing.warmup_ms)?;
            // A frame is timed once (its past is its predecessor's), right after GPU work that
            // touches no renderer state: not at the clock the CPU work since the last frame (its
            // error measures) left the GPU in.
            let mut frames = FrameLoop::new(FrameKind::Vpl, plan.timing.warmup_ms);
            let mut prev: Option<Frame> = None;
            for (i, cam) in cameras.iter().enumerate() {
                let (f, _) = frames.next(&mut renderer, cam, &s)?;
                let at = Along {
                    cameras: &cameras,
                    references: &references,
                    i,
                };
                let row = path_row(ctx, plan, (c, &s, alpha), &at, &f, prev.as_ref());
                say(&row);
                rows.push(row);
                prev = Some(f);
            }
        }
    }
    let text = to_csv(&rows);
    export::write_atomic(&plan.out_dir.join("path.csv"), |w| {
        use std::io::Write;
        w.write_all(text.as_bytes())?;
        Ok(())
    })?;
    plot(
        &plan.out_dir.join("path.png"),
        &format!(
            "{} along orbit:{}:{} ({}x{})",
            plan.scene_name, path.frames, path.degrees, plan.frame.width, plan.frame.height
        ),
        &rows,
    )?;
    Ok(rows)
}

/// Frame `i` of a path: the path's cameras and each frame's reference (image, GPU ms).
struct Along<'a> {
    cameras: &'a [Camera],
    references: &'a [(Vec<[f32; 3]>, f64)],
    i: usize,
}

/// The row of frame `f` (its predecessor `prev`) of configuration `c` rendered with `s` (temporal
/// reuse on or off, the accumulation's `alpha` when given).
fn path_row(
    ctx: &GpuContext,
    plan: &BenchPlan,
    (c, s, alpha): (&Config, &RenderSettings, Option<f32>),
    at: &Along,
    f: &Frame,
    prev: Option<&Frame>,
) -> PathRow {
    let i = at.i;
    let (reference, reference_ms) = &at.references[i];
    let mut label = sweep::label_ran(
        c,
        f.gamma_used.is_some(),
        f.vpl_clusters_used > 0,
        f.gamma_used,
    );
    if let Some(a) = alpha.filter(|_| f.ran(Pass::Accumulate)) {
        label = format!("{label} α{a}");
    }
    let instability = prev.map(|p| {
        metrics::instability(&f.radiance, reference, &p.radiance, &at.references[i - 1].0)
    });
    let world = |x: &dyn Fn(&Frame) -> &[[f32; 3]]| {
        prev.and_then(|p| {
            let cam = CameraParams::new(&at.cameras[i - 1], p.width, p.height);
            let eye = cam.eye_point();
            metrics::instability_world(
                &path_frame(f, x(f), reference),
                &path_frame(p, x(p), &at.references[i - 1].0),
                |q| cam.project(q - eye, 1e-6),
            )
        })
    };
    let instability_world = world(&|f| &f.radiance);
    let instability_world_direct_only = world(&|f| &f.direct);
    PathRow {
        label,
        frame: i as u32,
        frame_ms: f.frame_ms(),
        sp_cluster_ms: f.ms(Pass::SpCluster),
        mse: metrics::mse(&f.radiance, reference),
        rel_mse: metrics::rel_mse(&f.radiance, reference),
        instability,
        sp_clusters_used: f.sp_clusters_used,
        reference_ms: *reference_ms,
        visibility_ms: f.ms(Pass::Visibility),
        adapter: ctx.adapter_name.clone(),
        driver: ctx.driver.clone(),
        scene: plan.scene_name.clone(),
        instability_world,
        method: c.method,
        indirect_ms: Some(f.frame_ms() - f.ms(Pass::Primary) - f.ms(Pass::Direct)),
        instability_world_direct_only,
        cluster: s.cluster.clone(),
        frame_settings: FrameSettings {
            width: f.width,
            height: f.height,
            vpls: f.vpls,
            ..s.frame
        },
        report: f.report_of(c.method.method).cloned(),
    }
}

/// A frame's line on stderr.
fn say(row: &PathRow) {
    let opt = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.3e}"));
    eprintln!(
        "path: {} temporal {} frame {}: {:.1} ms (SP clustering {:.1} ms{}), MSE {:.3e}, instability {} (world {})",
        row.label,
        crate::settings::on_off(row.temporal()),
        row.frame,
        row.frame_ms,
        row.sp_cluster_ms,
        row.report
            .as_ref()
            .map_or(String::new(), |r| format!(", {r}")),
        row.mse,
        opt(row.instability),
        opt(row.instability_world)
    );
}

/// A measure of a row (`None`: not measured for it).
type Metric = fn(&PathRow) -> Option<f64>;

/// MSE (left) and instability (right) per frame, a line per configuration and temporal setting
/// (solid: on, dashed look: off drawn thinner).
pub fn plot(path: &Path, title: &str, rows: &[PathRow]) -> Result<()> {
    super::plot::register_fonts();
    let (w, h) = (super::plot::WIDTH, super::plot::HEIGHT);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("{e}"))?;
        let root = root
            .titled(title, ("sans-serif", 18))
            .map_err(|e| anyhow!("{e}"))?;
        let panels = root.split_evenly((1, 2));
        let mut series: Vec<(String, bool)> = Vec::new();
        for r in rows {
            if !series.contains(&(r.label.clone(), r.temporal())) {
                series.push((r.label.clone(), r.temporal()));
            }
        }
        let frames = rows.iter().map(|r| r.frame).max().unwrap_or(0).max(1);
        let panel_defs: [(&str, Metric); 2] =
            [("MSE", |r| Some(r.mse)), ("instability", |r| r.instability)];
        for (area, (name, value)) in panels.iter().zip(panel_defs) {
            let vals: Vec<f64> = rows
                .iter()
                .filter_map(value)
                .filter(|v| v.is_finite() && *v > 0.0)
                .collect();
            // A linear axis from 0: the frames' values lie within a factor of a few of each other.
            let hi = vals.iter().fold(0f64, |a, &v| a.max(v));
            let hi = if hi > 0.0 { hi * 1.25 } else { 1e-3 };
            let mut chart = ChartBuilder::on(area)
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(70)
                .build_cartesian_2d(0u32..frames, 0f64..hi)
                .map_err(|e| anyhow!("{e}"))?;
            chart
                .configure_mesh()
                .x_desc("frame")
                .y_desc(name)
                .y_label_formatter(&|v| format!("{v:.1e}"))
                .label_style(("sans-serif", 13))
                .draw()
                .map_err(|e| anyhow!("{e}"))?;
            for (i, (label, on)) in series.iter().enumerate() {
                let colour = Palette99::pick(i).to_rgba();
                let pts: Vec<(u32, f64)> = rows
                    .iter()
                    .filter(|r| &r.label == label && r.temporal() == *on)
                    .filter_map(|r| value(r).filter(|v| *v > 0.0).map(|v| (r.frame, v)))
                    .collect();
                let width = if *on { 3 } else { 1 };
                chart
                    .draw_series(LineSeries::new(
                        pts.iter().copied(),
                        colour.stroke_width(width),
                    ))
                    .map_err(|e| anyhow!("{e}"))?
                    .label(format!(
                        "{label}, temporal {}",
                        if *on { "on" } else { "off" }
                    ))
                    .legend(move |(x, y)| {
                        PathElement::new([(x, y), (x + 18, y)], colour.stroke_width(width))
                    });
                chart
                    .draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                    .map_err(|e| anyhow!("{e}"))?;
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 12))
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(|e| anyhow!("{e}"))?;
        }
        root.present().map_err(|e| anyhow!("{e}"))?;
    }
    export::write_png_rgb8(path, w, h, buf)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_path_parses_orbit_and_refuses_the_rest() {
        assert_eq!(
            parse_camera_path("orbit:6:3"),
            Ok(CameraPath {
                frames: 6,
                degrees: 3.0
            })
        );
        assert_eq!(parse_camera_path("orbit:1:-90").unwrap().degrees, -90.0);
        for bad in [
            "orbit:0:3",
            "orbit:6",
            "orbit:x:3",
            "orbit:6:nan",
            "line:6:3",
            "",
        ] {
            assert!(parse_camera_path(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn orbit_turns_about_the_target_and_keeps_it_in_view() {
        // A camera at (0, 1, 5) looking at the origin; a quarter turn in two frames.
        let start = Camera::look_at("c", Vec3::new(0.0, 1.0, 5.0), Vec3::ZERO, Vec3::Y, 0.8);
        let cams = CameraPath {
            frames: 3,
            degrees: 90.0,
        }
        .cameras(&start, Vec3::ZERO);
        assert_eq!(cams.len(), 3);
        assert_eq!(cams[0].transform, start.transform);
        // +90° about +Y takes +Z to +X: the eye goes to (5, 1, 0), 45° half way.
        assert!((cams[2].eye() - Vec3::new(5.0, 1.0, 0.0)).length() < 1e-5);
        let h = 5.0 / 2f32.sqrt();
        assert!((cams[1].eye() - Vec3::new(h, 1.0, h)).length() < 1e-5);
        for c in &cams {
            // Still looking at the target, same distance, same field of view.
            let to = (Vec3::ZERO - c.eye()).normalize();
            assert!(c.forward().dot(to) > 1.0 - 1e-6);
            assert!((c.eye().length() - 26f32.sqrt()).abs() < 1e-5);
            assert_eq!(c.yfov, 0.8);
        }
    }

    /// The orbit's target of a scene scaled by 1e-6 and by 1e6 (rendered with its geometry scaled
    /// into a unit frame, `Renderer::geometry_scale`) is the unscaled scene's target times the
    /// scale: the start camera is cast in the renderer's units. Cast in the scene's own units into
    /// the scaled BVH (as `run` did), the ray starts far outside the scaled scene and misses it.
    #[test]
    fn orbit_target_of_scaled_scenes() {
        let ctx = crate::gpu::GpuContext::new_headless().unwrap();
        let base = crate::scene::load("builtin:conference").unwrap();
        let target = |s: &Scene| {
            let r = Renderer::new(&ctx, s).unwrap();
            let cam = s.default_camera();
            let naive = orbit_target(&r.scene, &r.bvh, &cam);
            (orbit_target_of(&r, &cam), naive, r.geometry_scale)
        };
        let (t1, _, g1) = target(&base);
        assert_eq!(g1, 1.0);
        let size = {
            let (lo, hi) = base.bounds();
            (hi - lo).length()
        };
        for k in [1e-6f32, 1e6] {
            let mut s = base.clone();
            for t in &mut s.triangles {
                for p in &mut t.p {
                    *p *= k;
                }
            }
            for l in &mut s.lights {
                l.position *= k;
            }
            for c in &mut s.cameras {
                c.transform.w_axis = (c.transform.w_axis.truncate() * k).extend(1.0);
            }
            let (t, naive, g) = target(&s);
            assert_ne!(g, 1.0, "scale {k}: rendered in a unit frame");
            let err = (t / k - t1).length() / size;
            assert!(
                err < 1e-4,
                "scale {k}: target {t} against {} ({err:e})",
                t1 * k
            );
            let naive_err = (naive / k - t1).length() / size;
            assert!(
                naive_err > 1e-2,
                "scale {k}: the naive cast also hits ({naive_err:e})"
            );
        }
    }

    #[test]
    fn csv_and_means_of_frames_after_the_first() {
        let row = |frame: u32, on: bool, sp: f64, mse: f64, inst: Option<f64>| PathRow {
            label: "weighted 192/512".into(),
            cluster: ClusterSettings {
                temporal: on,
                ..Default::default()
            },
            frame,
            frame_ms: 10.0,
            sp_cluster_ms: sp,
            mse,
            rel_mse: 0.5,
            instability: inst,
            sp_clusters_used: 192,
            reference_ms: 100.0,
            visibility_ms: 5.0,
            adapter: "an adapter, with a comma".into(),
            driver: "a driver".into(),
            scene: "builtin:conference".into(),
            frame_settings: FrameSettings {
                width: 160,
                height: 120,
                vpls: 4096,
                ..Default::default()
            },
            instability_world: inst.map(|v| v / 2.0),
            report: Some(serde_json::json!({
                "sp_iterations": 1,
                "sp_warm_kept": on.then_some(180),
                "visibility_rows_reused": 0,
            }))
            .map(|mut v| {
                v.as_object_mut().unwrap().retain(|_, x| !x.is_null());
                v
            }),
            ..Default::default()
        };
        let rows = vec![
            row(0, false, 100.0, 9.0, None),
            row(1, false, 4.0, 1.0, Some(2.0)),
            row(2, false, 6.0, 3.0, Some(4.0)),
            row(0, true, 100.0, 9.0, None),
            row(1, true, 1.0, 2.0, Some(1.0)),
        ];
        // Frame 0 is left out of the means.
        assert_eq!(
            means(&rows, "weighted 192/512", false),
            Some([10.0, 5.0, 2.0, 3.0, 1.5])
        );
        assert_eq!(
            means(&rows, "weighted 192/512", true),
            Some([10.0, 1.0, 2.0, 1.0, 0.5])
        );
        assert_eq!(means(&rows, "other", true), None);
        let csv = to_csv(&rows);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 6);
        assert!(
            lines[0]
                .starts_with("label,temporal,frame,frame_ms,sp_cluster_ms,mse,rel_mse,instability")
        );
        // Frame 0 has an empty instability; temporal is written on/off.
        let f0: Vec<&str> = lines[1].split(',').collect();
        assert_eq!((f0[1], f0[2], f0[7]), ("off", "0", ""));
        let f4: Vec<&str> = lines[5].split(',').collect();
        assert_eq!(f4[1], "on");
        // The report in its columns (found by name: the adapter's cell holds a comma).
        let cell = |line: &str, c: &str| {
            let at = header().iter().position(|h| h == c).unwrap();
            super::super::csv::split_line(line)[at].clone()
        };
        assert_eq!(cell(lines[5], "sp_warm_kept"), "180");
        assert_eq!(cell(lines[1], "sp_warm_kept"), "");
        assert_eq!(cell(lines[1], "sp_iterations"), "1");
        assert_eq!(f4[7].parse::<f64>().unwrap(), 1.0);
        assert_eq!(from_csv(&csv).unwrap(), rows);
    }

    /// `path.csv` round-trips, a method's knobs in their columns; a file of the first version
    /// (through `reference_ms`) reads with the later columns' defaults, and one whose header is
    /// not a prefix of the current one is refused.
    #[test]
    fn path_csv_reads_back_and_old_files_read() {
        let mut r = PathRow {
            label: "a method 48/128".into(),
            cluster: ClusterSettings {
                temporal: true,
                temporal_alpha: 0.7,
                ..Default::default()
            },
            frame: 2,
            frame_ms: 12.5,
            mse: 1e-4,
            instability: Some(2e-5),
            report: Some(serde_json::json!({
                "sp_iterations": 2,
                "sp_warm_kept": 40,
                "visibility_rows_reused": 3,
            })),
            adapter: "a, \"quoted\" adapter".into(),
            instability_world: Some(1e-6),
            indirect_ms: Some(7.25),
            instability_world_direct_only: Some(5e-6),
            ..Default::default()
        };
        r.method.method = crate::method::REGISTRY[0].method;
        let text = to_csv(std::slice::from_ref(&r));
        let head = super::super::csv::split_line(text.lines().next().unwrap());
        assert_eq!(head, header());
        assert_eq!(
            head[18..22],
            [
                "method",
                "indirect_ms",
                "temporal_alpha",
                "instability_world_direct_only"
            ]
        );
        // The other settings, then the knobs and the report columns.
        let settings = super::super::csv::settings_columns().filter(|c| !COLUMNS.contains(c));
        let at = 22 + settings.count();
        let knobs = MethodSettings::columns().len();
        assert_eq!(head[at..at + knobs], MethodSettings::columns());
        assert_eq!(head[at + knobs..], crate::method::report_columns());
        assert_eq!(from_csv(&text).unwrap(), vec![r]);
        let old = "\
label,temporal,frame,frame_ms,sp_cluster_ms,mse,rel_mse,instability,sp_iterations,sp_warm_kept,\
sp_clusters_used,reference_ms
weighted 192/512 F6 g4,on,1,10.5,2.5,0.0001,0.002,0.00003,1,180,192,400
";
        let rows = from_csv(old).unwrap();
        assert_eq!(
            (
                rows[0].temporal(),
                rows[0].frame,
                rows[0]
                    .report
                    .as_ref()
                    .and_then(|r| r.get("sp_warm_kept"))
                    .and_then(|k| k.as_u64()),
                rows[0].reference_ms
            ),
            (true, 1, Some(180), 400.0)
        );
        let f = &rows[0].frame_settings;
        assert_eq!((rows[0].visibility_ms, rows[0].scene.as_str()), (0.0, ""));
        assert_eq!((f.width, f.height, f.vpls), (0, 0, 0));
        assert_eq!(
            (rows[0].instability_world, rows[0].indirect_ms),
            (None, None)
        );
        assert_eq!(rows[0].method, MethodSettings::default());
        assert!(from_csv(&old.replacen("label,temporal", "temporal,label", 1)).is_err());
        assert!(from_csv(&old.replacen(",on,", ",maybe,", 1)).is_err());
        let short = "label,temporal,frame\nx,on,0\n";
        assert!(from_csv(short).is_err());
    }

    /// A file as the version before the generated settings columns wrote it (commit d05e11d): its
    /// rows read, and written again every one of its columns has the same text (`temporal` on/off,
    /// `temporal_alpha` empty with temporal off, the floats as the `csv` crate writes them).
    #[test]
    fn a_path_file_before_the_settings_columns_reads_and_keeps_its_text() {
        let old = include_str!("testdata/path-d05e11d.csv");
        let rows = from_csv(old).unwrap();
        assert_eq!(rows.len(), 2);
        let (off, on) = (&rows[0], &rows[1]);
        assert_eq!((off.temporal(), on.temporal()), (false, true));
        assert_eq!(on.cluster.temporal_alpha, 0.5);
        let f = &on.frame_settings;
        assert_eq!((f.width, f.height, f.vpls), (96, 72, 1024));
        assert_eq!(
            (on.frame_ms, on.instability, on.indirect_ms),
            (10.0, Some(3e-5), Some(7.5))
        );
        assert_eq!(on.instability_world_direct_only, Some(5e-6));
        assert_eq!(off.report, None);
        let kept = on.report.as_ref().and_then(|r| r.get("sp_warm_kept"));
        assert_eq!(kept.and_then(|k| k.as_u64()), Some(40));
        let again = to_csv(&rows);
        let cell = super::super::csv::tests::cell;
        for c in super::super::csv::split_line(old.lines().next().unwrap()) {
            for n in [1, 2] {
                assert_eq!(cell(&again, n, &c), cell(old, n, &c), "{c}, line {n}");
            }
        }
        assert_eq!(from_csv(&again).unwrap(), rows);
    }
}
