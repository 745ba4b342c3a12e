//! `fuzzy-vpl view` (the default): the interactive viewer, or a scripted run of it.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use super::scene::{SceneArgs, ShotArgs, check_vpls};
use crate::export;
use crate::exposure::Exposure;
use crate::gpu::GpuContext;
use crate::input::bad;
use crate::render::RenderSettings;
use crate::settings::Invalid;

#[derive(Args)]
pub struct ViewArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// The camera, the frame and the clustering (in `view`, the frame's size is the image area at
    /// start, logical pixels; the window adds the side panel and the stats strip; the indirect
    /// scale is the render scale).
    #[command(flatten)]
    shot: ShotArgs,
    /// Render scale of the indirect light relative to the image area, 0.1..1 (the primary rays and
    /// the direct light are at the image area's size; moving, previews at half this scale).
    #[arg(long, default_value_t = 0.5, value_parser = parse_render_scale)]
    render_scale: f32,
    /// Scripted run: draw N window frames once the first full GI frame is shown (with --animate: N
    /// frames of moving, then one frame at rest), save the window to --screenshot and the
    /// measurements to --stats, exit.
    #[arg(long)]
    frames: Option<u32>,
    /// Where a scripted run saves the window (.png, UI included) or the image as displayed (.exr:
    /// linear radiance of the current view at the image area's resolution, no UI).
    #[arg(long, requires = "frames")]
    screenshot: Option<PathBuf>,
    /// Where a scripted run writes its JSON: settings, `motion` (camera change to image latency,
    /// GPU ms of the GI frames while moving) and `rest` (GPU ms of the frame at rest).
    #[arg(long, requires = "frames")]
    stats: Option<PathBuf>,
    /// The view to start in (a scripted run in reference or error computes the reference first).
    #[arg(long, value_enum, default_value = "final")]
    view: crate::app::views::View,
    /// Keep orbiting the camera (0.6 rad/s about the point looked at) to measure the viewer while
    /// moving; with --frames.
    #[arg(long)]
    animate: bool,
    /// Directory for the panel's screenshots.
    #[arg(long, default_value = ".")]
    shot_dir: PathBuf,
    /// Keep each finished reference as EXR beside the scene's bookmarks file (in
    /// `SCENE.fuzzy-vpl.json.refs/`; for built-ins in `$XDG_CONFIG_HOME/fuzzy-vpl/`, else
    /// `~/.config/fuzzy-vpl/`), and read a view's reference from there when it comes back; the
    /// panel's "keep on disk".
    #[arg(long)]
    keep_references: bool,
    /// How GI frames reach the window: `shared` (one device: the window displays the frames'
    /// buffers where they were rendered), `split` (a device for the GI: frames read back and
    /// uploaded), `auto` (shared on a hardware adapter, split on a software one).
    #[arg(long, value_enum, default_value = "auto")]
    display_path: crate::app::DisplayPath,
    /// No window: the same viewer painted into an offscreen texture of the window's size (the image
    /// area plus the panel and the stats strip; by default 900×550 + the panel = 1280×800), for a
    /// scripted run (--frames) on a machine without a display.
    #[arg(long, requires = "frames")]
    offscreen: bool,
    #[command(flatten)]
    b: BArgs,
}

/// The split view's B settings: the A settings (the ones above) with these changed. Giving any
/// pins B at start (`--view split` or `--view diff` shows it).
#[derive(Args, Clone, Debug, Default)]
#[command(next_help_heading = "Split view (B settings)")]
pub struct BArgs {
    /// B's weighting (hard, uniform, inverse-distance).
    #[arg(id = "b_weighting", long = "b-weighting", value_enum)]
    weighting: Option<crate::settings::Weighting>,
    /// B's K_SP.
    #[arg(id = "b_sp_clusters", long = "b-sp-clusters")]
    sp_clusters: Option<u32>,
    /// B's K_VPL.
    #[arg(id = "b_vpl_clusters", long = "b-vpl-clusters")]
    vpl_clusters: Option<u32>,
    /// B's F, 1..16.
    #[arg(id = "b_fuzziness", long = "b-fuzziness", value_parser = crate::settings::parse_fuzziness)]
    fuzziness: Option<u32>,
    /// B's n_t (a cosine in [-1, 1]).
    #[arg(id = "b_normal_threshold", long = "b-normal-threshold", value_parser = crate::settings::parse_normal_threshold, allow_hyphen_values = true)]
    normal_threshold: Option<f32>,
    /// B's p of the inverse-distance weights, [0, 64].
    #[arg(id = "b_weight_exponent", long = "b-weight-exponent", value_parser = crate::settings::parse_weight_exponent)]
    weight_exponent: Option<f32>,
}

impl BArgs {
    /// `a` with the B options applied, when any was given.
    fn pin(&self, a: &crate::app::UiSettings) -> Option<crate::app::UiSettings> {
        let b = self.clone();
        if b.weighting.is_none()
            && b.sp_clusters.is_none()
            && b.vpl_clusters.is_none()
            && b.fuzziness.is_none()
            && b.normal_threshold.is_none()
            && b.weight_exponent.is_none()
        {
            return None;
        }
        let mut s = a.clone();
        let c = &mut s.cluster;
        if let Some(w) = b.weighting {
            c.weighting = w;
        }
        if let Some(k) = b.sp_clusters {
            s.sp_on = k > 0;
            c.sp_clusters = k.max(1);
        }
        if let Some(k) = b.vpl_clusters {
            s.vpl_on = k > 0;
            c.vpl_clusters = k.max(1);
        }
        if let Some(f) = b.fuzziness {
            c.fuzziness = f;
        }
        if let Some(n) = b.normal_threshold {
            s.nt_degrees = n.clamp(-1.0, 1.0).acos().to_degrees();
        }
        if let Some(p) = b.weight_exponent {
            c.weight_exponent = p;
        }
        Some(s)
    }
}

fn parse_render_scale(v: &str) -> Result<f32, Invalid> {
    match v.trim().parse::<f32>() {
        Ok(s) if (0.1..=1.0).contains(&s) => Ok(s),
        _ => Err(Invalid("must be in [0.1, 1]".into())),
    }
}

/// The offscreen window's default image area: with the panel and the stats strip, 1280×800.
pub const OFFSCREEN_IMAGE: (u32, u32) = (900, 550);

/// `given`: the options the command line gave (`--paper` yields to them; `--offscreen` without
/// `--width`/`--height` takes `OFFSCREEN_IMAGE`).
pub fn run(mut a: ViewArgs, given: &[String]) -> Result<()> {
    a.shot.apply_paper(given);
    if a.offscreen {
        if !given.iter().any(|g| g == "width") {
            a.shot.frame.width = OFFSCREEN_IMAGE.0;
        }
        if !given.iter().any(|g| g == "height") {
            a.shot.frame.height = OFFSCREEN_IMAGE.1;
        }
    }
    if a.shot.frame.exposure == Exposure::Fixed(0.0) {
        return Err(bad(
            "--exposure 0: the viewer needs an exposure > 0 (or auto)",
        ));
    }
    if let Some(p) = &a.screenshot
        && !p
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("png") || e.eq_ignore_ascii_case("exr"))
    {
        return Err(bad(format!(
            "{}: --screenshot must end in .png (the window) or .exr (the image, linear)",
            p.display()
        )));
    }
    if a.frames.is_some() && a.screenshot.is_none() && a.stats.is_none() {
        return Err(bad("--frames needs --screenshot or --stats"));
    }
    for p in a.screenshot.iter().chain(&a.stats) {
        export::check_writable(p).map_err(bad)?;
    }
    let outputs: Vec<(&str, &std::path::Path)> =
        (a.screenshot.iter().map(|p| ("--screenshot", p.as_path())))
            .chain(a.stats.iter().map(|p| ("--stats", p.as_path())))
            .collect();
    let scene_file = std::path::Path::new(&a.scene.scene);
    let inputs: &[(&str, &std::path::Path)] = if a.scene.scene.starts_with("builtin:") {
        &[]
    } else {
        &[("the scene", scene_file)]
    };
    crate::files::check_distinct(&outputs, inputs).map_err(bad)?;
    // The panel's screenshots go there: found out at start, not at the first F11.
    if !a.shot_dir.is_dir() {
        return Err(bad(format!(
            "--shot-dir {}: not a directory",
            a.shot_dir.display()
        )));
    }
    export::check_writable(&a.shot_dir.join("screenshot.png"))
        .map_err(|e| bad(format!("--shot-dir {e}")))?;
    let scene = a.scene.load()?;
    // render's device limits apply to the viewer's GI worker too (it makes its own device).
    check_vpls(&GpuContext::new_headless()?, a.shot.frame.vpls)?;
    if let Some(i) = a.shot.camera {
        a.scene.camera(&scene, Some(i))?;
    }
    let rs = RenderSettings {
        frame: a.shot.frame,
        cluster: a.shot.cluster,
        method: a.shot.method,
        ..Default::default()
    };
    let mut settings = crate::app::UiSettings::new(&rs);
    settings.render_scale = a.render_scale;
    let b = a.b.pin(&settings);
    let args = a.scene.clone();
    let loader: crate::app::worker::Loader = std::sync::Arc::new(move |spec: &str| {
        let mut sa = args.clone();
        sa.scene = spec.to_string();
        sa.load()
    });
    crate::app::run(crate::app::ViewOptions {
        spec: a.scene.scene.clone(),
        scene,
        loader,
        width: a.shot.frame.width,
        height: a.shot.frame.height,
        camera: a.shot.camera,
        settings,
        frames: a.frames,
        screenshot: a.screenshot,
        view: a.view,
        animate: a.animate,
        stats: a.stats,
        shot_dir: a.shot_dir,
        b,
        refs_on_disk: a.keep_references,
        display_path: a.display_path,
        offscreen: a.offscreen,
    })
}
