//! `fuzzy-vpl bench-table`: one markdown table of several bench runs (`scripts/gpu-bench`): the
//! adapter, driver, commit and date above it, a row per configuration of each run's `results.csv`
//! (ms per pass, speed-up over the reference, MSE, FLIP) and a row per configuration and temporal
//! setting of each run's `path.csv` (means over the frames after the first).

use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::Path;

use anyhow::{Context, Result, bail};

use super::csv::{Row, from_csv};
use super::summary::fmt_ms as ms;

/// What the table states above its rows.
pub struct TableInfo<'a> {
    pub commit: &'a str,
    pub date: &'a str,
}

fn sci(v: f64) -> String {
    format!("{v:.2e}")
}

/// The per-pass columns of the table (then `indirect`, the method's own passes in all, and frame).
const PASSES: [&str; 5] = ["primary", "direct", "sp_cluster", "visibility", "shade"];

const HEADER: &str = "| run | scene | size | VPLs | setting | temporal | primary | direct | \
                      sp_cluster | visibility | shade | indirect | frame ms | reference ms | \
                      speed-up | MSE | FLIP |";

fn sweep_row(run: &str, r: &Row) -> String {
    let mut cells = vec![
        run.to_string(),
        format!("`{}`", r.scene),
        format!("{}×{}", r.frame.width, r.frame.height),
        r.frame.vpls.to_string(),
        r.label.clone(),
        "off".into(),
    ];
    cells.extend(PASSES.iter().map(|p| ms(r.stage(p))));
    cells.extend([
        ms(r.indirect_ms),
        format!("**{}**", ms(r.frame_ms())),
        ms(r.reference_ms),
        format!("{:.1}×", r.speedup),
        sci(r.mse),
        r.flip.map_or("–".into(), |f| format!("{f:.4}")),
    ]);
    format!("| {} |", cells.join(" | "))
}

/// A `path.csv`'s rows grouped by (label, temporal): the means over frames after the first of
/// frame_ms, sp_cluster_ms, visibility_ms, reference_ms and mse; the adapter and driver.
struct PathGroup {
    /// Scene, size and VPLs as the file gives them ("–" for files without the columns).
    scene: String,
    size: String,
    vpls: String,
    label: String,
    temporal: String,
    frames: usize,
    sums: BTreeMap<&'static str, f64>,
}

/// The means of a path group, in the order `read_path` sums them.
const PATH_MEANS: [&str; 5] = [
    "frame_ms",
    "sp_cluster_ms",
    "visibility_ms",
    "reference_ms",
    "mse",
];

/// An adapter and its driver.
type Device = (String, String);

fn read_path(text: &str) -> Result<(Vec<PathGroup>, Option<Device>)> {
    let rows = super::path::from_csv(text)?;
    let mut groups: Vec<PathGroup> = Vec::new();
    let mut seen_device = None;
    for r in &rows {
        if !r.adapter.is_empty() || !r.driver.is_empty() {
            seen_device = Some((r.adapter.clone(), r.driver.clone()));
        }
        if r.frame == 0 {
            continue;
        }
        let temporal = crate::settings::on_off(r.temporal());
        let at = match groups
            .iter()
            .position(|g| g.label == r.label && g.temporal == temporal)
        {
            Some(at) => at,
            None => {
                // Files without the frame's columns show "–".
                let or_dash = |v: String| {
                    if v.is_empty() || v == "0" {
                        "–".into()
                    } else {
                        v
                    }
                };
                groups.push(PathGroup {
                    scene: format!("`{}`", or_dash(r.scene.clone())),
                    size: format!(
                        "{}×{}",
                        or_dash(r.frame_settings.width.to_string()),
                        or_dash(r.frame_settings.height.to_string())
                    ),
                    vpls: or_dash(r.frame_settings.vpls.to_string()),
                    label: r.label.clone(),
                    temporal: temporal.into(),
                    frames: 0,
                    sums: BTreeMap::new(),
                });
                groups.len() - 1
            }
        };
        let g = &mut groups[at];
        g.frames += 1;
        let values = [
            r.frame_ms,
            r.sp_cluster_ms,
            r.visibility_ms,
            r.reference_ms,
            r.mse,
        ];
        for (m, v) in PATH_MEANS.iter().zip(values) {
            *g.sums.entry(m).or_default() += v;
        }
    }
    Ok((groups, seen_device))
}

fn path_row(run: &str, g: &PathGroup) -> String {
    let mean = |m: &str| g.sums.get(m).copied().unwrap_or(0.0) / g.frames.max(1) as f64;
    let frame = mean("frame_ms");
    let cells = [
        run.to_string(),
        g.scene.clone(),
        g.size.clone(),
        g.vpls.clone(),
        format!("{}, path of {} frames", g.label, g.frames),
        g.temporal.clone(),
        "–".into(),
        "–".into(),
        ms(mean("sp_cluster_ms")),
        ms(mean("visibility_ms")),
        "–".into(),
        "–".into(),
        format!("**{}**", ms(frame)),
        ms(mean("reference_ms")),
        if frame > 0.0 {
            format!("{:.1}×", mean("reference_ms") / frame)
        } else {
            "–".into()
        },
        sci(mean("mse")),
        "–".into(),
    ];
    format!("| {} |", cells.join(" | "))
}

/// The most bytes read from one `results.csv` or `path.csv` (a sweep's file holds a few hundred
/// rows of a few hundred bytes).
pub const MAX_CSV_BYTES: u64 = 64 << 20;

/// A bench CSV file's text: a regular file (a FIFO would block) of at most `MAX_CSV_BYTES`.
fn read_csv_file(path: &Path) -> Result<String> {
    crate::files::read_text(path, MAX_CSV_BYTES, "a bench CSV file")
        .map_err(|e| crate::input::bad(format!("{}: cannot read: {e}", path.display())))
}

/// The table of the runs in `dirs` (each holding `results.csv`, `path.csv` or both; the run is
/// named by the folder's name).
pub fn markdown(dirs: &[&Path], info: &TableInfo) -> Result<String> {
    let mut rows = Vec::new();
    let mut devices: Vec<Device> = Vec::new();
    let mut note = |a: &str, d: &str| {
        let dev = (a.to_string(), d.to_string());
        if !a.is_empty() && !devices.contains(&dev) {
            devices.push(dev);
        }
    };
    for dir in dirs {
        let run = dir
            .file_name()
            .map_or_else(|| dir.display().to_string(), |n| n.to_string_lossy().into());
        let (results, path) = (dir.join("results.csv"), dir.join("path.csv"));
        if !results.exists() && !path.exists() {
            bail!("{}: holds neither results.csv nor path.csv", dir.display());
        }
        if results.exists() {
            let text = read_csv_file(&results)?;
            for r in from_csv(&text).with_context(|| format!("{}", results.display()))? {
                note(&r.adapter, &r.driver);
                rows.push(sweep_row(&run, &r));
            }
        }
        if path.exists() {
            let text = read_csv_file(&path)?;
            let (groups, device) =
                read_path(&text).with_context(|| format!("{}", path.display()))?;
            if let Some((a, d)) = device {
                note(&a, &d);
            }
            for g in &groups {
                rows.push(path_row(&run, g));
            }
        }
    }
    let mut m = String::new();
    let adapters: Vec<String> = devices
        .iter()
        .map(|(a, d)| format!("**{a}**, driver {d}"))
        .collect();
    let _ = writeln!(
        m,
        "- adapter: {}\n- commit `{}`, {}\n- GPU timestamp ms (mean of the 3 best of each run's \
         repeats; a path frame once, after the warm-up); `indirect` is the method's own passes in \
         all (frame less primary and direct); path rows are means over the frames after the first; \
         speed-up = reference ÷ frame\n",
        if adapters.is_empty() {
            "unknown (files without the adapter columns)".into()
        } else {
            adapters.join("; ")
        },
        info.commit,
        info.date
    );
    if devices.iter().any(|(a, _)| a.contains("llvmpipe")) {
        let _ = writeln!(
            m,
            "**A software driver (lavapipe, on the CPU): these times say little about a GPU's.**\n"
        );
    }
    let _ = writeln!(m, "{HEADER}");
    let _ = writeln!(m, "|{}", " --- |".repeat(HEADER.matches(" | ").count() + 1));
    for r in rows {
        let _ = writeln!(m, "{r}");
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::super::csv::{tests::synthetic, to_csv};
    use super::super::path::{PathRow, to_csv as path_csv};
    use super::*;

    fn path_rows() -> Vec<PathRow> {
        let row = |frame: u32, on: bool, ms: f64| PathRow {
            label: "weighted 8000/2000".into(),
            cluster: crate::settings::ClusterSettings {
                temporal: on,
                temporal_alpha: 0.7,
                ..Default::default()
            },
            frame,
            frame_ms: ms,
            sp_cluster_ms: ms / 4.0,
            mse: 1e-5,
            rel_mse: 1e-3,
            instability: None,
            sp_clusters_used: 8000,
            reference_ms: 400.0,
            visibility_ms: 2.0,
            adapter: "NVIDIA H100 80GB HBM3 (Vulkan, 580.82.07)".into(),
            driver: "NVIDIA 580.82.07".into(),
            scene: "builtin:conference".into(),
            frame_settings: crate::settings::FrameSettings {
                width: 1024,
                height: 720,
                vpls: 8192,
                ..Default::default()
            },
            instability_world: None,
            ..Default::default()
        };
        vec![
            row(0, false, 99.0),
            row(1, false, 20.0),
            row(2, false, 30.0),
            row(0, true, 99.0),
            row(1, true, 10.0),
        ]
    }

    #[test]
    fn one_table_of_sweeps_and_paths() {
        let tmp = std::env::temp_dir().join(format!("fvpl-table-{}", std::process::id()));
        let (a, b) = (tmp.join("paper"), tmp.join("orbit"));
        std::fs::create_dir_all(&a).unwrap();
        std::fs::create_dir_all(&b).unwrap();
        let rows = [
            synthetic("weighted", 8000, 2000),
            synthetic("hard", 8000, 2000),
        ];
        std::fs::write(a.join("results.csv"), to_csv(&rows)).unwrap();
        std::fs::write(b.join("path.csv"), path_csv(&path_rows())).unwrap();
        let info = TableInfo {
            commit: "abc1234",
            date: "2026-11-26",
        };
        let md = markdown(&[a.as_path(), b.as_path()], &info).unwrap();
        let table: Vec<&str> = md.lines().filter(|l| l.starts_with('|')).collect();
        // Header, rule, two sweep rows, two path groups (off and on).
        assert_eq!(table.len(), 6, "{md}");
        let columns = table[0].matches('|').count();
        assert!(
            table.iter().all(|l| l.matches('|').count() == columns),
            "{md}"
        );
        assert!(md.contains("commit `abc1234`, 2026-11-26"));
        assert!(
            md.contains("llvmpipe") && md.contains("NVIDIA H100"),
            "{md}"
        );
        assert!(md.contains("A software driver"), "{md}");
        // The path means leave frame 0 out: off (20 + 30) / 2 = 25, on 10; speed-up 400 / 25.
        let off = table
            .iter()
            .find(|l| l.contains("| off |") && l.contains("orbit"))
            .unwrap();
        assert!(off.contains("**25.0**") && off.contains("16.0×"), "{off}");
        assert!(
            off.contains("path of 2 frames") && off.contains("1024×720 | 8192"),
            "{off}"
        );
        let on = table.iter().find(|l| l.contains("| on |")).unwrap();
        assert!(on.contains("**10.0**") && on.contains("40.0×"), "{on}");
        // A sweep row: its frame, speed-up and FLIP as the CSV holds them.
        let r = &rows[0];
        let w = table.iter().find(|l| l.contains(&r.label)).unwrap();
        assert!(w.contains(&format!("**{}**", ms(r.frame_ms()))), "{w}");
        assert!(w.contains(&format!("{:.1}×", r.speedup)), "{w}");
        // A folder with neither file is an error naming it.
        let e = markdown(&[tmp.as_path()], &info).unwrap_err().to_string();
        assert!(e.contains("neither"), "{e}");
        std::fs::remove_dir_all(&tmp).unwrap();
    }
}
