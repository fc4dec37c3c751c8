//! `lgh bench quality`: error against time, per method and scene, at equal VPLs: each
//! method at several settings against the exact brute force over the same VPLs, and the
//! convergence of `--accumulate` (lgh against brute, both accumulated over N frames).

use std::path::{Path, PathBuf};

use anyhow::{Result, anyhow};
use clap::Args;
use lgh_render::accumulate::{ACCUMULATE_SHADOW_SAMPLES, frame_settings, render_accumulated};
use lgh_render::frame::render_frame_with;
use lgh_render::image::ImageFormat;
use lgh_render::image::metrics::{diff, display_bytes, flip_mean};
use lgh_render::methods::brute::BRUTE;
use lgh_render::methods::lgh::{self, LGH, LghSettings};
use lgh_render::methods::slc::{SLC, SLC_CLAMPED};
use lgh_render::settings::{DEMO_FILTER_COLOR, ShadowSettings};
use lgh_render::{Component, Frame, FrameMemory, Image, RenderSettings, Silent, World};

use crate::bench_cmd::{BenchOptions, open_scene};
use crate::render_cmd::parse_size;

/// Arguments of `lgh bench quality`.
#[derive(Debug, Args)]
pub struct QualityBenchArgs {
    /// Scenes (files or builtin:NAME). Default: builtin:cornell and the project's test scenes
    /// (scenes/test/*.toml of the source tree).
    pub scenes: Vec<PathBuf>,
    /// Image size of the equal-VPL comparison, WIDTHxHEIGHT.
    #[arg(long, default_value = "320x180", value_parser = parse_size)]
    pub size: (u32, u32),
    /// VPLs of the equal-VPL comparison.
    #[arg(long, default_value_t = 20_000, value_parser = crate::caps::count(crate::caps::MAX_BENCH_VPLS))]
    pub vpls: usize,
    /// Frame counts of the accumulation curve, comma-separated, each 1-65536 (an empty
    /// list, `--accumulate ""`: no curve).
    #[arg(long, default_value = "1,2,4,8,16", value_parser = parse_counts)]
    pub accumulate: Counts,
    /// Image size of the accumulation curve.
    #[arg(long, default_value = "96x54", value_parser = parse_size)]
    pub accumulate_size: (u32, u32),
    /// VPLs per frame of the accumulation curve.
    #[arg(long, default_value_t = 2000, value_parser = crate::caps::count(crate::caps::MAX_BENCH_VPLS))]
    pub accumulate_vpls: usize,
    /// The error-against-time plot (log-log PNG: FLIP and rel_rmse per scene).
    #[arg(long, default_value = "bench-quality.png")]
    pub plot: PathBuf,
    /// Compare lgh and slc at equal time instead: each at every VPL count of `--sweep`
    /// against a converged reference (the mean of `--reference-frames` brute-force frames
    /// with independent VPLs), then each at its best count within each of `--budgets`.
    #[arg(long)]
    pub equal_time: bool,
    /// --equal-time: VPL counts of the sweep, comma-separated (a method stops at the first
    /// count that takes longer than the largest budget).
    #[arg(long, default_value = "5000,10000,20000,40000,80000,160000,320000,640000,1000000", value_parser = parse_vpl_counts)]
    pub sweep: Counts,
    /// --equal-time: time budgets in ms (VPL generation + indirect light), comma-separated.
    #[arg(long, default_value = "100,200,400", value_parser = parse_budgets)]
    pub budgets: Budgets,
    /// --equal-time: lgh's alphas, comma-separated, each its own curve (default: lgh's
    /// default alone); a method is taken at its best curve and VPL count within a budget.
    #[arg(long, default_value = "3", value_parser = parse_alphas)]
    pub alphas: Budgets,
    /// --equal-time: slc's error bounds, comma-separated, each its own curve (default:
    /// slc's default alone).
    #[arg(long, default_value = "0.0005", value_parser = parse_error_bounds)]
    pub error_bounds: Budgets,
    /// --equal-time: the VPL clamp's C (`--vpl-clamp`), comma-separated, each its own curve
    /// for both methods (default: the render default alone). A smaller C clamps less
    /// near-field light (less darkening in corners) at the price of more VPL noise; where
    /// the best trade lies depends on the scene and the VPL count (docs/design.md, "Clamps").
    #[arg(long, default_value = "4", value_parser = parse_vpl_clamps)]
    pub vpl_clamps: Budgets,
    /// --equal-time: lgh's n x n interleavings, comma-separated, each its own curve with
    /// every alpha and shadow-sample count (its default 2, and 4: a quarter of the lights a
    /// pixel, for the small budgets). slc keeps its own 8, cheaper than any smaller n and
    /// better than none even at equal VPLs (docs/design.md, "Interleaved sampling").
    #[arg(long, default_value = "2,4", value_parser = parse_interleaves)]
    pub interleaves: Counts,
    /// --equal-time: shadow samples, comma-separated, each its own curve for both methods
    /// (an empty list: each method's own, lgh 5 and slc 4). 2 serves the small budgets:
    /// a third fewer rays and targets for a few per cent more noise.
    #[arg(long, default_value = "2,3,4,5", value_parser = parse_shadow_samples)]
    pub shadow_samples: Counts,
    /// --equal-time: the converged reference of each scene (EXR, in the order of the
    /// scenes): read if it exists, else rendered and written there. Default: a file in
    /// `--reference-dir` named by scene, size and reference settings.
    #[arg(long)]
    pub reference: Vec<PathBuf>,
    /// --equal-time: where references are cached (with the mean of their first half beside
    /// each, `NAME.half.exr`, which says how converged they are).
    #[arg(long, default_value = "bench-references")]
    pub reference_dir: PathBuf,
    /// --equal-time: brute-force frames of a reference, each with its own VPLs and sub-pixel
    /// position.
    #[arg(long, default_value_t = 48, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub reference_frames: u32,
    /// --equal-time: shadow rays per pixel of each reference frame on the CPU, drawn in
    /// proportion to each VPL's unshadowed light (`--method brute-sampled`, unbiased for the
    /// brute force: a frame costs a sixth of brute's on the two rooms, and the VPLs' noise,
    /// which sets a reference's convergence, falls as fast); 0 = one ray per VPL (`brute`).
    /// The GPU's references (`--reference-device gpu`) trace one ray per VPL.
    #[arg(long, default_value_t = lgh_render::methods::brute::sampled::DEFAULT_BRUTE_RAYS, value_parser = clap::value_parser!(u32).range(0..=i64::from(lgh_render::methods::brute::sampled::MAX_BRUTE_RAYS)))]
    pub reference_rays: u32,
    /// --equal-time: where the references' brute force runs: `gpu` (wgpu: Vulkan, Metal or
    /// DX12) converges them in a fraction of the time on a real GPU.
    #[arg(long, value_enum, default_value_t = crate::render_cmd::args::Device::Cpu)]
    pub reference_device: crate::render_cmd::args::Device,
    /// --equal-time: make (or load) each scene's converged reference, print its file and
    /// how converged it is, and stop without the sweep: for a machine that makes references
    /// (with `--reference-device gpu`) for a sweep run elsewhere with `--reference`.
    #[arg(long, requires = "equal_time")]
    pub references_only: bool,
    /// --equal-time: VPLs of each reference frame.
    #[arg(long, default_value_t = 20_000, value_parser = crate::caps::count(crate::caps::MAX_BENCH_VPLS))]
    pub reference_vpls: usize,
    /// --equal-time: renders per point, each with its own seed (VPL set, shadow samples,
    /// SLC ranges): its time is their median, its errors their mean (rel_rmse: the root mean
    /// square).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub runs: u32,
    /// Threads and output.
    #[command(flatten)]
    pub options: BenchOptions,
}

/// One measured point.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Point {
    /// Scene name.
    pub scene: String,
    /// The curve: a method and its fixed settings.
    pub series: String,
    /// The setting varied along the curve.
    pub setting: String,
    /// Time of the indirect light (VPL generation included), ms.
    pub ms: f64,
    /// rel_rmse against the reference.
    pub rel_rmse: f64,
    /// Mean LDR-FLIP against the reference.
    pub flip: f64,
    /// Relative bias of the mean luminance.
    pub rel_bias: f64,
}

/// The scenes when none is given.
fn default_scenes() -> Vec<PathBuf> {
    let mut out = vec![PathBuf::from("builtin:cornell")];
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/test");
    if let Ok(entries) = std::fs::read_dir(&dir) {
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .collect();
        files.sort();
        out.extend(files);
    }
    out
}

/// Time of a frame's indirect light with its VPL generation.
pub fn ms(f: &Frame) -> f64 {
    f.timings.get("indirect").unwrap_or(0.0) + f.timings.get("vpl_generation").unwrap_or(0.0)
}

/// The metrics of `f` against `reference`.
pub fn measure(f: &Image, reference: &Image, exposure: f32) -> Result<(f64, f64, f64)> {
    let m = diff(f, reference).map_err(|e| anyhow!("{e}"))?;
    let flip = flip_mean(
        &display_bytes(f, ImageFormat::Exr, exposure),
        &display_bytes(reference, ImageFormat::Exr, exposure),
        f.width,
        f.height,
    )
    .map_err(|e| anyhow!("{e}"))?;
    Ok((m.rel_rmse, flip, m.rel_bias))
}

/// The curves of the equal-VPL comparison: (series, setting label, settings).
fn series(base: &RenderSettings) -> Vec<(&'static str, String, RenderSettings)> {
    let mut out = Vec::new();
    let shadows = |k: u32| ShadowSettings {
        samples: Some(k),
        ..ShadowSettings::default()
    };
    for k in [1, lgh::DEFAULT_SHADOW_SAMPLES, 16] {
        // The defaults: the unbiased estimate, alpha 3, six normal bins, the VPLs near the
        // pixel, 2 x 2.
        let lgh = RenderSettings {
            method: LGH,
            shadows: shadows(k),
            ..base.clone()
        };
        let mut plain = lgh.clone();
        plain.tiling.interleave = Some(1);
        // The paper: alpha 1 (and 2), S_1 first, candidates from S_2, no interleaving, one
        // hierarchy, the demo's filter.
        let mut paper = lgh.clone();
        paper.lgh = LghSettings::paper();
        paper.shadows.filter_color = DEMO_FILTER_COLOR;
        paper.shadows.filter_unshadowed = 0.0;
        paper.tiling.interleave = Some(1);
        let mut paper2 = paper.clone();
        paper2.lgh.alpha = 2.0;
        let mut paper4 = paper.clone();
        paper4.tiling.interleave = Some(4);
        out.push(("lgh", format!("k={k}"), lgh));
        out.push(("lgh 1x1", format!("k={k}"), plain));
        out.push(("lgh paper", format!("k={k}"), paper));
        out.push(("lgh paper alpha 2", format!("k={k}"), paper2));
        out.push(("lgh paper 4x4", format!("k={k}"), paper4));
    }
    let bounds = [
        ("slc", SLC, [0.01f32, 0.002, 0.0005]),
        ("slc-clamped", SLC_CLAMPED, [0.5, 0.1, 0.02]),
    ];
    for (name, method, bounds) in bounds {
        for eb in bounds {
            let s = RenderSettings {
                method,
                error_bound: Some(eb),
                ..base.clone()
            };
            out.push((name, format!("eb={eb}"), s));
        }
    }
    out
}

pub fn render(world: &World, s: &RenderSettings) -> Result<Frame> {
    render_frame_with(world, s, &Silent, &mut FrameMemory::default()).map_err(|e| anyhow!("{e}"))
}

/// Settings for the indirect light alone at `size` with `vpls` VPLs.
pub fn indirect_only(size: (u32, u32), vpls: usize) -> RenderSettings {
    RenderSettings {
        width: size.0,
        height: size.1,
        vpls,
        area_samples: 0,
        component: Component::Indirect,
        ..RenderSettings::default()
    }
}

/// The frame counts of `--accumulate` (a list that may be empty).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Counts(pub Vec<u32>);

impl std::ops::Deref for Counts {
    type Target = [u32];
    fn deref(&self) -> &[u32] {
        &self.0
    }
}

/// Time budgets in ms (or another list of positive numbers).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Budgets(pub Vec<f64>);

impl std::ops::Deref for Budgets {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        &self.0
    }
}

/// Parses a comma-separated list (empty items skipped; it may be empty) whose items all
/// pass `ok`; an item that does not is refused as "{item:?} is not {what}".
fn parse_list<T: std::str::FromStr>(
    s: &str,
    ok: impl Fn(&T) -> bool,
    what: &str,
) -> Result<Vec<T>, String> {
    s.split(',')
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .map(|t| match t.parse::<T>() {
            Ok(x) if ok(&x) => Ok(x),
            _ => Err(format!("{t:?} is not {what}")),
        })
        .collect()
}

/// Parses a comma-separated list of numbers above 0 and at most `max` (at least one), each
/// called `what` in the error.
fn parse_positive(s: &str, what: &str, max: f64) -> Result<Budgets, String> {
    let v = parse_list(
        s,
        |&x: &f64| x > 0.0 && x <= max,
        &format!("{what} (above 0, at most {max})"),
    )?;
    if v.is_empty() {
        return Err(format!("no {what} given"));
    }
    Ok(Budgets(v))
}

/// Parses `100,200,400` into budgets (ms).
fn parse_budgets(s: &str) -> Result<Budgets, String> {
    parse_positive(s, "time budget in ms", 1e7)
}

/// Parses `1.5,2,3` into lgh's alphas.
fn parse_alphas(s: &str) -> Result<Budgets, String> {
    parse_positive(s, "alpha", 16.0)
}

/// Parses `2,4` into lgh's interleavings (1 to 16; at least one).
fn parse_interleaves(s: &str) -> Result<Counts, String> {
    let v = parse_list(
        s,
        |n: &u32| (1..=16).contains(n),
        "an interleaving from 1 to 16",
    )?;
    if v.is_empty() {
        return Err("no interleaving given".into());
    }
    Ok(Counts(v))
}

/// Parses `3,5` (or nothing: each method's default) into shadow-sample counts of 1 to
/// the most a pixel takes.
fn parse_shadow_samples(s: &str) -> Result<Counts, String> {
    let max = lgh_render::shading::ratio::MAX_SHADOW_SAMPLES;
    parse_list(
        s,
        |n: &u32| (1..=max).contains(n),
        &format!("a shadow-sample count from 1 to {max}"),
    )
    .map(Counts)
}

/// Parses `4,2` into VPL clamp constants C (each above 0 and at most 1000, as
/// `--vpl-clamp`; 0, the fixed clamp, is the reference's and not a curve).
fn parse_vpl_clamps(s: &str) -> Result<Budgets, String> {
    parse_positive(s, "VPL clamp C", 1000.0)
}

/// Parses `0.0005,0.002` into slc's error bounds.
fn parse_error_bounds(s: &str) -> Result<Budgets, String> {
    parse_positive(s, "error bound", 1.0)
}

/// Parses `5000,10000` into VPL counts (1 to the benchmarks' cap; at least one).
fn parse_vpl_counts(s: &str) -> Result<Counts, String> {
    let max = crate::caps::MAX_BENCH_VPLS;
    let v = parse_list(
        s,
        |&n: &u32| n >= 1 && u64::from(n) <= max,
        &format!("a VPL count from 1 to {max}"),
    )?;
    if v.is_empty() {
        return Err("no VPL count given".into());
    }
    Ok(Counts(v))
}

/// Parses `1,2,4` (or nothing) into frame counts of 1 to 65536.
fn parse_counts(s: &str) -> Result<Counts, String> {
    parse_list(
        s,
        |n: &u32| (1..=65536).contains(n),
        "a frame count from 1 to 65536",
    )
    .map(Counts)
}

/// The means of the first n of `frames` frames of `s` ([`frame_settings`]: each its own VPLs
/// and sub-pixel position) for each n of `at`, in frame order, as (n, indirect light);
/// `each` runs after every frame.
///
/// # Errors
/// A frame fails to render.
pub fn prefix_means(
    world: &World,
    s: &RenderSettings,
    frames: u32,
    at: &[u32],
    each: impl Fn(),
) -> Result<Vec<(u32, Image)>> {
    let mut sum = vec![glam::Vec3::ZERO; s.width as usize * s.height as usize];
    let mut out = Vec::new();
    for k in 0..frames {
        let f = render(world, &frame_settings(s, k, frames))?;
        for (acc, p) in sum.iter_mut().zip(&f.indirect.pixels) {
            *acc += *p;
        }
        if at.contains(&(k + 1)) {
            let inv = 1.0 / (k + 1) as f32;
            let mean = sum.iter().map(|p| *p * inv).collect();
            out.push((k + 1, Image::from_pixels(s.width, s.height, mean)));
        }
        each();
    }
    Ok(out)
}

/// The accumulation curve of one scene: lgh --accumulate N against brute --accumulate N.
fn accumulation(
    world: &World,
    name: &str,
    args: &QualityBenchArgs,
    exposure: f32,
) -> Result<Vec<Point>> {
    let Some(&max_n) = args.accumulate.iter().max() else {
        return Ok(Vec::new());
    };
    let base = indirect_only(args.accumulate_size, args.accumulate_vpls);
    let brute = RenderSettings {
        method: BRUTE,
        ..base.clone()
    };
    // Brute-force frames do not depend on the frame count: the prefix means are the
    // accumulated references.
    let references = prefix_means(world, &brute, max_n, &args.accumulate, || {})?;
    let mut out = Vec::new();
    for (n, reference) in references {
        let lgh = RenderSettings {
            method: LGH,
            shadows: ShadowSettings {
                samples: Some(ACCUMULATE_SHADOW_SAMPLES),
                ..base.shadows
            },
            ..base.clone()
        };
        let f = render_accumulated(world, &lgh, n, &Silent, &mut FrameMemory::default())
            .map_err(|e| anyhow!("{e}"))?;
        let (rel_rmse, flip, rel_bias) = measure(&f.indirect, &reference, exposure)?;
        out.push(Point {
            scene: name.to_string(),
            series: "lgh --accumulate".into(),
            setting: format!("N={n}"),
            ms: ms(&f),
            rel_rmse,
            flip,
            rel_bias,
        });
    }
    Ok(out)
}

pub fn run(args: &QualityBenchArgs) -> Result<()> {
    let threads = args.options.threads()?;
    crate::bench_plot::check_plot_path(&args.plot)?;
    let scenes = if args.scenes.is_empty() {
        default_scenes()
    } else {
        args.scenes.clone()
    };
    if args.equal_time {
        return crate::bench_equal_time::run(args, &scenes, threads);
    }
    let mut points = Vec::new();
    let mut scene_names = Vec::new();
    for path in &scenes {
        let (name, world) = open_scene(Some(path), &args.options)?;
        let exposure = world.scene.exposure;
        let base = indirect_only(args.size, args.vpls);
        if !args.options.json {
            eprintln!("{name}: brute-force reference ({} VPLs)...", args.vpls);
        }
        let reference = render(
            &world,
            &RenderSettings {
                method: BRUTE,
                ..base.clone()
            },
        )?;
        for (series, setting, s) in series(&base) {
            let f = render(&world, &s)?;
            let (rel_rmse, flip, rel_bias) = measure(&f.indirect, &reference.indirect, exposure)?;
            points.push(Point {
                scene: name.clone(),
                series: series.into(),
                setting,
                ms: ms(&f),
                rel_rmse,
                flip,
                rel_bias,
            });
        }
        points.extend(accumulation(&world, &name, args, exposure)?);
        points.push(Point {
            scene: name.clone(),
            series: "brute (reference)".into(),
            setting: String::new(),
            ms: ms(&reference),
            rel_rmse: 0.0,
            flip: 0.0,
            rel_bias: 0.0,
        });
        scene_names.push(name);
    }
    crate::bench_plot::plot(&args.plot, &scene_names, &points, &[])?;
    if args.options.json {
        let v = serde_json::json!({
            "threads": threads,
            "width": args.size.0,
            "height": args.size.1,
            "vpls": args.vpls,
            "points": points,
            "plot": args.plot,
        });
        println!("{v}");
        return Ok(());
    }
    println!(
        "Indirect light against the brute force, {}x{}, {} VPLs ({}x{}, {} VPLs a frame for --accumulate), {threads} threads",
        args.size.0,
        args.size.1,
        args.vpls,
        args.accumulate_size.0,
        args.accumulate_size.1,
        args.accumulate_vpls
    );
    let sw = scene_column(points.iter().map(|p| p.scene.as_str()));
    println!(
        "{:<sw$} {:<18} {:<9} {:>9} {:>9} {:>7} {:>9}",
        "scene", "method", "setting", "ms", "rel_rmse", "FLIP", "rel_bias"
    );
    for p in &points {
        println!(
            "{:<sw$} {:<18} {:<9} {:>9.1} {:>9.4} {:>7.4} {:>+9.4}",
            p.scene, p.series, p.setting, p.ms, p.rel_rmse, p.flip, p.rel_bias
        );
    }
    println!();
    println!(
        "At the defaults (lgh k={}, slc eb={}), and slc at equal time:",
        lgh::DEFAULT_SHADOW_SAMPLES,
        lgh_render::methods::slc::DEFAULT_ERROR_BOUND
    );
    println!(
        "{:<sw$} {:>9} {:>9} {:>7} {:>9} {:>9} {:>7} {:>14} {:>7}  lgh wins",
        "scene", "lgh FLIP", "bias", "ms", "slc FLIP", "bias", "ms", "slc equal time", "ms"
    );
    for row in summary(&points) {
        println!(
            "{:<sw$} {:>9.4} {:>+9.4} {:>7.0} {:>9.4} {:>+9.4} {:>7.0} {:>14.4} {:>7.0}  {}",
            row.scene,
            row.lgh.flip,
            row.lgh.rel_bias,
            row.lgh.ms,
            row.slc.flip,
            row.slc.rel_bias,
            row.slc.ms,
            row.slc_in_time.flip,
            row.slc_in_time.ms,
            if row.lgh_wins() { "yes" } else { "no" }
        );
    }
    println!("plot: {}", args.plot.display());
    Ok(())
}

/// The width of a table's scene column: its longest name, at least 14 characters.
pub(crate) fn scene_column<'a>(names: impl Iterator<Item = &'a str>) -> usize {
    names.map(|s| s.chars().count()).fold(14, usize::max)
}

/// lgh against slc on one scene: both at their defaults, and slc at equal time.
struct SummaryRow<'a> {
    scene: &'a str,
    lgh: &'a Point,
    slc: &'a Point,
    /// slc at equal time: the lowest FLIP of slc and slc-clamped among the settings that took
    /// no longer than lgh at its defaults; if every one took longer, the fastest of them
    /// (which then has more time than lgh).
    slc_in_time: &'a Point,
}

impl SummaryRow<'_> {
    /// FLIP no higher than slc's at equal or lower time.
    fn lgh_wins(&self) -> bool {
        self.lgh.flip <= self.slc_in_time.flip
    }
}

/// [`SummaryRow::slc_in_time`] on `scene` for an lgh time of `ms`.
fn slc_in_time<'a>(points: &'a [Point], scene: &str, ms: f64) -> Option<&'a Point> {
    let slc = || {
        points
            .iter()
            .filter(move |p| p.scene == scene && (p.series == "slc" || p.series == "slc-clamped"))
    };
    slc()
        .filter(|p| p.ms <= ms)
        .min_by(|a, b| a.flip.total_cmp(&b.flip))
        .or_else(|| slc().min_by(|a, b| a.ms.total_cmp(&b.ms)))
}

/// The default settings' points of every scene (lgh with its default k, slc with its default
/// bound).
fn summary(points: &[Point]) -> Vec<SummaryRow<'_>> {
    let find = |scene: &str, series: &str, setting: &str| {
        points
            .iter()
            .find(|p| p.scene == scene && p.series == series && p.setting == setting)
    };
    let mut rows: Vec<SummaryRow> = Vec::new();
    for p in points {
        if rows.iter().any(|r| r.scene == p.scene) {
            continue;
        }
        if let (Some(lgh), Some(slc)) = (
            find(
                &p.scene,
                "lgh",
                &format!("k={}", lgh::DEFAULT_SHADOW_SAMPLES),
            ),
            find(&p.scene, "slc", "eb=0.0005"),
        ) && let Some(slc_in_time) = slc_in_time(points, &p.scene, lgh.ms)
        {
            rows.push(SummaryRow {
                scene: &p.scene,
                lgh,
                slc,
                slc_in_time,
            });
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(series: &str, ms: f64, flip: f64) -> Point {
        Point {
            scene: "s".into(),
            series: series.into(),
            setting: String::new(),
            ms,
            rel_rmse: 0.0,
            flip,
            rel_bias: 0.0,
        }
    }

    /// slc at equal time is its best setting in no more time than lgh's, slc-clamped
    /// included and lgh's own points never; with none that fast, slc's fastest.
    #[test]
    fn slc_at_equal_time_is_its_best_point_in_no_more_time() {
        let points = vec![
            point("lgh", 100.0, 0.01),
            point("slc", 80.0, 0.09),
            point("slc", 99.0, 0.07),
            point("slc-clamped", 100.0, 0.06),
            point("slc", 150.0, 0.02),
        ];
        let at = |ms| slc_in_time(&points, "s", ms).map(|p| (p.ms, p.flip));
        assert_eq!(at(100.0), Some((100.0, 0.06)));
        assert_eq!(at(90.0), Some((80.0, 0.09)));
        assert_eq!(at(50.0), Some((80.0, 0.09)));
        assert_eq!(slc_in_time(&points, "other", 100.0).map(|p| p.ms), None);
    }
}
