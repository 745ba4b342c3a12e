//! `fuzzy-vpl bench`: error against run time over a sweep of clustering settings (the paper's
//! Figs. 7, 9 and 11). One unclustered reference per camera, then every configuration of the sweep,
//! each timed `repeat` times (mean of the 3 best, `stats::best_of_runs`); the last run's image is
//! compared with the reference. Writes `results.csv`, images, plots and `summary.md`.

pub mod csv;
pub mod path;
pub mod plot;
pub mod summary;
pub mod sweep;
pub mod table;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};

use crate::gi::budget;
use crate::gi::pipeline::{FRAME_KEY, Frame, Pass, RenderSettings, Renderer};
use crate::gpu::GpuContext;
use crate::scene::{Camera, Scene};
use crate::settings::{ClusterSettings, FrameSettings, Method};
use crate::stats::ErrorStats;
use crate::{export, metrics, stats};
use csv::Row;
use summary::{CameraSummary, SummaryInfo};
use sweep::Sweep;

/// Everything a bench run needs besides the scene and the device.
pub struct BenchPlan {
    /// The scene as named on the command line (written in every row).
    pub scene_name: String,
    pub out_dir: PathBuf,
    /// Size, VPLs, seed, clamp, direct samples and exposure (PNG; `Auto` is resolved once a camera
    /// from its reference, so that every image of a camera is shown at the same exposure).
    pub frame: FrameSettings,
    /// Resolved (`Sweep::resolve`): every list has its values.
    pub sweep: Sweep,
    /// (name written in the rows, camera).
    pub cameras: Vec<(String, Camera)>,
    pub repeat: u32,
    pub reference_repeat: u32,
    /// The warm-up before each timed configuration, reference and camera-path frame.
    pub timing: crate::settings::TimingSettings,
    /// Draw the progress bar (it hides itself when stderr is not a terminal).
    pub progress: bool,
}

impl BenchPlan {
    /// The render settings of configuration `c`.
    pub fn settings(&self, c: &ClusterSettings) -> RenderSettings {
        RenderSettings {
            frame: self.frame,
            cluster: c.clone(),
            ..Default::default()
        }
    }

    /// The render settings of the unclustered reference.
    pub fn reference_settings(&self) -> RenderSettings {
        RenderSettings {
            frame: self.frame,
            reference: true,
            ..Default::default()
        }
    }
}

/// What a run produced.
pub struct BenchReport {
    pub rows: Vec<Row>,
    pub files: Vec<PathBuf>,
    pub wall_s: f64,
}

fn file_slug(label: &str) -> String {
    label
        .chars()
        .map(|c| match c {
            '/' => 'x',
            c if c.is_ascii_alphanumeric() || c == '-' => c,
            _ => '_',
        })
        .collect()
}

/// Renders `n` frames with `s` after the warm-up (`Renderer::warm_up`: on a GPU one untimed render,
/// then `warmup_ms` of GPU work, so no configuration is timed at the low clock the CPU work between
/// configurations leaves a GPU in); returns the last frame and the per-key mean of the 3 best
/// timings.
fn timed(
    renderer: &mut Renderer,
    camera: &Camera,
    s: &RenderSettings,
    n: u32,
    warmup_ms: f64,
    pb: &ProgressBar,
) -> Result<(Frame, BTreeMap<String, f64>)> {
    renderer.warm_up(camera, s, warmup_ms)?;
    let mut runs = Vec::new();
    let mut last = None;
    for _ in 0..n.max(1) {
        let f = renderer.render(camera, s)?;
        runs.push(f.timings_ms.clone());
        last = Some(f);
        pb.inc(1);
    }
    Ok((last.expect("n >= 1"), stats::best_of_runs(&runs)))
}

/// The Pareto front of `(time, error)` points read at `t`: the lowest error of a point whose time is
/// at most `t` (`None` when every point is slower).
pub fn front_at(points: &[(f64, f64)], t: f64) -> Option<f64> {
    points
        .iter()
        .filter(|p| p.0 <= t)
        .map(|p| p.1)
        .min_by(|a, b| a.total_cmp(b))
}

/// Whether `name` is a configuration's image as `run` names them: `NN[_camC]_<label>.png` or its
/// `_err.png` (two or more digits, an underscore, a label).
fn is_config_image(name: &str) -> bool {
    let digits = name.bytes().take_while(u8::is_ascii_digit).count();
    digits >= 2
        && name[digits..].starts_with('_')
        && name.len() > digits + 5
        && name.ends_with(".png")
}

/// Removes the configuration images an earlier run left in `images/`, so that the folder holds the
/// images of the rows of this run's `results.csv` and nothing else (a rerun with fewer or other
/// configurations used to leave the old ones beside the new). Other files are left alone.
fn remove_old_images(img_dir: &Path) -> Result<()> {
    let entries = std::fs::read_dir(img_dir)
        .with_context(|| format!("{}: cannot list", img_dir.display()))?;
    for e in entries.flatten() {
        let name = e.file_name();
        if name.to_str().is_some_and(is_config_image) && e.path().is_file() {
            std::fs::remove_file(e.path())
                .with_context(|| format!("{}: cannot remove", e.path().display()))?;
        }
    }
    Ok(())
}

fn write_csv(path: &Path, rows: &[Row]) -> Result<()> {
    let text = csv::to_csv(rows);
    export::write_atomic(path, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes())?;
        Ok(())
    })
}

pub fn run(ctx: &GpuContext, scene: &Scene, plan: &BenchPlan) -> Result<BenchReport> {
    let t0 = Instant::now();
    let out = &plan.out_dir;
    let img_dir = out.join("images");
    std::fs::create_dir_all(&img_dir)
        .with_context(|| format!("{}: cannot create", img_dir.display()))?;
    remove_old_images(&img_dir)?;
    let configs: Vec<ClusterSettings> = plan.sweep.configs();
    let budgets = plan.sweep.target_ms.len() as u64 * plan.sweep.modes.len() as u64;
    let frames = plan.cameras.len() as u64
        * (plan.reference_repeat.max(1) as u64
            + (configs.len() as u64 + budgets) * plan.repeat.max(1) as u64);
    let pb = if plan.progress {
        ProgressBar::new(frames)
    } else {
        ProgressBar::hidden()
    };
    pb.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{bar:32.cyan/blue}] {pos}/{len} frames, eta {eta} — {msg}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    let say = |line: String| pb.suspend(|| eprintln!("{line}"));
    let mut renderer = Renderer::new(ctx, scene)?;
    let base = plan.frame;
    let multi = plan.cameras.len() > 1;
    let mut rows: Vec<Row> = Vec::new();
    let mut files = Vec::new();
    let mut cam_summaries = Vec::new();
    let csv_path = out.join("results.csv");
    for (cam_name, camera) in &plan.cameras {
        let suffix = if multi {
            format!("_cam{cam_name}")
        } else {
            String::new()
        };
        // The reference: every pixel × every VPL.
        pb.set_message(format!("camera {cam_name}: reference"));
        let ref_settings = plan.reference_settings();
        let (reference, ref_t) = timed(
            &mut renderer,
            camera,
            &ref_settings,
            plan.reference_repeat,
            plan.timing.warmup_ms,
            &pb,
        )?;
        let reference_ms = ref_t[FRAME_KEY];
        let exposure = plan.frame.exposure.resolve(&reference.radiance);
        let ref_exr = format!("reference{suffix}.exr");
        export::write_exr(
            &out.join(&ref_exr),
            reference.width,
            reference.height,
            &reference.radiance,
        )?;
        let ref_png = out.join(format!("reference{suffix}.png"));
        export::write_image(
            &ref_png,
            reference.width,
            reference.height,
            &reference.radiance,
            exposure,
        )?;
        files.extend([out.join(&ref_exr), ref_png]);
        say(format!(
            "camera {cam_name}: reference {:.1} ms GPU ({} VPLs, mean luminance {:.3})",
            reference_ms,
            reference.vpls,
            metrics::mean_luminance(&reference.radiance)
        ));
        let mut cam_rows = Vec::new();
        // The sweep's configurations, then each --target-ms budget for each mode (from the mode's
        // first configuration; wang is a mode of its own, lightcluster has no K to choose).
        let mut jobs: Vec<(ClusterSettings, Option<f64>)> =
            configs.iter().map(|c| (c.clone(), None)).collect();
        for &t in &plan.sweep.target_ms {
            let mut seen = Vec::new();
            for c in configs.iter().filter(|c| c.method != Method::LightCluster) {
                let m = sweep::mode_name(c);
                if !seen.contains(&m) {
                    seen.push(m);
                    jobs.push((c.clone(), Some(t)));
                }
            }
        }
        for (i, (c, target_ms)) in jobs.iter().enumerate() {
            pb.set_message(format!("camera {cam_name}: {}", sweep::label(c)));
            // Under a budget the controller chooses the K's (and the direct light's samples where
            // the fewest clusters miss it).
            let (s, steps) = match target_ms {
                Some(t) => {
                    renderer.warm_up(camera, &plan.settings(c), plan.timing.warmup_ms)?;
                    let (chosen, b, _) = budget::fit(&mut renderer, camera, &plan.settings(c), *t)?;
                    (chosen, Some(b.steps))
                }
                None => (plan.settings(c), None),
            };
            let c = &s.cluster;
            let (frame, t) = timed(
                &mut renderer,
                camera,
                &s,
                plan.repeat,
                plan.timing.warmup_ms,
                &pb,
            )?;
            let mut label = sweep::label_ran(
                c,
                frame.ran(Pass::SpCluster) || frame.ran(Pass::WangCluster),
                frame.ran(Pass::VplCluster),
                frame.gamma_used,
            );
            if let Some(tm) = target_ms {
                label = format!("target {tm} ms {label}");
            }
            if frame.ran(Pass::Upsample) {
                label = format!("{label} indirect x{}", s.frame.indirect_scale);
            }
            let stages_ms: BTreeMap<String, f64> = csv::stages()
                .map(|k| (k.to_string(), t.get(k).copied().unwrap_or(0.0)))
                .collect();
            let frame_ms = stages_ms[FRAME_KEY];
            let labels = renderer.sp_labels(&frame)?;
            let (error, flip_map) = ErrorStats::measure(
                &frame.radiance,
                &reference.radiance,
                frame.width,
                frame.height,
                exposure,
                labels.as_deref(),
            );
            let row = Row {
                scene: plan.scene_name.clone(),
                camera: cam_name.clone(),
                width: frame.width,
                height: frame.height,
                vpls: frame.vpls,
                mode: sweep::mode_name(c).into(),
                vpl_clusters: c.vpl_clusters,
                sp_clusters: c.sp_clusters,
                fuzziness: c.fuzziness,
                gamma: c.gamma,
                gamma_used: frame.gamma_used,
                plane_gate_deg: c.plane_gate,
                weight_exponent: c.weight_exponent,
                normal_threshold: c.normal_threshold,
                iterations: c.iterations,
                stages_ms,
                reference_ms,
                speedup: if frame_ms > 0.0 {
                    reference_ms / frame_ms
                } else {
                    0.0
                },
                mse: error.mse,
                rel_mse: error.rel_mse,
                flip: Some(error.flip),
                border: error.border,
                interior: error.interior,
                border_ratio: error.border_ratio,
                flip_border: error.flip_border,
                target_ms: *target_ms,
                front_mse: None,
                sp_clusters_used: frame.sp_clusters_used,
                vpl_clusters_used: frame.vpl_clusters_used,
                shadow_rays: frame.shadow_rays,
                repeat: plan.repeat,
                label: label.clone(),
                method: c.method,
                indirect_ms: frame_ms
                    - t.get(Pass::Primary.name()).copied().unwrap_or(0.0)
                    - t.get(Pass::Direct.name()).copied().unwrap_or(0.0),
                adapter: ctx.adapter_name.clone(),
                driver: ctx.driver.clone(),
            };
            let stem = format!("{:02}{suffix}_{}", i + 1, file_slug(&label));
            let img = format!("images/{stem}.png");
            let err = format!("images/{stem}_err.png");
            export::write_image(
                &out.join(&img),
                frame.width,
                frame.height,
                &frame.radiance,
                exposure,
            )?;
            export::write_png_rgb8(
                &out.join(&err),
                frame.width,
                frame.height,
                metrics::error_map(&frame.radiance, &reference.radiance),
            )?;
            let flip_png = format!("images/{stem}_flip.png");
            export::write_png_rgb8(
                &out.join(&flip_png),
                frame.width,
                frame.height,
                metrics::flip_error_map(&flip_map, frame.width, frame.height),
            )?;
            files.extend([out.join(&img), out.join(&err), out.join(&flip_png)]);
            if let Some(steps) = &steps {
                for (k, st) in steps.iter().enumerate() {
                    say(format!(
                        "camera {cam_name}: {label}: frame {}: K_SP {} K_VPL {} -> {:.1} ms",
                        k + 1,
                        st.sp_clusters,
                        st.vpl_clusters,
                        st.frame_ms
                    ));
                }
            }
            say(format!(
                "camera {cam_name}: {label:<28} {:>9.2} ms  {:>6.1}x  {}",
                frame_ms,
                row.speedup,
                error.line()
            ));
            rows.push(row.clone());
            // Rewritten after every configuration, so an interrupted sweep keeps what it measured.
            write_csv(&csv_path, &rows)?;
            cam_rows.push((row, img, err));
        }
        // Each budget's row against the sweep's Pareto front: the lowest MSE of a fixed setting at
        // no more frame time.
        let fixed: Vec<(f64, f64)> = cam_rows
            .iter()
            .filter(|r| r.0.target_ms.is_none())
            .map(|r| (r.0.frame_ms(), r.0.mse))
            .collect();
        for r in cam_rows.iter_mut().filter(|r| r.0.target_ms.is_some()) {
            r.0.front_mse = front_at(&fixed, r.0.frame_ms());
            if let Some(f) = r.0.front_mse {
                say(format!(
                    "camera {cam_name}: {}: MSE {:.4e} at {:.1} ms; the best fixed setting at no more time: {:.4e} ({:+.1}%)",
                    r.0.label,
                    r.0.mse,
                    r.0.frame_ms(),
                    f,
                    (r.0.mse / f - 1.0) * 100.0
                ));
            }
        }
        let n = rows.len() - cam_rows.len();
        for (k, r) in cam_rows.iter().enumerate() {
            rows[n + k] = r.0.clone();
        }
        write_csv(&csv_path, &rows)?;
        let just: Vec<Row> = cam_rows.iter().map(|r| r.0.clone()).collect();
        let title = |what: &str| format!("{} — {what}", plan.scene_name);
        let mut plots = Vec::new();
        let stages_png = format!("stages{suffix}.png");
        plot::stages(
            &out.join(&stages_png),
            &title("GPU time per stage and MSE"),
            &just,
        )?;
        plots.push(("Stage times and MSE".to_string(), stages_png));
        if just.iter().any(|r| r.sp_clusters > 0 && r.vpl_clusters > 0) {
            let grid_png = format!("grid{suffix}.png");
            plot::grid(
                &out.join(&grid_png),
                &title("time and MSE over K_sp / K_vpl"),
                &just,
            )?;
            plots.push(("SP × VPL clusters: time against MSE".to_string(), grid_png));
        }
        let pareto_png = format!("pareto{suffix}.png");
        plot::pareto(
            &out.join(&pareto_png),
            &title("time against MSE by mode, Pareto front"),
            &just,
        )?;
        plots.push((
            "Modes: Pareto front of time and MSE".to_string(),
            pareto_png,
        ));
        if just.iter().any(|r| r.method != just[0].method) {
            let methods_png = format!("methods{suffix}.png");
            plot::methods(
                &out.join(&methods_png),
                &title("methods: indirect-light time against MSE, each method's front"),
                &just,
            )?;
            plots.push((
                "Methods: each one's Pareto front of indirect time and MSE".to_string(),
                methods_png,
            ));
        }
        files.extend(plots.iter().map(|p| out.join(&p.1)));
        cam_summaries.push(CameraSummary {
            camera: cam_name.clone(),
            reference_ms,
            reference_image: ref_exr,
            plots,
            rows: cam_rows,
        });
    }
    pb.finish_and_clear();
    write_csv(&csv_path, &rows)?;
    files.push(csv_path);
    let wall_s = t0.elapsed().as_secs_f64();
    let md = summary::markdown(&SummaryInfo {
        scene: &plan.scene_name,
        adapter: &ctx.adapter_name,
        driver: &ctx.driver,
        software: ctx.software,
        warmup_ms: plan.timing.warmup_ms,
        width: base.width,
        height: base.height,
        vpls: base.vpls,
        seed: base.seed,
        repeat: plan.repeat,
        reference_repeat: plan.reference_repeat,
        cameras: cam_summaries,
        wall_s,
    });
    let md_path = out.join("summary.md");
    export::write_atomic(&md_path, |w| {
        use std::io::Write;
        w.write_all(md.as_bytes())?;
        Ok(())
    })?;
    files.push(md_path);
    Ok(BenchReport {
        rows,
        files,
        wall_s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_configuration_images_count_as_old() {
        assert!(is_config_image("01_hard_192x512_g4.png"));
        assert!(is_config_image("12_cam0_weighted_48x128_F6_g4_err.png"));
        assert!(is_config_image("100_uniform_8x8_F6_g4.png"));
        assert!(!is_config_image("reference.png"));
        assert!(!is_config_image("1_hard.png"));
        assert!(!is_config_image("01_notes.txt"));
        assert!(!is_config_image("ab_hard.png"));
    }

    #[test]
    fn the_front_is_the_best_error_at_no_more_time() {
        let pts = [(10.0, 5.0), (20.0, 3.0), (30.0, 4.0), (40.0, 1.0)];
        assert_eq!(front_at(&pts, 5.0), None);
        assert_eq!(front_at(&pts, 10.0), Some(5.0));
        assert_eq!(front_at(&pts, 35.0), Some(3.0));
        assert_eq!(front_at(&pts, 40.0), Some(1.0));
    }

    #[test]
    fn slugs_are_file_names() {
        assert_eq!(file_slug("weighted 48/128 F6 g4"), "weighted_48x128_F6_g4");
        assert_eq!(file_slug("vpl-only -/128"), "vpl-only_-x128");
    }
}
