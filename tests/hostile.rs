//! Hostile and odd input to the `fuzzy-vpl` binary (issue 46): readers that would block, writes
//! that would replace what they should not, a full or closed stdout/stderr, developer variables,
//! signals during a write. Every case that could hang runs under a timeout, so a regression fails
//! the test instead of stalling CI.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::Duration;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fuzzy-vpl"))
}

/// Runs `cmd` (stderr piped, stdout piped unless `stdout` is given) to its end, killing it after
/// `limit` (a hang guard, not a speed test: polls 20 ms apart, counted, no clock read).
fn run_within(mut cmd: Command, stdout: Option<std::fs::File>, limit: Duration) -> Output {
    cmd.stdin(Stdio::null()).stderr(Stdio::piped());
    match stdout {
        Some(f) => cmd.stdout(f),
        None => cmd.stdout(Stdio::piped()),
    };
    let mut child = cmd.spawn().unwrap();
    let mut polls = 0;
    while child.try_wait().unwrap().is_none() {
        polls += 1;
        if polls * 20 > limit.as_millis() {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{cmd:?}: still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// `args` run within 30 s: exit 2 and one error line that contains every one of `needles`.
fn refused(args: &[&str], needles: &[&str]) -> String {
    let mut cmd = bin();
    cmd.args(args);
    let o = run_within(cmd, None, Duration::from_secs(30));
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    let lines = common::error_lines(&err);
    assert_eq!(lines.len(), 1, "{args:?}: {err}");
    for n in needles {
        assert!(lines[0].contains(n), "{args:?}: no {n:?} in {err}");
    }
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    err
}

fn mkfifo(p: &Path) {
    assert!(Command::new("mkfifo").arg(p).status().unwrap().success());
}

/// The names in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A small frame's options, as words.
const SMALL: &str = "--width 32 --height 24 --vpls 256 --vpl-clusters 64 --sp-clusters 32";

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A FIFO as `--compare`'s reference or as `bench-table`'s CSV files (they blocked forever), a
/// device or a folder as the reference: one line naming the file and what it is, at once.
#[test]
fn readers_refuse_fifos_devices_and_folders() {
    let d = common::scratch("hostile-readers");
    let fifo = d.join("ref.exr");
    mkfifo(&fifo);
    let out = d.join("o.png");
    refused(
        &["render", "-o", s(&out), "--compare", s(&fifo)],
        &["ref.exr", "FIFO"],
    );
    refused(
        &["render", "-o", s(&out), "--compare", "/dev/zero"],
        &["/dev/zero", "device"],
    );
    let dir = format!("{}/", d.display());
    refused(
        &["render", "-o", s(&out), "--compare", &dir],
        &[&dir, "directory"],
    );
    for name in ["results.csv", "path.csv"] {
        let run = d.join(format!("run-{name}"));
        std::fs::create_dir_all(&run).unwrap();
        mkfifo(&run.join(name));
        refused(&["bench-table", s(&run)], &[name, "FIFO"]);
    }
    // An oversized results.csv is refused before it is read (a sparse 100 MB file).
    let big = d.join("run-big");
    std::fs::create_dir_all(&big).unwrap();
    std::fs::File::create(big.join("results.csv"))
        .unwrap()
        .set_len(100 << 20)
        .unwrap();
    refused(
        &["bench-table", s(&big)],
        &["results.csv", "bytes, more than"],
    );
    assert!(!out.exists());
}

/// `--compare` takes a linear EXR only: a PNG (8-bit sRGB) or a text file is refused saying what it
/// is, even when named `.exr`.
#[test]
fn compare_takes_only_exr() {
    let d = common::scratch("hostile-compare");
    let png = d.join("ref.png");
    fuzzy_vpl::export::write_png_rgb8(&png, 2, 2, vec![128; 12]).unwrap();
    let disguised = d.join("png.exr");
    std::fs::copy(&png, &disguised).unwrap();
    let text = d.join("text.exr");
    std::fs::write(&text, "not an image").unwrap();
    let out = d.join("o.png");
    for (r, what) in [(&png, "PNG"), (&disguised, "PNG"), (&text, "not an image")] {
        refused(
            &["render", "-o", s(&out), "--compare", s(r)],
            &[s(r), "OpenEXR", what],
        );
    }
}

/// Outputs that name an existing device, FIFO, folder, socket or symbolic link are refused before
/// the render, and the thing they name is left as it was.
#[test]
fn outputs_refuse_what_is_not_a_regular_file() {
    let d = common::scratch("hostile-outputs");
    let fifo = d.join("fifo.json");
    mkfifo(&fifo);
    let folder = d.join("folder.png");
    std::fs::create_dir_all(&folder).unwrap();
    let target = d.join("target.png");
    std::fs::write(&target, "keep").unwrap();
    let link = d.join("link.png");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let dangling = d.join("dangling.exr");
    std::os::unix::fs::symlink(d.join("nowhere.exr"), &dangling).unwrap();
    let sock = d.join("sock.png");
    let _listener = std::os::unix::net::UnixListener::bind(&sock).unwrap();
    let o = d.join("o.png");
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (
            vec!["-o", s(&o), "--stats", "/dev/full"],
            vec!["/dev/full", "device"],
        ),
        (
            vec!["-o", s(&o), "--trace", "/dev/null"],
            vec!["/dev/null", "device"],
        ),
        (
            vec!["-o", s(&o), "--stats", s(&fifo)],
            vec!["fifo.json", "FIFO"],
        ),
        (vec!["-o", s(&folder)], vec!["folder.png", "directory"]),
        (vec!["-o", s(&sock)], vec!["sock.png", "socket"]),
        (vec!["-o", s(&link)], vec!["link.png", "symbolic link"]),
        (
            vec!["-o", s(&dangling)],
            vec!["dangling.exr", "symbolic link"],
        ),
    ];
    for (args, needles) in cases {
        let mut all = vec!["render"];
        all.extend(args);
        refused(&all, &needles);
    }
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "keep");
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert!(!d.join("nowhere.exr").exists() && !o.exists());
    let meta = std::fs::metadata("/dev/full").unwrap();
    assert!(std::os::unix::fs::FileTypeExt::is_char_device(
        &meta.file_type()
    ));
}

/// Two outputs naming one file (also through `./`, `..` or a hard link), or an output naming an
/// input (the scene, its buffer, the reference), are refused before the render; the input is
/// untouched.
#[test]
fn outputs_may_not_name_each_other_or_an_input() {
    let d = common::scratch("hostile-same");
    let scene = d.join("scene.gltf");
    std::fs::write(
        &scene,
        r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"scene.bin","byteLength":36}],
        "bufferViews":[{"buffer":0,"byteLength":36}],
        "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}],"scene":0}"#,
    )
    .unwrap();
    let tri: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    std::fs::write(d.join("scene.bin"), &tri).unwrap();
    let before = std::fs::read(&scene).unwrap();
    let reference = d.join("ref.exr");
    fuzzy_vpl::export::write_exr(&reference, 32, 24, &vec![[0.5; 3]; 32 * 24]).unwrap();
    std::fs::hard_link(&reference, d.join("hard.png")).unwrap();
    let p = |n: &str| d.join(n).display().to_string();
    let (a, dot_a, sub_a) = (
        p("a.png"),
        p("./a.png"),
        format!("{}/x/../a.png", d.display()),
    );
    std::fs::create_dir_all(d.join("x")).unwrap();
    let (st, sc, re, hard) = (p("st.json"), p("scene.gltf"), p("ref.exr"), p("hard.png"));
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (
            vec!["-o", &a, "--stats", &a],
            vec!["-o", "--stats", "same file"],
        ),
        (vec!["-o", &a, "-o", &dot_a], vec!["same file"]),
        (
            vec!["-o", &a, "--stats", &st, "--trace", &st],
            vec!["--stats", "--trace", "same file"],
        ),
        (vec!["-o", &a, "--stats", &sub_a], vec!["same file"]),
        (
            vec![&sc, "-o", &a, "--stats", &sc],
            vec!["--stats", "the scene", "input"],
        ),
        (
            vec![&sc, "-o", &a, "--trace", &sc],
            vec!["--trace", "the scene", "input"],
        ),
        (
            vec![&sc, "-o", &a, "--compare", &re, "--error-map", &hard],
            vec!["--error-map", "--compare", "input"],
        ),
    ];
    for (args, needles) in cases {
        let mut all = vec!["render"];
        all.extend(args);
        all.extend(SMALL.split_whitespace());
        refused(&all, &needles);
    }
    // The scene's buffer is found when the scene is loaded, before the render.
    let bin_out = p("scene.bin.png");
    std::fs::rename(d.join("scene.bin"), &bin_out).unwrap();
    let text = std::fs::read_to_string(&scene)
        .unwrap()
        .replace("scene.bin", "scene.bin.png");
    std::fs::write(&scene, text).unwrap();
    let mut args = vec!["render", &sc, "-o", &bin_out];
    args.extend(SMALL.split_whitespace());
    refused(&args, &["scene.bin.png", "the scene's file", "input"]);
    assert_eq!(std::fs::read(&bin_out).unwrap(), tri);
    std::fs::write(&scene, &before).unwrap();
    assert!(!d.join("a.png").exists());
}

/// A name of 251 + 4 = 255 bytes (NAME_MAX) is written, with no temporary file left; one of 257 is
/// refused before the render with the OS's reason; an output the file system cannot take (a file
/// size limit standing in for a full disk) is one line naming it, exit 2, no temporary file left.
#[test]
fn long_names_and_failed_writes_name_the_file_and_the_reason() {
    let d = common::scratch("hostile-names");
    let longest = d.join(format!("{}.png", "a".repeat(251)));
    let mut args = vec!["render", "-o", s(&longest)];
    args.extend(SMALL.split_whitespace());
    let (code, _, err) = common::run_cli(&args);
    assert_eq!(code, 0, "{err}");
    assert_eq!(listing(&d).len(), 1, "{:?}", listing(&d));
    let too_long = d.join(format!("{}.png", "b".repeat(253)));
    refused(
        &["render", "-o", s(&too_long)],
        &["bbbb", "File name too long"],
    );
    // 64 KiB at most per file: the EXR (256 × 256 × 12 bytes) cannot be written.
    let big = d.join("big.exr");
    let mut cmd = bin();
    cmd.args(["render", "-o", s(&big), "--width", "256", "--height", "256"])
        .args(SMALL.split_whitespace().skip(4));
    unsafe {
        std::os::unix::process::CommandExt::pre_exec(&mut cmd, || {
            let lim = libc::rlimit {
                rlim_cur: 64 << 10,
                rlim_max: 64 << 10,
            };
            libc::setrlimit(libc::RLIMIT_FSIZE, &lim);
            libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
            Ok(())
        });
    }
    let o = run_within(cmd, None, Duration::from_secs(300));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    let lines = common::error_lines(&err);
    assert_eq!(lines.len(), 1, "{err}");
    assert!(
        lines[0].contains("big.exr") && lines[0].contains("File too large"),
        "{err}"
    );
    assert_eq!(listing(&d).len(), 1, "{:?}", listing(&d));
}

/// A full stdout is an error naming stdout (exit 2), a full stderr is ignored: never a panic.
#[test]
fn full_stdout_and_stderr_are_not_panics() {
    let d = common::scratch("hostile-full");
    let full = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap()
    };
    let mut cmd = bin();
    cmd.args(["info", "builtin:cornell"]);
    let o = run_within(cmd, Some(full()), Duration::from_secs(60));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("stdout") && err.contains("No space left"),
        "{err}"
    );
    // bench-table of a run folder, to a full stdout.
    let run = d.join("run");
    std::fs::create_dir_all(&run).unwrap();
    std::fs::write(run.join("results.csv"), fuzzy_vpl::bench::csv::to_csv(&[])).unwrap();
    let mut cmd = bin();
    cmd.args(["bench-table", s(&run)]);
    let o = run_within(cmd, Some(full()), Duration::from_secs(60));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("stdout"), "{err}");
    // render with a full stderr (the progress line and the summary fail): writes its image.
    let out = d.join("o.png");
    let mut cmd = bin();
    cmd.args(["render", "-o", s(&out)])
        .args(SMALL.split_whitespace());
    cmd.stderr(full());
    let mut child = cmd.stdout(Stdio::null()).spawn().unwrap();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(0));
    assert!(out.exists());
}

/// The developer variables are checked like options: an empty shader folder (it panicked), a work
/// scale of 0, a pattern count past 8, a switch set to anything but 1: one line naming the
/// variable, exit 2, before any work. An unknown `FVPL_` name is a warning.
#[test]
fn developer_variables_are_checked_like_options() {
    let d = common::scratch("hostile-env");
    let empty = d.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    // A copy of the shaders with one file that does not parse (a wgpu validation panic later).
    let broken = d.join("broken");
    for sub in ["", "common", "kmeans"] {
        std::fs::create_dir_all(broken.join(sub)).unwrap();
        let from = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("shaders-wgsl")
            .join(sub);
        for e in std::fs::read_dir(&from).unwrap() {
            let e = e.unwrap();
            if e.file_type().unwrap().is_file() {
                std::fs::copy(e.path(), broken.join(sub).join(e.file_name())).unwrap();
            }
        }
    }
    let primary = broken.join("primary.wgsl");
    let text = std::fs::read_to_string(&primary).unwrap() + "\nfn broken(\n";
    std::fs::write(&primary, text).unwrap();
    let cases = [
        ("FVPL_SHADER_DIR", s(&empty).to_string(), "FVPL_SHADER_DIR"),
        (
            "FVPL_SHADER_DIR",
            s(&broken).to_string(),
            "pass primary does not validate",
        ),
        ("FVPL_SHADER_DIR", "/dev/null".into(), "not a directory"),
        ("FVPL_WORK_SCALE", "0".into(), "FVPL_WORK_SCALE=0"),
        ("FVPL_WORK_SCALE", "lots".into(), "FVPL_WORK_SCALE=lots"),
        ("FVPL_SHADE_PATTERNS", "9".into(), "FVPL_SHADE_PATTERNS=9"),
        ("FVPL_SHADE_TILE_CULL", "2".into(), "FVPL_SHADE_TILE_CULL=2"),
        ("FVPL_PROFILE_STEPS", "0".into(), "set it to 1"),
        ("FVPL_NO_ALPHA_TEST", "yes".into(), "FVPL_NO_ALPHA_TEST=yes"),
    ];
    for (var, value, needle) in cases {
        let mut cmd = bin();
        cmd.args(["render", "-o", s(&d.join("o.png"))])
            .env(var, &value);
        let o = run_within(cmd, None, Duration::from_secs(30));
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{var}={value}: {err}");
        let lines = common::error_lines(&err);
        assert_eq!(lines.len(), 1, "{var}={value}: {err}");
        assert!(lines[0].contains(needle), "{var}={value}: {err}");
    }
    // The shader folder holding the shaders works.
    let mut cmd = bin();
    cmd.args(["info", "builtin:cornell"])
        .env(
            "FVPL_SHADER_DIR",
            concat!(env!("CARGO_MANIFEST_DIR"), "/shaders-wgsl"),
        )
        .env("FVPL_SHADERDIR", "typo");
    let o = run_within(cmd, None, Duration::from_secs(30));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(
        err.contains("warning: FVPL_SHADERDIR is not a variable"),
        "{err}"
    );
}

/// A scene argument that is not UTF-8 is named (its bytes escaped), not "invalid UTF-8" alone.
#[test]
fn a_non_utf8_scene_name_is_named() {
    use std::os::unix::ffi::OsStrExt;
    let mut cmd = bin();
    cmd.arg("info")
        .arg(std::ffi::OsStr::from_bytes(b"sc\xffene.glb"));
    let o = run_within(cmd, None, Duration::from_secs(30));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("sc?ene.glb") && err.contains("UTF-8"), "{err}");
}

/// The URI policy on the command line: refused without `--allow-outside-uris`, loaded with it.
#[test]
fn allow_outside_uris_lets_a_trusted_scene_read_beside_its_folder() {
    let d = common::scratch("hostile-uri");
    let scene_dir = d.join("scene");
    std::fs::create_dir_all(&scene_dir).unwrap();
    let tri: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    std::fs::write(d.join("shared.bin"), &tri).unwrap();
    let scene = scene_dir.join("s.gltf");
    std::fs::write(
        &scene,
        r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"..%2Fshared.bin","byteLength":36}],
        "bufferViews":[{"buffer":0,"byteLength":36}],
        "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}],"scene":0}"#,
    )
    .unwrap();
    refused(
        &["info", s(&scene)],
        &["s.gltf", "..%2Fshared.bin", "--allow-outside-uris"],
    );
    let (code, out, err) = common::run_cli(&["info", s(&scene), "--allow-outside-uris"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("triangles:           1"), "{out}");
}

/// `--light-scale 1e-36` (inside the accepted 1e-44..1e36) wrote an all-black PNG: the automatic
/// exposure stopped at 1e30. Now the image is exposed to its log-average like any other.
#[test]
fn a_faint_light_scale_is_still_exposed() {
    let d = common::scratch("hostile-faint");
    let png = d.join("faint.png");
    let mut args = vec!["render", "-o", s(&png), "--light-scale", "1e-36"];
    args.extend(SMALL.split_whitespace());
    let (code, _, err) = common::run_cli(&args);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("warning"), "{err}");
    let (_, _, px) = fuzzy_vpl::export::read_exr(&png).unwrap();
    let lit = px.iter().filter(|p| p.iter().any(|&c| c > 0.1)).count();
    assert!(lit > px.len() / 4, "{lit} of {} pixels lit", px.len());
}

/// SIGINT, SIGTERM or SIGHUP during an atomic write removes the temporary file and ends the process
/// as killed by the signal; the file the write would have replaced keeps its old content. The
/// writer is this test binary run again (`signal_child_writer`), blocked in the middle of a write.
#[test]
fn a_signal_during_a_write_removes_the_temporary_file() {
    for (sig, name) in [
        (libc::SIGINT, "SIGINT"),
        (libc::SIGTERM, "SIGTERM"),
        (libc::SIGHUP, "SIGHUP"),
    ] {
        let d = common::scratch(&format!("hostile-signal-{name}"));
        let target = d.join("out.json");
        std::fs::write(&target, "old").unwrap();
        let mut cmd = Command::new(std::env::current_exe().unwrap());
        cmd.args(["signal_child_writer", "--exact", "--ignored", "--nocapture"])
            .env(CHILD_ENV, &target)
            .stdout(Stdio::null())
            .stderr(Stdio::null());
        // The child starts with the signal's default action, as from a shell: a test run under
        // `nohup` would have it inherit SIGHUP ignored, which the writer rightly leaves alone.
        use std::os::unix::process::CommandExt;
        // SAFETY: `signal` is async-signal-safe, as `pre_exec` requires.
        unsafe {
            cmd.pre_exec(move || {
                libc::signal(sig, libc::SIG_DFL);
                Ok(())
            });
        }
        let mut child = cmd.spawn().unwrap();
        // The temporary file exists once the child has written into it (up to 6,000 polls 10 ms
        // apart, 60 s: a hang guard).
        let mut polls = 0;
        let tmp = loop {
            if let Some(n) = listing(&d)
                .into_iter()
                .find(|n| n.starts_with(".fvpl-tmp-"))
            {
                break d.join(n);
            }
            polls += 1;
            if polls > 6000 || child.try_wait().unwrap().is_some() {
                let _ = child.kill();
                panic!("{name}: the child never started its write");
            }
            std::thread::sleep(Duration::from_millis(10));
        };
        while std::fs::metadata(&tmp).map_or(0, |m| m.len()) < 1000 {
            std::thread::sleep(Duration::from_millis(10));
        }
        unsafe { libc::kill(child.id() as i32, sig) };
        // Up to 3,000 polls 10 ms apart (30 s): a hang guard.
        let mut polls = 0;
        let status = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break s;
            }
            polls += 1;
            if polls > 3000 {
                let _ = child.kill();
                panic!("{name}: the child did not end");
            }
            std::thread::sleep(Duration::from_millis(10));
        };
        use std::os::unix::process::ExitStatusExt;
        assert_eq!(status.signal(), Some(sig), "{name}: {status:?}");
        assert_eq!(listing(&d), vec!["out.json".to_string()], "{name}");
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "old", "{name}");
    }
}

const CHILD_ENV: &str = "HOSTILE_SIGNAL_CHILD_TARGET";

/// The writer of `a_signal_during_a_write_removes_the_temporary_file`: writes 64 KiB into the
/// temporary file of an atomic write of the target, then waits (up to a minute) to be signalled.
#[test]
#[ignore = "run by a_signal_during_a_write_removes_the_temporary_file"]
fn signal_child_writer() {
    let Some(target) = std::env::var_os(CHILD_ENV) else {
        return;
    };
    let target = PathBuf::from(target);
    let _ = fuzzy_vpl::export::write_atomic(&target, |w| {
        use std::io::Write;
        w.write_all(&[b' '; 64 << 10])?;
        w.flush()?;
        std::thread::sleep(Duration::from_secs(60));
        Ok(())
    });
}
