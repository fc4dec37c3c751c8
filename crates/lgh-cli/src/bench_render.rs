//! `lgh bench render`: the LGH paper's Tables 2 and 3 on this machine.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::Args;
use lgh_core::timing::Timings;
use lgh_render::methods::MethodInputs;
use lgh_render::methods::lgh::{LGH, LGH_UNSHADOWED, LghSettings, LghStats};
use lgh_render::passes::gbuffer::GBuffer;
use lgh_render::passes::vpl_gen::{PathNumbers, generate_vpls};
use lgh_render::settings::{Device, ShadowSettings, Tiling};
use lgh_render::{FrameMemory, RenderSettings, Silent};

use crate::bench_cmd::median;
use crate::render_cmd::parse_size;

/// Arguments of `lgh bench render`.
#[derive(Debug, Args)]
pub struct RenderBenchArgs {
    /// Scene file (.toml, .gltf, .glb, .obj). Default: the built-in Cornell box.
    pub scene: Option<PathBuf>,
    /// VPL counts, comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "1000,10000,100000,1000000",
        value_parser = crate::caps::count(crate::caps::MAX_BENCH_VPLS)
    )]
    pub vpls: Vec<usize>,
    /// Image size, WIDTHxHEIGHT (the paper uses 1280x720).
    #[arg(long, default_value = "640x360", value_parser = parse_size)]
    pub size: (u32, u32),
    /// The LGH settings of every run.
    #[command(flatten)]
    pub lgh: LghSettings,
    /// Interleaving n (n x n sub-images) of the Table 3 runs, comma-separated (the paper's
    /// Table 3 compares 1, 2 and 4). Table 2 is without interleaving.
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub interleave: Vec<u32>,
    /// Frames rendered per configuration; every time reported is the median over them.
    #[arg(long, default_value_t = 1, value_parser = crate::caps::count_u32(crate::caps::MAX_RUNS))]
    pub runs: u32,
    /// Threads and output.
    #[command(flatten)]
    pub options: crate::bench_cmd::BenchOptions,
    /// Print Table 3 as a Markdown table, the form of docs/performance.md.
    #[arg(long)]
    pub markdown: bool,
    /// Where the lighting loop runs: cpu, or gpu (lgh's loop, shadow targets and rays on
    /// the GPU; "lighting" is then the GPU pass, from its timestamps where the adapter has
    /// them, and "gpu_transfer" the copies to and from it).
    #[arg(long, value_enum, default_value_t = Device::Cpu)]
    pub device: Device,
}

pub fn run(args: &RenderBenchArgs) -> Result<()> {
    if let Some(n) = args.interleave.iter().find(|n| !(1..=16).contains(*n)) {
        anyhow::bail!("--interleave {n}: expected 1 to 16");
    }
    let threads = args.options.threads()?;
    let (shadowed, unshadowed, device) = match args.device {
        Device::Cpu => (LGH, LGH_UNSHADOWED, "cpu".to_owned()),
        Device::Gpu => {
            let ctx = lgh_gpu::GpuContext::shared()?;
            (
                lgh_gpu::lgh::LGH_GPU,
                lgh_gpu::lgh::LGH_UNSHADOWED_GPU,
                ctx.adapter_name(),
            )
        }
    };
    let (name, world) = crate::bench_cmd::open_scene(args.scene.as_deref(), &args.options)?;
    let (w, h) = args.size;
    let frame = world.scene.camera().frame(w, h);
    // The G-buffer too is timed over `runs` renders, on the device's backend (on the GPU:
    // the rays and the read-back of the planes); like the frames after the first, the
    // renders after the first reuse its planes (the first also allocates them).
    let mut g = GBuffer::default();
    let mut g_times = Vec::new();
    for _ in 0..args.runs {
        let t = Instant::now();
        if !shadowed
            .get()
            .trace_gbuffer(&world, &frame, (w, h), &mut g, false)?
        {
            g.render_into(&world, &frame, w, h);
        }
        g_times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let gbuffer_ms = median(g_times);
    let mut rows = Vec::new();
    for &n in &args.vpls {
        let t = Instant::now();
        let set = match args.device {
            Device::Cpu => generate_vpls(&world, n, 3, 0, PathNumbers::Sobol),
            Device::Gpu => {
                lgh_gpu::vpls::generate_vpls(lgh_gpu::GpuContext::shared()?, &world, n, 3, 0)?
            }
        };
        let vpl_ms = t.elapsed().as_secs_f64() * 1e3;
        let mut memory = FrameMemory::default();
        let mut per_k = serde_json::Map::new();
        let mut build_ms = 0.0;
        // Table 2: k = 0, 1, 4 without interleaving; Table 3: k = 4 at each interleaving.
        let runs = [0u32, 1, 4]
            .map(|k| (k, 1))
            .into_iter()
            .chain(args.interleave.iter().filter(|&&n| n != 1).map(|&n| (4, n)));
        for (k, n) in runs {
            let settings = RenderSettings {
                width: w,
                height: h,
                lgh: args.lgh.clone(),
                shadows: ShadowSettings {
                    samples: Some(k),
                    ..ShadowSettings::default()
                },
                tiling: Tiling {
                    interleave: Some(n),
                    ..Tiling::default()
                },
                ..RenderSettings::default()
            };
            settings.validate()?;
            let inputs = MethodInputs {
                world: &world,
                gbuffer: &g,
                camera: &frame,
                vpls: &set.vpls,
                vpl_count: set.vpls.len(),
                vpl_bins: None,
                settings: &settings,
                progress: &Silent,
            };
            let mut samples: Vec<(Timings, f64)> = Vec::new();
            let mut last = None;
            for _ in 0..args.runs {
                let start = Instant::now();
                let method = if k > 0 { shadowed } else { unshadowed };
                let out = method.get().render(&inputs, &mut memory)?;
                let total = start.elapsed().as_secs_f64() * 1e3;
                samples.push((
                    out.timings.clone(),
                    total - out.timings.get("lgh_build").unwrap_or(0.0),
                ));
                last = Some(out);
            }
            let Some(stats) = last.as_ref().and_then(|o| o.stats::<LghStats>()) else {
                continue;
            };
            let get = |name: &str| {
                median(
                    samples
                        .iter()
                        .map(|(t, _)| t.get(name).unwrap_or(0.0))
                        .collect(),
                )
            };
            build_ms = get("lgh_build");
            per_k.insert(
                run_key(k, n),
                serde_json::json!({
                    "lighting_ms": get("lighting"),
                    "representatives_ms": get("representatives"),
                    "shadow_targets_ms": get("shadow_targets"),
                    "shadow_rays_ms": get("shadow_rays"),
                    "gpu_transfer_ms": get("gpu_transfer"),
                    "interleave_blur_ms": get("interleave_blur"),
                    "shadow_filter_ms": get("shadow_filter"),
                    "composite_ms": get("composite"),
                    "render_ms": median(samples.iter().map(|s| s.1).collect()),
                    "avg_overdraw": stats.avg_overdraw,
                    "grid_lights": stats.grid_lights,
                    "levels": stats.levels,
                }),
            );
        }
        rows.push(serde_json::json!({
            "vpls": set.vpls.len(),
            "vpl_generation_ms": vpl_ms,
            "lgh_build_ms": build_ms,
            "gbuffer_ms": gbuffer_ms,
            "runs": per_k,
        }));
    }
    if args.options.json {
        println!(
            "{}",
            serde_json::json!({"scene": name, "width": w, "height": h, "threads": threads, "device": device, "alpha": args.lgh.alpha, "rows": rows})
        );
        return Ok(());
    }
    let mut interleaves = vec![1];
    interleaves.extend(args.interleave.iter().filter(|&&n| n != 1));
    if args.markdown {
        print_markdown(&rows, &interleaves, gbuffer_ms);
        return Ok(());
    }
    println!(
        "LGH render times on {name}, {w}x{h}, alpha {}, {threads} threads, lighting loop on {device} (ms)",
        args.lgh.alpha
    );
    println!(
        "\nTable 2: {:>9} {:>9} {:>9} {:>11} {:>11} {:>11}",
        "VPLs", "VPL gen", "LGH build", "no shadows", "1 shadow", "4 shadows"
    );
    for r in &rows {
        let t = |k: u32| {
            r["runs"][format!("shadow_samples_{k}")]["render_ms"]
                .as_f64()
                .unwrap_or(0.0)
        };
        println!(
            "         {:>9} {:>9.1} {:>9.1} {:>11.1} {:>11.1} {:>11.1}",
            r["vpls"],
            r["vpl_generation_ms"].as_f64().unwrap_or(0.0),
            r["lgh_build_ms"].as_f64().unwrap_or(0.0),
            t(0),
            t(1),
            t(4)
        );
    }
    println!(
        "\nTable 3 (4 shadow samples): {:>9} {:>3} {:>9} {:>9} {:>9} {:>9} {:>11} {:>9} {:>11} {:>10} {:>9}",
        "VPLs",
        "il",
        "G-buffer",
        "reps",
        "lighting",
        "targets",
        "shadow rays",
        "blur",
        "shadow filt",
        "composite",
        "overdraw"
    );
    for r in &rows {
        for &n in &interleaves {
            let k = &r["runs"][run_key(4, n)];
            let f = |key: &str| k[key].as_f64().unwrap_or(0.0);
            println!(
                "                            {:>9} {:>3} {:>9.1} {:>9.1} {:>9.1} {:>9.1} {:>11.1} {:>9.1} {:>11.1} {:>10.1} {:>9.1}",
                r["vpls"],
                n,
                gbuffer_ms,
                f("representatives_ms"),
                f("lighting_ms"),
                f("shadow_targets_ms"),
                f("shadow_rays_ms"),
                f("interleave_blur_ms"),
                f("shadow_filter_ms"),
                f("composite_ms"),
                f("avg_overdraw")
            );
        }
    }
    Ok(())
}

/// The JSON key of the run with `k` shadow samples and n x n interleaving:
/// `shadow_samples_K`, with `_interleave_N` for n > 1.
fn run_key(k: u32, n: u32) -> String {
    if n == 1 {
        format!("shadow_samples_{k}")
    } else {
        format!("shadow_samples_{k}_interleave_{n}")
    }
}

/// The passes of the k = 4 runs as a Markdown table, one row per VPL count and interleaving.
fn print_markdown(rows: &[serde_json::Value], interleaves: &[u32], gbuffer_ms: f64) {
    let passes = [
        ("representatives_ms", "reps"),
        ("lighting_ms", "lighting"),
        ("shadow_targets_ms", "targets"),
        ("shadow_rays_ms", "rays"),
        ("interleave_blur_ms", "blur"),
        ("shadow_filter_ms", "a-trous"),
        ("composite_ms", "composite"),
        ("render_ms", "frame after build"),
    ];
    let names: Vec<&str> = passes.iter().map(|p| p.1).collect();
    println!("| VPLs | il | G-buffer | {} |", names.join(" | "));
    println!("| --- | --- | --- |{}", " --- |".repeat(passes.len()));
    for r in rows {
        for &n in interleaves {
            let k = &r["runs"][run_key(4, n)];
            let cells: Vec<String> = passes
                .iter()
                .map(|(key, _)| format!("{:.1}", k[*key].as_f64().unwrap_or(0.0)))
                .collect();
            println!(
                "| {} | {n} | {gbuffer_ms:.1} | {} |",
                r["vpls"],
                cells.join(" | ")
            );
        }
    }
}
