//! The bench plots, drawn with `plotters` into an RGB buffer and written as PNG by `export`.
//!
//! Text uses `ab_glyph` with the Ubuntu Light font embedded by the `epaint_default_fonts` crate
//! (Ubuntu Font Licence 1.0; the crate is egui's own font package), so no system font is needed.

use std::path::Path;
use std::sync::Once;

use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::prelude::*;

use super::csv::Row;
use crate::export;
use crate::method::Method;

pub const WIDTH: u32 = 960;
pub const HEIGHT: u32 = 540;

pub fn register_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let bytes = epaint_default_fonts::UBUNTU_LIGHT;
        if plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_err() {
            log::warn!("plot font did not load; labels will be missing");
        }
    });
}

/// Colour of a mode, the same in every plot.
pub fn mode_colour(mode: &str) -> RGBColor {
    match mode {
        "hard" => RGBColor(214, 39, 40),
        "uniform" => RGBColor(255, 127, 14),
        "weighted" => RGBColor(31, 119, 180),
        "vpl-only" => RGBColor(44, 160, 44),
        "sp-only" => RGBColor(148, 103, 189),
        m => match crate::method::REGISTRY
            .iter()
            .find(|r| r.method.name() == m)
        {
            Some(r) => RGBColor(r.colour[0], r.colour[1], r.colour[2]),
            None => RGBColor(90, 90, 90),
        },
    }
}

/// The frame's stages as drawn in the stacked bars (the rest of `frame` is drawn as "other").
const BAR_STAGES: &[(&str, RGBColor)] = &[
    ("primary", RGBColor(160, 160, 160)),
    ("direct", RGBColor(230, 200, 80)),
    ("sp_cluster", RGBColor(31, 119, 180)),
    ("visibility", RGBColor(214, 39, 40)),
    ("shade", RGBColor(255, 187, 120)),
    ("gather", RGBColor(44, 160, 44)),
];

/// Indices of the Pareto-optimal points when both coordinates are minimised (time, error), sorted by
/// the first. Non-finite points are never on the front; of equal points only the first is.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].0.is_finite() && points[i].1.is_finite())
        .collect();
    idx.sort_by(|&a, &b| {
        points[a]
            .0
            .total_cmp(&points[b].0)
            .then(points[a].1.total_cmp(&points[b].1))
            .then(a.cmp(&b))
    });
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in idx {
        if points[i].1 < best {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

/// The series' legend at `position`, on a light box.
fn legend<'a, DB, X, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    position: SeriesLabelPosition,
) -> Result<()>
where
    DB: DrawingBackend + 'a,
    X: plotters::coord::ranged1d::Ranged,
    Y: plotters::coord::ranged1d::Ranged,
{
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()
        .map_err(plot_err)
}

/// The builder of a time-against-MSE chart: its title, margin and label areas.
fn time_mse_chart<'a, 'b, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
) -> ChartBuilder<'a, 'b, DB> {
    let mut b = ChartBuilder::on(root);
    b.caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70);
    b
}

fn plot_err(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow!("plot: {e}")
}

/// Draws into a white RGB canvas and writes it as PNG.
fn render_png(
    path: &Path,
    draw: impl FnOnce(&DrawingArea<BitMapBackend<'_>, Shift>) -> Result<()>,
) -> Result<()> {
    register_fonts();
    let mut buf = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        draw(&root)?;
        root.present().map_err(plot_err)?;
    }
    export::write_png_rgb8(path, WIDTH, HEIGHT, buf)
}

/// A log-scale range covering `v` (positive values; others are clamped to a floor).
fn log_range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for x in v.filter(|x| x.is_finite()) {
        let x = x.max(1e-12);
        lo = lo.min(x);
        hi = hi.max(x);
    }
    if !(lo.is_finite() && hi > 0.0) {
        return (1e-6, 1.0);
    }
    (lo / 2.0, hi * 2.0)
}

fn max_of(v: impl Iterator<Item = f64>) -> f64 {
    v.filter(|x| x.is_finite()).fold(0.0, f64::max).max(1e-6)
}

fn sci(v: &f64) -> String {
    format!("{v:.0e}")
}

/// (a) Stacked GPU stage times per configuration, the MSE as a line on the right axis (Figs. 7, 9).
pub fn stages(path: &Path, title: &str, rows: &[Row]) -> Result<()> {
    let n = rows.len();
    // Headroom above the bars for the legend.
    let tmax = max_of(rows.iter().map(Row::frame_ms)) * 1.6;
    let (mlo, mhi) = log_range(rows.iter().map(|r| r.mse));
    let labels: Vec<String> = rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            if n <= 8 {
                r.label.clone()
            } else if n <= 16 {
                format!("{} {}", &r.mode[..1], short(r))
            } else {
                format!("#{}", i + 1)
            }
        })
        .collect();
    render_png(path, |root| {
        let x_range = -0.5f64..n as f64 - 0.5;
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(64)
            .right_y_label_area_size(70)
            .build_cartesian_2d(x_range.clone(), 0.0..tmax)
            .map_err(plot_err)?
            .set_secondary_coord(x_range, (mlo..mhi).log_scale());
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(n.max(1))
            .x_label_formatter(&|x| {
                let i = x.round();
                if (x - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < labels.len() {
                    labels[i as usize].clone()
                } else {
                    String::new()
                }
            })
            .y_desc("GPU time per frame (ms)")
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(plot_err)?;
        chart
            .configure_secondary_axes()
            .y_desc("MSE")
            .y_label_formatter(&sci)
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(plot_err)?;
        let mut base = vec![0.0f64; n];
        let mut layers: Vec<(String, RGBColor, Vec<f64>)> = BAR_STAGES
            .iter()
            .map(|(s, c)| (s.to_string(), *c, rows.iter().map(|r| r.stage(s)).collect()))
            .collect();
        let other: Vec<f64> = rows
            .iter()
            .map(|r| {
                let known: f64 = BAR_STAGES.iter().map(|(s, _)| r.stage(s)).sum();
                (r.frame_ms() - known).max(0.0)
            })
            .collect();
        layers.push(("other".into(), RGBColor(120, 120, 200), other));
        for (name, colour, vals) in layers {
            if vals.iter().all(|v| *v <= 0.0) {
                continue;
            }
            let rects: Vec<Rectangle<(f64, f64)>> = vals
                .iter()
                .enumerate()
                .map(|(i, v)| {
                    let (x, y0) = (i as f64, base[i]);
                    base[i] += v;
                    Rectangle::new([(x - 0.35, y0), (x + 0.35, y0 + v)], colour.filled())
                })
                .collect();
            chart
                .draw_series(rects)
                .map_err(plot_err)?
                .label(name)
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 12, y + 5)], colour.filled())
                });
        }
        let purple = RGBColor(128, 0, 160);
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .enumerate()
            .map(|(i, r)| (i as f64, r.mse.max(1e-12)))
            .collect();
        chart
            .draw_secondary_series(LineSeries::new(pts.clone(), purple.stroke_width(2)))
            .map_err(plot_err)?
            .label("MSE (right axis)")
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 12, y)], purple.stroke_width(2))
            });
        chart
            .draw_secondary_series(pts.iter().map(|p| Circle::new(*p, 4, purple.filled())))
            .map_err(plot_err)?;
        legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
        Ok(())
    })
}

/// Time (x) against MSE (log y), coloured by mode, each point labelled by `label(row)`; with
/// `front`, the Pareto front over all points is drawn as a line with rings.
fn scatter(
    path: &Path,
    title: &str,
    rows: &[&Row],
    label: impl Fn(&Row) -> String,
    front: bool,
) -> Result<()> {
    let tmax = max_of(rows.iter().map(|r| r.frame_ms())) * 1.15;
    let (mlo, mhi) = log_range(rows.iter().map(|r| r.mse));
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| (r.frame_ms(), r.mse.max(1e-12)))
        .collect();
    render_png(path, |root| {
        let mut chart = time_mse_chart(root, title)
            .build_cartesian_2d(0.0..tmax, (mlo..mhi).log_scale())
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc("GPU time per frame (ms)")
            .y_desc("MSE")
            .y_label_formatter(&sci)
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(plot_err)?;
        if front {
            let f = pareto_front(&pts);
            let line: Vec<(f64, f64)> = f.iter().map(|&i| pts[i]).collect();
            chart
                .draw_series(LineSeries::new(line.clone(), BLACK.stroke_width(2)))
                .map_err(plot_err)?
                .label("Pareto front")
                .legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 12, y)], BLACK.stroke_width(2))
                });
            chart
                .draw_series(
                    line.iter()
                        .map(|p| Circle::new(*p, 9, BLACK.stroke_width(2))),
                )
                .map_err(plot_err)?;
        }
        let mut modes: Vec<&str> = Vec::new();
        for r in rows {
            if !modes.contains(&r.mode.as_str()) {
                modes.push(&r.mode);
            }
        }
        for m in modes {
            let c = mode_colour(m);
            let sel: Vec<(f64, f64)> = rows
                .iter()
                .zip(&pts)
                .filter(|(r, _)| r.mode == m)
                .map(|(_, p)| *p)
                .collect();
            chart
                .draw_series(sel.iter().map(|p| Circle::new(*p, 5, c.filled())))
                .map_err(plot_err)?
                .label(m)
                .legend(move |(x, y)| Circle::new((x + 6, y), 5, c.filled()));
        }
        chart
            .draw_series(rows.iter().zip(&pts).map(|(r, p)| {
                EmptyElement::at(*p)
                    + Text::new(
                        label(r),
                        (7, -14),
                        ("sans-serif", 12).into_font().color(&BLACK),
                    )
            }))
            .map_err(plot_err)?;
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    })
}

/// (b) Time against MSE over the SP × VPL cluster grid (rows that cluster both), labelled
/// K_sp/K_vpl (Fig. 11 as a scatter).
pub fn grid(path: &Path, title: &str, rows: &[Row]) -> Result<()> {
    let sel: Vec<&Row> = rows
        .iter()
        .filter(|r| r.cluster.sp_clusters > 0 && r.cluster.vpl_clusters > 0)
        .collect();
    scatter(
        path,
        title,
        &sel,
        |r| format!("{}/{}", r.cluster.sp_clusters, r.cluster.vpl_clusters),
        false,
    )
}

/// (c) Every configuration by mode, with the Pareto front of time and MSE.
pub fn pareto(path: &Path, title: &str, rows: &[Row]) -> Result<()> {
    let sel: Vec<&Row> = rows.iter().collect();
    scatter(path, title, &sel, short, true)
}

/// Colour of a method in `methods.png`: the method whose knobs are the paper's `ClusterSettings`
/// (`MethodEntry::own_settings` false) takes its default mode's ("weighted"), the others their `mode`
/// column's (the method's name: its entry's `colour`).
pub fn method_colour(method: Method) -> RGBColor {
    match crate::method::entry(method).own_settings {
        true => mode_colour(method.name()),
        false => mode_colour("weighted"),
    }
}

/// (d) The methods side by side (docs/methods.md): each configuration's indirect-light time
/// (`indirect_ms`: the frame less primary rays and direct light, what the methods differ in)
/// against its MSE, each method's own Pareto front as a line in its colour.
pub fn methods(path: &Path, title: &str, rows: &[Row]) -> Result<()> {
    // Log time: the methods' times differ by orders of magnitude.
    let (tlo, thi) = log_range(rows.iter().map(|r| r.indirect_ms.max(1e-3)));
    let (mlo, mhi) = log_range(rows.iter().map(|r| r.mse));
    let mut names: Vec<Method> = Vec::new();
    for r in rows {
        if !names.contains(&r.method.method) {
            names.push(r.method.method);
        }
    }
    render_png(path, |root| {
        let mut chart = time_mse_chart(root, title)
            .build_cartesian_2d((tlo..thi).log_scale(), (mlo..mhi).log_scale())
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc("indirect light: GPU ms per frame (frame - primary - direct), log")
            .y_desc("MSE")
            .y_label_formatter(&sci)
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(plot_err)?;
        for &m in &names {
            let c = method_colour(m);
            let sel: Vec<&Row> = rows.iter().filter(|r| r.method.method == m).collect();
            let pts: Vec<(f64, f64)> = sel
                .iter()
                .map(|r| (r.indirect_ms.max(1e-3), r.mse.max(1e-12)))
                .collect();
            let line: Vec<(f64, f64)> = pareto_front(&pts).iter().map(|&i| pts[i]).collect();
            chart
                .draw_series(LineSeries::new(line, c.stroke_width(2)))
                .map_err(plot_err)?;
            chart
                .draw_series(pts.iter().map(|p| Circle::new(*p, 5, c.filled())))
                .map_err(plot_err)?
                .label(m.name())
                .legend(move |(x, y)| Circle::new((x + 6, y), 5, c.filled()));
            chart
                .draw_series(sel.iter().zip(&pts).map(|(r, p)| {
                    EmptyElement::at(*p)
                        + Text::new(
                            r.label.clone(),
                            (7, -14),
                            ("sans-serif", 12).into_font().color(&BLACK),
                        )
                }))
                .map_err(plot_err)?;
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    })
}

/// `48/128`: K_sp/K_vpl, `all` where not clustered (every pixel or every VPL).
fn short(r: &Row) -> String {
    let k = |v: u32| {
        if v == 0 {
            "all".to_string()
        } else {
            v.to_string()
        }
    };
    let p = if r.cluster.weight_exponent != 1.0 && matches!(r.mode.as_str(), "weighted" | "sp-only")
    {
        format!(" p{}", r.cluster.weight_exponent)
    } else {
        String::new()
    };
    format!(
        "{}/{}{p}",
        k(r.cluster.sp_clusters),
        k(r.cluster.vpl_clusters)
    )
}

#[cfg(test)]
mod tests {
    use super::super::csv::tests::synthetic;
    use super::*;

    #[test]
    fn pareto_front_minimises_both() {
        let p = [
            (1.0, 5.0),
            (2.0, 3.0),
            (2.5, 4.0), // dominated by (2, 3)
            (3.0, 1.0),
            (0.5, 9.0),
            (3.0, 1.0), // a duplicate: only the first is on the front
            (f64::NAN, 0.0),
            (4.0, 1.0), // same error, slower
        ];
        assert_eq!(pareto_front(&p), vec![4, 0, 1, 3]);
        assert!(pareto_front(&[]).is_empty());
        assert_eq!(pareto_front(&[(1.0, 1.0)]), vec![0]);
    }

    /// Each method's colour in `methods.png`: a method with knobs of its own its entry's `colour`, the
    /// paper's (the default) the weighted mode's; no two methods share one.
    #[test]
    fn method_colours_are_the_entries() {
        let mut seen = Vec::new();
        for r in crate::method::REGISTRY {
            let c = method_colour(r.method);
            match r.own_settings {
                true => assert_eq!(c, RGBColor(r.colour[0], r.colour[1], r.colour[2])),
                false => assert_eq!(c, mode_colour("weighted")),
            }
            assert!(!seen.contains(&c), "{} shares its colour", r.method);
            seen.push(c);
        }
        assert!(!crate::method::entry(Method::default()).own_settings);
    }

    #[test]
    fn plots_write_decodable_non_flat_pngs() {
        let d = std::env::temp_dir().join(format!("fuzzy-vpl-plot-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let mut rows = Vec::new();
        for m in ["hard", "uniform", "weighted"] {
            for sp in [48, 96] {
                rows.push(synthetic(m, sp, 128));
            }
        }
        rows.push(synthetic("vpl-only", 0, 128));
        let files = [
            (
                "stages.png",
                stages as fn(&Path, &str, &[Row]) -> Result<()>,
            ),
            ("grid.png", grid),
            ("pareto.png", pareto),
            ("methods.png", methods),
        ];
        for (name, f) in files {
            let p = d.join(name);
            f(&p, "synthetic", &rows).unwrap();
            let img = image::open(&p).unwrap().into_rgb8();
            assert_eq!(img.dimensions(), (WIDTH, HEIGHT), "{name}");
            let px: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
            let distinct: std::collections::HashSet<[u8; 3]> = px.iter().copied().collect();
            assert!(
                distinct.len() > 8,
                "{name}: only {} colours",
                distinct.len()
            );
            let white = px.iter().filter(|p| **p == [255, 255, 255]).count();
            assert!(white < px.len() * 99 / 100, "{name}: almost blank");
            // The mode colours are drawn.
            let blue = mode_colour("weighted");
            assert!(
                px.contains(&[blue.0, blue.1, blue.2]),
                "{name}: no weighted points"
            );
        }
        // Labels need no system font: the embedded one is registered and measures text.
        let (w, _) = ("sans-serif", 12).into_font().box_size("MSE").unwrap();
        assert!(w > 10, "{w}");
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn plots_survive_degenerate_rows() {
        let d = std::env::temp_dir().join(format!("fuzzy-vpl-plot0-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let mut r = synthetic("weighted", 48, 128);
        r.mse = 0.0;
        r.stages_mut().into_iter().for_each(|(_, v)| *v = 0.0);
        for rows in [vec![], vec![r]] {
            stages(&d.join("s.png"), "t", &rows).unwrap();
            grid(&d.join("g.png"), "t", &rows).unwrap();
            pareto(&d.join("p.png"), "t", &rows).unwrap();
        }
        let _ = std::fs::remove_dir_all(&d);
    }
}
