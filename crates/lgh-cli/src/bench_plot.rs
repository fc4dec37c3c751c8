//! The plot of `lgh bench quality`: error against time, log-log, one column per scene, FLIP
//! above and rel_rmse below, one curve per series, or with fronts (the equal-time plot) one
//! bold curve per method, its lowest error within each time over all of its series, over
//! its series drawn thin (plotters, drawn into memory and written as PNG). Text needs a
//! TrueType font: DejaVu Sans from the system (Debian's `fonts-dejavu-core`), or the file
//! `LGH_FONT` names; without one the plot has no labels.

use std::path::Path;

use anyhow::{Result, anyhow, bail};
use plotters::prelude::*;

use crate::bench_quality::Point;

/// True if `v` is 1, 2 or 5 times a power of ten.
fn is_125(v: f64) -> bool {
    let lead = v / 10f64.powf(v.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .iter()
        .any(|d| (lead - d).abs() < 1e-6 * d)
}

/// How many values 1, 2 or 5 times a power of ten lie in [`lo`, `hi`] (positive).
fn leading_125_within(lo: f64, hi: f64) -> usize {
    if !(lo > 0.0 && hi >= lo && hi.is_finite()) {
        return 0;
    }
    let mut n = 0;
    let mut decade = 10f64.powf(lo.log10().floor());
    while decade <= hi {
        n += [1.0, 2.0, 5.0]
            .iter()
            .filter(|&&d| (lo..=hi).contains(&(d * decade)))
            .count();
        decade *= 10.0;
    }
    n
}

/// A log axis's label for `v` with `decimals` places. With `sparse`, only values 1, 2 or 5
/// times a power of ten are labelled: the ticks of a log axis crowd at the top of each
/// decade, where every label would overlap its neighbours (an axis spanning fewer than two
/// such values labels every tick).
fn decade_label(v: f64, decimals: usize, sparse: bool) -> String {
    if !(v.is_finite() && v > 0.0) || (sparse && !is_125(v)) {
        return String::new();
    }
    format!("{v:.decimals$}")
}

/// Where to look for a font.
const FONTS: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
];

/// Registers a font for plotters' text once; false if none was found.
fn register_font() -> bool {
    static FOUND: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *FOUND.get_or_init(|| {
        let candidates = std::env::var("LGH_FONT")
            .into_iter()
            .chain(FONTS.map(String::from));
        for path in candidates {
            if let Ok(bytes) = std::fs::read(&path) {
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                if plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok() {
                    return true;
                }
            }
        }
        false
    })
}

/// Checks that the plot can be written there (a .png in an existing folder).
///
/// # Errors
/// Another extension, or a missing folder.
pub fn check_plot_path(path: &Path) -> Result<()> {
    if !path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"))
    {
        bail!("{}: the plot is a PNG (.png)", path.display());
    }
    lgh_render::output::check_output(path)?;
    Ok(())
}

/// Colours of the curves, by order of first appearance.
const COLOURS: [RGBColor; 12] = [
    RGBColor(214, 39, 40),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
    RGBColor(127, 127, 127),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
    RGBColor(0, 0, 128),
    RGBColor(0, 0, 0),
];

/// The lowest error reachable within each time: of the (ms, error) points, those whose
/// error is below that of every faster point, by time, as a staircase (each point's error
/// holds until the next point's time).
#[must_use]
pub fn front(points: impl IntoIterator<Item = (f64, f64)>) -> Vec<(f64, f64)> {
    let mut all: Vec<(f64, f64)> = points.into_iter().collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut steps: Vec<(f64, f64)> = Vec::new();
    for (ms, e) in all {
        match steps.last() {
            Some(&(_, best)) if e >= best => {}
            Some(&(_, best)) => steps.extend([(ms, best), (ms, e)]),
            None => steps.push((ms, e)),
        }
    }
    steps
}

/// Draws the plot of `points` for `scenes` into `path`: one curve per series, or, where
/// `fronts` names methods, one bold [`front`] per method over its series drawn thin (a
/// series belongs to the method its name starts with, as the equal-time table counts it).
///
/// # Errors
/// Drawing fails, or the file cannot be written.
pub fn plot(path: &Path, scenes: &[String], points: &[Point], fronts: &[&str]) -> Result<()> {
    let text = register_font();
    let (cw, ch) = (420u32, 320u32);
    let mut series: Vec<&str> = Vec::new();
    for p in points {
        if !series.contains(&p.series.as_str()) && p.ms > 0.0 && p.flip > 0.0 {
            series.push(&p.series);
        }
    }
    // The legend's names and the colour of each series (its method's where fronts are drawn).
    let method_of = |name: &str| {
        fronts
            .iter()
            .position(|m| crate::bench_equal_time::of_method(name, m))
    };
    let names: Vec<&str> = if fronts.is_empty() {
        series.clone()
    } else {
        fronts.to_vec()
    };
    let colour_of = |i: usize, name: &str| {
        let at = if fronts.is_empty() {
            Some(i)
        } else {
            method_of(name)
        };
        at.map(|k| COLOURS[k % COLOURS.len()])
    };
    // Room for every curve's name in the legend.
    let w = (cw * scenes.len().max(1) as u32).max(170 * names.len().max(8) as u32);
    let h = 2 * ch + 40;
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let (legend, body) = root.split_vertically(40);
        if text {
            for (i, name) in names.iter().enumerate() {
                let x = 10 + 170 * i as i32;
                let c = COLOURS[i % COLOURS.len()];
                legend
                    .draw(&Rectangle::new([(x, 14), (x + 20, 24)], c.filled()))
                    .map_err(|e| anyhow!("plot: {e}"))?;
                legend
                    .draw(&Text::new(
                        name.to_string(),
                        (x + 26, 12),
                        ("sans-serif", 14),
                    ))
                    .map_err(|e| anyhow!("plot: {e}"))?;
            }
        }
        if text && !fronts.is_empty() {
            legend
                .draw(&Text::new(
                    "bold: each method's lowest error within each time; thin: its curves",
                    (10 + 170 * names.len() as i32, 12),
                    ("sans-serif", 14),
                ))
                .map_err(|e| anyhow!("plot: {e}"))?;
        }
        let rows = body.split_evenly((2, scenes.len().max(1)));
        for (k, area) in rows.iter().enumerate() {
            let (row, col) = (k / scenes.len().max(1), k % scenes.len().max(1));
            let Some(scene) = scenes.get(col) else {
                continue;
            };
            let metric = |p: &Point| if row == 0 { p.flip } else { p.rel_rmse };
            let pts: Vec<&Point> = points
                .iter()
                .filter(|p| &p.scene == scene && p.ms > 0.0 && metric(p) > 0.0)
                .collect();
            if pts.is_empty() {
                continue;
            }
            let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, 0.0f64, f64::MAX, 0.0f64);
            for p in &pts {
                (x0, x1) = (x0.min(p.ms), x1.max(p.ms));
                (y0, y1) = (y0.min(metric(p)), y1.max(metric(p)));
            }
            let caption = format!("{scene}: {}", if row == 0 { "FLIP" } else { "rel_rmse" });
            // The axes' ranges: a margin around the points.
            let (xs, ys) = ((x0 * 0.8, x1 * 1.25), (y0 * 0.8, y1 * 1.25));
            let mut builder = ChartBuilder::on(area);
            builder.margin(8);
            if text {
                builder
                    .caption(caption, ("sans-serif", 16))
                    .x_label_area_size(30)
                    .y_label_area_size(48);
            }
            let mut chart = builder
                .build_cartesian_2d((xs.0..xs.1).log_scale(), (ys.0..ys.1).log_scale())
                .map_err(|e| anyhow!("plot: {e}"))?;
            let (x_sparse, y_sparse) = (
                leading_125_within(xs.0, xs.1) >= 2,
                leading_125_within(ys.0, ys.1) >= 2,
            );
            let x_label = |v: &f64| decade_label(*v, 0, x_sparse);
            let y_label = |v: &f64| decade_label(*v, 3, y_sparse);
            let mut mesh = chart.configure_mesh();
            if text {
                mesh.x_desc("ms (VPL generation + indirect light)")
                    .y_desc(if row == 0 { "FLIP" } else { "rel_rmse" })
                    .x_label_formatter(&x_label)
                    .y_label_formatter(&y_label)
                    .label_style(("sans-serif", 12));
            } else {
                mesh.disable_x_axis().disable_y_axis();
            }
            mesh.draw().map_err(|e| anyhow!("plot: {e}"))?;
            for (i, name) in series.iter().enumerate() {
                let Some(c) = colour_of(i, name) else {
                    continue;
                };
                let mut curve: Vec<(f64, f64)> = pts
                    .iter()
                    .filter(|p| p.series == *name)
                    .map(|p| (p.ms, metric(p)))
                    .collect();
                curve.sort_by(|a, b| a.0.total_cmp(&b.0));
                // Under fronts, each series thin and pale.
                let (line, dot) = if fronts.is_empty() {
                    (c.stroke_width(2), c.filled())
                } else {
                    (c.mix(0.3).stroke_width(1), c.mix(0.3).filled())
                };
                let r = if fronts.is_empty() { 3 } else { 2 };
                chart
                    .draw_series(LineSeries::new(curve.clone(), line))
                    .map_err(|e| anyhow!("plot: {e}"))?;
                chart
                    .draw_series(curve.iter().map(|&p| Circle::new(p, r, dot)))
                    .map_err(|e| anyhow!("plot: {e}"))?;
            }
            for (k, method) in fronts.iter().enumerate() {
                let c = COLOURS[k % COLOURS.len()];
                let steps = front(
                    pts.iter()
                        .filter(|p| crate::bench_equal_time::of_method(&p.series, method))
                        .map(|p| (p.ms, metric(p))),
                );
                chart
                    .draw_series(LineSeries::new(steps, c.stroke_width(3)))
                    .map_err(|e| anyhow!("plot: {e}"))?;
            }
        }
        root.present().map_err(|e| anyhow!("plot: {e}"))?;
    }
    lgh_render::image::save_png(path, w, h, &buf)?;
    if !text {
        eprintln!(
            "note: no font found for the plot's labels (install fonts-dejavu-core or set LGH_FONT)"
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{decade_label, front, leading_125_within};

    /// The front keeps only points that lower the error, as a staircase, whatever their
    /// order.
    #[test]
    fn the_front_is_the_best_error_within_each_time() {
        let pts = [
            (200.0, 0.05),
            (50.0, 0.1),
            (100.0, 0.12),
            (400.0, 0.06),
            (300.0, 0.04),
        ];
        assert_eq!(
            front(pts),
            [
                (50.0, 0.1),
                (200.0, 0.1),
                (200.0, 0.05),
                (300.0, 0.05),
                (300.0, 0.04)
            ]
        );
        assert!(front([]).is_empty());
        // Equal times: the lower error counts.
        assert_eq!(front([(10.0, 0.2), (10.0, 0.1)]), [(10.0, 0.1)]);
    }

    /// Only 1, 2 and 5 times a power of ten are labelled, unless the axis has fewer than two.
    #[test]
    fn log_axis_labels_skip_the_crowded_ticks() {
        assert_eq!(decade_label(100.0, 0, true), "100");
        assert_eq!(decade_label(200.0, 0, true), "200");
        assert_eq!(decade_label(500.0, 0, true), "500");
        assert_eq!(decade_label(0.05, 3, true), "0.050");
        assert_eq!(decade_label(0.01, 3, true), "0.010");
        for v in [300.0, 400.0, 700.0, 0.06, 0.07, 0.0, -1.0, f64::NAN] {
            assert_eq!(decade_label(v, 3, true), "", "{v}");
        }
        // An axis with one such value or none labels every tick.
        assert_eq!(decade_label(0.07, 3, false), "0.070");
        assert_eq!(leading_125_within(0.06, 0.09), 0);
        assert_eq!(leading_125_within(0.04, 0.11), 2);
        assert_eq!(leading_125_within(8.0, 600.0), 6);
        assert_eq!(leading_125_within(0.0, 1.0), 0);
    }
}
