//! `fuzzy-vpl bench`: error against run time over a sweep of clustering settings.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use super::scene::{SceneArgs, check_size, check_vpls};
use crate::bench::{self, path::CameraPath, sweep::Sweep};
use crate::export;
use crate::gpu::GpuContext;
use crate::input::bad;
use crate::render;
use crate::settings::{FrameSettings, TimingSettings, parse_on_off};

pub const BENCH_HELP: &str = "\
Lists are comma-separated; the sweep is every combination of modes x SP K x VPL K x F x gamma x n_t x
iterations x p x plane gate (values a mode ignores are dropped: hard has F = 1, vpl-only no SP K,
sp-only no VPL K).
Modes: hard, uniform, weighted (both clusterings, Eqs. 8 / 9), vpl-only, sp-only.
Methods (--methods, docs/methods.md): the modes and fuzzy knobs are the paper's (the default method's); every other method
takes its own knob lists (listed under its heading), and the K pairs and --iterations where it
clusters the shading points (its rows have the method's name as mode).
Each configuration is rendered --repeat times; its times are the mean of the 3 best (GPU timestamps),
its error is the last image's MSE against the unclustered reference of the same camera.
--quick: 96x72, 1024 VPLs, 128 VPL clusters, 48 and 96 SP clusters, every mode, repeat 3
(given options still override it).
Example: fuzzy-vpl bench builtin:conference --out-dir bench-conf --sp-clusters 768,1536,3072 --vpl-clusters 512,1024";

#[derive(Args)]
pub struct BenchArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Directory for results.csv, reference.exr, images/, the plots and summary.md (created).
    #[arg(long)]
    out_dir: PathBuf,
    /// A small sweep at low resolution that finishes in a few minutes on a software driver.
    #[arg(long)]
    quick: bool,
    #[command(flatten)]
    sweep: Sweep,
    /// The frame (with --quick: 96x72 and 1024 VPLs unless given).
    #[command(flatten)]
    frame: FrameSettings,
    /// glTF camera indices, comma-separated (default: the scene's default view); one reference each.
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    camera: Vec<usize>,
    /// Instead of the sweep's results.csv: render every configuration along a camera path,
    /// orbit:N:DEG (N frames, DEG degrees in all about the point the start camera looks at), each
    /// frame against its own reference; writes path.csv and path.png (docs/temporal.md).
    #[arg(long, value_name = "orbit:N:DEG", value_parser = crate::bench::path::parse_camera_path)]
    camera_path: Option<CameraPath>,
    /// Temporal reuse along --camera-path: on, off or both (off,on; default off).
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = parse_on_off, requires = "camera_path")]
    temporal: Vec<bool>,
    /// With --temporal on: the accumulation's α values (`render --temporal-alpha`; default the
    /// settings' default, 1 = no accumulation), e.g. 1,0.7.
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = crate::settings::parse_temporal_alpha, requires = "camera_path")]
    temporal_alpha: Vec<f32>,
    /// Renders per configuration; times are the mean of the 3 best (default 10; quick 3).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    repeat: Option<u32>,
    /// Renders of the reference (slow on a software driver), timed the same way.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    reference_repeat: u32,
    #[command(flatten)]
    timing: TimingSettings,
}

/// `a` with --quick's frame where the command line did not give one (`given`: the options it gave,
/// by id).
fn quick_frame(a: &BenchArgs, given: &[&str]) -> FrameSettings {
    let mut f = a.frame;
    if a.quick {
        let keep = |id: &str| given.contains(&id);
        if !keep("width") {
            f.width = 96;
        }
        if !keep("height") {
            f.height = 72;
        }
        if !keep("vpls") {
            f.vpls = 1024;
        }
    }
    f
}

pub fn run(mut a: BenchArgs, given: &[&str]) -> Result<()> {
    let frame = quick_frame(&a, given);
    if a.sweep.paper.contains(&true) {
        paper_ks(&mut a.sweep, &frame);
    }
    let sweep = a.sweep.resolve(a.quick).map_err(bad)?;
    let repeat = a.repeat.unwrap_or(if a.quick { 3 } else { 10 });
    if frame.vpls == 0 {
        return Err(bad("--vpls must be at least 1"));
    }
    let scene = a.scene.load()?;
    let cameras = if a.camera.is_empty() {
        vec![("default".to_string(), scene.default_camera())]
    } else {
        let mut seen = Vec::new();
        for &i in &a.camera {
            if !seen.iter().any(|(n, _)| *n == i.to_string()) {
                seen.push((i.to_string(), a.scene.camera(&scene, Some(i))?));
            }
        }
        seen
    };
    std::fs::create_dir_all(&a.out_dir)
        .map_err(|e| bad(format!("{}: cannot create: {e}", a.out_dir.display())))?;
    // The folder takes new files, and its images folder can be made: checked before any work.
    export::check_writable(&a.out_dir.join("results.csv")).map_err(bad)?;
    let images = a.out_dir.join("images");
    if images.exists() && !images.is_dir() {
        return Err(bad(format!(
            "{}: cannot create: not a directory",
            images.display()
        )));
    }
    let ctx = GpuContext::new_headless()?;
    check_vpls(&ctx, frame.vpls)?;
    check_size(&ctx, frame.width, frame.height, render::PIXEL_BYTES)?;
    std::fs::create_dir_all(&images)
        .map_err(|e| bad(format!("{}: cannot create: {e}", images.display())))?;
    let plan = bench::BenchPlan {
        scene_name: a.scene.scene.clone(),
        out_dir: a.out_dir.clone(),
        frame,
        paper_frame: bench::paper_frame(&frame, given.contains(&"clamp")),
        sweep,
        cameras,
        repeat,
        reference_repeat: a.reference_repeat,
        timing: a.timing,
        progress: true,
    };
    // Every configuration's visibility matrix fits the adapter: checked before any work.
    for c in plan.sweep.configs() {
        let s = plan.settings(&c);
        let p = render::Plan::new(&scene, &s);
        render::check_method_limits(&ctx, &p, &s).map_err(bad)?;
    }
    match &a.camera_path {
        Some(path) => along_path(&ctx, &scene, &plan, path, &a.temporal, &a.temporal_alpha),
        None => sweep_table(&ctx, &scene, &plan),
    }
}

/// `bench --paper`: without K lists or pairs, the paper's K ratios for the frame
/// (`settings::paper`), for every configuration (the frame without a G-term clamp is
/// `bench::paper_frame`).
fn paper_ks(sweep: &mut crate::bench::sweep::Sweep, frame: &FrameSettings) {
    use crate::settings::paper;
    let c = &sweep.cluster;
    if sweep.pairs.is_empty() && c.sp_clusters.is_empty() && c.vpl_clusters.is_empty() {
        let sp = paper::paper_sp_clusters(frame.pixels());
        let vpl = paper::paper_vpl_clusters(frame.vpls);
        sweep.pairs = vec![crate::bench::sweep::Pair(sp, vpl)];
    }
}

fn along_path(
    ctx: &GpuContext,
    scene: &crate::scene::Scene,
    plan: &bench::BenchPlan,
    path: &CameraPath,
    temporal: &[bool],
    alphas: &[f32],
) -> Result<()> {
    if plan.cameras.len() > 1 {
        return Err(bad(format!(
            "--camera-path starts from one camera; --camera lists {}",
            plan.cameras.len()
        )));
    }
    if plan.frames(&plan.sweep.configs()).len() > 1 {
        return Err(bad(
            "--camera-path compares every frame with one reference: --paper off,on needs --clamp \
             (the paper's frame has no clamp)",
        ));
    }
    let temporal = if temporal.is_empty() {
        &[false]
    } else {
        temporal
    };
    let f = &plan.frame;
    eprintln!(
        "bench {}: {} configuration(s) x temporal {temporal:?} along orbit:{}:{}, {}x{}, {} VPLs on {}",
        plan.scene_name,
        plan.sweep.configs().len(),
        path.frames,
        path.degrees,
        f.width,
        f.height,
        f.vpls,
        ctx.adapter_name
    );
    let default_alpha = [crate::settings::ClusterSettings::default().temporal_alpha];
    let alphas = if alphas.is_empty() {
        &default_alpha
    } else {
        alphas
    };
    let rows = bench::path::run(ctx, scene, plan, path, temporal, alphas)?;
    println!(
        "{:<32} {:>8} {:>10} {:>12} {:>11} {:>12} {:>12}",
        "configuration",
        "temporal",
        "frame ms",
        "SP clust. ms",
        "MSE",
        "instability",
        "inst. world"
    );
    let mut seen = Vec::new();
    for r in &rows {
        if seen.contains(&(&r.label, r.temporal())) {
            continue;
        }
        seen.push((&r.label, r.temporal()));
        if let Some([f, sp, mse, inst, world]) = bench::path::means(&rows, &r.label, r.temporal()) {
            println!(
                "{:<32} {:>8} {f:>10.2} {sp:>12.2} {mse:>11.3e} {inst:>12.3e} {world:>12.3e}",
                r.label,
                crate::settings::on_off(r.temporal())
            );
        }
    }
    println!(
        "(means over frames 1..{}) wrote path.csv and path.png to {}",
        path.frames.saturating_sub(1),
        plan.out_dir.display()
    );
    Ok(())
}

fn sweep_table(
    ctx: &GpuContext,
    scene: &crate::scene::Scene,
    plan: &bench::BenchPlan,
) -> Result<()> {
    let f = &plan.frame;
    eprintln!(
        "bench {}: {} configuration(s) x {} camera(s), {}x{}, {} VPLs, repeat {} (reference {}) on {}",
        plan.scene_name,
        plan.sweep.configs().len(),
        plan.cameras.len(),
        f.width,
        f.height,
        f.vpls,
        plan.repeat,
        plan.reference_repeat,
        ctx.adapter_name
    );
    let report = bench::run(ctx, scene, plan)?;
    println!(
        "{:<8} {:<28} {:>10} {:>10} {:>8} {:>11} {:>11}",
        "camera", "configuration", "frame ms", "ref ms", "speedup", "MSE", "rel. MSE"
    );
    for r in &report.rows {
        println!(
            "{:<8} {:<28} {:>10.2} {:>10.1} {:>7.1}x {:>11.3e} {:>11.3e}",
            r.camera,
            r.label,
            r.frame_ms(),
            r.reference_ms,
            r.speedup,
            r.mse,
            r.rel_mse
        );
    }
    println!(
        "wrote {} files to {} in {:.1} s: results.csv, summary.md, plots, images/",
        report.files.len(),
        plan.out_dir.display(),
        report.wall_s
    );
    Ok(())
}

/// `fuzzy-vpl bench-table`: one markdown table of bench runs (`scripts/gpu-bench`).
#[derive(Args)]
pub struct BenchTableArgs {
    /// Bench output folders (each with results.csv, path.csv or both); a row per configuration.
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// The commit the binary was built from, as printed above the table.
    #[arg(long, default_value = "unknown")]
    commit: String,
    /// The date printed above the table.
    #[arg(long, default_value = "unknown")]
    date: String,
}

pub fn table(a: BenchTableArgs) -> Result<()> {
    let dirs: Vec<&std::path::Path> = a.dirs.iter().map(|d| d.as_path()).collect();
    let info = bench::table::TableInfo {
        commit: &a.commit,
        date: &a.date,
    };
    let md = bench::table::markdown(&dirs, &info).map_err(|e| bad(format!("{e:#}")))?;
    print!("{md}");
    Ok(())
}
