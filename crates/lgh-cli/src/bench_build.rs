//! `lgh bench build`: the LGH paper's Table 1 on this machine.

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;
use glam::Vec3;
use lgh_core::lighting_grid::synthetic::lights_on_surfaces;
use lgh_core::lighting_grid::{
    Construction, GridBuilder, HierarchyBuilder, InputLights, LevelCount,
};
use lgh_gpu::grid::GpuGridBuilder;
use lgh_render::World;
use lgh_render::passes::vpl_gen::{PathNumbers, generate_vpls};
use lgh_render::settings::Device;

use crate::bench_cmd::median;
use crate::scene_arg::load_scene;

/// Arguments of `lgh bench build`.
#[derive(Debug, Args)]
pub struct BuildArgs {
    /// Numbers of input lights, comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "1000,10000,100000,1000000",
        value_parser = crate::caps::count(crate::caps::MAX_BENCH_VPLS)
    )]
    pub lights: Vec<usize>,
    /// Use the VPLs of this scene (light tracing, 3 bounces) instead of the synthetic set:
    /// lights on the faces of a 10 x 4 x 8 room and of 24 random boxes in it.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Number of levels: `auto` (largest l_max with |S1| < N/2) or a number 1..=10.
    #[arg(long, default_value_t = LevelCount::Auto)]
    pub levels: LevelCount,
    /// Timed runs per configuration, after one untimed warm-up build; the report gives
    /// medians.
    #[arg(long, default_value_t = 7, value_parser = crate::caps::count(crate::caps::MAX_RUNS))]
    pub runs: usize,
    /// Threads and output.
    #[command(flatten)]
    pub options: crate::bench_cmd::BenchOptions,
    /// Where the hierarchy is built: `cpu`, or `gpu` (the restriction on the GPU through
    /// wgpu, read back; the gather and all-scatter variants run on the CPU only). On the
    /// GPU the report adds each GPU pass's time from its timestamps.
    #[arg(long, value_enum, default_value_t = Device::Cpu)]
    pub device: Device,
    /// Print the totals as a Markdown table (rows: lights; columns: variants), the form of
    /// docs/performance.md.
    #[arg(long)]
    pub markdown: bool,
}

/// The builder of one variant: the CPU's, or the GPU's (which also gives pass times).
enum Builder<'c> {
    Cpu(Box<GridBuilder>),
    Gpu(Box<GpuGridBuilder<'c>>),
}

impl Builder<'_> {
    fn get(&mut self) -> &mut dyn HierarchyBuilder {
        match self {
            Self::Cpu(b) => b.as_mut(),
            Self::Gpu(b) => b.as_mut(),
        }
    }

    /// The GPU's pass times of the last build; an error if it fell back to the CPU.
    fn passes(&self) -> Result<Vec<(&'static str, f64)>> {
        match self {
            Self::Cpu(_) => Ok(Vec::new()),
            Self::Gpu(b) => match &b.fallback {
                Some(why) => bail!("the GPU build failed: {why}"),
                None => Ok(b.passes.clone()),
            },
        }
    }
}

struct Input {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    intensity: Vec<Vec3>,
}

pub fn run(args: &BuildArgs) -> Result<()> {
    let threads = args.options.threads()?;
    let levels = args.levels;
    if args.lights.is_empty() || args.lights.contains(&0) {
        bail!("--lights: give one or more positive counts");
    }
    let world = match &args.scene {
        Some(p) => Some(World::new(load_scene(Some(p))?)),
        None => None,
    };
    let ctx = match args.device {
        Device::Cpu => None,
        Device::Gpu => Some(lgh_gpu::GpuContext::shared()?),
    };
    let constructions: &[Construction] = match args.device {
        Device::Cpu => &[
            Construction::GatherFromS1,
            Construction::ScatterAll,
            Construction::Restrict,
        ],
        Device::Gpu => &[Construction::Restrict],
    };
    let device = ctx.map_or_else(|| "cpu".to_owned(), |c| c.adapter_name());
    let mut rows = Vec::new();
    for &n in &args.lights {
        let input = match &world {
            Some(w) => {
                let set = generate_vpls(w, n, 3, 0, PathNumbers::Sobol);
                Input {
                    intensity: set.vpls.flux.clone(),
                    positions: set.vpls.positions,
                    normals: set.vpls.normals,
                }
            }
            None => {
                let s = lights_on_surfaces(n, 1);
                Input {
                    positions: s.positions,
                    normals: s.normals,
                    intensity: s.intensity,
                }
            }
        };
        let lights = InputLights {
            positions: &input.positions,
            intensity: &input.intensity,
            normals: Some(&input.normals),
        };
        for &construction in constructions {
            let mut steps: BTreeMap<String, Vec<f64>> = BTreeMap::new();
            let mut order: Vec<String> = Vec::new();
            let mut totals = Vec::new();
            // One builder across runs, as a renderer keeps it across frames; the first (cold)
            // run is not timed, and gives the peak working memory.
            let mut builder = match ctx {
                Some(c) => Builder::Gpu(Box::new(GpuGridBuilder::new(c))),
                None => Builder::Cpu(Box::default()),
            };
            let base = crate::sysmem::reset_peak();
            builder.get().build(&lights, levels, construction)?;
            builder.passes()?;
            let peak = match (base, crate::sysmem::peak_bytes()) {
                (Some(b), Some(p)) => p.saturating_sub(b),
                _ => 0,
            };
            let mut gpu: BTreeMap<&'static str, Vec<f64>> = BTreeMap::new();
            let mut gpu_order = Vec::new();
            for _ in 0..args.runs.max(1) {
                let t = builder.get().build(&lights, levels, construction)?;
                for (name, ms) in builder.passes()? {
                    if !gpu.contains_key(name) {
                        gpu_order.push(name);
                    }
                    gpu.entry(name).or_default().push(ms);
                }
                for (name, ms) in &t.0 {
                    if !steps.contains_key(name) {
                        order.push(name.clone());
                    }
                    steps.entry(name.clone()).or_default().push(*ms);
                }
                totals.push(t.total());
            }
            let Some(grid) = builder.get().grid() else {
                continue;
            };
            let steps_ms: Vec<(String, f64)> = order
                .iter()
                .map(|k| (k.clone(), median(steps.get(k).cloned().unwrap_or_default())))
                .collect();
            rows.push(serde_json::json!({
                "lights": lights.positions.len(),
                "variant": construction.name(),
                "levels": grid.l_max(),
                "lights_per_level": grid.lights_per_level(),
                "steps_ms": steps_ms.iter().map(|(k, v)| (k.clone(), serde_json::json!(v))).collect::<serde_json::Map<_, _>>(),
                "step_order": order,
                "total_ms": median(totals),
                "gpu_passes_ms": gpu_order
                    .iter()
                    .map(|k| ((*k).to_owned(), serde_json::json!(median(gpu.get(k).cloned().unwrap_or_default()))))
                    .collect::<serde_json::Map<_, _>>(),
                "peak_bytes_per_light": peak as f64 / lights.positions.len() as f64,
            }));
        }
    }
    if args.options.json {
        println!(
            "{}",
            serde_json::json!({ "threads": threads, "device": device, "runs": rows })
        );
        return Ok(());
    }
    if args.markdown {
        print_markdown(&rows, &args.lights, threads);
        return Ok(());
    }
    println!(
        "Lighting grid hierarchy construction on {device}, median of {} runs, {threads} threads{}",
        args.runs.max(1),
        args.scene
            .as_ref()
            .map_or(" (synthetic lights on surfaces)".into(), |p| format!(
                " (VPLs of {})",
                p.display()
            ))
    );
    for r in &rows {
        println!(
            "\n{} lights, {} variant: {} levels, lights per level {}, peak {:.0} bytes/light",
            r["lights"],
            r["variant"],
            r["levels"],
            r["lights_per_level"],
            r["peak_bytes_per_light"]
        );
        if let Some(order) = r["step_order"].as_array() {
            for k in order.iter().filter_map(|k| k.as_str()) {
                println!(
                    "  {k:<12} {:>10.3} ms",
                    r["steps_ms"][k].as_f64().unwrap_or(0.0)
                );
            }
        }
        println!(
            "  {:<12} {:>10.3} ms",
            "total",
            r["total_ms"].as_f64().unwrap_or(0.0)
        );
        if let Some(passes) = r["gpu_passes_ms"].as_object().filter(|p| !p.is_empty()) {
            println!("  GPU passes (timestamps, within level_count and gpu_build):");
            for (k, v) in passes {
                println!("    {k:<14} {:>8.3} ms", v.as_f64().unwrap_or(0.0));
            }
        }
    }
    Ok(())
}

/// The total build times of `rows` as a Markdown table: one row per light count, one column
/// per construction.
fn print_markdown(rows: &[serde_json::Value], lights: &[usize], threads: usize) {
    let variants = ["restrict", "gather", "scatter"];
    println!("Hierarchy build, median ms, {threads} threads (`lgh bench build --markdown`):\n");
    println!("| lights | {} |", variants.join(" | "));
    println!("| --- |{}", " --- |".repeat(variants.len()));
    for &n in lights {
        let cells: Vec<String> = variants
            .iter()
            .map(|v| {
                rows.iter()
                    .find(|r| r["variant"] == *v && r["lights"].as_u64() == Some(n as u64))
                    .and_then(|r| r["total_ms"].as_f64())
                    .map_or("-".into(), |ms| format!("{ms:.2}"))
            })
            .collect();
        println!("| {n} | {} |", cells.join(" | "));
    }
}
