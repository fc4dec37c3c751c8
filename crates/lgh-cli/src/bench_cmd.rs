//! `lgh bench`: performance measurements.

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, Subcommand};
use lgh_render::World;
use lgh_render::raybench::{RayBench, bench_rays};
use lgh_render::world::accel::{AccelChoice, AccelKind};

use crate::scene_arg::load_scene;

/// The median of timed runs (the upper one of an even count; 0 for none).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() { 0.0 } else { v[v.len() / 2] }
}

/// The options every benchmark has.
#[derive(Debug, Args)]
pub struct BenchOptions {
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Print one JSON object instead of tables.
    #[arg(long)]
    pub json: bool,
    /// The ray tracer (`bench rays`: measure only this one).
    #[command(flatten)]
    pub accel: AccelChoice,
}

impl BenchOptions {
    /// Sets the worker threads; returns how many there are.
    ///
    /// # Errors
    /// The thread pool cannot be built.
    pub fn threads(&self) -> Result<usize> {
        crate::set_threads(self.threads)
    }
}

/// The scene of a benchmark (the built-in Cornell box if none is given), prepared with the
/// options' ray tracer, with its name.
///
/// # Errors
/// The scene cannot be loaded, or the ray tracer is not in this build.
pub fn open_scene(
    path: Option<&std::path::Path>,
    options: &BenchOptions,
) -> Result<(String, World)> {
    let scene = load_scene(path)?;
    let name = scene.name.clone();
    Ok((name, World::with_accel(scene, options.accel.kind())?))
}

/// Measure performance.
#[derive(Debug, Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    pub what: BenchWhat,
}

/// What to measure.
#[derive(Debug, Subcommand)]
pub enum BenchWhat {
    /// Rays per second on a scene: primary, shadow (any-hit) and bounce (closest-hit) rays,
    /// with the BVH build time.
    #[command(allow_negative_numbers = true)]
    Rays(RaysArgs),
    /// Lighting grid hierarchy construction (LGH paper Table 1): per-step times, levels and
    /// lights per level, for the paper's gather-from-S1 method and the all-scatter variant.
    #[command(allow_negative_numbers = true)]
    Build(BuildArgs),
    /// LGH rendering (LGH paper Tables 2 and 3): VPL generation, hierarchy construction, and
    /// render times without shadows, with 1 and with 4 shadow samples, with the per-pass
    /// breakdown.
    #[command(allow_negative_numbers = true)]
    Render(crate::bench_render::RenderBenchArgs),
    /// Stochastic light culling (Tokuyoshi & Harada 2016): slc, slc-clamped and LGH against
    /// the brute force at 16K-262K VPLs (time, lights per pixel, error; clamped also at equal
    /// time), and the area-light path tracer against uniform light sampling at equal time.
    #[command(allow_negative_numbers = true)]
    Slc(crate::bench_slc::SlcBenchArgs),
    /// Image quality against time (equal VPLs): every method at several settings against the
    /// exact brute force on each scene (rel_rmse, FLIP, bias, time), the convergence of
    /// `--accumulate`, and a log-log plot of error against time.
    #[command(allow_negative_numbers = true)]
    Quality(Box<crate::bench_quality::QualityBenchArgs>),
    /// Flicker of a static view with VPLs regenerated every frame, without and with temporal
    /// filtering (LGH paper 4.3), and the time per frame.
    #[command(allow_negative_numbers = true)]
    Temporal(crate::bench_temporal::TemporalBenchArgs),
}

/// Arguments of `lgh bench rays`.
#[derive(Debug, Args)]
pub struct RaysArgs {
    /// Scene file (.toml, .gltf, .glb, .obj). Default: the built-in Cornell box.
    pub scene: Option<PathBuf>,
    /// Rays of each kind (at most 100 million).
    #[arg(long, default_value_t = 1_000_000, value_parser = crate::caps::count(crate::caps::MAX_BENCH_RAYS))]
    pub rays: usize,
    /// Rounds (each measures every ray tracer once; the medians are reported).
    #[arg(long, default_value_t = 3, value_parser = crate::caps::count(100))]
    pub rounds: usize,
    /// Threads and output.
    #[command(flatten)]
    pub options: BenchOptions,
}

pub fn run(args: &BenchArgs) -> Result<()> {
    match &args.what {
        BenchWhat::Rays(a) => rays(a),
        BenchWhat::Build(a) => crate::bench_build::run(a),
        BenchWhat::Render(a) => crate::bench_render::run(a),
        BenchWhat::Slc(a) => crate::bench_slc::run(a),
        BenchWhat::Temporal(a) => crate::bench_temporal::run(a),
        BenchWhat::Quality(a) => crate::bench_quality::run(a),
    }
}

pub use crate::bench_build::BuildArgs;

fn rays(args: &RaysArgs) -> Result<()> {
    let threads = args.options.threads()?;
    let scene = load_scene(args.scene.as_deref())?;
    let name = scene.name.clone();
    // Every ray tracer this build has, alternated, unless --accel names one.
    let kinds = match args.options.accel.accel {
        None => AccelKind::available(),
        Some(k) => vec![k],
    };
    // One world per ray tracer; the rounds alternate them, so that a change of the machine's
    // speed during the run affects both alike.
    let worlds = kinds
        .iter()
        .map(|&k| Ok((k, World::with_accel(scene.clone(), k)?)))
        .collect::<Result<Vec<_>>>()?;
    let mut runs: Vec<Vec<RayBench>> = vec![Vec::new(); worlds.len()];
    for _ in 0..args.rounds {
        for ((kind, world), runs) in worlds.iter().zip(&mut runs) {
            runs.push(bench_rays(world, *kind, args.rays.max(1), 3)?);
        }
    }
    let med = |runs: &[RayBench], f: fn(&RayBench) -> f64| median(runs.iter().map(f).collect());
    let rows: Vec<serde_json::Value> = runs
        .iter()
        .map(|r| {
            serde_json::json!({
                "accel": r[0].accel.name(),
                "triangles": r[0].triangles,
                "rays": r[0].rays,
                "bvh_build_ms": med(r, |x| x.bvh_build_ms),
                "bvh_rebuild_ms": med(r, |x| x.bvh_rebuild_ms),
                "primary_rays_per_s": med(r, |x| x.primary_rays_per_s),
                "shadow_rays_per_s": med(r, |x| x.shadow_rays_per_s),
                "shadow_single_rays_per_s": med(r, |x| x.shadow_single_rays_per_s),
                "bounce_rays_per_s": med(r, |x| x.bounce_rays_per_s),
            })
        })
        .collect();
    if args.options.json {
        let v = serde_json::json!({
            "scene": name,
            "threads": threads,
            "rounds": args.rounds,
            "backends": rows,
        });
        println!("{v}");
        return Ok(());
    }
    let tri = runs
        .first()
        .and_then(|r| r.first())
        .map_or(0, |r| r.triangles);
    println!(
        "scene {name} ({tri} triangles, {threads} threads), medians of {} alternated rounds",
        args.rounds
    );
    println!(
        "{:<8} {:>10} {:>11} {:>9} {:>9} {:>9} {:>9}",
        "accel", "build ms", "rebuild ms", "primary", "shadow", "shadow 1", "bounce"
    );
    for row in &rows {
        let f = |k: &str| row[k].as_f64().unwrap_or(0.0);
        println!(
            "{:<8} {:>10.1} {:>11.1} {:>9.2} {:>9.2} {:>9.2} {:>9.2}",
            row["accel"].as_str().unwrap_or(""),
            f("bvh_build_ms"),
            f("bvh_rebuild_ms"),
            f("primary_rays_per_s") / 1e6,
            f("shadow_rays_per_s") / 1e6,
            f("shadow_single_rays_per_s") / 1e6,
            f("bounce_rays_per_s") / 1e6,
        );
    }
    println!("(rays in millions per second; shadow: batches of 256, shadow 1: one at a time)");
    Ok(())
}
