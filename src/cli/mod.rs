//! `fuzzy-vpl`: the command line (docs/design.md, "CLI"). One file per subcommand; the settings they
//! share are the types of `crate::settings`, flattened in.

mod bench;
mod env;
mod info;
mod raybench;
mod render;
mod scene;
mod view;

use std::process::ExitCode;

use crate::input::bad;
use anyhow::Result;
use clap::{Parser, Subcommand};

pub use scene::SceneArgs;

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
    View(view::ViewArgs),
    /// Render one frame headless to EXR (linear HDR) or PNG (tone-mapped sRGB).
    #[command(after_help = LIGHTS_HELP)]
    Render(render::RenderArgs),
    /// Print what a scene holds and which passes would run.
    #[command(after_help = LIGHTS_HELP)]
    Info(info::InfoArgs),
    /// Ray throughput of the WGSL traversal against obvhs on all CPU cores (primary and shadow rays).
    Raybench(raybench::RaybenchArgs),
    /// Error against run time over a sweep of clustering settings: results.csv, plots, summary.md.
    #[command(after_help = bench::BENCH_HELP)]
    Bench(Box<bench::BenchArgs>),
    /// One markdown table of bench output folders (scripts/gpu-bench): adapter, driver, commit,
    /// date, ms per pass, speed-up, MSE and FLIP.
    BenchTable(bench::BenchTableArgs),
}

/// The command line. Every option that takes a value accepts a negative number as that value
/// (`--light-scale -1` is then refused by the option's own check, with its range, rather than read
/// as an unknown flag `-1`), and `view` starts lighter than `render` so a software driver stays
/// interactive (4096 VPLs, 1024 SP and 512 VPL clusters) with temporal reuse on.
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
    let view_defaults = [
        ("vpls", "4096"),
        ("sp_clusters", "1024"),
        ("vpl_clusters", "512"),
        ("temporal", "on"),
    ];
    let c = <Cli as clap::CommandFactory>::command().mut_subcommand("view", |v| {
        view_defaults
            .iter()
            .fold(v, |v, (id, d)| v.mut_arg(*id, |a| a.default_value(*d)))
    });
    negatives(c)
}

/// The ids of the options the subcommand's command line gave (not defaults).
fn given_ids(m: &clap::ArgMatches) -> Vec<String> {
    let Some((_, sub)) = m.subcommand() else {
        return Vec::new();
    };
    sub.ids()
        .filter(|id| sub.value_source(id.as_str()) == Some(clap::parser::ValueSource::CommandLine))
        .map(|id| id.to_string())
        .collect()
}

/// One line for a clap error: a value a `settings` parser refused reads `--option VALUE: why`;
/// otherwise clap's message and its details up to the first blank line.
fn one_line(e: &clap::Error) -> String {
    use clap::error::{ContextKind, ContextValue, ErrorKind};
    if e.kind() == ErrorKind::ValueValidation
        && let Some(why) =
            std::error::Error::source(e).and_then(|s| s.downcast_ref::<crate::settings::Invalid>())
        && let (Some(ContextValue::String(arg)), Some(ContextValue::String(value))) = (
            e.get(ContextKind::InvalidArg),
            e.get(ContextKind::InvalidValue),
        )
    {
        let flag = arg.split_whitespace().next().unwrap_or(arg);
        return format!("{flag} {value}: {why}");
    }
    let text = e.render().to_string();
    let line: Vec<&str> = text
        .lines()
        .map(str::trim)
        .take_while(|l| !l.is_empty())
        .collect();
    format!(
        "{} (see --help)",
        line.join(" ").trim_start_matches("error: ")
    )
}

pub fn main() -> ExitCode {
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
    // With the ids of the options the command line gave (bench's --quick fills in the others).
    let parse = |args: Vec<std::ffi::OsString>| {
        command().try_get_matches_from(args).and_then(|m| {
            let given = given_ids(&m);
            <Cli as clap::FromArgMatches>::from_arg_matches(&m).map(|c| (c, given))
        })
    };
    let mut args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    if args.len() == 1 {
        args.push("view".into());
    }
    let args = view::b_option_aliases(args);
    let args_for_errors = args.clone();
    let (cli, given) = match parse(args) {
        Ok(c) => c,
        Err(e) => {
            use clap::error::ErrorKind;
            match e.kind() {
                ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
                    return match e.print() {
                        Ok(()) => finish(Ok(())),
                        Err(why) => finish(Err(bad(format!("cannot write to stdout: {why}")))),
                    };
                }
                ErrorKind::InvalidUtf8 => {
                    eprintln!("error: {}", not_utf8(&args_for_errors));
                    return ExitCode::from(2);
                }
                ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
                    let _ = e.print();
                    return ExitCode::from(2);
                }
                _ => {}
            }
            eprintln!("error: {}", one_line(&e));
            return ExitCode::from(2);
        }
    };
    match env::check() {
        Ok(warnings) => {
            for w in warnings {
                eprintln!("warning: {w}");
            }
        }
        Err(e) => return finish(Err(bad(e))),
    }
    let result: Result<()> = match cli.command {
        None => match parse(vec!["fuzzy-vpl".into(), "view".into()]) {
            Ok((
                Cli {
                    command: Some(Command::View(a)),
                },
                _,
            )) => view::run(a, &[], &[]),
            _ => unreachable!("`fuzzy-vpl view` parses"),
        },
        Some(Command::View(a)) => view::run(a, &given, &args_for_errors),
        Some(Command::Render(a)) => render::run(a, &given),
        Some(Command::Info(a)) => info::run(a),
        Some(Command::Raybench(a)) => raybench::run(a),
        Some(Command::Bench(a)) => {
            let given: Vec<&str> = given.iter().map(String::as_str).collect();
            bench::run(*a, &given)
        }
        Some(Command::BenchTable(a)) => bench::table(a),
    };
    finish(result)
}

/// The exit code of a run and its error line: 2 for bad input (the user's files, options or
/// environment, a failed write to stdout), else 1. A run whose results could not all be written
/// to stdout fails, naming it.
fn finish(result: Result<()>) -> ExitCode {
    let result = result.and_then(|()| match crate::stdio::stdout_failure() {
        Some(why) => Err(bad(format!("cannot write to stdout: {why}"))),
        None => Ok(()),
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let is_input = e.downcast_ref::<crate::input::BadInput>().is_some()
                || e.downcast_ref::<crate::scene::SceneError>().is_some()
                || e.downcast_ref::<crate::gi::scene_gpu::TooBig>().is_some()
                || e.downcast_ref::<crate::app::Unavailable>().is_some();
            eprintln!("error: {e}");
            if is_input {
                ExitCode::from(2)
            } else {
                ExitCode::from(1)
            }
        }
    }
}

/// The message for a command line with an argument that is not UTF-8 (a file name in another
/// encoding): which argument, shown with its bytes escaped.
fn not_utf8(args: &[std::ffi::OsString]) -> String {
    match args.iter().find(|a| a.to_str().is_none()) {
        Some(a) => format!(
            "argument \"{}\" is not valid UTF-8; fuzzy-vpl takes UTF-8 file names and values (rename the file)",
            a.to_string_lossy().replace('\u{FFFD}', "?")
        ),
        None => "an argument is not valid UTF-8".into(),
    }
}
