//! `summary.md`: the machine, the method, the plots and a table of the rows.

use std::fmt::Write;

use super::csv::Row;
use super::plot::pareto_front;

/// What the summary states besides the rows.
pub struct SummaryInfo<'a> {
    pub scene: &'a str,
    pub adapter: &'a str,
    pub driver: &'a str,
    /// A software driver (lavapipe): its times say little about a GPU's, and the summary says so.
    pub software: bool,
    pub warmup_ms: f64,
    pub width: u32,
    pub height: u32,
    pub vpls: u32,
    pub seed: u32,
    pub repeat: u32,
    pub reference_repeat: u32,
    /// Per camera: its name, the reference frame time (ms), the reference image's file name,
    /// the plot files (relative to the summary) and the rows' image files (image, error map).
    pub cameras: Vec<CameraSummary>,
    pub wall_s: f64,
}

pub struct CameraSummary {
    pub camera: String,
    pub reference_ms: f64,
    pub reference_image: String,
    /// With `--paper off,on`: the paper's reference (no clamp), its frame time and image.
    pub paper_reference: Option<(f64, String)>,
    pub plots: Vec<(String, String)>,
    pub rows: Vec<(Row, String, String)>,
}

/// A time in ms as tables show it: "–" for 0, two decimals below 10, one above.
pub(crate) fn fmt_ms(v: f64) -> String {
    if v == 0.0 {
        "–".into()
    } else if v < 10.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.1}")
    }
}

pub fn markdown(s: &SummaryInfo) -> String {
    let mut m = String::new();
    let _ = writeln!(m, "# fuzzy-vpl bench: `{}`\n", s.scene);
    let _ = writeln!(
        m,
        "- adapter: **{}**, driver {}{}\n- {}×{} pixels, {} VPLs, seed {}\n- times are **GPU timestamp** durations \
         (wgpu timestamp queries, summed per pass), each the **mean of the 3 best of {}** runs (the \
         paper's method); the references are timed the same way over {} run(s); before each \
         configuration's and reference's timed runs the GPU is kept busy for {} ms (clock warm-up; \
         on a GPU adapter after one untimed render)\n- `frame` is the whole \
         per-frame GPU time (primary rays, direct light, SP clustering, visibility, shading or gather); \
         VPL tracing and VPL clustering are resident work, built once per setting and listed apart\n\
         - speedup = reference frame time ÷ configuration frame time; MSE is the paper's (RGB clamped \
         to [0, 1]) against the unclustered reference, rel. MSE is (x − ref)² / (ref² + 0.01)\n\
         - the sweep took {:.0} s of wall time\n",
        s.adapter,
        s.driver,
        if s.software {
            " — **a software driver (CPU)**: these times say little about a GPU's"
        } else {
            ""
        },
        s.width,
        s.height,
        s.vpls,
        s.seed,
        s.repeat,
        s.reference_repeat,
        s.warmup_ms,
        s.wall_s
    );
    for c in &s.cameras {
        let _ = writeln!(
            m,
            "## Camera {}\n\nReference (every pixel × every VPL, no clustering): **{} ms** per frame, \
             image [`{}`]({}).\n",
            c.camera,
            fmt_ms(c.reference_ms),
            c.reference_image,
            c.reference_image
        );
        if let Some((ms, img)) = &c.paper_reference {
            let _ = writeln!(
                m,
                "The `paper` rows' reference (`--paper`: no G-term clamp): **{} ms** per frame, \
                 image [`{img}`]({img}).\n",
                fmt_ms(*ms)
            );
        }
        for (title, file) in &c.plots {
            let _ = writeln!(m, "### {title}\n\n![{title}]({file})\n");
        }
        let pts: Vec<(f64, f64)> = c.rows.iter().map(|r| (r.0.frame_ms(), r.0.mse)).collect();
        let front = pareto_front(&pts);
        let _ = writeln!(
            m,
            "| # | mode | K_sp | K_vpl | F | γ | frame ms | SP clustering | visibility | shade | gather \
             | VPL clustering (resident) | speedup | MSE | rel. MSE | FLIP | border ratio | SP / VPL clusters used | shadow rays \
             | image |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
        );
        for (i, (r, img, err)) in c.rows.iter().enumerate() {
            let star = if front.contains(&i) { " ★" } else { "" };
            let _ = writeln!(
                m,
                "| {} | {}{} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.1}× | {:.3e} | {:.3e} | {} | {} \
                 | {} / {} | {} | [png]({}) · [error]({}) |",
                i + 1,
                r.mode,
                star,
                r.cluster.sp_clusters,
                r.cluster.vpl_clusters,
                r.cluster.fuzziness,
                gamma_cell(r),
                fmt_ms(r.frame_ms()),
                fmt_ms(r.stage("sp_cluster")),
                fmt_ms(r.stage("visibility")),
                fmt_ms(r.stage("shade")),
                fmt_ms(r.stage("gather")),
                fmt_ms(r.stage("vpl_cluster")),
                r.speedup,
                r.mse,
                r.rel_mse,
                r.flip.map_or("–".to_string(), |f| format!("{f:.4}")),
                r.border_ratio
                    .map_or("–".to_string(), |b| format!("{b:.2}")),
                r.sp_clusters_used,
                r.vpl_clusters_used,
                r.shadow_rays,
                img,
                err
            );
        }
        let _ = writeln!(
            m,
            "\n★ = on the Pareto front of frame time and MSE. K = 0 means not clustered; F = 1 for hard; \
             γ as asked → as used (at most pixels / K_sp), – where no SP clustering ran. A label's \
             \"(K_sp off)\" or \"(K_vpl off)\": that K was not below the pixel or VPL count, so that \
             clustering did not run.\n"
        );
    }
    let _ = writeln!(
        m,
        "All rows are in [`results.csv`](results.csv). On a software driver (lavapipe) absolute times \
         are only comparable within one run; the ratios (speedup) are what carries over."
    );
    m
}

/// The γ column: the γ asked, "asked → used" where Alg. 1 sampled with less (γ at most pixels /
/// K_sp), "–" where no SP clustering ran.
fn gamma_cell(r: &Row) -> String {
    match r.gamma_used {
        None => "–".into(),
        Some(g) if r.cluster.gamma != crate::settings::Gamma::Fixed(g) => {
            format!("{} → {g}", r.cluster.gamma)
        }
        Some(g) => g.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::super::csv::tests::synthetic;
    use super::*;

    #[test]
    fn summary_embeds_plots_and_states_the_method() {
        let rows = vec![
            (
                synthetic("hard", 48, 128),
                "a.png".into(),
                "a_err.png".into(),
            ),
            (
                synthetic("weighted", 48, 128),
                "b.png".into(),
                "b_err.png".into(),
            ),
        ];
        let s = SummaryInfo {
            scene: "builtin:cornell",
            adapter: "llvmpipe (LLVM 19, 256 bits)",
            driver: "llvmpipe Mesa 25.0",
            software: true,
            warmup_ms: 200.0,
            width: 96,
            height: 72,
            vpls: 1024,
            seed: 1,
            repeat: 3,
            reference_repeat: 1,
            cameras: vec![CameraSummary {
                camera: "default".into(),
                reference_ms: 50.0,
                reference_image: "reference.exr".into(),
                paper_reference: None,
                plots: vec![("Stage times".into(), "stages.png".into())],
                rows,
            }],
            wall_s: 12.0,
        };
        let md = markdown(&s);
        assert!(md.contains("llvmpipe"));
        assert!(
            md.contains("driver llvmpipe Mesa 25.0 — **a software driver"),
            "{md}"
        );
        let md = markdown(&SummaryInfo {
            software: false,
            ..s
        });
        assert!(!md.contains("a software driver (CPU)"), "{md}");
        assert!(md.contains("![Stage times](stages.png)"));
        assert!(md.contains("mean of the 3 best of 3"));
        assert!(md.contains("GPU timestamp"));
        assert_eq!(md.lines().filter(|l| l.starts_with("| 1 |")).count(), 1);
        assert!(md.contains("weighted ★"));
    }
}
