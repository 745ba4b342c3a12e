//! The `fuzzy-vpl` binary: exit codes, outputs, stats JSON, bad input.

mod common;

use std::process::Command;

use common::run_cli as run;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_fuzzy-vpl"))
}

#[test]
fn no_arguments_without_a_display_says_how_to_render() {
    // No arguments opens the viewer; without any display that is one clear line and exit 2.
    let o = bin()
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    let lines = common::error_lines(&err);
    assert_eq!(lines.len(), 1, "{err}");
    assert!(lines[0].contains("fuzzy-vpl render"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn render_cornell_128_exr_with_stats() {
    let d = common::scratch("cli-exr");
    let exr = d.join("c.exr");
    let stats = d.join("s.json");
    let (code, _, err) = run(&common::cmd(
        "render builtin:cornell --width 128 --height 128",
        &["-o", common::arg(&exr), "--stats", common::arg(&stats)],
    ));
    assert_eq!(code, 0, "{err}");
    let (w, h, px) = fuzzy_vpl::export::read_exr(&exr).unwrap();
    assert_eq!((w, h), (128, 128));
    assert!(common::all_finite(&px));
    assert!(fuzzy_vpl::metrics::mean_luminance(&px) > 0.02);
    // An independent OpenEXR reader (Debian's openexr tools) opens it as float RGB.
    let o = Command::new("exrheader")
        .arg(&exr)
        .output()
        .expect("exrheader not found: apt-get install openexr");
    let header = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{header}");
    for c in [
        "R, 32-bit floating-point",
        "G, 32-bit floating-point",
        "B, 32-bit floating-point",
    ] {
        assert!(header.contains(c), "{header}");
    }
    assert!(header.contains("(0 0) - (127 127)"), "{header}");
    let j = common::read_json(&stats);
    for k in [
        "scene",
        "width",
        "height",
        "adapter",
        "settings",
        "counts",
        "passes",
        "timings_ms",
    ] {
        assert!(j.get(k).is_some(), "stats lack {k}");
    }
    // The contract's keys (docs/design.md), written out rather than taken from the code.
    for k in [
        "vpl_trace",
        "vpl_cluster",
        "primary",
        "sp_cluster",
        "visibility",
        "shade",
        "direct",
        "reference",
        "gather",
        "frame",
    ] {
        assert!(j["timings_ms"][k].is_number(), "timings_ms lacks {k}");
    }
    assert!(j["timings_ms"]["frame"].as_f64().unwrap() > 0.0);
    // The warm-up before the timed render (default 200 ms of GPU work) and the device it ran on.
    assert!(j["warmup_ms"].as_f64().unwrap() >= 200.0, "{j}");
    assert!(!j["driver"].as_str().unwrap().is_empty(), "{j}");
    let software = j["adapter"].as_str().unwrap().contains("llvmpipe");
    let kind = if software { "software" } else { "hardware" };
    assert_eq!(j["device_type"], kind, "{j}");
    assert_eq!(j["counts"]["triangles"], 32);
    // The contract's settings, and the values the k-means used (γ at most pixels / K).
    for k in [
        "vpls",
        "vpl_clusters",
        "sp_clusters",
        "fuzziness",
        "gamma",
        "normal_threshold",
    ] {
        assert!(j["settings"][k].is_number(), "settings lack {k}");
    }
    assert!(j["settings"]["gamma_used"].as_u64().unwrap() >= 1);
    // γ defaults to auto: 16,384 pixels are below the rule's 19,200 sampled points, so γ 4.
    assert_eq!(j["settings"]["gamma_auto"], true);
    assert_eq!(j["settings"]["gamma"], 4);
    // The method (docs/methods.md): colom unless --method says otherwise.
    assert_eq!(j["settings"]["method"], "colom");
    assert!(j["settings"]["normal_threshold_used"].as_f64().unwrap() < 1.0);
    assert!(j["settings"].get("path_trace_spp").is_none());
    assert!(j["settings"].get("plane_gate_deg").is_none());
    assert!(j.get("error").is_none());
    // No temporary files left beside the outputs.
    let names: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
}

#[test]
fn compare_fills_error_and_writes_error_map() {
    let d = common::scratch("cli-compare");
    let r = d.join("ref.exr");
    let base = common::cmd("render builtin:cornell --width 32 --height 32", &[]);
    let (code, _, err) = run(&[&base[..], &["-o", r.to_str().unwrap(), "--seed", "1"]].concat());
    assert_eq!(code, 0, "{err}");
    let stats = d.join("s.json");
    let map = d.join("err.png");
    let (code, _, err) = run(&[
        &base[..],
        &[
            "-o",
            d.join("x.png").to_str().unwrap(),
            "--seed",
            "2",
            "--compare",
            r.to_str().unwrap(),
            "--error-map",
            map.to_str().unwrap(),
            "--stats",
            stats.to_str().unwrap(),
        ],
    ]
    .concat());
    assert_eq!(code, 0, "{err}");
    let j = common::read_json(&stats);
    let mse = j["error"]["mse"].as_f64().unwrap();
    let rel = j["error"]["rel_mse"].as_f64().unwrap();
    // Different seeds: small, non-zero noise difference.
    assert!(mse > 0.0 && mse < 0.01, "mse {mse}");
    assert!(rel > 0.0 && rel < 0.1, "rel_mse {rel}");
    assert!(image::open(&map).unwrap().width() == 32);
    // FLIP beside them, in the stats and on stderr; no SP clustering at 32×32 with K 3072: no
    // border measure.
    let flip = j["error"]["flip"].as_f64().unwrap();
    assert!(flip > 0.0 && flip < 0.2, "flip {flip}");
    assert!(j["error"].get("border").is_none(), "{j}");
    assert!(
        err.contains("MSE") && err.contains("rel_mse") && err.contains("FLIP"),
        "{err}"
    );
    // With SP clusters the border measure is there; the FLIP map is drawn with --error-metric flip.
    let (code, _, err) = run(&[
        &base[..],
        &[
            "-o",
            d.join("y.png").to_str().unwrap(),
            "--sp-clusters",
            "24",
            "--weighting",
            "hard",
            "--compare",
            r.to_str().unwrap(),
            "--error-map",
            map.to_str().unwrap(),
            "--error-metric",
            "flip",
            "--stats",
            stats.to_str().unwrap(),
        ],
    ]
    .concat());
    assert_eq!(code, 0, "{err}");
    let j = common::read_json(&stats);
    for k in ["flip", "border", "interior", "flip_border"] {
        let v = j["error"][k].as_f64().unwrap_or(f64::NAN);
        assert!(v.is_finite() && v >= 0.0, "{k}: {j}");
    }
    assert!(err.contains("border"), "{err}");
    let m = image::open(&map).unwrap().into_rgb8();
    assert_eq!(m.dimensions(), (32, 32));
}

/// `render builtin:cornell` at 48 × 32 with 256 VPLs and `--target-ms ms` into scratch `name`,
/// which must exit 0: (stderr, the stats JSON, the image's path).
fn render_target_ms(name: &str, ms: &str) -> (String, serde_json::Value, std::path::PathBuf) {
    let d = common::scratch(name);
    let (stats, out) = (d.join("s.json"), d.join("t.exr"));
    let words = "render builtin:cornell --width 48 --height 32 --vpls 256 --target-ms";
    let rest = [ms, "-o", common::arg(&out), "--stats", common::arg(&stats)];
    let (code, _, err) = run(&common::cmd(words, &rest));
    assert_eq!(code, 0, "{err}");
    (err, common::read_json(&stats), out)
}

/// `--target-ms`: a few frames choose the K's; the stats hold the budget, each frame's K's and time,
/// and the K's chosen (the last frame's) in `settings`.
#[test]
fn target_ms_chooses_the_cluster_counts_and_says_so() {
    let (err, j, png) = render_target_ms("cli-target", "100000");
    assert!(err.contains("--target-ms 100000: frame 1"), "{err}");
    assert_eq!(j["settings"]["target_ms"].as_f64(), Some(100000.0), "{j}");
    let steps = j["target"]["steps"].as_array().unwrap();
    assert!(!steps.is_empty() && steps.len() <= 8, "{j}");
    let last = steps.last().unwrap();
    // Far above any frame: the direct light keeps the user's 16 samples.
    assert_eq!(last["direct_samples"].as_u64(), Some(16), "{j}");
    assert_eq!(j["settings"]["direct_samples"].as_u64(), Some(16), "{j}");
    // A budget far above any frame: K_VPL at its most, half the VPLs; K_SP on the line,
    // 1% of the pixels × sqrt(128 / (0.244 × 256)) = 22.
    assert_eq!(last["sp_clusters"], j["settings"]["sp_clusters"]);
    assert_eq!(last["vpl_clusters"], j["settings"]["vpl_clusters"]);
    assert_eq!(j["settings"]["vpl_clusters"].as_u64(), Some(128), "{j}");
    assert_eq!(j["settings"]["sp_clusters"].as_u64(), Some(22), "{j}");
    let (w, h, px) = fuzzy_vpl::export::read_exr(&png).unwrap();
    assert_eq!((w, h), (48, 32));
    assert!(common::all_finite(&px));
}

#[test]
fn bad_input_exits_2_with_one_line() {
    let d = common::scratch("cli-bad");
    let missing = d.join("nope.gltf");
    let out = d.join("o.png");
    let bad_json = d.join("bad.gltf");
    std::fs::write(&bad_json, "{ not json").unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec![
                "render".into(),
                missing.display().to_string(),
                "-o".into(),
                out.display().to_string(),
            ],
            "nope.gltf",
        ),
        (
            vec!["info".into(), bad_json.display().to_string()],
            "bad.gltf",
        ),
        (
            vec![
                "render".into(),
                "builtin:cornell".into(),
                "-o".into(),
                d.join("o.jpg").display().to_string(),
            ],
            "o.jpg",
        ),
        (
            vec!["info".into(), "builtin:nosuch".into()],
            "builtin:nosuch",
        ),
        (
            vec![
                "render".into(),
                "builtin:cornell".into(),
                "-o".into(),
                out.display().to_string(),
                "--camera".into(),
                "5".into(),
            ],
            "camera",
        ),
        (
            vec![
                "render".into(),
                "builtin:cornell".into(),
                "-o".into(),
                out.display().to_string(),
                "--sun".into(),
                "0,0,0,1".into(),
            ],
            "--sun",
        ),
        (
            vec![
                "render".into(),
                "builtin:cornell".into(),
                "-o".into(),
                out.display().to_string(),
                "--compare".into(),
                missing.display().to_string(),
            ],
            "nope.gltf",
        ),
    ];
    for (args, needle) in cases {
        let a: Vec<&str> = args.iter().map(|s| s.as_str()).collect();
        let (code, _, err) = run(&a);
        assert_eq!(code, 2, "{a:?}: {err}");
        let lines = common::error_lines(&err);
        assert_eq!(lines.len(), 1, "{a:?}: {err}");
        assert!(lines[0].contains(needle), "{a:?}: {err}");
        assert!(!err.contains("panicked"), "{a:?}: {err}");
    }
    assert!(!out.exists());
}

/// Bad arguments, outputs that cannot be written and a reference with NaN are refused before any
/// rendering: exit 2 and stderr is exactly one line naming the option or file and the words of its
/// cause.
#[test]
fn bad_arguments_and_unwritable_outputs_exit_2_with_exactly_one_line() {
    let d = common::scratch("cli-bad-args");
    let out = d.join("o.exr");
    let nan_ref = d.join("nan.exr");
    let mut px = vec![[0.5f32; 3]; 16];
    px[5][1] = f32::NAN;
    fuzzy_vpl::export::write_image(&nan_ref, 4, 4, &px, 1.0).unwrap();
    let o = out.display().to_string();
    let nodir = d.join("nodir").join("x.exr").display().to_string();
    let nodir_png = d.join("nodir").join("v.png").display().to_string();
    let dir = d.display().to_string();
    let bench_dir = d.join("bench").display().to_string();
    let png = d.join("v.png").display().to_string();
    let nodir_dir = d.join("nodir").display().to_string();
    let nan = nan_ref.display().to_string();
    let stats_dir_needle = format!("{dir}|cannot write: it is a directory");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["render", "-o", &o, "--fuzziness", "2.5"],
            "--fuzziness 2.5|must be 1..16",
        ),
        (
            vec!["render", "-o", &o, "--seed=-1"],
            "--seed|not in 0..=4294967295",
        ),
        (
            vec!["render", "-o", &o, "--width", "3", "--width", "4"],
            "--width|cannot be used multiple times",
        ),
        (
            vec!["render", "-o", &o, "--error-map", "e.png"],
            "--compare|required arguments were not provided",
        ),
        (
            vec!["render", "-o", &o, "--error-metric", "flip"],
            "--error-map|required arguments were not provided",
        ),
        (
            vec!["render", "-o", &o, "--target-ms", "0"],
            "--target-ms 0|> 0 and at most 1e7",
        ),
        (
            vec!["view", "--b-fuzziness", "0"],
            "--fuzziness 0|must be 1..16",
        ),
        (
            vec!["view", "--b-weighting", "soft"],
            "--weighting|possible values: hard, uniform, inverse-distance",
        ),
        (
            vec!["view", "--target-ms", "0"],
            "--target-ms 0|> 0 and at most 1e7",
        ),
        (
            vec!["render", "-o", &o, "--target-ms", "-5"],
            "--target-ms -5|> 0 and at most 1e7",
        ),
        (
            vec!["render", "-o", &o, "--target-ms", "inf"],
            "--target-ms inf|> 0 and at most 1e7",
        ),
        (
            vec!["render", "-o", &o, "--target-ms", "100", "--reference"],
            "--target-ms|--reference and --path-trace cluster nothing",
        ),
        (
            vec!["render", "-o", &o, "--no-such-option"],
            "--no-such-option|unexpected argument",
        ),
        (
            vec!["render", "-o", &nodir],
            "nodir|cannot write: no directory",
        ),
        (vec!["render", "-o", &o, "--stats", &dir], &stats_dir_needle),
        (
            vec!["render", "-o", &o, "--compare", &nan],
            "nan.exr|non-finite pixel|at pixel 5",
        ),
        (
            vec!["render", "-o", &o, "--light-scale", "5e37"],
            "--light-scale|emits 1.350e39|does not fit in f32",
        ),
        // The Cornell box's ceiling emits 27: scaled by 1e35 it emits 2.7e36, past the 1e36 an image
        // lit by it may reach in f32.
        (
            vec!["render", "-o", &o, "--light-scale", "1e35"],
            "emits 2.700e36 with --light-scale",
        ),
        (
            vec!["render", "-o", &o, "--path-trace", "0"],
            "--path-trace|0 is not in 1..=",
        ),
        (
            vec!["render", "-o", &o, "--vpls", "100000000"],
            "--vpls 100000000|at most",
        ),
        (
            vec!["render", "-o", &o, "--plane-gate", "0"],
            "--plane-gate 0|must be an angle in (0, 90] degrees",
        ),
        // 200,000 SP clusters x 8192 VPLs: a 205 MB visibility matrix (lavapipe binds 128 MiB).
        (
            common::cmd("render --sp-clusters 200000 --vpl-clusters 0", &["-o", &o]),
            "--sp-clusters 200000",
        ),
        (
            vec!["render", "-o", &o, "--plane-gate", "91"],
            "--plane-gate 91|must be an angle in (0, 90] degrees",
        ),
        (
            vec!["render", "-o", &o, "--plane-gate", "NaN"],
            "--plane-gate NaN|must be an angle in (0, 90] degrees",
        ),
        (
            vec!["view", "--frames", "1", "--screenshot", &nodir_png],
            "nodir",
        ),
        (
            common::cmd("view --vpls 4294967295 --frames 1", &["--screenshot", &png]),
            "--vpls 4294967295",
        ),
        (
            vec!["render", "-o", &o, "--direct-samples", "4294967295"],
            "--direct-samples 4294967295",
        ),
        (
            vec!["render", "-o", &o, "--direct-samples", "0"],
            "--direct-samples 0",
        ),
        (
            common::cmd(
                "view --direct-samples 65537 --frames 1",
                &["--screenshot", &png],
            ),
            "--direct-samples 65537",
        ),
        (
            common::cmd(
                "bench --quick --direct-samples 70000",
                &["--out-dir", &bench_dir],
            ),
            "--direct-samples 70000",
        ),
        (
            vec!["view", "--shot-dir", &nodir_dir],
            "--shot-dir|not a directory",
        ),
        (vec!["view", "--shot-dir", &o], "--shot-dir|not a directory"),
        // 64 bytes a pixel in one storage binding: lavapipe's 128 MiB holds 2,097,152 pixels.
        (
            vec!["render", "-o", &o, "--width", "2048", "--height", "1100"],
            "--width/--height 2048x1100",
        ),
        (
            common::cmd(
                "bench --quick --width 2048 --height 1100",
                &["--out-dir", &bench_dir],
            ),
            "--width/--height 2048x1100",
        ),
        (
            common::cmd(
                "bench --modes sp-only --sp-clusters 200000",
                &["--out-dir", &bench_dir],
            ),
            "--sp-clusters 200000",
        ),
    ];
    // Each needle's parts ('|') all in the line: the option or file and the words of the cause,
    // so that another check refusing the same option or file does not pass for this one.
    for (a, needle) in cases {
        let (code, _, err) = run(&a);
        assert_eq!(code, 2, "{a:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{a:?}: {err}");
        assert!(
            err.starts_with("error: ") && needle.split('|').all(|part| err.contains(part)),
            "{a:?}: {err}"
        );
    }
    assert!(!out.exists());
}

/// A negative number given to an option is read as that option's value and refused with the
/// option's own message (clap used to read `-1` as an unknown flag: "unexpected argument '-1'");
/// an output named as a directory (`-o dir/`) is refused before rendering. Exit 2, one line.
#[test]
fn negative_values_and_directory_outputs_get_clear_messages() {
    let d = common::scratch("cli-negative");
    let o = d.join("o.png").display().to_string();
    let dir_slash = format!("{}/", d.display());
    let dir_png = d.join("sub.png");
    std::fs::create_dir_all(&dir_png).unwrap();
    let dir_png = dir_png.display().to_string();
    let bench_dir = d.join("bench").display().to_string();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["render", "-o", &o, "--light-scale", "-1"],
            "--light-scale -1: must be a finite number >= 0",
        ),
        (vec!["render", "-o", &o, "--exposure", "-2"], "--exposure"),
        (vec!["render", "-o", &o, "--clamp", "-0.5"], "--clamp -0.5"),
        (
            vec!["render", "-o", &o, "--width", "-5"],
            "--width -5: must be 1..16384",
        ),
        (
            vec!["render", "-o", &o, "--vpls", "-1e3"],
            "'--vpls <VPLS>'",
        ),
        (
            common::cmd("view --render-scale -1 --frames 1", &["--screenshot", &o]),
            "--render-scale",
        ),
        (
            vec!["bench", "--out-dir", &bench_dir, "--light-scale", "-3"],
            "--light-scale -3",
        ),
        (vec!["info", "--light-scale", "-1"], "--light-scale -1"),
        (
            vec!["render", "-o", &dir_slash],
            "output must end in .exr or .png",
        ),
        (vec!["render", "-o", &dir_png], "it is a directory"),
    ];
    for (a, needle) in cases {
        let (code, _, err) = run(&a);
        assert_eq!(code, 2, "{a:?}: {err}");
        let lines = common::error_lines(&err);
        assert_eq!(lines.len(), 1, "{a:?}: {err}");
        assert!(lines[0].contains(needle), "{a:?}: {err}");
        assert!(!err.contains("unexpected argument"), "{a:?}: {err}");
    }
    assert!(!d.join("o.png").exists());
}

/// A valid scene without any light renders black with a warning, exit 0.
#[test]
fn scene_without_light_renders_black() {
    let d = common::scratch("cli-dark");
    // One triangle facing +Z, no material, no light.
    let pos = [-1.0f32, -1.0, 0.0, 1.0, -1.0, 0.0, 0.0, 1.0, 0.0].map(f32::to_le_bytes);
    std::fs::write(d.join("t.bin"), pos.concat()).unwrap();
    let path = d.join("dark.gltf");
    let gltf = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
      "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[-1,-1,0],"max":[1,1,0]}],
      "bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"uri":"t.bin","byteLength":36}]}"#;
    std::fs::write(&path, gltf).unwrap();
    let out = d.join("dark.exr");
    let (code, _, err) = run(&common::cmd(
        "render --width 16 --height 16",
        &[common::arg(&path), "-o", common::arg(&out)],
    ));
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("warning") && err.contains("no light"), "{err}");
    let (_, _, px) = fuzzy_vpl::export::read_exr(&out).unwrap();
    assert!(px.iter().flatten().all(|c| *c == 0.0));
    // The same scene with a point light from the command line is lit.
    let (code, _, err) = run(&common::cmd(
        "render --width 16 --height 16 --point 0,0,2,5",
        &[common::arg(&path), "-o", common::arg(&out)],
    ));
    assert_eq!(code, 0, "{err}");
    let (_, _, px) = fuzzy_vpl::export::read_exr(&out).unwrap();
    assert!(common::all_finite(&px));
    assert!(px.iter().any(|p| p[0] > 0.0));
}

/// Lights of zero power are no light: `info` warns and lists no VPL pass, as it does for a scene
/// whose emitters are all scaled to 0 (a point light given on the command line included).
#[test]
fn zero_power_lights_are_no_light() {
    for extra in [
        &["--light-scale", "0"][..],
        &["--point", "0.3,0.3,0.3,5", "--light-scale", "0"],
    ] {
        let mut a = vec!["info", "builtin:cornell"];
        a.extend_from_slice(extra);
        let (code, out, err) = run(&a);
        assert_eq!(code, 0, "{extra:?}: {err}");
        assert!(err.contains("no light"), "{extra:?}: {err}");
        assert!(!out.contains("vpl_trace"), "{extra:?}: {out}");
    }
}

#[test]
fn info_prints_counts_and_passes() {
    let (code, out, err) = run(&["info", "builtin:conference"]);
    assert_eq!(code, 0, "{err}");
    for k in [
        "triangles:",
        "emissive triangles:",
        "punctual lights:",
        "cameras:",
        "bounds:",
        "features:",
        "passes",
    ] {
        assert!(out.contains(k), "{out}");
    }
    assert!(out.contains("1448"), "{out}");
}

/// `info SCENE | head -1`: a reader that closes the pipe early ends the program quietly (SIGPIPE), no
/// panic message.
#[test]
fn closed_stdout_is_not_a_panic() {
    use std::process::Stdio;
    let mut child = bin()
        .args(["info", "builtin:conference"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Close the read end before the program writes.
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
}

/// `--plane-gate`: the stats name it when it gated a fuzzy frame, not for hard clustering (F = 1, no
/// slot to gate); the gated image is finite and differs from the ungated one.
#[test]
fn plane_gate_is_reported_where_it_applies() {
    let d = common::scratch("cli-gate");
    let render = |name: &str, extra: &[&str]| {
        let exr = d.join(format!("{name}.exr"));
        let stats = d.join(format!("{name}.json"));
        let mut a = common::cmd(
            "render builtin:conference --width 64 --height 48 --vpls 512 --vpl-clusters 128 \
             --sp-clusters 48",
            &["-o", common::arg(&exr), "--stats", common::arg(&stats)],
        );
        a.extend_from_slice(extra);
        let (code, _, err) = run(&a);
        assert_eq!(code, 0, "{err}");
        let j = common::read_json(&stats);
        let px = fuzzy_vpl::export::read_exr(&exr).unwrap().2;
        assert!(common::all_finite(&px), "{name}");
        (j, px)
    };
    let (j_off, px_off) = render("off", &["--weighting", "uniform"]);
    let (j_on, px_on) = render("on", &["--weighting", "uniform", "--plane-gate", "20"]);
    let (j_hard, _) = render("hard", &["--weighting", "hard", "--plane-gate", "20"]);
    assert!(j_off["settings"].get("plane_gate_deg").is_none());
    assert_eq!(j_on["settings"]["plane_gate_deg"].as_f64(), Some(20.0));
    assert!(j_hard["settings"].get("plane_gate_deg").is_none());
    assert!(px_on != px_off, "the gate changed nothing");
}

/// A scene path (or a file it names) that is not a regular file is refused at once: a FIFO used to
/// block forever, /dev/zero to be read until memory ran out.
#[test]
fn scene_files_that_are_not_regular_files_are_refused() {
    let d = common::scratch("cli-fifo");
    let fifo = d.join("fifo.glb");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    std::fs::create_dir_all(d.join("dir.glb")).unwrap();
    // A glTF whose buffer is the FIFO.
    let gltf = d.join("buf.gltf");
    std::fs::write(
        &gltf,
        r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"fifo.glb","byteLength":36}]}"#,
    )
    .unwrap();
    let cases = [
        (fifo.display().to_string(), "FIFO"),
        ("/dev/zero".to_string(), "device"),
        (d.join("dir.glb").display().to_string(), "directory"),
        (gltf.display().to_string(), "FIFO"),
    ];
    for (path, kind) in cases {
        let mut child = bin()
            .args(["info", &path])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        // A hang guard, not a speed test: 1,500 polls 20 ms apart (at least 30 s).
        let mut polls = 0;
        while child.try_wait().unwrap().is_none() {
            polls += 1;
            if polls > 1500 {
                let _ = child.kill();
                let _ = child.wait();
                panic!("info {path}: still running after 1,500 polls (30 s)");
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{path}: {err}");
        assert_eq!(err.lines().count(), 1, "{path}: {err}");
        assert!(
            err.contains("not a regular file") && err.contains(kind),
            "{path}: {err}"
        );
    }
}

/// `render builtin:cornell` with `frame` and `extra` and one direct sample, into `o`, which must
/// exit 0; its stats JSON (written to `stats`).
fn render_stats(
    o: &std::path::Path,
    stats: &std::path::Path,
    frame: &[&str],
    extra: &[&str],
) -> serde_json::Value {
    let mut args = common::cmd(
        "render builtin:cornell --direct-samples 1",
        &["-o", common::arg(o), "--stats", common::arg(stats)],
    );
    args.extend_from_slice(frame);
    args.extend_from_slice(extra);
    let (code, _, err) = run(&args);
    assert_eq!(code, 0, "{extra:?}: {err}");
    serde_json::from_slice(&std::fs::read(stats).unwrap()).unwrap()
}

/// `--gamma auto` (the default) writes the rule's γ for the frame's size and K into the stats, and the
/// k-means samples with it; a γ asked is written as asked.
#[test]
fn auto_gamma_is_written_as_chosen() {
    let d = common::scratch("auto-gamma");
    let o = d.join("a.png");
    let stats = d.join("a.json");
    let render = |extra: &[&str]| -> serde_json::Value {
        let frame = common::cmd(
            "--width 400 --height 300 --sp-clusters 100 --vpls 512 --vpl-clusters 64",
            &[],
        );
        render_stats(&o, &stats, &frame, extra)
    };
    // 120,000 pixels, K 100: 40 a cluster allows 30, 19,200 in all allows 6.
    for extra in [&[][..], &["--gamma", "auto"][..]] {
        let j = render(extra);
        assert_eq!(j["settings"]["gamma_auto"], true, "{extra:?}");
        assert_eq!(j["settings"]["gamma"], 6, "{extra:?}");
        assert_eq!(j["settings"]["gamma_used"], 6, "{extra:?}");
    }
    let j = render(&["--gamma", "3"]);
    assert_eq!(j["settings"]["gamma_auto"], false);
    assert_eq!(j["settings"]["gamma"], 3);
    assert_eq!(j["settings"]["gamma_used"], 3);
    let (code, _, err) = run(&["render", "-o", o.to_str().unwrap(), "--gamma", "0"]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(common::error_lines(&err).len(), 1, "{err}");
    assert!(err.contains("--gamma"), "{err}");
}

/// `--paper` sets the paper's choices and the stats record them; an option given on the command
/// line wins over it (`--clamp`, `--cluster-light`, `--sp-clusters`), and without `--paper` every
/// switch is at its default. 96×72 with 256 VPLs: the paper's K ratios give 75 SP clusters
/// (6912 · 8000 / 737,280 = 75.0) and 64 VPL clusters (256 / 4).
#[test]
fn paper_sets_the_papers_choices_and_given_options_win() {
    let d = common::scratch("paper");
    let o = d.join("p.exr");
    let stats = d.join("p.json");
    let render = |extra: &[&str]| -> serde_json::Value {
        let frame = ["--width", "96", "--height", "72", "--vpls", "256"];
        render_stats(&o, &stats, &frame, extra)
    };
    let s = &render(&["--paper"])["settings"];
    assert_eq!(s["paper"], true);
    assert_eq!(s["cluster_light"], "point");
    assert_eq!(
        (&s["reseed"], &s["ring_fallback"], &s["position_fallback"]),
        (&false.into(), &false.into(), &false.into())
    );
    assert_eq!(s["centroid_normal"], "mean");
    assert_eq!(
        (&s["sp_clusters"], &s["vpl_clusters"]),
        (&75.into(), &64.into())
    );
    assert_eq!(s["clamp"], 0.0);
    assert_eq!(s["fuzziness"], 6);
    assert_eq!(s["weighting"], "inverse-distance");
    let s = &render(&common::cmd(
        "--paper --clamp 0.01 --cluster-light spread --sp-clusters 50",
        &[],
    ))["settings"];
    assert_eq!(
        (s["paper"].clone(), s["cluster_light"].clone()),
        (true.into(), "spread".into())
    );
    assert_eq!(
        (&s["sp_clusters"], &s["vpl_clusters"]),
        (&50.into(), &64.into())
    );
    assert!(
        (s["clamp"].as_f64().unwrap() - 0.01).abs() < 1e-7,
        "{}",
        s["clamp"]
    );
    assert_eq!(s["reseed"], false);
    let s = &render(&[])["settings"];
    assert_eq!(s["paper"], false);
    assert_eq!(s["cluster_light"], "spread");
    assert_eq!(
        (&s["reseed"], &s["ring_fallback"], &s["position_fallback"]),
        (&true.into(), &true.into(), &true.into())
    );
    assert_eq!(s["centroid_normal"], "normalised");
}

/// A one-quad glTF (two triangles, data: URI) whose material is `material` (JSON) and which
/// requires `required`.
fn quad_gltf(path: &std::path::Path, material: &str, required: &[&str]) {
    let pos: [[f32; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let mut bin: Vec<u8> = pos.iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
    bin.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut b64 = String::new();
    for c in bin.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            b64.push(if k <= c.len() {
                A[(n >> (18 - 6 * k) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    let req = serde_json::to_string(required).unwrap();
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "extensionsUsed": {req}, "extensionsRequired": {req},
        "buffers": [{{"byteLength": {len}, "uri": "data:application/octet-stream;base64,{b64}"}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 12}}],
        "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                        "min": [0, 0, 0], "max": [1, 1, 0]}},
                      {{"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}}],
        "materials": [{material}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}}],
        "nodes": [{{"mesh": 0}}], "scenes": [{{"nodes": [0]}}], "scene": 0}}"#,
        len = bin.len()
    );
    std::fs::write(path, json).unwrap();
}

/// `info` names the alpha test where a material needs it, and says it is compiled out elsewhere.
#[test]
fn info_lists_the_alpha_test_where_it_runs() {
    let d = common::scratch("cli-alpha");
    let masked = d.join("masked.gltf");
    quad_gltf(
        &masked,
        r#"{"alphaMode": "MASK", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.25]}}"#,
        &[],
    );
    let (code, out, err) = run(&["info", masked.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("alpha-test"), "{out}");
    assert!(
        out.contains("alpha test:          2 triangles (1 alpha-masked materials)"),
        "{out}"
    );
    let (code, out, err) = run(&["info", "builtin:cornell"]);
    assert_eq!(code, 0, "{err}");
    assert!(!out.contains("alpha-test"), "{out}");
    assert!(out.contains("alpha test:          none"), "{out}");
}

/// Required extensions: one that only a specular renderer needs loads with one warning; an unknown
/// one exits 2 with one line naming the file and the extension unless `--allow-extension` names
/// it; one that changes geometry exits 2 even then.
#[test]
fn required_extensions_on_the_command_line() {
    let d = common::scratch("cli-ext");
    let spec = d.join("specular.gltf");
    quad_gltf(&spec, r#"{"name": "m"}"#, &["KHR_materials_specular"]);
    let (code, _, err) = run(&["info", spec.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    // (The other warning says the quad has no light.)
    let warnings: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("warning: ") && l.contains("extension"))
        .collect();
    assert_eq!(warnings.len(), 1, "{err}");
    assert!(warnings[0].contains("KHR_materials_specular"), "{err}");

    let vendor = d.join("vendor.gltf");
    quad_gltf(&vendor, r#"{"name": "m"}"#, &["VENDOR_paint"]);
    let (code, _, err) = run(&["info", vendor.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    let lines = common::error_lines(&err);
    assert_eq!(lines.len(), 1, "{err}");
    assert!(
        lines[0].contains("vendor.gltf") && lines[0].contains("VENDOR_paint"),
        "{err}"
    );
    let (code, _, err) = run(&[
        "info",
        vendor.to_str().unwrap(),
        "--allow-extension",
        "VENDOR_paint",
    ]);
    assert_eq!(code, 0, "{err}");

    let draco = d.join("draco.gltf");
    quad_gltf(&draco, r#"{"name": "m"}"#, &["KHR_draco_mesh_compression"]);
    let (code, _, err) = run(&[
        "info",
        draco.to_str().unwrap(),
        "--allow-extension",
        "KHR_draco_mesh_compression",
    ]);
    assert_eq!(code, 2, "{err}");
    let lines = common::error_lines(&err);
    assert_eq!(lines.len(), 1, "{err}");
    assert!(
        lines[0].contains("draco.gltf") && lines[0].contains("Draco"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

/// A 1 TiB sparse file as the scene is refused with exit 2 and one line naming its size against the
/// cap (it used to abort with exit 134 reserving 1 TiB). That the loader reads none of it is
/// `scene_load::huge_sparse_files_are_refused_or_read_only_as_declared` (bytes read, not a clock).
#[test]
fn a_terabyte_scene_file_is_refused_at_once() {
    let d = common::scratch("cli-sparse");
    for name in ["huge.glb", "huge.gltf"] {
        let p = d.join(name);
        std::fs::File::create(&p).unwrap().set_len(1 << 40).unwrap();
        let (code, _, err) = run(&["info", p.to_str().unwrap()]);
        assert_eq!(code, 2, "{err}");
        let lines = common::error_lines(&err);
        assert_eq!(lines.len(), 1, "{err}");
        assert!(
            lines[0].contains(name)
                && lines[0].contains("larger than")
                && lines[0].contains("1.0 TiB"),
            "{err}"
        );
        std::fs::remove_file(&p).unwrap();
    }
}

/// PNG exposure is automatic by default: the stats' `settings.exposure` is the exposure the PNG was
/// written with, `exposure::auto_exposure` of the frame (checked against the EXR of the same frame),
/// and the PNG is exactly that exposure's tone mapping. The EXR stays unscaled: the same with
/// `--exposure 2`, which is written as fixed. A scene lit 1000× dimmer gives the same PNG (within one
/// 8-bit step on average: the image is linear in the emitters).
#[test]
fn png_exposure_is_automatic_and_written_in_the_stats() {
    let d = common::scratch("cli-exposure");
    let render = |tag: &str, extra: &[&str]| -> (serde_json::Value, Vec<[f32; 3]>, Vec<u8>) {
        let exr = d.join(format!("{tag}.exr"));
        let png = d.join(format!("{tag}.png"));
        let stats = d.join(format!("{tag}.json"));
        let mut args = common::cmd(
            "render builtin:cornell --width 64 --height 48 --vpls 256 --vpl-clusters 32 \
             --sp-clusters 64 --direct-samples 2",
            &[
                "-o",
                common::arg(&exr),
                "-o",
                common::arg(&png),
                "--stats",
                common::arg(&stats),
            ],
        );
        args.extend_from_slice(extra);
        let (code, _, err) = run(&args);
        assert_eq!(code, 0, "{extra:?}: {err}");
        let j = common::read_json(&stats);
        let (_, _, px) = fuzzy_vpl::export::read_exr(&exr).unwrap();
        assert!(common::all_finite(&px));
        let rgb = image::open(&png).unwrap().into_rgb8().into_raw();
        (j, px, rgb)
    };
    let (j, px, rgb) = render("auto", &[]);
    assert_eq!(j["settings"]["exposure_auto"], true);
    let used = j["settings"]["exposure"].as_f64().unwrap() as f32;
    let want = fuzzy_vpl::exposure::auto_exposure(&px);
    assert_eq!(used, want, "stats exposure {used}, auto of the EXR {want}");
    assert_eq!(rgb, fuzzy_vpl::export::to_srgb8(&px, used));
    // The key: the log-average luminance × exposure is 0.18 (f64 sums: 1e-6 relative).
    let la = fuzzy_vpl::exposure::log_average_luminance(&px).unwrap();
    assert!((la * used as f64 / 0.18 - 1.0).abs() < 1e-6);

    let (j2, px2, rgb2) = render("fixed", &["--exposure", "2"]);
    assert_eq!(j2["settings"]["exposure_auto"], false);
    assert_eq!(j2["settings"]["exposure"], 2.0);
    assert_eq!(px2, px, "the EXR depends on the exposure");
    assert_eq!(rgb2, fuzzy_vpl::export::to_srgb8(&px, 2.0));

    let (_, px3, rgb3) = render("dim", &["--light-scale", "0.001"]);
    let mean = |p: &[[f32; 3]]| fuzzy_vpl::metrics::mean_luminance(p);
    assert!(mean(&px3) < 0.002 * mean(&px), "the dim scene is not dim");
    let diff: f64 = rgb3
        .iter()
        .zip(&rgb)
        .map(|(a, b)| (*a as f64 - *b as f64).abs())
        .sum::<f64>()
        / rgb.len() as f64;
    assert!(diff <= 1.0, "mean |PNG dim - PNG| = {diff} 8-bit steps");
}

/// A closed box room (walls 2 across, an emissive panel under the ceiling) as a glTF whose root node
/// scales it by `k`, with a camera inside as the node's child.
fn scaled_room(dir: &std::path::Path, name: &str, k: f64) -> std::path::PathBuf {
    let quad = |a: [f32; 3], b: [f32; 3], c: [f32; 3], d: [f32; 3]| [a, b, c, a, c, d];
    // Walls facing inwards, then the light panel under the ceiling, facing down.
    let mut pos: Vec<[f32; 3]> = [
        quad(
            [-1., -1., -1.],
            [1., -1., -1.],
            [1., 1., -1.],
            [-1., 1., -1.],
        ),
        quad([-1., -1., 1.], [-1., 1., 1.], [1., 1., 1.], [1., -1., 1.]),
        quad(
            [-1., -1., -1.],
            [-1., 1., -1.],
            [-1., 1., 1.],
            [-1., -1., 1.],
        ),
        quad([1., -1., -1.], [1., -1., 1.], [1., 1., 1.], [1., 1., -1.]),
        quad(
            [-1., -1., -1.],
            [-1., -1., 1.],
            [1., -1., 1.],
            [1., -1., -1.],
        ),
        quad([-1., 1., -1.], [1., 1., -1.], [1., 1., 1.], [-1., 1., 1.]),
    ]
    .concat();
    let walls = pos.len();
    pos.extend(quad(
        [-0.3, 0.95, -0.3],
        [0.3, 0.95, -0.3],
        [0.3, 0.95, 0.3],
        [-0.3, 0.95, 0.3],
    ));
    let bytes: Vec<u8> = pos.iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
    std::fs::write(dir.join(format!("{name}.bin")), &bytes).unwrap();
    let acc = |first: usize, count: usize| {
        serde_json::json!({"bufferView": 0, "byteOffset": first * 12, "componentType": 5126,
            "count": count, "type": "VEC3", "min": [-1, -1, -1], "max": [1, 1, 1]})
    };
    let j = serde_json::json!({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"scale": [k, k, k], "mesh": 0, "children": [1]},
                  {"camera": 0, "translation": [0.2, 0.1, 0.9]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 1.2, "znear": 0.01}}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.6, 0.5, 1]}},
                      {"emissiveFactor": [1, 1, 1], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 10}}}],
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0},
                                   {"attributes": {"POSITION": 1}, "material": 1}]}],
        "accessors": [acc(0, walls), acc(walls, pos.len() - walls)],
        "bufferViews": [{"buffer": 0, "byteLength": bytes.len()}],
        "buffers": [{"uri": format!("{name}.bin"), "byteLength": bytes.len()}]
    });
    let p = dir.join(format!("{name}.gltf"));
    std::fs::write(&p, serde_json::to_vec(&j).unwrap()).unwrap();
    p
}

/// A glTF room scaled by 1e-40 … 1e38 renders the image of the unscaled room (EXR, 48x36: mean
/// luminance within 0.5%, rel_mse ≤ 1e-3); it used to come out black with exit 0 at 1e±12. Scales
/// whose vertices do not fit f32 are refused with exit 2 and one line, never rendered black.
#[test]
fn a_gltf_room_at_any_finite_scale_renders_the_same_image() {
    let d = common::scratch("cli-scale");
    let render = |k: f64| -> (i32, String, Vec<[f32; 3]>) {
        let p = scaled_room(&d, &format!("room{k:e}"), k);
        let exr = d.join(format!("room{k:e}.exr"));
        let (code, _, err) = run(&common::cmd(
            "render --width 48 --height 36 --vpls 256 --vpl-clusters 32 --sp-clusters 48 \
             --direct-samples 4",
            &[common::arg(&p), "-o", common::arg(&exr)],
        ));
        let px = if code == 0 {
            fuzzy_vpl::export::read_exr(&exr).unwrap().2
        } else {
            Vec::new()
        };
        (code, err, px)
    };
    let (code, err, one) = render(1.0);
    assert_eq!(code, 0, "{err}");
    let l1 = fuzzy_vpl::metrics::mean_luminance(&one);
    assert!(l1 > 0.05, "the unscaled room is dark: {l1}");
    for k in [1e-40, 1e-15, 1e-12, 1e12, 1e15, 1e38] {
        let (code, err, px) = render(k);
        assert_eq!(code, 0, "scale {k}: {err}");
        assert!(common::all_finite(&px));
        let lk = fuzzy_vpl::metrics::mean_luminance(&px);
        let rel = fuzzy_vpl::metrics::rel_mse(&px, &one);
        println!("room at {k:e}: mean luminance {lk:.5} (1: {l1:.5}), rel_mse {rel:.2e}");
        assert!((lk / l1 - 1.0).abs() < 5e-3, "scale {k}: {lk} vs {l1}");
        assert!(rel <= 1e-3, "scale {k}: rel_mse {rel}");
    }
    // info names the unit frame and prints the bounds in the scene's own units.
    let p = scaled_room(&d, "info", 1e-15);
    let (code, out, err) = run(&["info", p.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("scaled by 2^48"), "{out}");
    assert!(
        out.contains("(-1.000e-15, -1.000e-15, -1.000e-15)"),
        "{out}"
    );
    // 1e-46 rounds every vertex to 0 (f32's smallest subnormal is 1.4e-45); 1e39 overflows f32.
    for k in [1e-46, 1e39] {
        let (code, err, _) = render(k);
        println!("room at {k:e}: exit {code}: {err}");
        assert_eq!(code, 2, "{err}");
        assert_eq!(common::error_lines(&err).len(), 1, "{err}");
    }
}

/// `render --trace` writes every timed dispatch as a Chrome trace event under its pass's name, with
/// the stats' pass times as the sums of those events (`wgpu-profiler`'s queries).
#[test]
fn render_writes_a_chrome_trace_of_its_passes() {
    let d = common::scratch("cli-trace");
    let (trace, stats) = (d.join("t.json"), d.join("s.json"));
    let (code, _, err) = common::run_cli(&common::cmd(
        "render --width 32 --height 24 --vpls 256 --vpl-clusters 32 --sp-clusters 48",
        &[
            "-o",
            d.join("o.exr").to_str().unwrap(),
            "--trace",
            common::arg(&trace),
            "--stats",
            common::arg(&stats),
        ],
    ));
    assert_eq!(code, 0, "{err}");
    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&trace).unwrap()).expect("the trace is JSON");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let events = t["traceEvents"].as_array().unwrap();
    for pass in s["passes"].as_array().unwrap() {
        let name = pass.as_str().unwrap();
        let dur_us: f64 = events
            .iter()
            .filter(|e| e["name"] == name)
            .map(|e| e["dur"].as_f64().unwrap())
            .sum();
        assert!(dur_us > 0.0, "{name}: no trace event");
        let ms = s["timings_ms"][name].as_f64().unwrap();
        // Event durations are µs; the stats' the same queries summed in ms (measured: equal to
        // rounding).
        assert!(
            (dur_us / 1e3 - ms).abs() <= 1e-6 * ms.max(1.0),
            "{name}: {dur_us} µs vs {ms} ms"
        );
    }
    std::fs::remove_dir_all(&d).unwrap();
}

/// `render --layer final|direct|indirect` writes that light, and the stats' `mean_luminance_indirect`
/// is the indirect layer's: final = direct + indirect pixel by pixel, the indirect light is part
/// of the image, not all of it.
#[test]
fn render_layers_add_up_and_the_stats_name_the_indirect_light() {
    let d = common::scratch("cli-layers");
    let mut images = Vec::new();
    for layer in ["final", "direct", "indirect"] {
        let exr = d.join(format!("{layer}.exr"));
        let stats = d.join(format!("{layer}.json"));
        let (code, _, err) = common::run_cli(&common::cmd(
            "render builtin:cornell --width 48 --height 36 --vpls 512 --vpl-clusters 64 \
             --sp-clusters 16 --warmup-ms 0",
            &[
                "--layer",
                layer,
                "-o",
                common::arg(&exr),
                "--stats",
                common::arg(&stats),
            ],
        ));
        assert_eq!(code, 0, "{err}");
        let (_, _, px) = fuzzy_vpl::export::read_exr(&exr).unwrap();
        assert!(common::all_finite(&px));
        let j = common::read_json(&stats);
        images.push((px, j));
    }
    let (fin, direct, indirect) = (&images[0].0, &images[1].0, &images[2].0);
    for ((f, d), i) in fin.iter().zip(direct).zip(indirect) {
        for c in 0..3 {
            assert!(
                (f[c] - (d[c] + i[c])).abs() <= 1e-6 * (1.0 + f[c]),
                "{f:?} {d:?} {i:?}"
            );
        }
    }
    let lum = fuzzy_vpl::metrics::mean_luminance;
    let stated = images[0].1["mean_luminance_indirect"].as_f64().unwrap();
    assert!(
        (stated - lum(indirect)).abs() <= 1e-6 * lum(indirect),
        "{stated}"
    );
    assert!(lum(indirect) > 0.05 * lum(fin) && lum(indirect) < 0.9 * lum(fin));
    // The same frame whatever the layer: the stats agree.
    assert_eq!(images[0].1["mean_luminance"], images[2].1["mean_luminance"]);
    // A bad layer: one line, exit 2.
    let (code, _, err) = common::run_cli(&["render", "--layer", "albedo", "-o", "x.png"]);
    assert_eq!(code, 2, "{err}");
}

/// `--temporal-alpha` in (0, 1]: the bounds by hand, and a value inside read as itself
/// (cargo-mutants: `parse_temporal_alpha` as `Ok(1.0)`, its `&&` as `||` and `>` as `>=` survived).
#[test]
fn temporal_alpha_is_in_zero_one() {
    use fuzzy_vpl::settings::parse_temporal_alpha;
    assert_eq!(parse_temporal_alpha("0.25").unwrap(), 0.25);
    assert_eq!(parse_temporal_alpha("1").unwrap(), 1.0);
    for bad in ["0", "-0.5", "1.0001", "2", "nan"] {
        assert!(parse_temporal_alpha(bad).is_err(), "{bad}");
    }
}

/// A weighting's name (what the stats JSON and the CSV write) is its `--weighting` value and its
/// serde name (cargo-mutants: `Weighting::name` as "" and as "xyzzy" survived the quick binaries).
#[test]
fn weighting_names_are_the_cli_and_serde_names() {
    use clap::ValueEnum;
    use fuzzy_vpl::settings::Weighting;
    for w in Weighting::ALL {
        assert_eq!(w.name(), w.to_possible_value().unwrap().get_name());
        let json = serde_json::to_string(&w).unwrap();
        assert_eq!(json, format!("\"{}\"", w.name()));
    }
    assert_eq!(Weighting::InverseDistance.name(), "inverse-distance");
}

/// `--target-ms` through the command line with a budget that binds on any adapter (1 µs, far
/// below any frame): the controller cuts K and the direct light from the first frame on, every
/// frame over the budget, and the settings it ends on are the ones rendered.
#[test]
fn target_ms_with_a_binding_budget_cuts_k_and_the_direct_light() {
    let (_, j, out) = render_target_ms("cli-target-binding", "0.001");
    let steps = j["target"]["steps"].as_array().unwrap();
    println!("steps {steps:?}");
    assert!(steps.len() >= 2, "{j}");
    for st in steps {
        assert!(st["frame_ms"].as_f64().unwrap() > 0.001, "{st}");
    }
    let first = &steps[0];
    let last = steps.last().unwrap();
    let k = |s: &serde_json::Value, f: &str| s[f].as_u64().unwrap();
    // Below the start's K's and the user's 16 samples: the budget bound.
    assert!(
        k(last, "vpl_clusters") < k(first, "vpl_clusters"),
        "{steps:?}"
    );
    assert!(k(last, "direct_samples") < 16, "{steps:?}");
    for f in ["sp_clusters", "vpl_clusters", "direct_samples"] {
        assert_eq!(last[f], j["settings"][f], "{f}: {j}");
    }
    let (_, _, px) = fuzzy_vpl::export::read_exr(&out).unwrap();
    assert!(common::all_finite(&px));
}

/// `render` of `builtin:cornell` at 32 × 24, 256 VPLs, K_SP 32, K_VPL 64.
const FRAME_32X24: &str =
    "render builtin:cornell --width 32 --height 24 --vpls 256 --sp-clusters 32 --vpl-clusters 64";

/// `render --method wang` and `--method lightcluster`: the method's own passes run (not the
/// reference nor colom's), the stats name the method, and its indirect light is within 20% of the
/// reference's on the same frame (measured at 32×24: wang 1.068, lightcluster 1.000).
#[test]
fn render_runs_wang_and_lightcluster() {
    let d = common::scratch("cli-methods");
    let render = |name: &str, extra: &[&str]| -> serde_json::Value {
        let (out, stats) = (
            d.join(format!("{name}.exr")),
            d.join(format!("{name}.json")),
        );
        let mut args = common::cmd(FRAME_32X24, extra);
        args.extend(["-o", common::arg(&out), "--stats", common::arg(&stats)]);
        let (code, _, err) = run(&args);
        assert_eq!(code, 0, "{args:?}: {err}");
        let (_, _, px) = fuzzy_vpl::export::read_exr(&out).unwrap();
        assert!(common::all_finite(&px), "{name}");
        common::read_json(&stats)
    };
    let reference = render("reference", &["--reference"]);
    let ind_ref = reference["mean_luminance_indirect"].as_f64().unwrap();
    for (method, own) in [
        ("wang", &["wang_cluster", "wang_gather", "wang_interp"][..]),
        (
            "lightcluster",
            &["lightcluster_cluster", "lightcluster_shade"][..],
        ),
    ] {
        let j = render(method, &["--method", method]);
        assert_eq!(j["settings"]["method"].as_str(), Some(method), "{j}");
        let passes: Vec<&str> = j["passes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| p.as_str().unwrap())
            .collect();
        for p in own {
            assert!(passes.contains(p), "{method}: {passes:?}");
        }
        for p in ["reference", "sp_cluster", "shade"] {
            assert!(!passes.contains(&p), "{method}: {passes:?}");
        }
        let ratio = j["mean_luminance_indirect"].as_f64().unwrap() / ind_ref;
        println!("{method}: passes {passes:?}, indirect / reference {ratio:.3}");
        assert!(
            (ratio - 1.0).abs() <= 0.2,
            "{method}: indirect ratio {ratio}"
        );
    }
}

/// `raybench` from the command line on a small frame: a primary and a shadow row for the scene,
/// as many primary rays as pixels, a shadow ray per primary hit, every throughput finite and
/// positive and the ratio GPU ÷ CPU BVH2; the same rows in `--json`. A scene that does not load
/// exits 2 with one line.
#[test]
fn raybench_reports_both_ray_kinds() {
    let d = common::scratch("cli-raybench");
    let json = d.join("rays.json");
    let (code, out, err) = run(&common::cmd(
        "raybench builtin:cornell --width 32 --height 24",
        &["--json", common::arg(&json)],
    ));
    assert_eq!(code, 0, "{err}");
    assert!(out.starts_with("adapter: "), "{out}");
    let rows = common::read_json(&json);
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), 2, "{rows:?}");
    let s = fuzzy_vpl::scene::load("builtin:cornell").unwrap();
    for (row, kind) in rows.iter().zip(["primary", "shadow"]) {
        assert_eq!(row["kind"].as_str(), Some(kind), "{row}");
        assert_eq!(row["scene"].as_str(), Some(s.name.as_str()), "{row}");
        assert_eq!(row["triangles"].as_u64(), Some(s.triangles.len() as u64));
        let f = |k: &str| row[k].as_f64().unwrap();
        for k in [
            "gpu_mrays_s",
            "cpu_bvh2_mrays_s",
            "cpu_cwbvh_mrays_s",
            "ratio",
        ] {
            assert!(f(k).is_finite() && f(k) > 0.0, "{k}: {row}");
        }
        assert!((f("ratio") - f("gpu_mrays_s") / f("cpu_bvh2_mrays_s")).abs() <= 1e-9 * f("ratio"));
        assert!(out.contains(kind), "{out}");
    }
    // The camera inside the closed box: every primary ray hits, each gives a shadow ray.
    assert_eq!(rows[0]["rays"].as_u64(), Some(32 * 24));
    let shadow = rows[1]["rays"].as_u64().unwrap();
    assert!(shadow > 0 && shadow <= 32 * 24, "{shadow}");
    common::assert_refused(&["raybench", "nope.glb"], "nope.glb");
}

/// `FVPL_NO_BOUNDS` and `FVPL_NO_LOOPBOUND` (docs/testing.md) turn off wgpu's bounds checks and
/// loop bounding in the shaders (`gpu::shader::module`) to measure what they cost; a frame is the
/// same with them, bit for bit (no access out of bounds, every loop ends).
#[test]
fn frames_without_bounds_checks_or_loop_bounding_are_the_same() {
    let d = common::scratch("cli-no-bounds");
    let render = |name: &str, env: &[&str]| {
        let out = d.join(format!("{name}.exr"));
        let mut c = bin();
        c.args(common::cmd(FRAME_32X24, &["-o", common::arg(&out)]));
        for e in env {
            c.env(e, "1");
        }
        let o = c.output().unwrap();
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        let (_, _, px) = fuzzy_vpl::export::read_exr(&out).unwrap();
        assert!(common::all_finite(&px), "{name}");
        px
    };
    let checked = render("checked", &[]);
    assert!(checked.iter().flatten().any(|&c| c > 0.0));
    assert_eq!(render("no-bounds", &["FVPL_NO_BOUNDS"]), checked);
    assert_eq!(render("no-loopbound", &["FVPL_NO_LOOPBOUND"]), checked);
}
