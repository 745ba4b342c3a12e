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
    /// the direct light are at the image area's size; moving, previews at half this scale). The
    /// same setting as --indirect-scale, which `view` also takes (with the same range); give one.
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
    /// B's value of any option of `view` (repeatable): `--b weighting=hard --b sp-clusters=48` is
    /// B = A with `--weighting hard --sp-clusters 48`, a method's knobs included, read by the same
    /// parsers (B keeps A's image size). `--b-KEY VALUE` is the same as `--b KEY=VALUE`.
    #[arg(id = "b_pairs", long = "b", value_name = "KEY=VALUE", value_parser = parse_pair)]
    pairs: Vec<(String, String)>,
}

/// `view`'s `--b-KEY VALUE` (and `--b-KEY=VALUE`) as `--b KEY=VALUE`, for every KEY: B's options
/// are declared once, as A's (`BArgs::pairs`). Other commands' arguments, and anything after `--`,
/// are left as they are.
pub fn b_option_aliases(args: Vec<std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    if args.get(1).and_then(|a| a.to_str()) != Some("view") {
        return args;
    }
    let mut out = Vec::with_capacity(args.len());
    let mut rest = args.into_iter();
    while let Some(a) = rest.next() {
        let Some(key) = a
            .to_str()
            .and_then(|t| t.strip_prefix("--b-"))
            .map(str::to_string)
        else {
            let end = a == "--";
            out.push(a);
            if end {
                out.extend(rest.by_ref());
            }
            continue;
        };
        let pair = match key.split_once('=') {
            Some((k, v)) => Some(format!("{k}={v}")),
            None => rest
                .next()
                .map(|v| format!("{key}={}", v.to_string_lossy())),
        };
        match pair {
            Some(p) => out.extend(["--b".into(), p.into()]),
            // No value: clap says so, naming the option as given.
            None => out.push(format!("--b-{key}").into()),
        }
    }
    out
}

/// `--indirect-scale` is `view`'s render scale under `render`'s name: taken when given alone, and
/// refused beside `--render-scale` (two values for one setting).
fn one_render_scale(a: &mut ViewArgs, given: &[String]) -> Result<()> {
    let has = |id: &str| given.iter().any(|g| g == id);
    match (has("indirect_scale"), has("render_scale")) {
        (true, true) => Err(bad(
            "--indirect-scale and --render-scale are one setting in view (the render scale): give one",
        )),
        (true, false) => {
            let s = a.shot.frame.indirect_scale;
            a.render_scale = parse_render_scale(&s.to_string())
                .map_err(|e| bad(format!("--indirect-scale {s}: {e} in view")))?;
            Ok(())
        }
        _ => Ok(()),
    }
}

/// `KEY=VALUE` of `--b`: the option's name (with `-` or `_`) and its text.
fn parse_pair(v: &str) -> Result<(String, String), Invalid> {
    match v.split_once('=') {
        Some((k, val)) if !k.trim().is_empty() => Ok((
            k.trim().trim_start_matches("--").replace('_', "-"),
            val.to_string(),
        )),
        _ => Err(Invalid("must be KEY=VALUE, e.g. weighting=hard".into())),
    }
}

/// `a`'s settings as the viewer starts from them.
fn ui_settings(a: &ViewArgs) -> crate::app::UiSettings {
    let rs = RenderSettings {
        frame: a.shot.frame,
        cluster: a.shot.cluster.clone(),
        method: a.shot.method,
        ..Default::default()
    };
    let mut settings = crate::app::UiSettings::new(&rs);
    settings.render_scale = a.render_scale;
    settings
}

/// B's settings: with `--b KEY=VALUE` pairs, the command line `argv` parsed again with each pair
/// as `--KEY VALUE` after it (the last value of an option wins), through the same parsers and
/// `--paper` rule as A, at A's image size. `None` without B options.
fn b_settings(argv: &[std::ffi::OsString], a: &ViewArgs) -> Result<Option<crate::app::UiSettings>> {
    if a.b.pairs.is_empty() {
        return Ok(None);
    }
    let mut argv = b_option_aliases(argv.to_vec());
    for (k, v) in &a.b.pairs {
        argv.push(format!("--{k}").into());
        argv.push(v.into());
    }
    let cmd = super::command().mut_subcommand("view", |v| v.args_override_self(true));
    let m = cmd
        .try_get_matches_from(argv)
        .map_err(|e| bad(format!("--b: {}", super::one_line(&e))))?;
    let given = super::given_ids(&m);
    let cli = <super::Cli as clap::FromArgMatches>::from_arg_matches(&m)
        .map_err(|e| bad(format!("--b: {}", super::one_line(&e))))?;
    let Some(super::Command::View(mut b)) = cli.command else {
        return Err(bad("--b: only `view` has a B"));
    };
    b.shot.apply_paper(&given);
    one_render_scale(&mut b, &given)?;
    (b.shot.frame.width, b.shot.frame.height) = (a.shot.frame.width, a.shot.frame.height);
    Ok(Some(ui_settings(&b)))
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
/// `--width`/`--height` takes `OFFSCREEN_IMAGE`); `argv`: the command line (B's `--b KEY=VALUE`
/// parses it again).
pub fn run(mut a: ViewArgs, given: &[String], argv: &[std::ffi::OsString]) -> Result<()> {
    a.shot.apply_paper(given);
    one_render_scale(&mut a, given)?;
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
    let settings = ui_settings(&a);
    let b = b_settings(argv, &a)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::UiSettings;
    use crate::settings::Controlled;

    /// `view ARGS` as `cli::main` parses it, with its command line.
    fn view(args: &[&str]) -> (ViewArgs, Vec<std::ffi::OsString>) {
        let argv: Vec<std::ffi::OsString> = ["fuzzy-vpl", "view"]
            .iter()
            .chain(args)
            .map(Into::into)
            .collect();
        let argv = b_option_aliases(argv);
        let m = super::super::command()
            .try_get_matches_from(argv.clone())
            .unwrap();
        let given = super::super::given_ids(&m);
        let cli = <super::super::Cli as clap::FromArgMatches>::from_arg_matches(&m).unwrap();
        let Some(super::super::Command::View(mut a)) = cli.command else {
            panic!("not view")
        };
        a.shot.apply_paper(&given);
        (a, argv)
    }

    fn b(args: &[&str]) -> Result<Option<UiSettings>> {
        let (a, argv) = view(args);
        b_settings(&argv, &a)
    }

    /// `--b-KEY VALUE` and `--b-KEY=VALUE` are `--b KEY=VALUE` for any KEY of `view`; other
    /// commands and what follows `--` are left as they are.
    #[test]
    fn b_short_forms_are_pairs() {
        let os = |v: &[&str]| v.iter().map(std::ffi::OsString::from).collect::<Vec<_>>();
        let got = b_option_aliases(os(&[
            "fuzzy-vpl",
            "view",
            "--b-normal-threshold",
            "-0.5",
            "--b-fuzziness=3",
            "--",
            "--b-x",
            "1",
        ]));
        let want = [
            "fuzzy-vpl",
            "view",
            "--b",
            "normal-threshold=-0.5",
            "--b",
            "fuzziness=3",
        ];
        assert_eq!(got, os(&[&want[..], &["--", "--b-x", "1"]].concat()));
        let render = os(&["fuzzy-vpl", "render", "--b-fuzziness", "3"]);
        assert_eq!(b_option_aliases(render.clone()), render);
        // Any option, not only the clustering's: B's K and an n_t below 0, by either form.
        let by_short = b(&["--b-sp-clusters", "48", "--b-normal-threshold", "-0.5"])
            .unwrap()
            .unwrap();
        let by_pair = b(&["--b", "sp-clusters=48", "--b", "normal-threshold=-0.5"]).unwrap();
        assert_eq!(Some(by_short.clone()), by_pair);
        assert_eq!(
            (
                by_short.cluster.sp_clusters,
                by_short.cluster.normal_threshold
            ),
            (48, -0.5)
        );
    }

    /// `--b KEY=VALUE` sets any option of B through the option's own parser, the rest is A's; the
    /// pair and the `--b-` option give the same B; a value the parser refuses is one line naming
    /// `--b`, the option and the value.
    #[test]
    fn b_pairs_set_any_option_through_its_parser() {
        assert!(b(&[]).unwrap().is_none());
        let by_pair = b(&["--b", "weighting=hard"]).unwrap().unwrap();
        assert_eq!(by_pair.cluster.weighting, crate::settings::Weighting::Hard);
        assert_eq!(Some(by_pair), b(&["--b-weighting", "hard"]).unwrap());
        // A method's own knob: the registry's last method, its first declared control, set to
        // a value other than the default (a choice's second value, a slider's low end).
        let method = *crate::method::Method::ALL.last().unwrap();
        let ms = crate::method::MethodSettings {
            method,
            ..Default::default()
        };
        let c = ms.controls()[0];
        let value = match c.widget {
            crate::settings::Widget::Choice(values) => values[1].0.to_string(),
            crate::settings::Widget::Slider(r) => format!("{}", r.lo),
            w => panic!(
                "{}: a method knob's widget is a choice or a slider, not {w:?}",
                c.name
            ),
        };
        assert_ne!(ms.knob(c.name), Some(value.clone()), "{}", c.name);
        let a_args = ["--fuzziness", "4", "--method", method.name()];
        let (a, _) = view(&a_args);
        let a = ui_settings(&a);
        let knob = format!("{}={value}", c.name);
        let pairs = [
            "--b",
            "fuzziness=3",
            "--b",
            &knob,
            "--b",
            "temporal_alpha=0.25",
        ];
        let pinned = b(&[&a_args[..], &pairs[..]].concat()).unwrap().unwrap();
        assert_eq!(pinned.cluster.fuzziness, 3);
        // As the knob writes it back (an f32 slider's low end may print otherwise): equal numbers.
        let got = pinned.method.knob(c.name).unwrap();
        let num = |t: &str| t.parse::<f64>().ok();
        assert!(
            got == value || num(&got).is_some() && num(&got) == num(&value),
            "{got}"
        );
        assert_eq!(pinned.cluster.temporal_alpha, 0.25);
        let mut back = pinned.clone();
        back.cluster.fuzziness = 4;
        let _ = back
            .method
            .set_column(c.name, &a.method.knob(c.name).unwrap());
        back.cluster.temporal_alpha = a.cluster.temporal_alpha;
        assert_eq!(back, a, "B differs from A beyond its pairs");
        let e = b(&["--b", "fuzziness=0"]).unwrap_err().to_string();
        assert!(e.contains("--b: --fuzziness 0: must be 1..16"), "{e}");
        let e = b(&["--b", "no-such-option=1"]).unwrap_err().to_string();
        assert!(
            e.starts_with("--b: ") && e.contains("--no-such-option"),
            "{e}"
        );
        assert!(parse_pair("fuzziness").is_err() && parse_pair("=3").is_err());
    }

    /// `--indirect-scale` is view's render scale; beside `--render-scale` it is refused.
    #[test]
    fn indirect_scale_is_the_render_scale() {
        let scale = |args: &[&str]| {
            let (mut a, argv) = view(args);
            let m = super::super::command().try_get_matches_from(argv).unwrap();
            one_render_scale(&mut a, &super::super::given_ids(&m)).map(|()| a.render_scale)
        };
        assert_eq!(scale(&[]).unwrap(), 0.5);
        assert_eq!(scale(&["--render-scale", "0.25"]).unwrap(), 0.25);
        assert_eq!(scale(&["--indirect-scale", "0.25"]).unwrap(), 0.25);
        let e = scale(&["--indirect-scale", "0.05"])
            .unwrap_err()
            .to_string();
        assert!(e.contains("--indirect-scale 0.05"), "{e}");
        let both = scale(&["--indirect-scale", "0.25", "--render-scale", "0.5"]);
        assert!(both.unwrap_err().to_string().contains("one setting"));
    }
}
