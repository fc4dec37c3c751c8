//! `lgh bench slc`: stochastic light culling against its clamped baseline and LGH at equal
//! time (Tokuyoshi & Harada 2016, Figs. 4-6), and the many-area-light path tracer against
//! uniform light sampling at equal time (their Fig. 9).

use std::path::PathBuf;

use anyhow::{Result, anyhow};
use clap::Args;
use lgh_render::image::metrics::diff;
use lgh_render::methods::lgh::{LGH_UNSHADOWED, LghStats};
use lgh_render::methods::pt::{PT_CLAMPED, PT_SLC, PT_UNIFORM, PtSettings, PtStats};
use lgh_render::methods::slc::{SLC, SLC_CLAMPED, SlcStats};
use lgh_render::methods::{Method, brute};
use lgh_render::settings::{ShadowSettings, Tiling};
use lgh_render::{Component, Frame, Image, RenderSettings, Silent, World, render_frame};

use crate::render_cmd::parse_size;
use crate::scene_arg::load_scene;

/// Arguments of `lgh bench slc`.
#[derive(Debug, Args)]
pub struct SlcBenchArgs {
    /// Scene for the VPL part (file or builtin:NAME). Default: the built-in Cornell box.
    pub scene: Option<PathBuf>,
    /// VPL counts, comma-separated (the paper's 16K, 65K, 262K).
    #[arg(long, value_delimiter = ',', default_value = "16384,65536,262144", value_parser = crate::caps::count(crate::caps::MAX_BENCH_VPLS))]
    pub vpls: Vec<usize>,
    /// Image size of the VPL part, WIDTHxHEIGHT.
    #[arg(long, default_value = "320x180", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Error bound of `slc` (the paper's 0.0005).
    #[arg(long, default_value_t = 0.0005)]
    pub error_bound: f32,
    /// Interleaving of `slc` and `slc-clamped` (the paper's 8).
    #[arg(long, default_value_t = 8)]
    pub interleave: u32,
    /// Skip the path-tracing part.
    #[arg(long)]
    pub no_pt: bool,
    /// Image size of the path-tracing part (scene builtin:emitter-room).
    #[arg(long, default_value = "160x90", value_parser = parse_size)]
    pub pt_size: (u32, u32),
    /// Time budget of each path tracer in the equal-time comparison, in ms.
    #[arg(long, default_value_t = 4000.0)]
    pub pt_budget_ms: f64,
    /// Samples per pixel of the `pt-uniform` reference.
    #[arg(long, default_value_t = 1024, value_parser = crate::caps::count_u32(65536))]
    pub pt_reference_spp: u32,
    /// Error bound of `pt-slc`, relative to the emitter room's pixel values.
    #[arg(long, default_value_t = 0.005)]
    pub pt_error_bound: f32,
    /// Threads and output.
    #[command(flatten)]
    pub options: crate::bench_cmd::BenchOptions,
}

fn indirect_ms(f: &Frame) -> f64 {
    f.timings
        .get("indirect")
        .or_else(|| f.timings.get("path_tracing"))
        .unwrap_or(0.0)
}

fn render(world: &World, s: &RenderSettings) -> Result<Frame> {
    render_frame(world, s, &Silent).map_err(|e| anyhow!("{e}"))
}

/// One measured method: time, culling and error against the reference.
fn row(
    method: &str,
    vpls: usize,
    f: &Frame,
    reference: &Image,
    eb: Option<f32>,
) -> Result<serde_json::Value> {
    let m = diff(&f.image, reference).map_err(|e| anyhow!("{e}"))?;
    Ok(serde_json::json!({
        "vpls": vpls,
        "method": method,
        "ms": indirect_ms(f),
        "avg_lights_per_pixel": f.stats::<SlcStats>().map(|s| s.avg_lights_per_pixel),
        "avg_overdraw": f.stats::<LghStats>().map(|s| s.avg_overdraw),
        "error_bound": eb,
        "rel_rmse": m.rel_rmse,
        "rel_bias": m.rel_bias,
    }))
}

pub fn run(args: &SlcBenchArgs) -> Result<()> {
    for (flag, v) in [
        ("--error-bound", f64::from(args.error_bound)),
        ("--pt-error-bound", f64::from(args.pt_error_bound)),
        ("--pt-budget-ms", args.pt_budget_ms),
    ] {
        if !v.is_finite() || v <= 0.0 {
            anyhow::bail!("{flag} {v}: must be a positive number");
        }
    }
    let threads = args.options.threads()?;
    let (name, world) = crate::bench_cmd::open_scene(args.scene.as_deref(), &args.options)?;
    let base = RenderSettings {
        width: args.size.0,
        height: args.size.1,
        area_samples: 0,
        component: Component::Indirect,
        shadows: ShadowSettings {
            samples: Some(0),
            ..ShadowSettings::default()
        },
        ..RenderSettings::default()
    };
    let slc_tiling = Tiling {
        interleave: Some(args.interleave),
        ..Tiling::default()
    };
    let mut vpl_rows = Vec::new();
    for &n in &args.vpls {
        let s = RenderSettings {
            vpls: n,
            method: brute::BRUTE_UNSHADOWED,
            ..base.clone()
        };
        let reference = render(&world, &s)?;
        let r = &reference.image;
        vpl_rows.push(row("brute-unshadowed", n, &reference, r, None)?);
        let slc = render(
            &world,
            &RenderSettings {
                vpls: n,
                method: SLC,
                error_bound: Some(args.error_bound),
                tiling: slc_tiling,
                ..base.clone()
            },
        )?;
        let budget = indirect_ms(&slc);
        vpl_rows.push(row("slc", n, &slc, r, Some(args.error_bound))?);
        // Clamped at the same bound, and at the bound whose time matches slc (bisection on
        // log epsilon: a larger bound means shorter ranges, less time).
        let clamped = |eb: f32| {
            render(
                &world,
                &RenderSettings {
                    vpls: n,
                    method: SLC_CLAMPED,
                    error_bound: Some(eb),
                    tiling: slc_tiling,
                    ..base.clone()
                },
            )
        };
        let same = clamped(args.error_bound)?;
        vpl_rows.push(row("slc-clamped", n, &same, r, Some(args.error_bound))?);
        let (mut lo, mut hi) = (args.error_bound.ln(), (args.error_bound * 1e5).ln());
        let mut best = same;
        let mut best_eb = args.error_bound;
        for _ in 0..7 {
            let mid = 0.5 * (lo + hi);
            let f = clamped(mid.exp())?;
            if indirect_ms(&f) > budget {
                lo = mid;
            } else {
                hi = mid;
            }
            if (indirect_ms(&f) - budget).abs() < (indirect_ms(&best) - budget).abs() {
                best = f;
                best_eb = mid.exp();
            }
        }
        vpl_rows.push(row("slc-clamped-equal-time", n, &best, r, Some(best_eb))?);
        let lgh = render(
            &world,
            &RenderSettings {
                vpls: n,
                method: LGH_UNSHADOWED,
                ..base.clone()
            },
        )?;
        vpl_rows.push(row("lgh-unshadowed", n, &lgh, r, None)?);
    }

    let mut pt_rows = Vec::new();
    if !args.no_pt {
        let room = load_scene(Some(std::path::Path::new("builtin:emitter-room")))?;
        let room = World::new(room);
        let pt = |method: Method, spp: u32, seed: u64| {
            render(
                &room,
                &RenderSettings {
                    width: args.pt_size.0,
                    height: args.pt_size.1,
                    seed,
                    method,
                    component: Component::Indirect,
                    error_bound: Some(args.pt_error_bound),
                    pt: PtSettings {
                        spp,
                        ..PtSettings::default()
                    },
                    ..RenderSettings::default()
                },
            )
        };
        let reference = pt(PT_UNIFORM, args.pt_reference_spp, 1_000_003)?;
        for method in [PT_UNIFORM, PT_SLC, PT_CLAMPED] {
            let probe = pt(method, 4, 7)?;
            let per_spp = indirect_ms(&probe) / 4.0;
            let spp = ((args.pt_budget_ms / per_spp.max(1e-3)) as u32).clamp(1, 1 << 16);
            let f = pt(method, spp, 7)?;
            let m = diff(&f.image, &reference.image).map_err(|e| anyhow!("{e}"))?;
            pt_rows.push(serde_json::json!({
                "method": method.name(),
                "spp": spp,
                "ms": indirect_ms(&f),
                "avg_overlapping_lights": f.stats::<PtStats>().map(|p| p.avg_overlapping),
                "rel_rmse": m.rel_rmse,
                "rel_bias": m.rel_bias,
            }));
        }
    }

    if args.options.json {
        let v = serde_json::json!({
            "scene": name,
            "threads": threads,
            "width": args.size.0,
            "height": args.size.1,
            "vpl_rows": vpl_rows,
            "pt_rows": pt_rows,
        });
        println!("{v}");
        return Ok(());
    }
    println!(
        "{name}, {}x{}, {threads} threads; indirect light against brute-unshadowed",
        args.size.0, args.size.1
    );
    println!(
        "{:>8} {:<24} {:>10} {:>12} {:>10} {:>10} {:>9}",
        "VPLs", "method", "ms", "lights/px", "rel_rmse", "rel_bias", "eps"
    );
    for r in &vpl_rows {
        let lp = r["avg_lights_per_pixel"]
            .as_f64()
            .or(r["avg_overdraw"].as_f64());
        println!(
            "{:>8} {:<24} {:>10.1} {:>12} {:>10.4} {:>+10.4} {:>9}",
            r["vpls"].as_u64().unwrap_or(0),
            r["method"].as_str().unwrap_or(""),
            r["ms"].as_f64().unwrap_or(0.0),
            lp.map_or("-".into(), |v| format!("{v:.1}")),
            r["rel_rmse"].as_f64().unwrap_or(f64::NAN),
            r["rel_bias"].as_f64().unwrap_or(f64::NAN),
            r["error_bound"]
                .as_f64()
                .map_or("-".into(), |v| format!("{v:.2e}")),
        );
    }
    if !pt_rows.is_empty() {
        println!(
            "\nbuiltin:emitter-room, {}x{}, equal time {} ms, against pt-uniform at {} spp",
            args.pt_size.0, args.pt_size.1, args.pt_budget_ms, args.pt_reference_spp
        );
        for r in &pt_rows {
            println!(
                "{:<12} {:>6} spp {:>9.0} ms  rel_rmse {:.4}  rel_bias {:+.4}",
                r["method"].as_str().unwrap_or(""),
                r["spp"].as_u64().unwrap_or(0),
                r["ms"].as_f64().unwrap_or(0.0),
                r["rel_rmse"].as_f64().unwrap_or(f64::NAN),
                r["rel_bias"].as_f64().unwrap_or(f64::NAN),
            );
        }
    }
    Ok(())
}
