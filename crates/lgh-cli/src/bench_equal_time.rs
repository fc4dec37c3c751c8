//! `lgh bench quality --equal-time`: for a time budget, which method gives the image closest
//! to the converged result? Each method renders the indirect light at a sweep of VPL counts;
//! every image is measured against a converged reference (the mean of many brute-force
//! frames, each with its own VPL set and sub-pixel position, so that VPL noise counts as
//! error); each method is then taken at its best VPL count within each budget.
//!
//! References are cached as EXR (`--reference-dir`, or one file per scene with
//! `--reference`), with the mean of the first half of their frames beside them
//! (`NAME.half.exr`): the FLIP between the two says how far the reference is from converged.

use std::path::PathBuf;

use anyhow::{Result, bail};
use lgh_core::rng::hash;
#[cfg(doc)]
use lgh_render::accumulate::frame_seed;
use lgh_render::methods::lgh::LGH;
use lgh_render::methods::slc::SLC;
use lgh_render::{Image, RenderSettings, World};

use crate::bench_cmd::open_scene;
use crate::bench_quality::{Point, QualityBenchArgs, indirect_only, measure, ms, render};
use crate::bench_reference::{print_references, reference, settings_json};

/// The curves of the sweep: (series name, the method it belongs to, settings without the
/// VPL count), at each of `--vpl-clamps`: lgh at each of `--alphas` x `--interleaves` x
/// `--shadow-samples`, slc at each of `--error-bounds` x `--shadow-samples`. A curve is
/// named after its method and the settings where it departs from the method's defaults
/// (`lgh`, `lgh alpha 2 n=4 k=3`, `slc k=3 c=2`).
fn curves(args: &QualityBenchArgs) -> Vec<(String, &'static str, RenderSettings)> {
    let base = indirect_only(args.size, 0);
    // None: the method's own number of shadow samples.
    let ks: Vec<Option<u32>> = if args.shadow_samples.is_empty() {
        vec![None]
    } else {
        args.shadow_samples.iter().copied().map(Some).collect()
    };
    let named = |method: &str, parts: Vec<String>| {
        std::iter::once(method.to_string())
            .chain(parts)
            .collect::<Vec<_>>()
            .join(" ")
    };
    let mut out = Vec::new();
    let lgh_n = lgh_render::methods::lgh::DEFAULT_INTERLEAVE;
    // The shadow samples and the clamp of a curve (named "k=K", "c=C" where they are not
    // its method's and the render's defaults): both methods' curves at each clamp.
    let finish = |mut parts: Vec<String>, mut s: RenderSettings, k: Option<u32>, c: f64| {
        if let Some(k) = k {
            if k != s.method.get().default_shadow_samples() {
                parts.push(format!("k={k}"));
            }
            s.shadows.samples = Some(k);
        }
        if c as f32 != s.vpl_clamp {
            parts.push(format!("c={c}"));
        }
        s.vpl_clamp = c as f32;
        (parts, s)
    };
    for &c in args.vpl_clamps.iter() {
        for &alpha in args.alphas.iter() {
            for &n in args.interleaves.iter() {
                for &k in &ks {
                    let mut s = RenderSettings {
                        method: LGH,
                        ..base.clone()
                    };
                    let mut parts = Vec::new();
                    if s.lgh.alpha != alpha as f32 {
                        parts.push(format!("alpha {alpha}"));
                    }
                    s.lgh.alpha = alpha as f32;
                    if n != lgh_n {
                        parts.push(format!("n={n}"));
                        s.tiling.interleave = Some(n);
                    }
                    let (parts, s) = finish(parts, s, k, c);
                    out.push((named("lgh", parts), "lgh", s));
                }
            }
        }
        for &bound in args.error_bounds.iter() {
            for &k in &ks {
                let s = RenderSettings {
                    method: SLC,
                    error_bound: Some(bound as f32),
                    ..base.clone()
                };
                let mut parts = Vec::new();
                // Compared as the f32 the settings hold (0.0005 has no exact binary form).
                if bound as f32 != lgh_render::methods::slc::DEFAULT_ERROR_BOUND {
                    parts.push(format!("eb={bound}"));
                }
                let (parts, s) = finish(parts, s, k, c);
                out.push((named("slc", parts), "slc", s));
            }
        }
    }
    out
}

/// How much lower than slc's both of lgh's errors must be to count as a win (the quality
/// issue's 15%).
pub const WIN_MARGIN: f64 = 0.15;

/// A method at its best curve and VPL count within a budget.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Pick {
    /// The curve of the point with the lowest FLIP within the budget.
    pub series_flip: String,
    /// Its VPLs.
    pub vpls_flip: usize,
    /// Its time and FLIP.
    pub ms_flip: f64,
    pub flip: f64,
    /// The curve of the point with the lowest rel_rmse within the budget.
    pub series_rmse: String,
    /// Its VPLs.
    pub vpls_rmse: usize,
    /// Its time and rel_rmse.
    pub ms_rmse: f64,
    pub rel_rmse: f64,
}

/// One row of the equal-time table.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    pub scene: String,
    pub budget_ms: f64,
    /// None if no point of the method fits the budget.
    pub lgh: Option<Pick>,
    pub slc: Option<Pick>,
}

impl Row {
    /// True if lgh's FLIP and rel_rmse are both at least [`WIN_MARGIN`] below slc's (slc
    /// with no point in the budget loses).
    #[must_use]
    pub fn lgh_wins(&self) -> bool {
        match (&self.lgh, &self.slc) {
            (Some(l), Some(s)) => {
                l.flip <= (1.0 - WIN_MARGIN) * s.flip
                    && l.rel_rmse <= (1.0 - WIN_MARGIN) * s.rel_rmse
            }
            (Some(_), None) => true,
            _ => false,
        }
    }
}

/// The VPL count of a point's setting (`V=20000`).
fn vpls_of(p: &Point) -> usize {
    p.setting
        .trim_start_matches("V=")
        .parse()
        .unwrap_or_default()
}

/// True if `series` is a curve of `method` (`lgh`, `lgh alpha 2`).
pub(crate) fn of_method(series: &str, method: &str) -> bool {
    series == method
        || series
            .strip_prefix(method)
            .is_some_and(|r| r.starts_with(' '))
}

/// `method` on `scene` at its best point (over its curves) within `budget` ms, per metric.
#[must_use]
pub fn pick(points: &[Point], scene: &str, method: &str, budget: f64) -> Option<Pick> {
    let within = || {
        points
            .iter()
            .filter(move |p| p.scene == scene && of_method(&p.series, method) && p.ms <= budget)
    };
    let f = within().min_by(|a, b| a.flip.total_cmp(&b.flip))?;
    let r = within().min_by(|a, b| a.rel_rmse.total_cmp(&b.rel_rmse))?;
    Some(Pick {
        series_flip: f.series.clone(),
        vpls_flip: vpls_of(f),
        ms_flip: f.ms,
        flip: f.flip,
        series_rmse: r.series.clone(),
        vpls_rmse: vpls_of(r),
        ms_rmse: r.ms,
        rel_rmse: r.rel_rmse,
    })
}

/// The sweep of one method on one scene: each VPL count in turn until the time passes the
/// largest budget (larger counts only take longer). Each point is `--runs` renders, each
/// with its own seed ([`sweep_seed`]: its own VPL set, shadow samples and SLC ranges): its
/// time is their median, its errors their mean ([`over_runs`]). One render's errors depend
/// on its VPL set: where a few hundred pixels of near-field light hold half the squared
/// error (the conference room lit by a spot aimed at its ceiling), one seed's rel_rmse of
/// the same method was 0.15 and another's 0.40.
fn sweep(
    world: &World,
    args: &QualityBenchArgs,
    name: &str,
    (series, settings): (&str, &RenderSettings),
    reference: &Image,
) -> Result<Vec<Point>> {
    let exposure = world.scene.exposure;
    let largest = args.budgets.iter().copied().fold(0.0, f64::max);
    let mut out = Vec::new();
    for &vpls in args.sweep.iter() {
        let mut times = Vec::new();
        let mut errors = Vec::new();
        for run in 0..args.runs.max(1) {
            let mut s = RenderSettings {
                vpls: vpls as usize,
                seed: sweep_seed(run),
                ..settings.clone()
            };
            s.slc.frame_seed = settings.slc.frame_seed.wrapping_add(run);
            let f = render(world, &s)?;
            times.push(ms(&f));
            errors.push(measure(&f.indirect, reference, exposure)?);
        }
        let (rel_rmse, flip, rel_bias) = over_runs(&errors);
        let point = Point {
            scene: name.to_string(),
            series: series.to_string(),
            setting: format!("V={vpls}"),
            ms: crate::bench_cmd::median(times),
            rel_rmse,
            flip,
            rel_bias,
        };
        let done = point.ms > largest;
        out.push(point);
        if done {
            break;
        }
    }
    Ok(out)
}

/// Random-stream tag of the sweep's seeds.
const STREAM_SWEEP: u64 = 0x005e_ede7;

/// The seed of render `run` of each point of the sweep. Never one of the reference's frames'
/// seeds ([`frame_seed`] of seed 0): light paths with the same seed are the same paths, so a
/// render with a reference frame's seed would have its VPLs (a prefix of that frame's), and
/// its VPL noise would not be independent of the reference's.
#[must_use]
pub fn sweep_seed(run: u32) -> u64 {
    hash(&[STREAM_SWEEP, u64::from(run)])
}

/// A point's errors from its renders' (rel_rmse, FLIP, rel_bias): rel_rmse as the root mean
/// square over the renders (the rel_rmse of all their pixels together: the reference, its
/// denominator, is the same), FLIP and rel_bias as their means.
#[must_use]
pub fn over_runs(errors: &[(f64, f64, f64)]) -> (f64, f64, f64) {
    let n = errors.len().max(1) as f64;
    let sum = |f: fn(&(f64, f64, f64)) -> f64| errors.iter().map(f).sum::<f64>() / n;
    (sum(|e| e.0 * e.0).sqrt(), sum(|e| e.1), sum(|e| e.2))
}

/// The equal-time table of every scene and budget.
#[must_use]
pub fn table(points: &[Point], scenes: &[String], budgets: &[f64]) -> Vec<Row> {
    let mut rows = Vec::new();
    for scene in scenes {
        for &budget in budgets {
            rows.push(Row {
                scene: scene.clone(),
                budget_ms: budget,
                lgh: pick(points, scene, "lgh", budget),
                slc: pick(points, scene, "slc", budget),
            });
        }
    }
    rows
}

/// Runs the equal-time benchmark.
///
/// # Errors
/// A scene, reference or output cannot be read or written, or a render fails.
pub fn run(args: &QualityBenchArgs, scenes: &[PathBuf], threads: usize) -> Result<()> {
    let mut points = Vec::new();
    let mut names = Vec::new();
    let mut convergence = Vec::new();
    let mut paths = Vec::new();
    if !args.reference.is_empty() && args.reference.len() != scenes.len() {
        bail!(
            "--reference: {} given for {} scene(s); name one file per scene, in order",
            args.reference.len(),
            scenes.len()
        );
    }
    for (index, path) in scenes.iter().enumerate() {
        let (name, world) = open_scene(Some(path), &args.options)?;
        let reference = reference(&world, args, &name, path, index)?;
        let curves = if args.references_only {
            Vec::new()
        } else {
            curves(args)
        };
        for (series, _, settings) in curves {
            if !args.options.json {
                eprintln!("{name}: {series} at up to {} VPL counts", args.sweep.len());
            }
            points.extend(sweep(
                &world,
                args,
                &name,
                (&series, &settings),
                &reference.image,
            )?);
        }
        convergence.push((name.clone(), reference.half_flip));
        names.push(name);
        paths.push(reference.path);
    }
    if args.references_only {
        return print_references(args, &convergence, &paths);
    }
    crate::bench_plot::plot(&args.plot, &names, &points, &["lgh", "slc"])?;
    let rows = table(&points, &names, &args.budgets);
    if args.options.json {
        let mut v = settings_json(args);
        let convergence: Vec<_> = convergence
            .iter()
            .map(|(s, f)| serde_json::json!({"scene": s, "half_flip": f}))
            .collect();
        for (key, value) in [
            ("threads", serde_json::json!(threads)),
            ("points", serde_json::json!(points)),
            ("table", serde_json::json!(rows)),
            ("convergence", serde_json::json!(convergence)),
            ("plot", serde_json::json!(args.plot)),
        ] {
            v.insert(key.into(), value);
        }
        println!("{}", serde_json::Value::Object(v));
        return Ok(());
    }
    print_table(args, &points, &rows, &convergence, threads);
    Ok(())
}

/// The points, the equal-time table and the references' convergence, as text.
fn print_table(
    args: &QualityBenchArgs,
    points: &[Point],
    rows: &[Row],
    convergence: &[(String, Option<f64>)],
    threads: usize,
) {
    // The scene column as wide as its longest name.
    let names = points.iter().map(|p| p.scene.as_str());
    let sw = crate::bench_quality::scene_column(
        names.chain(convergence.iter().map(|(s, _)| s.as_str())),
    );
    println!(
        "Indirect light against a converged reference ({}), {}x{}, {threads} threads",
        crate::bench_reference::describe(args),
        args.size.0,
        args.size.1
    );
    println!(
        "{:<sw$} {:<16} {:>9} {:>9} {:>9} {:>7} {:>9}",
        "scene", "method", "VPLs", "ms", "rel_rmse", "FLIP", "rel_bias"
    );
    for p in points {
        println!(
            "{:<sw$} {:<16} {:>9} {:>9.1} {:>9.4} {:>7.4} {:>+9.4}",
            p.scene,
            p.series,
            vpls_of(p),
            p.ms,
            p.rel_rmse,
            p.flip,
            p.rel_bias
        );
    }
    println!();
    println!(
        "At equal time (each method at its best curve and VPL count within the budget; lgh wins if both errors are {:.0}% below slc's):",
        WIN_MARGIN * 100.0
    );
    println!(
        "{:<sw$} {:>7} {:>22} {:>22} {:>6} {:>22} {:>22} {:>6}  lgh wins",
        "scene",
        "budget",
        "lgh FLIP (VPLs)",
        "slc FLIP (VPLs)",
        "ratio",
        "lgh rmse (VPLs)",
        "slc rmse (VPLs)",
        "ratio"
    );
    // The error, the VPLs and the curve where it is not the method's default.
    let cell = |v: Option<(f64, usize, &str)>| match v {
        Some((e, n, series)) => match series.split_once(' ') {
            Some((_, setting)) => format!("{e:.4} ({}, {setting})", short_count(n)),
            None => format!("{e:.4} ({})", short_count(n)),
        },
        None => "-".into(),
    };
    for r in rows {
        let ratio = |l: Option<f64>, s: Option<f64>| match (l, s) {
            (Some(l), Some(s)) if s > 0.0 => format!("{:.2}", l / s),
            _ => "-".into(),
        };
        let (lf, sf) = (
            r.lgh.as_ref().map(|p| p.flip),
            r.slc.as_ref().map(|p| p.flip),
        );
        let (lr, sr) = (
            r.lgh.as_ref().map(|p| p.rel_rmse),
            r.slc.as_ref().map(|p| p.rel_rmse),
        );
        println!(
            "{:<sw$} {:>5.0}ms {:>22} {:>22} {:>6} {:>22} {:>22} {:>6}  {}",
            r.scene,
            r.budget_ms,
            cell(
                r.lgh
                    .as_ref()
                    .map(|p| (p.flip, p.vpls_flip, p.series_flip.as_str()))
            ),
            cell(
                r.slc
                    .as_ref()
                    .map(|p| (p.flip, p.vpls_flip, p.series_flip.as_str()))
            ),
            ratio(lf, sf),
            cell(
                r.lgh
                    .as_ref()
                    .map(|p| (p.rel_rmse, p.vpls_rmse, p.series_rmse.as_str()))
            ),
            cell(
                r.slc
                    .as_ref()
                    .map(|p| (p.rel_rmse, p.vpls_rmse, p.series_rmse.as_str()))
            ),
            ratio(lr, sr),
            if r.lgh_wins() { "yes" } else { "no" }
        );
    }
    println!();
    let smallest = rows
        .iter()
        .flat_map(|r| [&r.lgh, &r.slc])
        .flatten()
        .map(|p| p.flip)
        .fold(f64::INFINITY, f64::min);
    println!(
        "Convergence of the references (FLIP of the first half of the frames against all; converged if below a tenth of the smallest FLIP in the table, {:.4}):",
        smallest / 10.0
    );
    for (scene, half) in convergence {
        match half {
            Some(f) => println!(
                "{scene:<sw$} {f:.4}  {}",
                if *f < smallest / 10.0 {
                    "converged"
                } else {
                    "NOT converged: more --reference-frames"
                }
            ),
            None => println!("{scene:<sw$} unknown (no half file beside the reference)"),
        }
    }
    println!("plot: {}", args.plot.display());
}

/// 20000 as "20K", 1000000 as "1M".
fn short_count(n: usize) -> String {
    if n >= 1_000_000 && n.is_multiple_of(1_000_000) {
        format!("{}M", n / 1_000_000)
    } else if n >= 1000 && n.is_multiple_of(1000) {
        format!("{}K", n / 1000)
    } else {
        n.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(series: &str, vpls: usize, ms: f64, flip: f64, rel_rmse: f64) -> Point {
        Point {
            scene: "s".into(),
            series: series.into(),
            setting: format!("V={vpls}"),
            ms,
            rel_rmse,
            flip,
            rel_bias: 0.0,
        }
    }

    /// The bench's arguments as clap parses `args`.
    fn try_parsed(args: &[&str]) -> Result<QualityBenchArgs, clap::Error> {
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            args: QualityBenchArgs,
        }
        let argv = std::iter::once("bench").chain(args.iter().copied());
        <Cli as clap::Parser>::try_parse_from(argv).map(|c| c.args)
    }

    fn parsed(args: &[&str]) -> QualityBenchArgs {
        try_parsed(args).unwrap()
    }

    /// Every combination of the axes is a curve, named by where it departs from its
    /// method's defaults, and carries those settings.
    #[test]
    fn the_curves_cross_every_axis() {
        let names = |a: &QualityBenchArgs| curves(a).into_iter().map(|c| c.0).collect::<Vec<_>>();
        let alone = ["--interleaves", "2", "--shadow-samples", ""];
        assert_eq!(names(&parsed(&alone)), ["lgh", "slc"]);
        // 2 interleavings x 4 shadow-sample counts for lgh, 4 counts for slc.
        assert_eq!(curves(&parsed(&[])).len(), 2 * 4 + 4);
        let a = parsed(&[
            "--interleaves",
            "2,4",
            "--shadow-samples",
            "3,5",
            "--alphas",
            "3",
        ]);
        assert_eq!(
            names(&a),
            [
                "lgh k=3",
                "lgh",
                "lgh n=4 k=3",
                "lgh n=4",
                "slc k=3",
                "slc k=5"
            ]
        );
        let c = curves(&a);
        assert_eq!(c[2].2.tiling.interleave, Some(4));
        assert_eq!(c[2].2.shadows.samples, Some(3));
        assert_eq!(c[1].2.tiling.interleave, None);
        assert_eq!(c[5].2.method, SLC);
        assert_eq!(c[5].2.shadows.samples, Some(5));
        // Each curve counts for its own method in the table.
        assert!(c.iter().all(|(name, method, _)| of_method(name, method)));
        // The default clamp is the render's alone (its curves carry no "c=").
        assert_eq!(
            *parsed(&[]).vpl_clamps,
            [f64::from(lgh_render::settings::DEFAULT_VPL_CLAMP)]
        );
        // Each clamp crosses both methods' curves.
        let clamps = parsed(&[
            "--interleaves",
            "4",
            "--shadow-samples",
            "3",
            "--vpl-clamps",
            "4,2",
        ]);
        assert_eq!(
            names(&clamps),
            ["lgh n=4 k=3", "slc k=3", "lgh n=4 k=3 c=2", "slc k=3 c=2"]
        );
        let c = curves(&clamps);
        assert_eq!(c[0].2.vpl_clamp, 4.0);
        assert_eq!((c[2].2.vpl_clamp, c[3].2.vpl_clamp), (2.0, 2.0));
        assert!(c.iter().all(|(name, method, _)| of_method(name, method)));
        for bad in [
            &["--interleaves", "0"][..],
            &["--interleaves", ""],
            &["--shadow-samples", "17"],
            &["--vpl-clamps", "0"],
            &["--vpl-clamps", ""],
            &["--vpl-clamps", "nan"],
        ] {
            assert!(try_parsed(bad).is_err(), "{bad:?}");
        }
    }

    /// A point's errors over its renders: rel_rmse pools their squared errors, FLIP and
    /// rel_bias are means; one render's are its own.
    #[test]
    fn a_points_errors_are_those_of_all_its_renders() {
        let one = (0.3, 0.05, -0.02);
        assert_eq!(over_runs(&[one]), one);
        let (rmse, flip, bias) = over_runs(&[(0.3, 0.05, -0.02), (0.4, 0.07, 0.04)]);
        assert!((rmse - 0.125f64.sqrt()).abs() < 1e-12, "{rmse}");
        assert!((flip - 0.06).abs() < 1e-12 && (bias - 0.01).abs() < 1e-12);
    }

    /// The sweep's renders never repeat a reference frame's seed (the same light paths).
    #[test]
    fn the_sweep_never_draws_a_reference_frames_paths() {
        let frames: std::collections::HashSet<u64> = (0..10_000)
            .map(|k| lgh_render::accumulate::frame_seed(0, k))
            .collect();
        let runs: std::collections::HashSet<u64> = (0..1000).map(sweep_seed).collect();
        assert_eq!(runs.len(), 1000);
        assert!(runs.is_disjoint(&frames));
    }

    /// Each method is taken at its best point within the budget, per metric; lgh wins only
    /// with both errors 15% below slc's.
    #[test]
    fn equal_time_picks_the_best_point_within_the_budget() {
        let points = vec![
            point("lgh", 10_000, 50.0, 0.10, 0.30),
            point("lgh", 20_000, 90.0, 0.08, 0.32),
            point("lgh", 40_000, 180.0, 0.06, 0.20),
            point("slc", 10_000, 60.0, 0.11, 0.40),
            point("slc", 20_000, 150.0, 0.09, 0.35),
        ];
        let p = pick(&points, "s", "lgh", 100.0).unwrap();
        assert_eq!((p.vpls_flip, p.flip), (20_000, 0.08));
        assert_eq!((p.vpls_rmse, p.rel_rmse), (10_000, 0.30));
        assert!(pick(&points, "s", "lgh", 40.0).is_none());
        let rows = table(&points, &["s".to_string()], &[100.0, 200.0, 40.0]);
        // 100 ms: lgh 0.08 / 0.30 against slc 0.11 / 0.40: both 15% lower.
        assert!(rows[0].lgh_wins());
        // 200 ms: 0.06 / 0.20 against 0.09 / 0.35.
        assert!(rows[1].lgh_wins());
        // 40 ms: nobody fits.
        assert!(!rows[2].lgh_wins());
        // A method's other curves count too, and a series name only starts like one.
        let more = [
            points.clone(),
            vec![
                point("lgh alpha 2", 40_000, 95.0, 0.05, 0.25),
                point("lghx", 10_000, 10.0, 0.001, 0.001),
            ],
        ]
        .concat();
        let p = pick(&more, "s", "lgh", 100.0).unwrap();
        assert_eq!(
            (p.series_flip.as_str(), p.vpls_flip),
            ("lgh alpha 2", 40_000)
        );
        assert_eq!(p.series_rmse, "lgh alpha 2");
        let close = vec![
            point("lgh", 10_000, 50.0, 0.095, 0.10),
            point("slc", 10_000, 50.0, 0.10, 0.40),
        ];
        assert!(!table(&close, &["s".to_string()], &[100.0])[0].lgh_wins());
        assert_eq!(short_count(20_000), "20K");
        assert_eq!(short_count(1_000_000), "1M");
        assert_eq!(short_count(1500), "1500");
    }
}
