//! `lgh bench`: performance measurements.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::{Args, Subcommand};
use lgh_render::World;
use lgh_render::raybench::bench_rays;

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

/// The scene of a benchmark (the built-in Cornell box if none is given), prepared, with its
/// name.
///
/// # Errors
/// The scene cannot be loaded.
pub fn open_scene(path: Option<&std::path::Path>) -> Result<(String, World)> {
    let scene = load_scene(path)?;
    let name = scene.name.clone();
    Ok((name, World::new(scene)))
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
    Quality(crate::bench_quality::QualityBenchArgs),
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
    /// Rays of each kind.
    #[arg(long, default_value_t = 1_000_000)]
    pub rays: usize,
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
    let t = Instant::now();
    let world = World::new(scene);
    let build_ms = t.elapsed().as_secs_f64() * 1e3;
    let r = bench_rays(&world, args.rays.max(1), build_ms);
    if args.options.json {
        let v = serde_json::json!({
            "scene": name,
            "threads": threads,
            "triangles": r.triangles,
            "rays": r.rays,
            "bvh_build_ms": r.bvh_build_ms,
            "primary_rays_per_s": r.primary_rays_per_s,
            "shadow_rays_per_s": r.shadow_rays_per_s,
            "bounce_rays_per_s": r.bounce_rays_per_s,
        });
        println!("{v}");
    } else {
        println!(
            "scene       {name} ({} triangles, {threads} threads)",
            r.triangles
        );
        println!("bvh build   {:.1} ms", r.bvh_build_ms);
        println!("primary     {:.2} Mrays/s", r.primary_rays_per_s / 1e6);
        println!("shadow      {:.2} Mrays/s", r.shadow_rays_per_s / 1e6);
        println!("bounce      {:.2} Mrays/s", r.bounce_rays_per_s / 1e6);
    }
    Ok(())
}
