//! `fuzzy-vpl bench`: the quick sweep end to end (GPU, lavapipe in CI) and its bad input (no GPU).

mod common;

use std::process::Command;

use fuzzy_vpl::bench::csv;

fn run(args: &[&str]) -> (i32, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_fuzzy-vpl"))
        .args(args)
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn quick_bench_writes_csv_plots_and_summary() {
    let d = common::scratch("bench-quick");
    let t = std::time::Instant::now();
    let (code, out, err) = run(&[
        "bench",
        "builtin:cornell",
        "--quick",
        "--out-dir",
        d.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    eprintln!("bench --quick took {:.1} s", t.elapsed().as_secs_f64());
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
        assert_eq!((r.width, r.height, r.vpls), (96, 72, 1024));
        assert!(r.mse.is_finite() && r.mse >= 0.0, "{r:?}");
        assert!(r.rel_mse.is_finite() && r.rel_mse >= 0.0, "{r:?}");
        assert!(r.frame_ms() > 0.0 && r.reference_ms > 0.0, "{r:?}");
        assert!((r.speedup - r.reference_ms / r.frame_ms()).abs() < 1e-6 * r.speedup.max(1.0));
        assert!(r.shadow_rays > 0);
        if r.sp_clusters > 0 {
            assert!(
                r.sp_clusters_used > 0 && r.stage("sp_cluster") > 0.0,
                "{r:?}"
            );
        }
        if r.vpl_clusters > 0 {
            assert_eq!(r.vpl_clusters_used, r.vpl_clusters, "{r:?}");
        }
    }
    // Clustered frames are faster than the unclustered reference.
    assert!(rows.iter().all(|r| r.speedup > 1.0), "{rows:?}");
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
        2 * rows.len()
    );
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
