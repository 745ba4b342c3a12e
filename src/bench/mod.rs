//! `fuzzy-vpl bench`: error against run time over a sweep of clustering settings (the paper's
//! Figs. 7, 9 and 11). One unclustered reference per camera, then every configuration of the sweep,
//! each timed `repeat` times as `render` times it (`render::timed`: mean of the 3 best); the last run's image is
//! compared with the reference. Writes `results.csv`, images, plots and `summary.md`.

pub mod csv;
pub mod path;
pub mod plot;
pub mod summary;
pub mod sweep;
pub mod table;

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};

use crate::gi::pass::Pass;
use crate::gpu::GpuContext;
use crate::render::timed::{FrameKind, Timed, Timing, timed};
use crate::render::{FRAME_KEY, Frame, RenderSettings, Renderer};
use crate::scene::{Camera, Scene};
use crate::settings::FrameSettings;
use crate::stats::ErrorStats;
use crate::{export, metrics};
use csv::Row;
use summary::{CameraSummary, SummaryInfo};
use sweep::Config;
use sweep::Sweep;

/// Everything a bench run needs besides the scene and the device.
pub struct BenchPlan {
    /// The scene as named on the command line (written in every row).
    pub scene_name: String,
    pub out_dir: PathBuf,
    /// Size, VPLs, seed, clamp, direct samples and exposure (PNG; `Auto` is resolved once a camera
    /// from its reference, so that every image of a camera is shown at the same exposure).
    pub frame: FrameSettings,
    /// The frame of the configurations with `--paper` (`ClusterSettings::paper`): `frame` without a
    /// G-term clamp unless --clamp was given (`paper_frame`).
    pub paper_frame: FrameSettings,
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

/// `bench --paper`'s frame: `frame` without a G-term clamp (the paper's Eq. 5 and 6 have none),
/// unless the command line gave --clamp (`clamp_given`).
pub fn paper_frame(frame: &FrameSettings, clamp_given: bool) -> FrameSettings {
    FrameSettings {
        clamp: if clamp_given { frame.clamp } else { 0.0 },
        ..*frame
    }
}

impl BenchPlan {
    /// The frame of configuration `c`: `paper_frame` with `--paper`, else `frame`.
    pub fn frame_of(&self, c: &Config) -> FrameSettings {
        if c.paper {
            self.paper_frame
        } else {
            self.frame
        }
    }

    /// The render settings of configuration `c`.
    pub fn settings(&self, c: &Config) -> RenderSettings {
        RenderSettings {
            frame: self.frame_of(c),
            cluster: c.cluster.clone(),
            method: c.method,
            ..Default::default()
        }
    }

    /// The distinct frames of `configs`, in order: one reference each (two where `--paper off,on`
    /// changes the clamp).
    pub fn frames(&self, configs: &[Config]) -> Vec<FrameSettings> {
        let mut out: Vec<FrameSettings> = Vec::new();
        for f in configs.iter().map(|c| self.frame_of(c)) {
            if !out.contains(&f) {
                out.push(f);
            }
        }
        out
    }

    /// The render settings of the unclustered reference of `frame`.
    pub fn reference_settings(&self, frame: FrameSettings) -> RenderSettings {
        RenderSettings {
            frame,
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
    let configs: Vec<Config> = plan.sweep.configs();
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
    let mut b = Bench {
        ctx,
        plan,
        renderer: Renderer::new(ctx, scene)?,
        pb,
        rows: Vec::new(),
        files: Vec::new(),
        csv_path: out.join("results.csv"),
    };
    let mut cam_summaries = Vec::new();
    for (cam_name, camera) in &plan.cameras {
        cam_summaries.push(b.camera(cam_name, camera, &configs)?);
    }
    b.pb.finish_and_clear();
    write_csv(&b.csv_path, &b.rows)?;
    b.files.push(b.csv_path.clone());
    let wall_s = t0.elapsed().as_secs_f64();
    let base = plan.frame;
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
    b.files.push(md_path);
    Ok(BenchReport {
        rows: b.rows,
        files: b.files,
        wall_s,
    })
}

/// A camera's reference: its frame, its timings' frame ms, the exposure every image of the camera
/// is shown at, and the EXR's name.
struct Reference {
    frame: Frame,
    ms: f64,
    exposure: f32,
    exr: String,
}

/// A bench run in progress: the rows and files so far.
struct Bench<'a> {
    ctx: &'a GpuContext,
    plan: &'a BenchPlan,
    renderer: Renderer<'a>,
    pb: ProgressBar,
    rows: Vec<Row>,
    files: Vec<PathBuf>,
    csv_path: PathBuf,
}

impl Bench<'_> {
    fn say(&self, line: String) {
        self.pb.suspend(|| eprintln!("{line}"));
    }

    /// The times of `s` as `render` takes them (`render::timed`), the progress bar ticking.
    fn timed(&mut self, camera: &Camera, s: &RenderSettings, repeat: u32) -> Result<Timed> {
        let timing = Timing {
            repeat,
            warmup_ms: self.plan.timing.warmup_ms,
            kind: FrameKind::Vpl,
        };
        let pb = self.pb.clone();
        timed(&mut self.renderer, camera, s, timing, &mut || pb.inc(1))
    }

    /// One camera: its reference, every configuration of the sweep, then each --target-ms budget
    /// for each mode (from the mode's first configuration; another method is a mode of its own,
    /// where it has a K to choose); the budgets' rows against the sweep's front; the plots.
    fn camera(
        &mut self,
        cam_name: &str,
        camera: &Camera,
        configs: &[Config],
    ) -> Result<CameraSummary> {
        let suffix = if self.plan.cameras.len() > 1 {
            format!("_cam{cam_name}")
        } else {
            String::new()
        };
        // One reference per frame: the first is `reference`, a second (`--paper off,on`, the
        // paper's frame without the clamp) `reference_paper`.
        let mut references = Vec::new();
        for (i, f) in self.plan.frames(configs).into_iter().enumerate() {
            let name = if i == 0 {
                "reference"
            } else {
                "reference_paper"
            };
            references.push((f, self.reference(cam_name, camera, f, name, &suffix)?));
        }
        let mut jobs: Vec<(Config, Option<f64>)> =
            configs.iter().map(|c| (c.clone(), None)).collect();
        let has_k = |c: &&Config| {
            let r = c.method.entry();
            r.clusters_sps || (r.vpl_clusters)(&c.method)
        };
        for &t in &self.plan.sweep.target_ms {
            let mut seen = Vec::new();
            for c in configs.iter().filter(has_k) {
                let m = sweep::mode_name(c);
                if !seen.contains(&m) {
                    seen.push(m);
                    jobs.push((c.clone(), Some(t)));
                }
            }
        }
        let mut cam_rows = Vec::new();
        for (i, (c, target_ms)) in jobs.iter().enumerate() {
            let stem_no = format!("{:02}{suffix}", i + 1);
            let frame = self.plan.frame_of(c);
            let reference = &references
                .iter()
                .find(|r| r.0 == frame)
                .expect("a frame's")
                .1;
            let row = self.measure(cam_name, camera, c, *target_ms, reference, &stem_no)?;
            cam_rows.push(row);
        }
        self.mark_front(cam_name, &mut cam_rows);
        let n = self.rows.len() - cam_rows.len();
        for (k, r) in cam_rows.iter().enumerate() {
            self.rows[n + k] = r.0.clone();
        }
        write_csv(&self.csv_path, &self.rows)?;
        let just: Vec<Row> = cam_rows.iter().map(|r| r.0.clone()).collect();
        let plots = self.plots(&just, &suffix)?;
        let reference = &references[0].1;
        Ok(CameraSummary {
            camera: cam_name.to_string(),
            reference_ms: reference.ms,
            reference_image: reference.exr.clone(),
            paper_reference: references.get(1).map(|r| (r.1.ms, r.1.exr.clone())),
            plots,
            rows: cam_rows,
        })
    }

    /// The reference of `frame`: every pixel × every VPL, timed and written as EXR and PNG
    /// (`name{suffix}`).
    fn reference(
        &mut self,
        cam_name: &str,
        camera: &Camera,
        frame: FrameSettings,
        name: &str,
        suffix: &str,
    ) -> Result<Reference> {
        self.pb.set_message(format!("camera {cam_name}: {name}"));
        let s = self.plan.reference_settings(frame);
        let t = self.timed(camera, &s, self.plan.reference_repeat)?;
        let (frame, ms) = (t.frame, t.timings_ms[FRAME_KEY]);
        let out = &self.plan.out_dir;
        let exposure = s.frame.exposure.resolve(&frame.radiance);
        let exr = format!("{name}{suffix}.exr");
        export::write_exr(&out.join(&exr), frame.width, frame.height, &frame.radiance)?;
        let png = out.join(format!("{name}{suffix}.png"));
        export::write_image(&png, frame.width, frame.height, &frame.radiance, exposure)?;
        self.files.extend([out.join(&exr), png]);
        self.say(format!(
            "camera {cam_name}: {name} {:.1} ms GPU ({} VPLs, clamp {}, mean luminance {:.3})",
            ms,
            frame.vpls,
            s.frame.clamp,
            metrics::mean_luminance(&frame.radiance)
        ));
        Ok(Reference {
            frame,
            ms,
            exposure,
            exr,
        })
    }

    /// One configuration (under a budget, the controller chooses its K's, and the direct light's
    /// samples where the fewest clusters miss it): timed, compared with the reference, its images
    /// written and its row added (the CSV rewritten, so an interrupted sweep keeps what it
    /// measured). Returns the row and its image and error image.
    fn measure(
        &mut self,
        cam_name: &str,
        camera: &Camera,
        c: &Config,
        target_ms: Option<f64>,
        reference: &Reference,
        stem_no: &str,
    ) -> Result<(Row, String, String)> {
        self.pb
            .set_message(format!("camera {cam_name}: {}", sweep::label(c)));
        let mut s = self.plan.settings(c);
        s.cluster.target_ms = target_ms;
        let t = self.timed(camera, &s, self.plan.repeat)?;
        let frame = &t.frame;
        let c = &Config {
            cluster: t.settings.cluster.clone(),
            method: t.settings.method,
        };
        let mut label = sweep::label_ran(
            c,
            frame.ran(Pass::SpCluster)
                || (c.method.entry_with_own_settings())
                    .is_some_and(|r| r.clusters_sps && frame.ran(r.passes[0])),
            frame.ran(Pass::VplCluster),
            frame.gamma_used,
        );
        if let Some(tm) = target_ms {
            label = format!("target {tm} ms {label}");
        }
        if frame.ran(Pass::Upsample) {
            label = format!("{label} indirect x{}", t.settings.frame.indirect_scale);
        }
        let labels = self.renderer.sp_labels(frame)?;
        let (error, flip_map) = ErrorStats::measure(
            &frame.radiance,
            &reference.frame.radiance,
            frame.width,
            frame.height,
            reference.exposure,
            labels.as_deref(),
        );
        let mut row = Row {
            label: label.clone(),
            ..self.row(cam_name, c, &t, reference, &error)
        };
        row.cluster.target_ms = target_ms;
        let out = &self.plan.out_dir;
        let stem = format!("{stem_no}_{}", file_slug(&label));
        let img = format!("images/{stem}.png");
        let err = format!("images/{stem}_err.png");
        let (w, h) = (frame.width, frame.height);
        export::write_image(&out.join(&img), w, h, &frame.radiance, reference.exposure)?;
        let err_map = metrics::error_map(&frame.radiance, &reference.frame.radiance);
        export::write_png_rgb8(&out.join(&err), w, h, err_map)?;
        let flip_png = format!("images/{stem}_flip.png");
        let flip = metrics::flip_error_map(&flip_map, w, h);
        export::write_png_rgb8(&out.join(&flip_png), w, h, flip)?;
        self.files
            .extend([out.join(&img), out.join(&err), out.join(&flip_png)]);
        for (k, st) in t.budget.iter().flat_map(|b| &b.steps).enumerate() {
            self.say(format!(
                "camera {cam_name}: {label}: frame {}: K_SP {} K_VPL {} -> {:.1} ms",
                k + 1,
                st.sp_clusters,
                st.vpl_clusters,
                st.frame_ms
            ));
        }
        self.say(format!(
            "camera {cam_name}: {label:<28} {:>9.2} ms  {:>6.1}x  {}",
            row.frame_ms(),
            row.speedup,
            error.line()
        ));
        self.rows.push(row.clone());
        write_csv(&self.csv_path, &self.rows)?;
        Ok((row, img, err))
    }

    /// A configuration's CSV row (no budget, no label).
    fn row(
        &self,
        cam_name: &str,
        c: &Config,
        t: &Timed,
        reference: &Reference,
        error: &ErrorStats,
    ) -> Row {
        let frame = &t.frame;
        let ms = |k: &str| t.timings_ms.get(k).copied().unwrap_or(0.0);
        let stage = |p: Pass| ms(p.name());
        let frame_ms = ms(FRAME_KEY);
        let mut row = Row {
            scene: self.plan.scene_name.clone(),
            camera: cam_name.to_string(),
            mode: sweep::mode_name(c).into(),
            gamma_used: frame.gamma_used,
            reference_ms: reference.ms,
            speedup: if frame_ms > 0.0 {
                reference.ms / frame_ms
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
            front_mse: None,
            sp_clusters_used: frame.sp_clusters_used,
            vpl_clusters_used: frame.vpl_clusters_used,
            shadow_rays: frame.shadow_rays,
            repeat: self.plan.repeat,
            label: String::new(),
            method: c.method,
            indirect_ms: frame_ms - stage(Pass::Primary) - stage(Pass::Direct),
            adapter: self.ctx.adapter_name.clone(),
            driver: self.ctx.driver.clone(),
            report: frame.report_of(c.method.method).cloned(),
            cluster: c.cluster.clone(),
            frame: FrameSettings {
                width: frame.width,
                height: frame.height,
                vpls: frame.vpls,
                ..t.settings.frame
            },
            ..Default::default()
        };
        for (name, v) in row.stages_mut() {
            *v = ms(name);
        }
        row
    }

    /// Each budget's row against the sweep's Pareto front: the lowest MSE of a fixed setting at no
    /// more frame time.
    fn mark_front(&self, cam_name: &str, cam_rows: &mut [(Row, String, String)]) {
        let fixed: Vec<(f64, f64)> = cam_rows
            .iter()
            .filter(|r| r.0.cluster.target_ms.is_none())
            .map(|r| (r.0.frame_ms(), r.0.mse))
            .collect();
        for r in cam_rows
            .iter_mut()
            .filter(|r| r.0.cluster.target_ms.is_some())
        {
            r.0.front_mse = front_at(&fixed, r.0.frame_ms());
            if let Some(f) = r.0.front_mse {
                self.say(format!(
                    "camera {cam_name}: {}: MSE {:.4e} at {:.1} ms; the best fixed setting at no more time: {:.4e} ({:+.1}%)",
                    r.0.label,
                    r.0.mse,
                    r.0.frame_ms(),
                    f,
                    (r.0.mse / f - 1.0) * 100.0
                ));
            }
        }
    }

    /// A camera's plots: stage times, the K grid, the modes' front, and the methods' fronts.
    fn plots(&mut self, just: &[Row], suffix: &str) -> Result<Vec<(String, String)>> {
        let out = &self.plan.out_dir;
        let title = |what: &str| format!("{} — {what}", self.plan.scene_name);
        let mut plots = Vec::new();
        let stages_png = format!("stages{suffix}.png");
        plot::stages(
            &out.join(&stages_png),
            &title("GPU time per stage and MSE"),
            just,
        )?;
        plots.push(("Stage times and MSE".to_string(), stages_png));
        if just
            .iter()
            .any(|r| r.cluster.sp_clusters > 0 && r.cluster.vpl_clusters > 0)
        {
            let grid_png = format!("grid{suffix}.png");
            plot::grid(
                &out.join(&grid_png),
                &title("time and MSE over K_sp / K_vpl"),
                just,
            )?;
            plots.push(("SP × VPL clusters: time against MSE".to_string(), grid_png));
        }
        let pareto_png = format!("pareto{suffix}.png");
        plot::pareto(
            &out.join(&pareto_png),
            &title("time against MSE by mode, Pareto front"),
            just,
        )?;
        plots.push((
            "Modes: Pareto front of time and MSE".to_string(),
            pareto_png,
        ));
        if just
            .iter()
            .any(|r| r.method.method != just[0].method.method)
        {
            let methods_png = format!("methods{suffix}.png");
            plot::methods(
                &out.join(&methods_png),
                &title("methods: indirect-light time against MSE, each method's front"),
                just,
            )?;
            plots.push((
                "Methods: each one's Pareto front of indirect time and MSE".to_string(),
                methods_png,
            ));
        }
        self.files.extend(plots.iter().map(|p| out.join(&p.1)));
        Ok(plots)
    }
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
