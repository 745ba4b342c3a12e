//! `fuzzy-vpl`: command-line front end (docs/design.md, "CLI").

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::{Args, Parser, Subcommand};

use fuzzy_vpl::bench::{self, sweep};
use fuzzy_vpl::exposure::Exposure;
use fuzzy_vpl::gi::pipeline::{FrameSettings, Renderer, Weighting};
use fuzzy_vpl::gpu::GpuContext;
use fuzzy_vpl::scene::{self, Scene, extra_lights};
use fuzzy_vpl::{export, metrics, stats};

const LIGHTS_HELP: &str = "\
Added lights (for scenes that ship without any):
  --sun DX,DY,DZ,E[,R,G,B]     directional light; (DX,DY,DZ) points towards the sun, E is the
                               irradiance at normal incidence, optional linear RGB colour
  --point X,Y,Z,I[,R,G,B]      point light at (X,Y,Z) with intensity I (per steradian)
  --light-scale F              multiplies every emitter (emissive materials and lights) by F
Example: fuzzy-vpl render ../shared/scenes/livingroom_lowpoly/livingroom.glb -o lr.png --sun 0.3,1,0.2,3";

#[derive(Parser)]
#[command(name = "fuzzy-vpl", version, about = "VPL global illumination with fuzzy k-means clustering (Colom, Marques, Santos 2022) on wgpu", after_help = LIGHTS_HELP)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Open the interactive viewer (the default with no subcommand: builtin:cornell).
    #[command(after_help = LIGHTS_HELP)]
    View(ViewArgs),
    /// Render one frame headless to EXR (linear HDR) or PNG (tone-mapped sRGB).
    #[command(after_help = LIGHTS_HELP)]
    Render(RenderArgs),
    /// Print what a scene holds and which passes would run.
    #[command(after_help = LIGHTS_HELP)]
    Info(InfoArgs),
    /// Ray throughput of the WGSL traversal against obvhs on all CPU cores (primary and shadow rays).
    Raybench(RaybenchArgs),
    /// Error against run time over a sweep of clustering settings: results.csv, plots, summary.md.
    #[command(after_help = BENCH_HELP)]
    Bench(BenchArgs),
}

const BENCH_HELP: &str = "\
Lists are comma-separated; the sweep is every combination of modes x SP K x VPL K x F x gamma
(values a mode ignores are dropped: hard has F = 1, vpl-only no SP K, sp-only no VPL K).
Modes: hard, uniform, weighted (both clusterings, Eqs. 8 / 9), vpl-only, sp-only.
Each configuration is rendered --repeat times; its times are the mean of the 3 best (GPU timestamps),
its error is the last image's MSE against the unclustered reference of the same camera.
--quick: 96x72, 1024 VPLs, 128 VPL clusters, 48 and 96 SP clusters, every mode, repeat 3
(given options still override it).
Example: fuzzy-vpl bench builtin:conference --out-dir bench-conf --sp-clusters 768,1536,3072 --vpl-clusters 512,1024";

#[derive(Args)]
struct BenchArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Directory for results.csv, reference.exr, images/, the plots and summary.md (created).
    #[arg(long)]
    out_dir: PathBuf,
    /// A small sweep at low resolution that finishes in a few minutes on a software driver.
    #[arg(long)]
    quick: bool,
    /// Modes to compare: hard,uniform,weighted,vpl-only,sp-only (default hard,uniform,weighted;
    /// quick: all five).
    #[arg(long, value_name = "LIST")]
    modes: Option<String>,
    /// SP cluster counts (default 768,1536,3072; quick 48,96).
    #[arg(long, value_name = "LIST")]
    sp_clusters: Option<String>,
    /// VPL cluster counts (default 1024; quick 128).
    #[arg(long, value_name = "LIST")]
    vpl_clusters: Option<String>,
    /// F values, 1..16 (default 6).
    #[arg(long, value_name = "LIST")]
    fuzziness: Option<String>,
    /// γ values: `auto` (the default: the largest γ in 4..16 that keeps 40 sampled points a cluster
    /// and 19,200 in all) or factors of at least 1, e.g. auto,4,16.
    #[arg(long, value_name = "LIST")]
    gamma: Option<String>,
    /// K_SP/K_VPL pairs to measure instead of every --sp-clusters × --vpl-clusters, e.g. the paper's
    /// light, intermediate and high settings at 640x480: 461/750,3072/2000,12288/4000.
    #[arg(long, value_name = "LIST")]
    pairs: Option<String>,
    /// p values of the inverse-distance weights w'_f = dist^-p, for weighted and sp-only (default 1,
    /// Eq. 10).
    #[arg(long, value_name = "LIST")]
    weight_exponent: Option<String>,
    /// Plane gates of the fuzzy modes' F lists: `off` (the paper, default) or angles in degrees,
    /// e.g. off,20 (see render --plane-gate).
    #[arg(long, value_name = "LIST")]
    plane_gate: Option<String>,
    /// Instead of the sweep's results.csv: render every configuration along a camera path,
    /// orbit:N:DEG (N frames, DEG degrees in all about the point the start camera looks at), each
    /// frame against its own reference; writes path.csv and path.png (docs/temporal.md).
    #[arg(long, value_name = "orbit:N:DEG", value_parser = fuzzy_vpl::bench::path::parse_camera_path)]
    camera_path: Option<fuzzy_vpl::bench::path::CameraPath>,
    /// Temporal reuse along --camera-path: on, off or both (off,on).
    #[arg(long, value_name = "LIST", value_delimiter = ',', default_value = "off", value_parser = fuzzy_vpl::gi::pipeline::parse_on_off, action = clap::ArgAction::Set, requires = "camera_path")]
    temporal: Vec<bool>,
    /// Image width (default 640; quick 96).
    #[arg(long)]
    width: Option<u32>,
    /// Image height (default 480; quick 72).
    #[arg(long)]
    height: Option<u32>,
    /// Number of VPLs (default 8192; quick 1024).
    #[arg(long)]
    vpls: Option<u32>,
    /// glTF camera indices, comma-separated (default: the scene's default view); one reference each.
    #[arg(long, value_name = "LIST")]
    camera: Option<String>,
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// Renders per configuration; times are the mean of the 3 best (default 10; quick 3).
    #[arg(long)]
    repeat: Option<u32>,
    /// Renders of the reference (slow on a software driver), timed the same way.
    #[arg(long, default_value_t = 1)]
    reference_repeat: u32,
    /// n_t of Eq. (7): cosine of the largest normal angle within a cluster.
    #[arg(long, default_value_t = 0.866, allow_hyphen_values = true)]
    normal_threshold: f32,
    /// k-means iterations.
    #[arg(long, default_value_t = 10)]
    iterations: u32,
    /// Area-light samples (shadow rays) per pixel for direct light, 1..=65536.
    #[arg(long, default_value_t = 16)]
    direct_samples: u32,
    /// G-term clamp as a fraction of the scene diagonal.
    #[arg(long, default_value_t = fuzzy_vpl::gi::pipeline::DEFAULT_CLAMP)]
    clamp: f32,
    /// Exposure of the PNG images: `auto` (the default: the reference's log-average luminance shown
    /// as middle grey 0.18, Reinhard et al. 2002, for every image of a camera) or a factor >= 0.
    #[arg(long, default_value = "auto", value_parser = Exposure::parse)]
    exposure: Exposure,
}

#[derive(Args)]
struct RaybenchArgs {
    /// Scenes to measure.
    #[arg(default_values_t = ["builtin:cornell".to_string(), "builtin:conference".to_string()])]
    scenes: Vec<String>,
    #[arg(long, default_value_t = 640)]
    width: u32,
    #[arg(long, default_value_t = 480)]
    height: u32,
    /// Also write the rows as JSON here.
    #[arg(long)]
    json: Option<PathBuf>,
}

#[derive(Args, Clone)]
struct SceneArgs {
    /// A .gltf/.glb path or builtin:NAME (builtin:cornell, builtin:conference).
    #[arg(default_value = "builtin:cornell")]
    scene: String,
    /// Add a directional light: DX,DY,DZ,E[,R,G,B] (direction towards the sun).
    #[arg(long, value_name = "DX,DY,DZ,E[,R,G,B]", allow_hyphen_values = true)]
    sun: Vec<String>,
    /// Add a point light: X,Y,Z,I[,R,G,B].
    #[arg(long, value_name = "X,Y,Z,I[,R,G,B]", allow_hyphen_values = true)]
    point: Vec<String>,
    /// Multiply every emitter's power by this factor.
    #[arg(long, default_value_t = 1.0)]
    light_scale: f32,
    /// Load a file that requires glTF extension NAME, which fuzzy-vpl does not know, ignoring it
    /// (repeatable). Only for extensions that change neither geometry nor diffuse colour.
    #[arg(long, value_name = "NAME")]
    allow_extension: Vec<String>,
}

#[derive(Args)]
struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Output image: .exr (linear radiance) or .png (exposure, clamp, sRGB).
    /// Repeat -o to write several files of the same frame (e.g. -o a.exr -o a.png).
    #[arg(short, long, required = true)]
    output: Vec<PathBuf>,
    /// Write the stats JSON (docs/design.md, "Stats JSON") here.
    #[arg(long)]
    stats: Option<PathBuf>,
    /// Fill the stats' error block against this reference EXR.
    #[arg(long)]
    compare: Option<PathBuf>,
    #[arg(long, default_value_t = 640)]
    width: u32,
    #[arg(long, default_value_t = 480)]
    height: u32,
    /// Use the Nth glTF camera (0-based); default: the scene's first camera, else a view of its bounds.
    #[arg(long)]
    camera: Option<usize>,
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// Area-light samples (shadow rays) per pixel for direct light, 1..=65536.
    #[arg(long, default_value_t = 16)]
    direct_samples: u32,
    /// PNG exposure: `auto` (the default: the image's log-average luminance is shown as middle grey
    /// 0.18, Reinhard et al. 2002) or a factor >= 0. EXR stays linear, unscaled radiance.
    #[arg(long, default_value = "auto", value_parser = Exposure::parse)]
    exposure: Exposure,
    /// Render N times; timings are the mean of the 3 best (the paper's method).
    #[arg(long, default_value_t = 1)]
    repeat: u32,
    /// Temporal reuse (on|off): each render's SP clustering starts from the previous one's
    /// centroids where the view still sees them (docs/temporal.md). A single frame has no past, so
    /// only --repeat's later renders reuse.
    #[arg(long, default_value = "off", value_name = "on|off", value_parser = fuzzy_vpl::gi::pipeline::parse_on_off, action = clap::ArgAction::Set)]
    temporal: bool,
    /// Number of VPLs (traced once, resident).
    #[arg(long, default_value_t = 8192)]
    vpls: u32,
    /// Indirect bounce budget: the most VPLs a light path deposits (the path tracer gets the same).
    #[arg(long, default_value_t = fuzzy_vpl::gi::vpl_trace::MAX_DEPTH)]
    bounces: u32,
    /// Indirect light without any clustering: every pixel gathers every VPL with its own shadow ray
    /// (Eq. 5; the paper's reference).
    #[arg(long)]
    reference: bool,
    /// K of the VPL clustering (0 = no VPL clustering; off when ≥ --vpls).
    #[arg(long, default_value_t = 1024)]
    vpl_clusters: u32,
    /// K of the shading-point clustering (0 = no SP clustering; off when ≥ the pixel count).
    #[arg(long, default_value_t = 3072)]
    sp_clusters: u32,
    #[command(flatten)]
    cluster: ClusterArgs,
    /// Eq. (10) weights from the distances to the SP clusters' representatives (the paper's text)
    /// instead of their centroids (Alg. 2).
    #[arg(long)]
    weights_to_reps: bool,
    /// Render with the diffuse path tracer instead (SPP samples per pixel, same bounce budget as the
    /// VPLs): the check of the VPL reference's own bias.
    #[arg(long, value_name = "SPP", conflicts_with = "reference")]
    path_trace: Option<u32>,
    /// Write a false-colour per-pixel error image against --compare (log10 rel. error, -4..0).
    #[arg(long, requires = "compare")]
    error_map: Option<PathBuf>,
}

/// The clustering settings `render` and `view` share (their K and VPL defaults differ, so those stay
/// with each command; `bench` takes lists instead).
#[derive(Args)]
struct ClusterArgs {
    /// F: SP clusters per pixel (fuzziness), 1..16.
    #[arg(long, default_value_t = 6)]
    fuzziness: u32,
    /// γ: SP downsampling factor for the k-means iterations, or `auto`: the largest γ in 4..16 that
    /// keeps 40 sampled points a cluster and 19,200 in all. Either way at most pixels / K, so that at
    /// least K points are sampled.
    #[arg(long, default_value = "auto", value_parser = fuzzy_vpl::gi::kmeans::parse_gamma)]
    gamma: u32,
    /// n_t of Eq. (7): cosine of the largest normal angle within a cluster, in [-1, 1] (Eq. 7's test
    /// is strict, so 1 is read as 1 - 2^-20: the same normal only).
    #[arg(long, default_value_t = 0.866, allow_hyphen_values = true)]
    normal_threshold: f32,
    /// k-means iterations.
    #[arg(long, default_value_t = 10)]
    iterations: u32,
    /// How a pixel's F clusters combine visibility: hard (F = 1), uniform (Eq. 8), inverse-distance
    /// (Eq. 9).
    #[arg(long, value_enum, default_value_t = Weighting::InverseDistance)]
    weighting: Weighting,
    /// p of the inverse-distance weights, w'_f = dist^-p: 1 is Eq. (10); larger p falls off faster
    /// (the paper's §6 suggestion), 0 is Eq. (8)'s plain mean (but a point on a centroid still takes
    /// it alone), 64 is nearly hard clustering.
    #[arg(long, default_value_t = fuzzy_vpl::gi::pipeline::DEFAULT_WEIGHT_EXPONENT)]
    weight_exponent: f32,
    /// Not in the paper (off by default): the fuzzy modes' slots 2..F keep only SP clusters whose
    /// centroid lies within DEG degrees of the pixel's tangent plane, seen from the pixel. Eq. (7)
    /// gates on normals alone, so without it a floor pixel's F clusters include a chair seat above
    /// it (docs/clustering.md, "The plane gate"). (0, 90].
    #[arg(long, value_name = "DEG")]
    plane_gate: Option<f32>,
    /// G-term clamp: the VPL distance in 1/d² is at least CLAMP × scene diagonal (scale-free).
    #[arg(long, default_value_t = fuzzy_vpl::gi::pipeline::DEFAULT_CLAMP)]
    clamp: f32,
}

impl ClusterArgs {
    /// Refuses settings no clustering can use (exit 2 with one line).
    fn check(&self) -> Result<()> {
        check_fuzziness(self.fuzziness)?;
        check_normal_threshold(self.normal_threshold)?;
        check_iterations(self.iterations)?;
        check_clamp(self.clamp)?;
        check_weight_exponent(self.weight_exponent)?;
        match self.plane_gate {
            Some(g) if !fuzzy_vpl::gi::kmeans::valid_plane_gate(g) => Err(bad(format!(
                "--plane-gate {g}: must be an angle in (0, 90] degrees"
            ))),
            _ => Ok(()),
        }
    }

    /// `fs` with these settings.
    fn apply(&self, fs: FrameSettings) -> FrameSettings {
        FrameSettings {
            fuzziness: self.fuzziness,
            gamma: self.gamma,
            normal_threshold: self.normal_threshold,
            iterations: self.iterations,
            weighting: self.weighting,
            weight_exponent: self.weight_exponent,
            plane_gate_deg: self.plane_gate,
            clamp: self.clamp,
            ..fs
        }
    }
}

#[derive(Args)]
struct ViewArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Size of the image area at start, logical pixels (the window adds the side panel).
    #[arg(long, default_value_t = 640)]
    width: u32,
    #[arg(long, default_value_t = 480)]
    height: u32,
    /// Start from the Nth glTF camera (0-based).
    #[arg(long)]
    camera: Option<usize>,
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// Area-light samples (shadow rays) per pixel for direct light, 1..=65536.
    #[arg(long, default_value_t = 16)]
    direct_samples: u32,
    /// Display exposure: `auto` (the default: each frame's log-average luminance shown as middle grey
    /// 0.18) or a factor > 0.
    #[arg(long, default_value = "auto", value_parser = Exposure::parse)]
    exposure: Exposure,
    /// VPLs (the viewer starts lighter than `render` so a software driver stays interactive).
    #[arg(long, default_value_t = 4096)]
    vpls: u32,
    #[arg(long, default_value_t = 512)]
    vpl_clusters: u32,
    #[arg(long, default_value_t = 1024)]
    sp_clusters: u32,
    #[command(flatten)]
    cluster: ClusterArgs,
    /// Temporal reuse (on|off): reprojection of the last frame while the camera moves, clusterings
    /// warm-started from the previous frame, direct light accumulated at rest (docs/temporal.md).
    #[arg(long, default_value = "on", value_name = "on|off", value_parser = fuzzy_vpl::gi::pipeline::parse_on_off, action = clap::ArgAction::Set)]
    temporal: bool,
    /// Render scale of the GI image relative to the image area, 0.1..1.
    #[arg(long, default_value_t = 0.5)]
    render_scale: f32,
    /// Scripted run: draw N window frames once the first full GI frame is shown (with --animate: N
    /// frames of orbiting, then one frame at rest), save the window to --screenshot and the
    /// measurements to --stats, exit.
    #[arg(long)]
    frames: Option<u32>,
    /// Where a scripted run saves the window (PNG, UI included).
    #[arg(long, requires = "frames")]
    screenshot: Option<PathBuf>,
    /// Where a scripted run writes its JSON: settings, `motion` (camera change to image latency,
    /// GPU ms of the GI frames while moving) and `rest` (GPU ms of the frame at rest).
    #[arg(long, requires = "frames")]
    stats: Option<PathBuf>,
    /// The view to start in (a scripted run in reference or error computes the reference first).
    #[arg(long, value_enum, default_value = "final")]
    view: fuzzy_vpl::app::views::View,
    /// Keep orbiting the camera (0.6 rad/s about the point looked at) to measure the viewer while
    /// moving; with --frames.
    #[arg(long)]
    animate: bool,
    /// Directory for the panel's screenshots.
    #[arg(long, default_value = ".")]
    shot_dir: PathBuf,
}

#[derive(Args)]
struct InfoArgs {
    #[command(flatten)]
    scene: SceneArgs,
}

/// The command line with every option that takes a value accepting a negative number as that value
/// (`--light-scale -1` is then refused by the option's own check, with its range, rather than read
/// as an unknown flag `-1`).
fn command() -> clap::Command {
    fn negatives(c: clap::Command) -> clap::Command {
        let ids: Vec<clap::Id> = c
            .get_arguments()
            .filter(|a| !a.is_positional() && a.get_action().takes_values())
            .map(|a| a.get_id().clone())
            .collect();
        let c = ids
            .iter()
            .fold(c, |c, id| c.mut_arg(id, |a| a.allow_negative_numbers(true)));
        let subs: Vec<String> = c
            .get_subcommands()
            .map(|s| s.get_name().to_string())
            .collect();
        subs.iter()
            .fold(c, |c, name| c.mut_subcommand(name, negatives))
    }
    negatives(<Cli as clap::CommandFactory>::command())
}

/// An error that is the user's input: exit code 2.
#[derive(Debug)]
struct BadInput(String);
impl std::fmt::Display for BadInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}
impl std::error::Error for BadInput {}

fn bad(msg: impl Into<String>) -> anyhow::Error {
    BadInput(msg.into()).into()
}

fn main() -> ExitCode {
    // `fuzzy-vpl info SCENE | head` closes stdout early: end quietly like other command-line tools
    // instead of panicking on the failed print (Rust ignores SIGPIPE by default).
    // SAFETY: first thing in main, before any other thread exists.
    #[cfg(unix)]
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL)
    };
    // Mesa's Vulkan loader complains on stderr when XDG_RUNTIME_DIR is unset (headless machines, CI).
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        let dir = std::env::temp_dir().join("fuzzy-vpl-runtime");
        if std::fs::create_dir_all(&dir).is_ok() {
            // SAFETY: first thing in main, before any other thread exists.
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
        }
    }
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    // Bad arguments get one line and exit code 2 (docs/design.md, "Exit codes"); help and version
    // print in full.
    let cli = match command()
        .try_get_matches()
        .and_then(|m| <Cli as clap::FromArgMatches>::from_arg_matches(&m))
    {
        Ok(c) => c,
        Err(e) => {
            use clap::error::ErrorKind;
            match e.kind() {
                ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
                    let _ = e.print();
                    return ExitCode::SUCCESS;
                }
                ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
                    let _ = e.print();
                    return ExitCode::from(2);
                }
                _ => {}
            }
            // The message and its details (e.g. the missing arguments) up to the first blank line.
            let text = e.render().to_string();
            let line: Vec<&str> = text
                .lines()
                .map(str::trim)
                .take_while(|l| !l.is_empty())
                .collect();
            eprintln!("{} (see --help)", line.join(" "));
            return ExitCode::from(2);
        }
    };
    let result = match cli.command {
        None => view(ViewArgs::parse_from(["view"])),
        Some(Command::View(a)) => view(a),
        Some(Command::Render(a)) => render(a),
        Some(Command::Info(a)) => info(a),
        Some(Command::Raybench(a)) => raybench(a),
        Some(Command::Bench(a)) => bench(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let is_input = e.downcast_ref::<BadInput>().is_some()
                || e.downcast_ref::<scene::SceneError>().is_some()
                || e.downcast_ref::<fuzzy_vpl::gi::scene_gpu::TooBig>()
                    .is_some()
                || e.downcast_ref::<fuzzy_vpl::app::Unavailable>().is_some();
            eprintln!("error: {e}");
            if is_input {
                ExitCode::from(2)
            } else {
                ExitCode::from(1)
            }
        }
    }
}

/// The most VPLs this device holds: the VPL buffer is one storage binding.
fn check_vpls(ctx: &GpuContext, vpls: u32) -> Result<()> {
    use fuzzy_vpl::gi::vpl_trace::VPL_BYTES;
    let binding = ctx.max_binding();
    let most = binding / VPL_BYTES;
    if vpls as u64 > most {
        return Err(bad(format!(
            "--vpls {vpls}: at most {most} on this adapter ({VPL_BYTES} bytes a VPL in one {binding}-byte storage binding)"
        )));
    }
    Ok(())
}

/// The largest image this device renders: each per-pixel buffer is one storage binding.
fn check_size(ctx: &GpuContext, width: u32, height: u32, bytes_per_pixel: u64) -> Result<()> {
    fuzzy_vpl::gi::pipeline::check_frame_size(ctx, width, height, bytes_per_pixel).map_err(|e| {
        bad(format!(
            "--width/--height {width}x{height}: {} pixels, at most {} on this adapter ({} bytes a pixel in one {}-byte storage binding)",
            width as u64 * height as u64,
            e.most,
            e.bytes,
            e.binding
        ))
    })
}

fn load_scene(a: &SceneArgs) -> Result<Scene> {
    let opts = scene::LoadOptions {
        allow_extensions: a.allow_extension.clone(),
    };
    let mut s = scene::load_with(&a.scene, &opts)?;
    for w in &s.report.warnings {
        eprintln!("warning: {}: {w}", a.scene);
    }
    for v in &a.sun {
        s.lights
            .push(extra_lights::parse_sun(v).map_err(|e| bad(format!("--sun {v}: {e}")))?);
    }
    for v in &a.point {
        s.lights
            .push(extra_lights::parse_point(v).map_err(|e| bad(format!("--point {v}: {e}")))?);
    }
    if !(a.light_scale.is_finite() && a.light_scale >= 0.0) {
        return Err(bad(format!(
            "--light-scale {}: must be a finite number >= 0",
            a.light_scale
        )));
    }
    // The scaled emitters and the image they light must stay within f32: above 1e36 the image
    // overflows, below 1e-44 it rounds to 0.
    let brightest = s.max_emission() * a.light_scale as f64;
    if brightest > 0.0 && !(1e-44..=1e36).contains(&brightest) {
        return Err(bad(format!(
            "{}: the brightest emitter emits {brightest:.3e} with --light-scale {}; outside 1e-44..1e36 the image does not fit in f32",
            a.scene, a.light_scale
        )));
    }
    s.scale_light_power(a.light_scale as f64);
    if !s.has_light() {
        eprintln!(
            "warning: {}: the scene has no light (no emissive material, no punctual light of non-zero power); it renders black. Add one with --sun or --point.",
            a.scene
        );
    }
    Ok(s)
}

fn render(a: RenderArgs) -> Result<()> {
    for out in &a.output {
        let ext = out
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        if !matches!(ext.as_deref(), Some("exr") | Some("png")) {
            return Err(bad(format!(
                "{}: output must end in .exr or .png",
                out.display()
            )));
        }
    }
    if a.width == 0 || a.height == 0 || a.width > 16384 || a.height > 16384 {
        return Err(bad(format!(
            "--width/--height {}x{}: must be 1..16384",
            a.width, a.height
        )));
    }
    if a.repeat == 0 {
        return Err(bad("--repeat must be at least 1"));
    }
    if a.path_trace == Some(0) {
        return Err(bad("--path-trace 0: must be at least 1 sample a pixel"));
    }
    a.cluster.check()?;
    check_direct_samples(a.direct_samples)?;
    if !(1..=64).contains(&a.bounces) {
        return Err(bad(format!("--bounces {}: must be 1..64", a.bounces)));
    }
    if let Some(p) = &a.error_map
        && p.extension().and_then(|e| e.to_str()) != Some("png")
    {
        return Err(bad(format!(
            "{}: --error-map must end in .png",
            p.display()
        )));
    }
    // Every output can be written: checked before the (possibly long) render.
    for p in a.output.iter().chain(&a.stats).chain(&a.error_map) {
        export::check_writable(p).map_err(bad)?;
    }
    let reference = match &a.compare {
        Some(p) => {
            let (w, h, px) = export::read_exr(p).map_err(|e| bad(format!("{e:#}")))?;
            if let Some(i) = px.iter().position(|c| c.iter().any(|x| !x.is_finite())) {
                return Err(bad(format!(
                    "{}: reference has a non-finite pixel (NaN or infinity) at pixel {i}",
                    p.display()
                )));
            }
            if (w, h) != (a.width, a.height) {
                return Err(bad(format!(
                    "{}: reference is {w}x{h}, the render is {}x{}",
                    p.display(),
                    a.width,
                    a.height
                )));
            }
            Some(px)
        }
        None => None,
    };
    let scene = load_scene(&a.scene)?;
    let camera = match a.camera {
        Some(i) => scene.cameras.get(i).cloned().ok_or_else(|| {
            bad(format!(
                "{}: --camera {i}: the scene has {} camera(s)",
                a.scene.scene,
                scene.cameras.len()
            ))
        })?,
        None => scene.default_camera(),
    };
    let ctx = GpuContext::new_headless()?;
    check_vpls(&ctx, a.vpls)?;
    let bytes = match a.path_trace {
        Some(_) => fuzzy_vpl::gi::pipeline::PATH_TRACE_PIXEL_BYTES,
        None => fuzzy_vpl::gi::pipeline::PIXEL_BYTES,
    };
    check_size(&ctx, a.width, a.height, bytes)?;
    let mut renderer = Renderer::new(&ctx, &scene)?;
    let settings = a.cluster.apply(FrameSettings {
        width: a.width,
        height: a.height,
        seed: a.seed,
        direct_samples: a.direct_samples,
        vpls: a.vpls,
        bounces: a.bounces,
        reference: a.reference,
        vpl_clusters: a.vpl_clusters,
        sp_clusters: a.sp_clusters,
        weights_to_reps: a.weights_to_reps,
        temporal: a.temporal,
        progress: true,
        control: None,
        ..Default::default()
    });
    if a.path_trace.is_none() {
        let plan = fuzzy_vpl::gi::pipeline::Plan::new(&scene, &settings);
        fuzzy_vpl::gi::pipeline::check_visibility_size(&ctx, &plan, &settings).map_err(bad)?;
    }
    let mut runs = Vec::new();
    let mut frame = None;
    for _ in 0..a.repeat {
        let f = match a.path_trace {
            Some(spp) => renderer.path_trace(&camera, &settings, spp)?,
            None => renderer.render(&camera, &settings)?,
        };
        runs.push(f.timings_ms.clone());
        frame = Some(f);
    }
    let frame = frame.expect("repeat >= 1");
    let non_finite = frame
        .radiance
        .iter()
        .flatten()
        .filter(|c| !c.is_finite())
        .count();
    if non_finite > 0 {
        eprintln!("warning: {non_finite} non-finite pixel channels in the output");
    }
    // Never a silent black image: a lit scene rendering all black says so (no light at all was
    // warned about when loading).
    if scene.has_light() && frame.radiance.iter().flatten().all(|&c| c == 0.0) {
        eprintln!(
            "warning: {}: the image is black although the scene has light (the camera sees no lit surface)",
            a.scene.scene
        );
    }
    let exposure = a.exposure.resolve(&frame.radiance);
    for out in &a.output {
        export::write_image(out, frame.width, frame.height, &frame.radiance, exposure)?;
    }
    if let (Some(p), Some(r)) = (&a.error_map, &reference) {
        export::write_png_rgb8(
            p,
            frame.width,
            frame.height,
            metrics::error_map(&frame.radiance, r),
        )?;
    }
    let error = reference.as_ref().map(|r| stats::ErrorStats {
        mse: metrics::mse(&frame.radiance, r),
        rel_mse: metrics::rel_mse(&frame.radiance, r),
    });
    let timings_ms = stats::best_of_runs(&runs);
    eprintln!(
        "{}: {}x{} in {:.1} ms GPU ({}), mean luminance {:.4} -> {}",
        a.scene.scene,
        frame.width,
        frame.height,
        timings_ms["frame"],
        frame.passes.join(" + "),
        metrics::mean_luminance(&frame.radiance),
        a.output
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    if let Some(p) = &a.stats {
        let s = stats::Stats {
            scene: a.scene.scene.clone(),
            width: frame.width,
            height: frame.height,
            adapter: ctx.adapter_name.clone(),
            settings: stats::Settings {
                vpls: frame.vpls,
                vpl_clusters: settings.vpl_clusters,
                sp_clusters: settings.sp_clusters,
                fuzziness: settings.f(),
                gamma: fuzzy_vpl::gi::kmeans::resolve_gamma(
                    settings.gamma,
                    frame.width * frame.height,
                    settings.sp_clusters,
                ),
                gamma_auto: settings.gamma == fuzzy_vpl::gi::kmeans::AUTO_GAMMA,
                normal_threshold: settings.normal_threshold,
                iterations: settings.iterations,
                weighting: settings.weighting.name().into(),
                weight_exponent: settings.weight_exponent,
                reference: a.reference,
                seed: a.seed,
                direct_samples: settings.direct_samples,
                light_scale: a.scene.light_scale,
                exposure,
                exposure_auto: a.exposure.is_auto(),
                clamp: settings.clamp,
                gamma_used: frame.gamma_used,
                normal_threshold_used: fuzzy_vpl::gi::kmeans::effective_normal_threshold(
                    settings.normal_threshold,
                ),
                bounces: settings.bounces,
                path_trace_spp: a.path_trace.map(|n| n.max(1)),
                plane_gate_deg: settings
                    .plane_gate_deg
                    .filter(|_| frame.gamma_used.is_some() && settings.f() > 1),
                temporal: settings.temporal,
            },
            counts: stats::Counts {
                triangles: scene.triangles.len() as u64,
                vpls: frame.vpls as u64,
                sp_clusters_used: frame.sp_clusters_used as u64,
                vpl_clusters_used: frame.vpl_clusters_used as u64,
                shading_points: frame.shading_points as u64,
                shadow_rays: frame.shadow_rays,
                emissive_triangles: renderer.gpu.emitters.len() as u64,
                punctual_lights: scene.lights.len() as u64,
                sp_iterations: frame.sp_iterations,
                sp_warm_kept: frame.sp_warm_kept,
                visibility_rows_reused: frame.visibility_rows_reused,
            },
            passes: frame.passes.iter().map(|s| s.to_string()).collect(),
            timings_ms,
            repeat: a.repeat,
            mean_luminance: metrics::mean_luminance(&frame.radiance),
            bvh_build_ms: renderer.bvh.build_ms,
            error,
        };
        let json = serde_json::to_string_pretty(&s)?;
        export::write_atomic(p, |w| {
            use std::io::Write;
            w.write_all(json.as_bytes())?;
            Ok(())
        })?;
    }
    Ok(())
}

impl ViewArgs {
    /// `ViewArgs` with every default (for `fuzzy-vpl` with no arguments).
    fn parse_from<'a>(args: impl IntoIterator<Item = &'a str>) -> ViewArgs {
        #[derive(Parser)]
        struct Wrap {
            #[command(flatten)]
            a: ViewArgs,
        }
        Wrap::parse_from(args).a
    }
}

fn view(a: ViewArgs) -> Result<()> {
    if a.width == 0 || a.height == 0 || a.width > 16384 || a.height > 16384 {
        return Err(bad(format!(
            "--width/--height {}x{}: must be 1..16384",
            a.width, a.height
        )));
    }
    a.cluster.check()?;
    check_direct_samples(a.direct_samples)?;
    if a.exposure == Exposure::Fixed(0.0) {
        return Err(bad(
            "--exposure 0: the viewer needs an exposure > 0 (or auto)",
        ));
    }
    if !(0.1..=1.0).contains(&a.render_scale) {
        return Err(bad(format!(
            "--render-scale {}: must be in [0.1, 1]",
            a.render_scale
        )));
    }
    if let Some(p) = &a.screenshot
        && !p
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("png"))
    {
        return Err(bad(format!(
            "{}: --screenshot must end in .png",
            p.display()
        )));
    }
    if a.frames.is_some() && a.screenshot.is_none() && a.stats.is_none() {
        return Err(bad("--frames needs --screenshot or --stats"));
    }
    for p in a.screenshot.iter().chain(&a.stats) {
        export::check_writable(p).map_err(bad)?;
    }
    // The panel's screenshots go there: found out at start, not at the first F11.
    if !a.shot_dir.is_dir() {
        return Err(bad(format!(
            "--shot-dir {}: not a directory",
            a.shot_dir.display()
        )));
    }
    export::check_writable(&a.shot_dir.join("screenshot.png"))
        .map_err(|e| bad(format!("--shot-dir {e}")))?;
    let scene = load_scene(&a.scene)?;
    // render's device limits apply to the viewer's GI worker too (it makes its own device).
    check_vpls(&GpuContext::new_headless()?, a.vpls)?;
    if let Some(i) = a.camera
        && i >= scene.cameras.len()
    {
        return Err(bad(format!(
            "{}: --camera {i}: the scene has {} camera(s)",
            a.scene.scene,
            scene.cameras.len()
        )));
    }
    let fs = a.cluster.apply(FrameSettings {
        seed: a.seed,
        direct_samples: a.direct_samples,
        vpls: a.vpls,
        vpl_clusters: a.vpl_clusters,
        sp_clusters: a.sp_clusters,
        temporal: a.temporal,
        ..Default::default()
    });
    let fixed = match a.exposure {
        Exposure::Fixed(e) => e,
        Exposure::Auto => 1.0,
    };
    let mut settings = fuzzy_vpl::app::UiSettings::from_frame_settings(&fs, fixed);
    settings.exposure_auto = a.exposure.is_auto();
    settings.render_scale = a.render_scale;
    let args = a.scene.clone();
    let loader: fuzzy_vpl::app::worker::Loader = std::sync::Arc::new(move |spec: &str| {
        let mut sa = args.clone();
        sa.scene = spec.to_string();
        load_scene(&sa)
    });
    fuzzy_vpl::app::run(fuzzy_vpl::app::ViewOptions {
        spec: a.scene.scene.clone(),
        scene,
        loader,
        width: a.width,
        height: a.height,
        camera: a.camera,
        settings,
        frames: a.frames,
        screenshot: a.screenshot,
        view: a.view,
        animate: a.animate,
        stats: a.stats,
        shot_dir: a.shot_dir,
    })
}

fn info(a: InfoArgs) -> Result<()> {
    let s = load_scene(&a.scene)?;
    let (lo, hi) = s.bounds();
    println!("scene:               {}", a.scene.scene);
    println!("triangles:           {}", s.triangles.len());
    println!("dropped degenerate:  {}", s.report.dropped_degenerate);
    println!(
        "generated normals:   {} triangles",
        s.report.generated_normals
    );
    println!("materials:           {}", s.materials.len());
    println!("textures:            {}", s.textures.len());
    println!("emissive triangles:  {}", s.emissive_triangle_count());
    let kinds = |k: fn(&scene::LightKind) -> bool| s.lights.iter().filter(|l| k(&l.kind)).count();
    println!(
        "punctual lights:     {} (point {}, spot {}, directional {})",
        s.lights.len(),
        kinds(|k| matches!(k, scene::LightKind::Point)),
        kinds(|k| matches!(k, scene::LightKind::Spot { .. })),
        kinds(|k| matches!(k, scene::LightKind::Directional)),
    );
    println!("cameras:             {}", s.cameras.len());
    // Fixed decimals for everyday units, exponents for scenes in other units (1e-15 or 1e12).
    let num = |x: f32, d: usize| {
        if x == 0.0 || (1e-3..1e6).contains(&x.abs()) {
            format!("{x:.d$}")
        } else {
            format!("{x:.3e}")
        }
    };
    for (i, c) in s.cameras.iter().enumerate() {
        let e = c.eye();
        println!(
            "  [{i}] {:<16} eye ({}, {}, {}) yfov {:.1} deg",
            c.name,
            num(e.x, 3),
            num(e.y, 3),
            num(e.z, 3),
            c.yfov.to_degrees()
        );
    }
    println!(
        "bounds:              ({}, {}, {}) .. ({}, {}, {})",
        num(lo.x, 4),
        num(lo.y, 4),
        num(lo.z, 4),
        num(hi.x, 4),
        num(hi.y, 4),
        num(hi.z, 4)
    );
    let g = s.geometry_scale();
    if g != 1.0 {
        println!(
            "unit frame:          rendered with the geometry scaled by 2^{} (Scene::geometry_scale)",
            g.log2().round() as i32
        );
    }
    match fuzzy_vpl::gi::scene_gpu::check_fits(&s, u64::MAX) {
        Ok(()) => println!(
            "GPU data:            {} of at most {} triangles",
            s.triangles.len(),
            fuzzy_vpl::gi::scene_gpu::MAX_TRIANGLES
        ),
        Err(e) => println!("GPU data:            does not fit: {e}"),
    }
    println!(
        "extensions used:     {}",
        s.report.extensions_used.join(", ")
    );
    println!("features:            {}", s.features().join(", "));
    println!(
        "passes (render):     {}",
        Renderer::passes_for(&s, &FrameSettings::default()).join(" -> ")
    );
    let tested = s.alpha_test_flags().into_iter().filter(|&f| f).count();
    if tested > 0 {
        let materials = s
            .materials
            .iter()
            .filter(|m| m.alpha_cutoff.is_some())
            .count();
        println!(
            "alpha test:          {tested} triangles ({materials} alpha-masked materials); in every pass that traces rays"
        );
    } else {
        println!("alpha test:          none (the passes are compiled without it)");
    }
    Ok(())
}

fn raybench(a: RaybenchArgs) -> Result<()> {
    let ctx = GpuContext::new_headless()?;
    println!(
        "adapter: {}; CPU: {} threads (rayon)",
        ctx.adapter_name,
        rayon::current_num_threads()
    );
    println!(
        "{:<40} {:>8} {:>9} {:>9} {:>12} {:>12} {:>12} {:>7}",
        "scene", "rays", "triangles", "kind", "GPU Mray/s", "CPU BVH2", "CPU CWBVH", "GPU/CPU"
    );
    let mut rows = Vec::new();
    for spec in &a.scenes {
        let s = scene::load(spec)?;
        let cam = s.default_camera();
        for r in fuzzy_vpl::raybench::run(&ctx, &s, &cam, a.width, a.height)? {
            println!(
                "{:<40} {:>8} {:>9} {:>9} {:>12.3} {:>12.3} {:>12.3} {:>7.2}",
                r.scene,
                r.rays,
                r.triangles,
                r.kind,
                r.gpu_mrays_s,
                r.cpu_bvh2_mrays_s,
                r.cpu_cwbvh_mrays_s,
                r.ratio
            );
            rows.push(r);
        }
    }
    if let Some(p) = &a.json {
        let json = serde_json::to_string_pretty(&rows)?;
        export::write_atomic(p, |w| {
            use std::io::Write;
            w.write_all(json.as_bytes())?;
            Ok(())
        })?;
    }
    Ok(())
}

fn bench(a: BenchArgs) -> Result<()> {
    let base_sweep = if a.quick {
        sweep::Sweep::quick_default()
    } else {
        sweep::Sweep::full_default()
    };
    let sweep = sweep::Sweep::parse(
        &sweep::SweepArgs {
            modes: a.modes.clone(),
            sp_clusters: a.sp_clusters.clone(),
            vpl_clusters: a.vpl_clusters.clone(),
            fuzziness: a.fuzziness.clone(),
            gamma: a.gamma.clone(),
            weight_exponent: a.weight_exponent.clone(),
            plane_gate: a.plane_gate.clone(),
            pairs: a.pairs.clone(),
        },
        base_sweep,
    )
    .map_err(bad)?;
    let q = |quick: u32, full: u32| if a.quick { quick } else { full };
    let width = a.width.unwrap_or(q(96, 640));
    let height = a.height.unwrap_or(q(72, 480));
    let vpls = a.vpls.unwrap_or(q(1024, 8192));
    let repeat = a.repeat.unwrap_or(q(3, 10));
    if width == 0 || height == 0 || width > 16384 || height > 16384 {
        return Err(bad(format!(
            "--width/--height {width}x{height}: must be 1..16384"
        )));
    }
    if vpls == 0 {
        return Err(bad("--vpls must be at least 1"));
    }
    if repeat == 0 || a.reference_repeat == 0 {
        return Err(bad("--repeat and --reference-repeat must be at least 1"));
    }
    check_normal_threshold(a.normal_threshold)?;
    check_iterations(a.iterations)?;
    check_clamp(a.clamp)?;
    check_direct_samples(a.direct_samples)?;
    let cam_list: Option<Vec<usize>> = a
        .camera
        .as_deref()
        .map(|c| sweep::parse_list("--camera", c))
        .transpose()
        .map_err(bad)?;
    let scene = load_scene(&a.scene)?;
    let cameras = match cam_list {
        None => vec![("default".to_string(), scene.default_camera())],
        Some(l) => l
            .into_iter()
            .map(|i| {
                scene
                    .cameras
                    .get(i)
                    .cloned()
                    .map(|c| (i.to_string(), c))
                    .ok_or_else(|| {
                        bad(format!(
                            "{}: --camera {i}: the scene has {} camera(s)",
                            a.scene.scene,
                            scene.cameras.len()
                        ))
                    })
            })
            .collect::<Result<_>>()?,
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
    check_vpls(&ctx, vpls)?;
    check_size(&ctx, width, height, fuzzy_vpl::gi::pipeline::PIXEL_BYTES)?;
    std::fs::create_dir_all(&images)
        .map_err(|e| bad(format!("{}: cannot create: {e}", images.display())))?;
    let plan = bench::BenchPlan {
        scene_name: a.scene.scene.clone(),
        out_dir: a.out_dir.clone(),
        base: FrameSettings {
            width,
            height,
            seed: a.seed,
            direct_samples: a.direct_samples,
            vpls,
            normal_threshold: a.normal_threshold,
            iterations: a.iterations,
            clamp: a.clamp,
            ..FrameSettings::default()
        },
        sweep,
        cameras,
        repeat,
        reference_repeat: a.reference_repeat,
        exposure: a.exposure,
        progress: true,
    };
    // Every configuration's visibility matrix fits the adapter: checked before any work.
    for c in plan.sweep.configs() {
        let s = c.settings(&plan.base);
        let p = fuzzy_vpl::gi::pipeline::Plan::new(&scene, &s);
        fuzzy_vpl::gi::pipeline::check_visibility_size(&ctx, &p, &s).map_err(bad)?;
    }
    if let Some(path) = &a.camera_path {
        if plan.cameras.len() > 1 {
            return Err(bad(format!(
                "--camera-path starts from one camera; --camera lists {}",
                plan.cameras.len()
            )));
        }
        eprintln!(
            "bench {}: {} configuration(s) x temporal {:?} along orbit:{}:{}, {width}x{height}, {vpls} VPLs on {}",
            a.scene.scene,
            plan.sweep.configs().len(),
            a.temporal,
            path.frames,
            path.degrees,
            ctx.adapter_name
        );
        let rows = bench::path::run(&ctx, &scene, &plan, path, &a.temporal)?;
        println!(
            "{:<32} {:>8} {:>10} {:>12} {:>11} {:>12}",
            "configuration", "temporal", "frame ms", "SP clust. ms", "MSE", "instability"
        );
        let mut seen = Vec::new();
        for r in &rows {
            if seen.contains(&(&r.label, r.temporal)) {
                continue;
            }
            seen.push((&r.label, r.temporal));
            if let Some([f, sp, mse, inst]) = bench::path::means(&rows, &r.label, r.temporal) {
                println!(
                    "{:<32} {:>8} {f:>10.2} {sp:>12.2} {mse:>11.3e} {inst:>12.3e}",
                    r.label,
                    if r.temporal { "on" } else { "off" }
                );
            }
        }
        println!(
            "(means over frames 1..{}) wrote path.csv and path.png to {}",
            path.frames.saturating_sub(1),
            a.out_dir.display()
        );
        return Ok(());
    }
    let configs = plan.sweep.configs().len();
    eprintln!(
        "bench {}: {} configuration(s) x {} camera(s), {width}x{height}, {vpls} VPLs, repeat {repeat} \
         (reference {}) on {}",
        a.scene.scene,
        configs,
        plan.cameras.len(),
        a.reference_repeat,
        ctx.adapter_name
    );
    let report = bench::run(&ctx, &scene, &plan)?;
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
        a.out_dir.display(),
        report.wall_s
    );
    Ok(())
}

/// The most area-light samples a pixel (the default is 16): far beyond any useful count, while
/// without a bound --direct-samples 4294967295 blocked for hours.
const MAX_DIRECT_SAMPLES: u32 = 65536;

fn check_direct_samples(n: u32) -> Result<()> {
    if !(1..=MAX_DIRECT_SAMPLES).contains(&n) {
        return Err(bad(format!(
            "--direct-samples {n}: must be 1..={MAX_DIRECT_SAMPLES}"
        )));
    }
    Ok(())
}

fn check_normal_threshold(nt: f32) -> Result<()> {
    if !(nt.is_finite() && (-1.0..=1.0).contains(&nt)) {
        return Err(bad(format!(
            "--normal-threshold {nt}: must be a cosine in [-1, 1]"
        )));
    }
    Ok(())
}

fn check_clamp(c: f32) -> Result<()> {
    if !(c.is_finite() && (0.0..1.0).contains(&c)) {
        return Err(bad(format!("--clamp {c}: must be in [0, 1)")));
    }
    Ok(())
}

fn check_iterations(i: u32) -> Result<()> {
    if i > 1000 {
        return Err(bad(format!("--iterations {i}: at most 1000")));
    }
    Ok(())
}

fn check_fuzziness(f: u32) -> Result<()> {
    if !(1..=16).contains(&f) {
        return Err(bad(format!("--fuzziness {f}: must be 1..16")));
    }
    Ok(())
}

fn check_weight_exponent(p: f32) -> Result<()> {
    if !fuzzy_vpl::gi::pipeline::valid_weight_exponent(p) {
        return Err(bad(format!(
            "--weight-exponent {p}: must be a number in [0, 64]"
        )));
    }
    Ok(())
}
