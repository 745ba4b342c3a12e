//! `fuzzy-vpl bench`: the quick sweep end to end (GPU, lavapipe in CI) and its bad input (no GPU).

mod common;

use clap::Parser;
use common::run_cli as run;
use fuzzy_vpl::bench::csv;
use fuzzy_vpl::bench::sweep::{Sweep, label, mode_name};
use fuzzy_vpl::method::Method;

/// The sweep of `bench ARGS` (`quick` defaults or the full ones).
fn parse(args: &[&str], quick: bool) -> Result<Sweep, String> {
    #[derive(Parser)]
    struct Wrap {
        #[command(flatten)]
        s: Sweep,
    }
    let w = Wrap::try_parse_from(std::iter::once("bench").chain(args.iter().copied()))
        .map_err(|e| e.to_string())?;
    w.s.resolve(quick)
}

#[test]
fn quick_bench_writes_csv_plots_and_summary() {
    let d = common::scratch("bench-quick");
    let (code, out, err) = run(&[
        "bench",
        "builtin:cornell",
        "--quick",
        "--out-dir",
        d.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("speedup"), "{out}");
    let text = std::fs::read_to_string(d.join("results.csv")).unwrap();
    assert!(text.lines().next().unwrap().split(',').any(|h| h == "mse"));
    let rows = csv::from_csv(&text).unwrap();
    assert!(rows.len() >= 4, "{} rows", rows.len());
    let modes: std::collections::HashSet<&str> = rows.iter().map(|r| r.mode.as_str()).collect();
    for m in ["hard", "uniform", "weighted", "vpl-only", "sp-only"] {
        assert!(modes.contains(m), "no {m} row");
    }
    for r in &rows {
        assert_eq!(
            (r.frame.width, r.frame.height, r.frame.vpls),
            (96, 72, 1024)
        );
        assert!(r.mse.is_finite() && r.mse >= 0.0, "{r:?}");
        assert!(r.rel_mse.is_finite() && r.rel_mse >= 0.0, "{r:?}");
        assert!(r.frame_ms() > 0.0 && r.reference_ms > 0.0, "{r:?}");
        assert!((r.speedup - r.reference_ms / r.frame_ms()).abs() < 1e-6 * r.speedup.max(1.0));
        assert!(r.shadow_rays > 0);
        if r.cluster.sp_clusters > 0 {
            assert!(
                r.sp_clusters_used > 0 && r.stage("sp_cluster") > 0.0,
                "{r:?}"
            );
        }
        if r.cluster.vpl_clusters > 0 {
            assert_eq!(r.vpl_clusters_used, r.cluster.vpl_clusters, "{r:?}");
        }
    }
    // The speed-ups themselves are measurements (a clock), printed in the summary, not asserted.
    assert!(rows.iter().all(|r| r.speedup > 0.0), "{rows:?}");
    let (w, h, px) = fuzzy_vpl::export::read_exr(&d.join("reference.exr")).unwrap();
    assert_eq!((w, h), (96, 72));
    assert!(common::all_finite(&px));
    for p in ["stages.png", "grid.png", "pareto.png"] {
        let img = image::open(d.join(p)).unwrap();
        assert!(img.width() > 100, "{p}");
    }
    let md = std::fs::read_to_string(d.join("summary.md")).unwrap();
    assert!(md.contains("![") && md.contains("pareto.png"));
    assert!(md.contains("mean of the 3 best of 3"));
    assert_eq!(
        std::fs::read_dir(d.join("images")).unwrap().count(),
        3 * rows.len()
    );
    // FLIP in every row; the border measure where SP clusters ran.
    for r in &rows {
        let f = r.flip.unwrap();
        assert!(f.is_finite() && (0.0..=1.0).contains(&f), "{r:?}");
        assert_eq!(r.border.is_some(), r.sp_clusters_used > 0, "{r:?}");
        assert!(r.border.is_none_or(|b| b.is_finite() && b >= 0.0), "{r:?}");
    }
    assert!(md.contains("FLIP"));
    // `bench-table` from the command line on this run: the commit and date above the table, its
    // header, and one row per CSV row (run named by its folder), each with its configuration's
    // label and MSE; a folder without a CSV exits 2 with one line naming it.
    let run_name = d.file_name().unwrap().to_str().unwrap().to_string();
    let (code, table, err) = run(&common::cmd(
        "bench-table --commit abc1234 --date 2026-11-28",
        &[common::arg(&d)],
    ));
    assert_eq!(code, 0, "{err}");
    assert!(table.contains("commit `abc1234`, 2026-11-28"), "{table}");
    assert!(table.contains("| run | scene | size |"), "{table}");
    let lines: Vec<&str> = table
        .lines()
        .filter(|l| l.starts_with(&format!("| {run_name} |")))
        .collect();
    assert_eq!(lines.len(), rows.len(), "{table}");
    for (l, r) in lines.iter().zip(&rows) {
        assert!(l.contains(&r.label), "{l} / {}", r.label);
        assert!(l.contains(&format!("{:.2e}", r.mse)), "{l} / {:e}", r.mse);
    }
    let empty = common::scratch("bench-table-empty");
    common::assert_refused(
        &["bench-table", empty.to_str().unwrap()],
        "holds neither results.csv nor path.csv",
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// The rows and images say what ran: a K_sp at or above the pixel count runs without SP clustering
/// and is labelled so, γ is reported as Alg. 1 used it, and a rerun leaves no image of an earlier
/// run's configurations (other files in images/ stay).
#[test]
fn bench_rows_say_what_ran_and_reruns_leave_no_stale_images() {
    let d = common::scratch("bench-ran");
    std::fs::create_dir_all(d.join("images")).unwrap();
    std::fs::write(d.join("images/07_weighted_99x99_F6_g4.png"), b"old").unwrap();
    std::fs::write(d.join("images/notes.txt"), b"mine").unwrap();
    // 16 x 12 = 192 pixels: K_sp 8 with γ 64 samples with γ 192 / 8 = 24; K_sp 400 is not below 192.
    let (code, _, err) = run(&common::cmd(
        "bench builtin:cornell --width 16 --height 12 --vpls 64 --modes hard --sp-clusters 8,400 \
         --vpl-clusters 16 --gamma 64 --repeat 1",
        &["--out-dir", common::arg(&d)],
    ));
    assert_eq!(code, 0, "{err}");
    let rows = csv::from_csv(&std::fs::read_to_string(d.join("results.csv")).unwrap()).unwrap();
    assert_eq!(rows.len(), 2, "{rows:?}");
    let (clustered, off) = (&rows[0], &rows[1]);
    assert_eq!(
        (clustered.cluster.sp_clusters, clustered.cluster.gamma),
        (8, fuzzy_vpl::settings::Gamma::Fixed(64))
    );
    assert_eq!(clustered.gamma_used, Some(24), "{clustered:?}");
    assert_eq!(clustered.label, "hard 8/16 g24");
    assert_eq!(off.cluster.sp_clusters, 400);
    assert_eq!((off.sp_clusters_used, off.gamma_used), (0, None), "{off:?}");
    assert_eq!(off.stage("sp_cluster"), 0.0);
    assert_eq!(off.label, "hard -/16 (K_sp off)");
    let mut names: Vec<String> = std::fs::read_dir(d.join("images"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "01_hard_8x16_g24.png",
            "01_hard_8x16_g24_err.png",
            "01_hard_8x16_g24_flip.png",
            "02_hard_-x16__K_sp_off_.png",
            "02_hard_-x16__K_sp_off__err.png",
            "02_hard_-x16__K_sp_off__flip.png",
            "notes.txt",
        ]
    );
    let md = std::fs::read_to_string(d.join("summary.md")).unwrap();
    assert!(md.contains("| 64 → 24 |"), "{md}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn bad_sweep_options_exit_2_with_one_line() {
    let d = common::scratch("bench-bad");
    let dir = d.to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["--modes", "hard,fuzzy"], "fuzzy"),
        (&["--sp-clusters", "192,abc"], "--sp-clusters"),
        (&["--vpl-clusters", "128,,256"], "empty"),
        (&["--fuzziness", "6,17"], "--fuzziness 17"),
        (&["--gamma", "0"], "--gamma"),
        (&["--repeat", "0"], "--repeat"),
        (&["--camera", "7"], "camera"),
        (&["--width", "0"], "--width"),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["bench", "builtin:cornell", "--quick", "--out-dir", dir];
        args.extend_from_slice(extra);
        let (code, _, err) = run(&args);
        assert_eq!(code, 2, "{extra:?}: {err}");
        let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("error")).collect();
        assert_eq!(lines.len(), 1, "{extra:?}: {err}");
        assert!(lines[0].contains(needle), "{extra:?}: {err}");
    }
    let (code, _, err) = run(&["bench", "no/such/scene.glb", "--out-dir", dir]);
    assert_eq!(code, 2, "{err}");
    assert!(!d.join("results.csv").exists());
    let _ = std::fs::remove_dir_all(&d);
}

/// `bench --camera-path orbit:N:DEG --temporal off,on`: one row per frame and setting, frame 0
/// without instability, the warm start visible in the rows, and the plot.
/// A path CSV's header and rows.
fn path_csv(text: &str) -> (Vec<&str>, Vec<Vec<String>>) {
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').collect();
    (header, lines.map(csv::split_line).collect())
}

/// `row`'s value in column `name` of `header`.
fn cell(header: &[&str], row: &[String], name: &str) -> String {
    row[header.iter().position(|h| *h == name).unwrap()].clone()
}

#[test]
fn camera_path_writes_path_csv_and_plot() {
    let d = common::scratch("bench-path");
    let (code, out, err) = run(&common::cmd(
        "bench builtin:conference --camera-path orbit:3:2 --temporal off,on --modes weighted \
         --sp-clusters 48 --vpl-clusters 64 --width 64 --height 48 --vpls 512 --direct-samples 1",
        &["--out-dir", common::arg(&d)],
    ));
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("instability"), "{out}");
    let text = std::fs::read_to_string(d.join("path.csv")).unwrap();
    let (header, rows) = path_csv(&text);
    // Every column the contract names (docs/design.md, "path.csv"), then the generated ones.
    let contract = fuzzy_vpl::bench::path::COLUMNS.iter();
    for c in contract.chain(&["instability_world", "seed", "direct_samples"]) {
        assert!(header.contains(c), "no column {c} in {header:?}");
    }
    let col = |row: &[String], name: &str| cell(&header, row, name);
    assert_eq!(rows.len(), 6, "{text}");
    for (i, r) in rows.iter().enumerate() {
        let (on, frame) = (i >= 3, i % 3);
        assert_eq!(col(r, "temporal"), if on { "on" } else { "off" });
        assert_eq!(col(r, "frame"), frame.to_string());
        let inst = col(r, "instability");
        if frame == 0 {
            assert!(inst.is_empty(), "{r:?}");
        } else {
            let v: f64 = inst.parse().unwrap();
            assert!(v.is_finite() && v >= 0.0, "{r:?}");
        }
        let mse: f64 = col(r, "mse").parse().unwrap();
        assert!(mse.is_finite() && mse > 0.0, "{r:?}");
        assert!(
            col(r, "sp_cluster_ms").parse::<f64>().unwrap() > 0.0,
            "{r:?}"
        );
        // Warm starts keep clusters from frame 1 on, and only with temporal reuse.
        assert_eq!(
            col(r, "sp_warm_kept").is_empty(),
            !on || frame == 0,
            "{r:?}"
        );
        // The accumulation's α (the default) with temporal reuse only; the scale of the world
        // measure (an image without indirect light) from frame 1 on.
        assert_eq!(col(r, "temporal_alpha"), if on { "0.7" } else { "" });
        assert_eq!(col(r, "label").ends_with(" α0.7"), on, "{r:?}");
        // Every setting has a column: the clustering's and the frame's as the frame ran.
        let settings = (
            col(r, "sp_clusters"),
            col(r, "direct_samples"),
            col(r, "seed"),
        );
        assert_eq!(settings, ("48".into(), "1".into(), "1".into()), "{r:?}");
        let floor = col(r, "instability_world_direct_only");
        assert_eq!(floor.is_empty(), frame == 0, "{r:?}");
    }
    let img = image::open(d.join("path.png")).unwrap().into_rgb8();
    assert_eq!(img.dimensions(), (960, 540));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn camera_path_refuses_a_bad_path() {
    let d = common::scratch("bench-path-bad");
    for bad in ["orbit:0:3", "circle:3:3", "orbit:3"] {
        let (code, _, err) = run(&common::cmd(
            "bench builtin:cornell",
            &["--out-dir", common::arg(&d), "--camera-path", bad],
        ));
        assert_eq!(code, 2, "{bad}: {err}");
        assert!(err.contains("orbit:N:DEG"), "{bad}: {err}");
    }
    let (code, _, err) = run(&common::cmd(
        "bench builtin:cornell --temporal on",
        &["--out-dir", common::arg(&d)],
    ));
    assert_eq!(code, 2, "{err}");
}

/// The contract's columns (docs/design.md, "Bench outputs"), written out rather than taken from the code.
#[test]
fn header_has_the_contract_columns_in_order() {
    let h = csv::header();
    // The columns, white-space separated; then every setting without a column among them
    // (`ClusterSettings`' fields, then `FrameSettings`', in declaration order: a field added to
    // them is a column); then every method's knobs (docs/design.md), then the report columns.
    let want = "scene camera width height vpls mode vpl_clusters sp_clusters fuzziness gamma \
         normal_threshold iterations vpl_trace_ms vpl_cluster_ms primary_ms sp_cluster_ms \
         visibility_ms shade_ms gather_ms direct_ms frame_ms reference_ms speedup mse rel_mse \
         sp_clusters_used vpl_clusters_used shadow_rays repeat label weight_exponent gamma_used \
         plane_gate_deg flip border interior border_ratio flip_border target_ms front_mse \
         method indirect_ms adapter driver";
    let knobs_want = "wang_alpha d_init lightcluster_visibility voxel_res cluster_step \
         cluster_iterations cluster_angle face_rays near_voxels filter_radius filter_passes \
         cluster_gather escape_rays";
    let want: Vec<String> = want.split_whitespace().map(String::from).collect();
    assert_eq!(h[..want.len()], want);
    let at = want.len();
    let settings: Vec<&str> = csv::settings_columns()
        .filter(|c| !want.iter().any(|w| w == c))
        .collect();
    assert!(
        settings.contains(&"temporal") && settings.contains(&"seed"),
        "{settings:?}"
    );
    assert_eq!(h[at..at + settings.len()], settings);
    // A method added later appends its knobs: the knobs above stay a prefix of the knob columns,
    // in the registry's order, before the report columns (read by name).
    let knobs_want: Vec<String> = knobs_want.split_whitespace().map(String::from).collect();
    assert_eq!(h[at + settings.len()..][..knobs_want.len()], knobs_want);
    let at = at + settings.len();
    let knobs = fuzzy_vpl::method::MethodSettings::columns();
    assert_eq!(h[at..at + knobs.len()], knobs);
    // Then every method's report columns (colom's counts), the last ones.
    assert_eq!(h[at + knobs.len()..], fuzzy_vpl::method::report_columns());
    assert_eq!(
        fuzzy_vpl::method::report_columns(),
        ["sp_iterations", "sp_warm_kept", "visibility_rows_reused"]
    );
    let csv = csv::to_csv(&[]);
    assert_eq!(csv.lines().count(), 1);
    assert_eq!(csv::split_line(csv.trim_end()), h);
}

/// `--target-ms`: after the sweep, one row per budget and mode, its K's chosen for the budget, with
/// the sweep's best MSE at no more time beside it.
#[test]
fn target_ms_rows_follow_the_sweep() {
    let d = common::scratch("bench-target");
    let (code, _, err) = run(&common::cmd(
        "bench builtin:cornell --width 24 --height 16 --vpls 128 --modes hard,weighted \
         --pairs 8/16,32/48 --target-ms 100000 --repeat 1",
        &["--out-dir", common::arg(&d)],
    ));
    assert_eq!(code, 0, "{err}");
    let rows = csv::from_csv(&std::fs::read_to_string(d.join("results.csv")).unwrap()).unwrap();
    assert_eq!(rows.len(), 4 + 2, "{rows:?}");
    for r in &rows[..4] {
        assert_eq!((r.cluster.target_ms, r.front_mse), (None, None), "{r:?}");
    }
    for r in &rows[4..] {
        assert_eq!(r.cluster.target_ms, Some(100000.0), "{r:?}");
        assert!(r.label.starts_with("target 100000 ms "), "{r:?}");
        // A budget above any frame: half the VPLs as VPL clusters.
        assert_eq!(r.cluster.vpl_clusters, 128 / 2, "{r:?}");
        assert!(r.mse.is_finite() && r.flip.is_some(), "{r:?}");
        // The front at its time, when a fixed setting was as fast: never above every fixed row.
        if let Some(f) = r.front_mse {
            assert!(rows[..4].iter().any(|x| x.mse == f), "{r:?}");
        }
    }
    assert!(err.contains("best fixed setting") || rows[4..].iter().all(|r| r.front_mse.is_none()));
    let _ = std::fs::remove_dir_all(&d);
}

/// `scripts/gpu-bench --quick` end to end on lavapipe (CI has no GPU): every run of the script
/// finishes and the table has a row for each configuration, named adapter and driver, the software
/// warning, and finite figures; after it, the viewer's table (offscreen, shared display path) with
/// its one row.
#[test]
fn gpu_bench_script_runs_and_prints_one_table() {
    let d = common::scratch("gpu-bench-quick");
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/scripts/gpu-bench");
    let out = std::process::Command::new(script)
        .args(["--quick", "--out", d.to_str().unwrap()])
        .args(["--bin", env!("CARGO_BIN_EXE_fuzzy-vpl")])
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(out.status.success(), "{stderr}");
    assert_eq!(std::fs::read_to_string(d.join("table.md")).unwrap(), stdout);
    let (stdout, viewer) = stdout
        .split_once("| viewer (offscreen, shared, moving) |")
        .unwrap_or_else(|| panic!("no viewer table: {stdout}"));
    let viewer_rows: Vec<&str> = viewer
        .lines()
        .skip(2)
        .filter(|l| l.starts_with("| "))
        .collect();
    assert_eq!(viewer_rows.len(), 1, "{viewer}");
    assert!(
        viewer_rows[0].starts_with("| builtin:conference 160x120 |"),
        "{viewer}"
    );
    assert!(
        !viewer.contains("NaN") && !viewer.contains("inf"),
        "{viewer}"
    );
    let rows: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| ---"))
        .collect();
    // Header; paper 6 (3 settings x hard, weighted); patterns3 1; orbit 2 (off, on); methods 7
    // (colom and wang at 2 settings each, lightcluster, cvrtgi, restir); dense 2 + 2.
    assert_eq!(rows.len(), 1 + 6 + 1 + 2 + 7 + 4, "{stdout}");
    for run in [
        "paper",
        "patterns3",
        "orbit",
        "methods",
        "dense-3m",
        "dense-8m",
    ] {
        assert!(
            rows.iter().any(|r| r.starts_with(&format!("| {run} |"))),
            "no {run} row"
        );
    }
    assert!(
        stdout.contains("llvmpipe") && stdout.contains("driver "),
        "{stdout}"
    );
    assert!(stdout.contains("A software driver"), "{stdout}");
    assert!(stdout.contains("builtin:dense-8m"), "{stdout}");
    assert!(
        !stdout.contains("NaN") && !stdout.contains("inf"),
        "{stdout}"
    );
    // The pattern table changes no image: its row's MSE is the weighted intermediate row's.
    let mse = |run: &str| {
        let r = rows
            .iter()
            .find(|r| r.starts_with(&format!("| {run} |")) && r.contains("weighted 48/192"))
            .unwrap();
        r.split('|').nth(16).unwrap().trim().to_string()
    };
    assert_eq!(mse("paper"), mse("patterns3"));
    // Bad arguments: one line, exit 2.
    let bad = std::process::Command::new(script)
        .arg("--nope")
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
}

/// `bench --methods`: each method takes its own knob lists (and the K pairs where it clusters the
/// shading points), labelled with its name; bad lists name the option.
#[test]
fn methods_expand_with_their_own_knobs() {
    let s = parse(
        &[
            "--methods",
            "colom,wang",
            "--modes",
            "weighted",
            "--pairs",
            "48/128",
            "--wang-alpha",
            "0.1,0.5",
        ],
        true,
    )
    .unwrap();
    let labels: Vec<String> = s.configs().iter().map(label).collect();
    assert_eq!(
        labels,
        [
            "weighted 48/128 F6 gauto",
            "wang 48/128 a0.1",
            "wang 48/128 a0.5"
        ]
    );
    let c = s.configs();
    assert_eq!(mode_name(&c[0]), "weighted");
    assert_eq!(mode_name(&c[1]), "wang");
    assert_eq!(c[2].method.method, Method::Wang);
    assert_eq!(
        parse(&[], true).unwrap().method.methods,
        vec![Method::Colom]
    );
    let s = parse(&["--methods", "lightcluster", "--d-init", "0.05,0.2"], true).unwrap();
    let labels: Vec<String> = s.configs().iter().map(label).collect();
    assert_eq!(labels, ["lightcluster d0.05", "lightcluster d0.2"]);
    assert_eq!(mode_name(&s.configs()[0]), "lightcluster");
    assert!(parse(&["--d-init", "0"], true).is_err());
    // restir sweeps M, k and n by default (8 and 32, 3 and 5, 1 and 2), its other knobs at theirs.
    let s = parse(&["--methods", "restir"], true).unwrap();
    let labels: Vec<String> = s.configs().iter().map(label).collect();
    assert_eq!(labels.len(), 8, "{labels:?}");
    assert_eq!(
        (labels[0].as_str(), labels[7].as_str()),
        ("restir M8 k3 n1", "restir M32 k5 n2")
    );
    let s = parse(
        &["--methods", "restir", "--restir-combine", "unbiased"],
        true,
    )
    .unwrap();
    assert!(label(&s.configs()[0]).ends_with(" unbiased"));
    assert!(parse(&["--restir-candidates", "0"], true).is_err());
    let e = parse(&["--methods", "colom,foo"], true).unwrap_err();
    assert!(e.contains("--methods") && e.contains("foo"), "{e}");
    let e = parse(&["--wang-alpha", "0"], true).unwrap_err();
    assert!(e.contains("--wang-alpha"), "{e}");
    let e = parse(&["--methods", "wang", "--sp-clusters", "0"], true).unwrap_err();
    assert!(e.contains("wang"), "{e}");
}

/// `bench --methods colom,restir` at a tiny size (issue 43): restir's M and iteration lists (its k
/// one value, to keep it short; by default bench sweeps M, k and n) beside
/// colom's K's on the same fronts against the same reference, each row finite (MSE, rel MSE,
/// FLIP), restir's rows labelled with their knobs, and the knobs' columns filled for its rows only;
/// then the camera path with `--temporal off,on` (α 1: restir's own temporal reuse, no
/// accumulation), whose rows report MSE and `instability_world` from frame 1 on.
#[test]
fn bench_methods_colom_restir_at_a_tiny_size() {
    let d = common::scratch("bench-restir");
    let size = "--width 32 --height 24 --vpls 256 --direct-samples 1";
    let mut args = common::cmd(
        "bench builtin:cornell --methods colom,restir --modes weighted --pairs 24/32,48/64 \
         --restir-candidates 4,16 --restir-neighbours 5 --restir-iterations 0,1 --repeat 1 \
         --reference-repeat 1",
        &["--out-dir", common::arg(&d)],
    );
    args.extend(size.split_whitespace());
    let (code, _, err) = run(&args);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(d.join("results.csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    assert!(header.contains(&"restir_candidates") && header.contains(&"restir_combine"));
    let rows = csv::from_csv(&text).unwrap();
    let restir: Vec<&csv::Row> = rows.iter().filter(|r| r.mode == "restir").collect();
    assert_eq!(rows.len() - restir.len(), 2, "{text}");
    let labels: Vec<&str> = restir.iter().map(|r| r.label.as_str()).collect();
    assert_eq!(
        labels,
        [
            "restir M4 k5 n0",
            "restir M4 k5 n1",
            "restir M16 k5 n0",
            "restir M16 k5 n1"
        ],
        "{text}"
    );
    for r in &rows {
        assert!(r.mse.is_finite() && r.mse > 0.0, "{r:?}");
        assert!(r.rel_mse.is_finite() && r.rel_mse > 0.0, "{r:?}");
        let f = r.flip.unwrap();
        assert!(f.is_finite() && (0.0..=1.0).contains(&f), "{r:?}");
        assert!(r.frame_ms() > 0.0 && r.shadow_rays > 0, "{r:?}");
    }
    for p in ["pareto.png", "stages.png"] {
        assert!(image::open(d.join(p)).unwrap().width() > 100, "{p}");
    }
    // The camera path, restir alone at its defaults.
    let p = common::scratch("bench-restir-path");
    let mut args = common::cmd(
        "bench builtin:conference --methods restir --restir-candidates 8 --restir-neighbours 5 \
         --restir-iterations 1 --camera-path orbit:3:2 --temporal off,on --temporal-alpha 1",
        &["--out-dir", common::arg(&p)],
    );
    args.extend(size.split_whitespace());
    let (code, _, err) = run(&args);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(p.join("path.csv")).unwrap();
    let (header, rows) = path_csv(&text);
    let col = |row: &[String], name: &str| cell(&header, row, name);
    assert_eq!(rows.len(), 6, "{text}");
    for (i, r) in rows.iter().enumerate() {
        let (on, frame) = (i >= 3, i % 3);
        assert_eq!(col(r, "temporal"), if on { "on" } else { "off" });
        assert!(col(r, "label").starts_with("restir"), "{r:?}");
        let mse: f64 = col(r, "mse").parse().unwrap();
        assert!(mse.is_finite() && mse > 0.0, "{r:?}");
        let world = col(r, "instability_world");
        if frame > 0 {
            let v: f64 = world.parse().unwrap();
            assert!(v.is_finite() && v >= 0.0, "{r:?}");
        }
    }
    let _ = std::fs::remove_dir_all(&d);
    let _ = std::fs::remove_dir_all(&p);
}

/// `bench --paper off,on`: each configuration with the defaults and with `--paper` (the same K's,
/// the paper's ratios for the frame), the paper's row labelled `paper` and measured against its own
/// reference (no G-term clamp); a camera path needs one reference and refuses both without --clamp.
#[test]
fn paper_off_on_runs_both_side_by_side() {
    let d = common::scratch("bench-paper-off-on");
    let dir = d.to_str().unwrap();
    let args = common::cmd(
        "bench builtin:cornell --width 32 --height 24 --vpls 64 --modes hard --paper off,on \
         --repeat 1",
        &["--out-dir", dir],
    );
    let (code, _, err) = run(&args);
    assert_eq!(code, 0, "{err}");
    let rows = csv::from_csv(&std::fs::read_to_string(d.join("results.csv")).unwrap()).unwrap();
    assert_eq!(rows.len(), 2, "{rows:?}");
    let (def, paper) = (&rows[0], &rows[1]);
    // 768 pixels and 64 VPLs: the paper's K ratios, 8 / 16, for both.
    let ks = |r: &csv::Row| (r.cluster.sp_clusters, r.cluster.vpl_clusters);
    assert_eq!(ks(def), (8, 16), "{def:?}");
    assert_eq!(ks(paper), (8, 16), "{paper:?}");
    assert!(!def.label.contains("paper"), "{def:?}");
    assert!(paper.label.ends_with(" paper"), "{paper:?}");
    assert!(def.mse.is_finite() && paper.mse.is_finite());
    assert_ne!(def.mse, paper.mse, "the same image both ways");
    // Two references, one a frame (at this size no pixel is near enough a VPL for the clamp to
    // change the image: both are the same to the bit here, so the test reads the files, not pixels).
    for f in ["reference.exr", "reference_paper.exr"] {
        let (w, h, px) = fuzzy_vpl::export::read_exr(&d.join(f)).unwrap();
        assert_eq!((w, h), (32, 24), "{f}");
        assert!(common::all_finite(&px), "{f}");
    }
    assert!(def.reference_ms > 0.0 && paper.reference_ms > 0.0);
    let md = std::fs::read_to_string(d.join("summary.md")).unwrap();
    assert!(md.contains("reference_paper.exr"), "{md}");
    // With --clamp both frames are one: one reference, both rows against it.
    let mut clamped = args.to_vec();
    clamped.extend(["--clamp", "0.02"]);
    let (code, _, err) = run(&clamped);
    assert_eq!(code, 0, "{err}");
    let rows = csv::from_csv(&std::fs::read_to_string(d.join("results.csv")).unwrap()).unwrap();
    assert_eq!(rows.len(), 2, "{rows:?}");
    assert!(rows[1].label.ends_with(" paper"), "{rows:?}");
    assert_eq!(rows[0].reference_ms, rows[1].reference_ms);
    let md = std::fs::read_to_string(d.join("summary.md")).unwrap();
    assert!(!md.contains("reference_paper.exr"), "{md}");
    let mut path = args.to_vec();
    path.extend(["--camera-path", "orbit:2:10"]);
    let (code, _, err) = run(&path);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--clamp"), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}
