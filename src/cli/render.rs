//! `fuzzy-vpl render`: one frame headless to EXR / PNG, with stats and an error against a reference.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use super::scene::{SceneArgs, ShotArgs, check_size, check_vpls};
use crate::gpu::GpuContext;
use crate::input::bad;
use crate::render;
use crate::render::Frame;
use crate::render::timed::{FrameKind, Timed, Timing, timed};
use crate::render::{RenderSettings, Renderer};
use crate::settings::{FrameSettings, TimingSettings};
use crate::{export, metrics, stats};

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Output image: .exr (linear radiance) or .png (exposure, clamp, sRGB).
    /// Repeat -o to write several files of the same frame (e.g. -o a.exr -o a.png).
    #[arg(short, long, required = true)]
    output: Vec<PathBuf>,
    /// Write the stats JSON (docs/design.md, "Stats JSON") here.
    #[arg(long)]
    stats: Option<PathBuf>,
    /// Write the GPU timer queries of the render (every dispatch of every pass) as a Chrome trace
    /// (chrome://tracing, Perfetto) here.
    #[arg(long, value_name = "TRACE.json")]
    trace: Option<PathBuf>,
    /// Fill the stats' error block against this reference: an OpenEXR file of linear radiance
    /// (as -o X.exr writes); a PNG or JPEG (8-bit sRGB) is refused.
    #[arg(long)]
    compare: Option<PathBuf>,
    /// Write a false-colour per-pixel error image against --compare (log10 rel. error, -4..0; or
    /// the FLIP map with --error-metric flip).
    #[arg(long, requires = "compare")]
    error_map: Option<PathBuf>,
    /// What --error-map draws: rel-mse (log10 of the per-pixel relative error, blue to red) or flip
    /// (the per-pixel FLIP error of the tone-mapped images, magma from 0 to 1).
    #[arg(long, value_enum, default_value_t = ErrorMetric::RelMse, requires = "error_map")]
    error_metric: ErrorMetric,
    #[command(flatten)]
    shot: ShotArgs,
    /// Render N times; timings are the mean of the 3 best (the paper's method).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    repeat: u32,
    #[command(flatten)]
    timing: TimingSettings,
    /// Which light the output images hold: final (emission, direct and indirect light), direct
    /// (emission and direct light) or indirect (the VPLs' light alone). --compare and the stats'
    /// error are of the final image whatever the layer.
    #[arg(long, value_enum, default_value_t = Layer::Final)]
    layer: Layer,
    /// Indirect light without any clustering: every pixel gathers every VPL with its own shadow ray
    /// (Eq. 5; the paper's reference).
    #[arg(long)]
    reference: bool,
    /// Render with the diffuse path tracer instead (SPP samples per pixel, same bounce budget as the
    /// VPLs): the check of the VPL reference's own bias.
    #[arg(long, value_name = "SPP", conflicts_with = "reference", value_parser = clap::value_parser!(u32).range(1..))]
    path_trace: Option<u32>,
}

/// What `render -o` writes (`--layer`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Layer {
    Final,
    Direct,
    Indirect,
}

/// What `--error-map` draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ErrorMetric {
    RelMse,
    Flip,
}

/// The extension of `p`, lower case.
fn extension(p: &std::path::Path) -> Option<String> {
    p.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
}

/// The reference EXR of `--compare`: finite, of the render's size.
fn read_reference(p: &std::path::Path, f: &FrameSettings) -> Result<Vec<[f32; 3]>> {
    let (w, h, px) = export::read_linear_exr(p)?;
    crate::files::note_inputs(&[("--compare", p)]);
    if let Some(i) = px.iter().position(|c| c.iter().any(|x| !x.is_finite())) {
        return Err(bad(format!(
            "{}: reference has a non-finite pixel (NaN or infinity) at pixel {i}",
            p.display()
        )));
    }
    if (w, h) != (f.width, f.height) {
        return Err(bad(format!(
            "{}: reference is {w}x{h}, the render is {}x{}",
            p.display(),
            f.width,
            f.height
        )));
    }
    Ok(px)
}

pub fn run(mut a: RenderArgs, given: &[String]) -> Result<()> {
    a.shot.apply_paper(given);
    check_outputs(&a)?;
    let reference = a
        .compare
        .as_deref()
        .map(|p| read_reference(p, &a.shot.frame))
        .transpose()?;
    let scene = a.scene.load()?;
    let read: Vec<(&str, &std::path::Path)> = scene
        .report
        .files
        .iter()
        .map(|f| ("the scene's file", f.as_path()))
        .collect();
    crate::files::check_distinct(&outputs(&a), &read).map_err(bad)?;
    let camera = a.scene.camera(&scene, a.shot.camera)?;
    let ctx = GpuContext::new_headless()?;
    check_vpls(&ctx, a.shot.frame.vpls)?;
    let bytes = match a.path_trace {
        Some(_) => render::PATH_TRACE_PIXEL_BYTES,
        None => render::PIXEL_BYTES,
    };
    check_size(&ctx, a.shot.frame.width, a.shot.frame.height, bytes)?;
    let mut renderer = Renderer::new(&ctx, &scene)?;
    renderer.profiler.keep_trace = a.trace.is_some();
    let settings = RenderSettings {
        frame: a.shot.frame,
        cluster: a.shot.cluster.clone(),
        method: a.shot.method,
        reference: a.reference,
        progress: true,
        control: None,
    };
    if a.path_trace.is_none() {
        let plan = render::Plan::new(&scene, &settings);
        render::check_method_limits(&ctx, &plan, &settings).map_err(bad)?;
    }
    if settings.cluster.target_ms.is_some() && (a.reference || a.path_trace.is_some()) {
        return Err(bad(
            "--target-ms: chooses the cluster counts; --reference and --path-trace cluster nothing",
        ));
    }
    let t = frames(&a, &mut renderer, &camera, &settings)?;
    if let Some(p) = &a.trace {
        renderer.profiler.write_trace(p)?;
    }
    warn_about(&t.frame, &scene, &a.scene.scene);
    let image = match a.layer {
        Layer::Final => &t.frame.radiance,
        Layer::Direct => &t.frame.direct,
        Layer::Indirect => &t.frame.indirect,
    };
    let exposure = a.shot.frame.exposure.resolve(image);
    for out in &a.output {
        export::write_image(out, t.frame.width, t.frame.height, image, exposure)?;
    }
    let error = compare(&a, &renderer, &t.frame, reference.as_deref())?;
    let frame = &t.frame;
    let outputs: Vec<String> = a.output.iter().map(|p| p.display().to_string()).collect();
    let passes: Vec<&str> = frame.passes.iter().map(|p| p.name()).collect();
    eprintln!(
        "{}: {}x{} in {:.1} ms GPU ({}), mean luminance {:.4} -> {}",
        a.scene.scene,
        frame.width,
        frame.height,
        t.timings_ms[render::FRAME_KEY],
        passes.join(" + "),
        metrics::mean_luminance(&frame.radiance),
        outputs.join(", ")
    );
    if let Some(p) = &a.stats {
        let s = stats::Stats {
            scene: a.scene.scene.clone(),
            width: frame.width,
            height: frame.height,
            adapter: ctx.adapter_name.clone(),
            settings: stats::Settings::new(
                &t.settings,
                &a.scene.lights,
                frame,
                exposure,
                a.path_trace,
            ),
            counts: stats::Counts::new(&scene, frame, renderer.gpu.emitters.len() as u64),
            passes: passes.iter().map(|s| s.to_string()).collect(),
            timings_ms: t.timings_ms.clone(),
            repeat: a.repeat,
            warmup_ms: t.warmup_ms,
            driver: ctx.driver.clone(),
            device_type: ctx.kind().into(),
            mean_luminance: metrics::mean_luminance(&frame.radiance),
            mean_luminance_indirect: metrics::mean_luminance(&frame.indirect),
            bvh_build_ms: renderer.bvh.build_ms,
            error,
            target: t.budget.map(|b| stats::Target {
                target_ms: b.target_ms,
                steps: b.steps,
            }),
        };
        export::write_json(p, &s)?;
    }
    Ok(())
}

/// Every output's extension and that it can be written: checked before the (possibly long) render.
fn check_outputs(a: &RenderArgs) -> Result<()> {
    for out in &a.output {
        if !matches!(extension(out).as_deref(), Some("exr") | Some("png")) {
            return Err(bad(format!(
                "{}: output must end in .exr or .png",
                out.display()
            )));
        }
    }
    if let Some(p) = &a.error_map
        && extension(p).as_deref() != Some("png")
    {
        return Err(bad(format!(
            "{}: --error-map must end in .png",
            p.display()
        )));
    }
    let outputs = outputs(a);
    for (_, p) in &outputs {
        export::check_writable(p).map_err(bad)?;
    }
    let mut inputs: Vec<(&str, &std::path::Path)> = Vec::new();
    if !a.scene.scene.starts_with("builtin:") {
        inputs.push(("the scene", std::path::Path::new(&a.scene.scene)));
    }
    if let Some(c) = &a.compare {
        inputs.push(("--compare", c));
    }
    crate::files::check_distinct(&outputs, &inputs).map_err(bad)?;
    Ok(())
}

/// Every file the run writes, with the option that names it.
fn outputs(a: &RenderArgs) -> Vec<(&'static str, &std::path::Path)> {
    let mut all: Vec<(&'static str, &std::path::Path)> =
        a.output.iter().map(|p| ("-o", p.as_path())).collect();
    for (opt, p) in [
        ("--stats", &a.stats),
        ("--trace", &a.trace),
        ("--error-map", &a.error_map),
    ] {
        all.extend(p.as_deref().map(|p| (opt, p)));
    }
    all
}

/// The timed frames (`render::timed`): the path tracer's (`--path-trace`) or the VPL frame's (with
/// `--target-ms`, the controller's first); the controller's steps printed.
fn frames(
    a: &RenderArgs,
    renderer: &mut Renderer,
    camera: &crate::scene::Camera,
    settings: &RenderSettings,
) -> Result<Timed> {
    let timing = Timing {
        repeat: a.repeat,
        warmup_ms: a.timing.warmup_ms,
        kind: a.path_trace.map_or(FrameKind::Vpl, FrameKind::PathTrace),
    };
    let t = timed(renderer, camera, settings, timing, &mut || {})?;
    if let Some(b) = &t.budget {
        for (i, st) in b.steps.iter().enumerate() {
            eprintln!(
                "--target-ms {}: frame {}: K_SP {} K_VPL {} direct samples {} -> {:.1} ms",
                b.target_ms,
                i + 1,
                st.sp_clusters,
                st.vpl_clusters,
                st.direct_samples,
                st.frame_ms
            );
        }
    }
    Ok(t)
}

/// Warnings about the image: non-finite channels, and a lit scene rendering all black (no light
/// at all was warned about when loading).
fn warn_about(frame: &Frame, scene: &crate::scene::Scene, name: &str) {
    let non_finite = frame
        .radiance
        .iter()
        .flatten()
        .filter(|c| !c.is_finite())
        .count();
    if non_finite > 0 {
        eprintln!("warning: {non_finite} non-finite pixel channels in the output");
    }
    if scene.has_light() && frame.radiance.iter().flatten().all(|&c| c == 0.0) {
        eprintln!(
            "warning: {name}: the image is black although the scene has light (the camera sees no lit surface)"
        );
    }
}

/// `--compare`: the error against the reference (both tone-mapped with the reference's exposure,
/// compared as shown), printed, and `--error-map` written.
fn compare(
    a: &RenderArgs,
    renderer: &Renderer,
    frame: &Frame,
    reference: Option<&[[f32; 3]]>,
) -> Result<Option<stats::ErrorStats>> {
    let Some(r) = reference else {
        return Ok(None);
    };
    let labels = renderer.sp_labels(frame)?;
    let (error, flip) = stats::ErrorStats::measure(
        &frame.radiance,
        r,
        frame.width,
        frame.height,
        a.shot.frame.exposure.resolve(r),
        labels.as_deref(),
    );
    if let Some(p) = &a.error_map {
        let map = match a.error_metric {
            ErrorMetric::RelMse => metrics::error_map(&frame.radiance, r),
            ErrorMetric::Flip => metrics::flip_error_map(&flip, frame.width, frame.height),
        };
        export::write_png_rgb8(p, frame.width, frame.height, map)?;
    }
    eprintln!("error against the reference: {}", error.line());
    Ok(Some(error))
}
