//! `lgh bench temporal`: flicker of the indirect light of a static view whose VPLs are
//! regenerated every frame (LGH paper 4.3), without and with temporal filtering, and the
//! flicker of the unshadowed lighting alone (shadows off), which filtering only the shadow
//! ratio cannot remove.

use std::path::PathBuf;

use anyhow::{Result, anyhow};
use clap::Args;
use lgh_render::denoise::temporal::{TemporalSettings, TemporalTarget};
use lgh_render::methods::lgh::LGH;
use lgh_render::sequence::{Sequence, flicker};
use lgh_render::{Component, RenderSettings, Silent, World};

use crate::render_cmd::parse_size;

/// Arguments of `lgh bench temporal`.
#[derive(Debug, Args)]
pub struct TemporalBenchArgs {
    /// Scene (file or builtin:NAME). Default: the built-in Cornell box.
    pub scene: Option<PathBuf>,
    /// Frames per run (the first frames warm the history up and count too).
    #[arg(long, default_value_t = 16, value_parser = crate::caps::count_u32(crate::caps::MAX_BENCH_FRAMES))]
    pub frames: u32,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "320x180", value_parser = parse_size)]
    pub size: (u32, u32),
    /// VPLs per frame.
    #[arg(long, default_value_t = 10_000, value_parser = crate::caps::count(crate::caps::MAX_BENCH_VPLS))]
    pub vpls: usize,
    /// Weight of the current frame in the moving average.
    #[arg(long, default_value_t = 0.1)]
    pub taa_alpha: f32,
    /// Threads and output.
    #[command(flatten)]
    pub options: crate::bench_cmd::BenchOptions,
}

/// Mean flicker over consecutive frames and mean frame time of one run.
fn run_one(
    world: &World,
    base: &RenderSettings,
    frames: u32,
    taa: Option<TemporalSettings>,
) -> Result<(f64, f64)> {
    let mut seq = Sequence::new(taa);
    let mut prev: Option<Vec<glam::Vec3>> = None;
    let (mut sum, mut n, mut ms) = (0.0, 0u32, 0.0);
    for f in 0..frames {
        let s = RenderSettings {
            seed: u64::from(f),
            ..base.clone()
        };
        let mut frame = seq.render(world, &s, &Silent).map_err(|e| anyhow!("{e}"))?;
        ms += frame.timings.get("total").unwrap_or(0.0);
        let current = std::mem::take(&mut frame.indirect.pixels);
        if let Some(p) = &prev {
            sum += flicker(p, &current);
            n += 1;
        }
        prev = Some(current);
        seq.recycle(frame);
    }
    Ok((sum / f64::from(n.max(1)), ms / f64::from(frames.max(1))))
}

pub fn run(args: &TemporalBenchArgs) -> Result<()> {
    let threads = args.options.threads()?;
    let (name, world) = crate::bench_cmd::open_scene(args.scene.as_deref(), &args.options)?;
    let base = RenderSettings {
        width: args.size.0,
        height: args.size.1,
        vpls: args.vpls,
        area_samples: 0,
        method: LGH,
        component: Component::Indirect,
        ..RenderSettings::default()
    };
    let taa = |target| TemporalSettings {
        alpha: args.taa_alpha,
        target,
        ..TemporalSettings::default()
    };
    taa(TemporalTarget::ShadowRatio).validate()?;
    let (without, ms) = run_one(&world, &base, args.frames, None)?;
    // The flicker of the unshadowed lighting A alone: the part no shadow filter can remove.
    let mut no_shadows = base.clone();
    no_shadows.shadows.samples = Some(0);
    let (unshadowed, _) = run_one(&world, &no_shadows, args.frames, None)?;
    let (with_ratio, ms_ratio) = run_one(
        &world,
        &base,
        args.frames,
        Some(taa(TemporalTarget::ShadowRatio)),
    )?;
    let (with_indirect, ms_ind) = run_one(
        &world,
        &base,
        args.frames,
        Some(taa(TemporalTarget::Indirect)),
    )?;
    // How many times lower the flicker is with each filter (issue target: 3x).
    let lower = |with: f64| {
        if with > 0.0 {
            without / with
        } else {
            f64::INFINITY
        }
    };
    if args.options.json {
        println!(
            "{}",
            serde_json::json!({
                "scene": name,
                "threads": threads,
                "frames": args.frames,
                "width": args.size.0,
                "height": args.size.1,
                "vpls": args.vpls,
                "taa_alpha": args.taa_alpha,
                "flicker_without_taa": without,
                "flicker_unshadowed_lighting": unshadowed,
                "flicker_with_taa": with_ratio,
                "flicker_with_taa_indirect": with_indirect,
                "reduction_with_taa": lower(with_ratio),
                "reduction_with_taa_indirect": lower(with_indirect),
                "frame_ms_without_taa": ms,
                "frame_ms_with_taa": ms_ratio,
                "frame_ms_with_taa_indirect": ms_ind,
            })
        );
    } else {
        println!(
            "{name}, {}x{}, {} VPLs regenerated per frame, {} frames, {threads} threads",
            args.size.0, args.size.1, args.vpls, args.frames
        );
        println!("flicker (mean |frame - previous| / mean, indirect light):");
        println!("  without temporal filter     {without:.4}   {ms:.0} ms/frame");
        println!(
            "  (unshadowed lighting alone  {unshadowed:.4}: the floor of the shadow-ratio TAA)"
        );
        println!(
            "  TAA on the shadow ratio     {with_ratio:.4}   {ms_ratio:.0} ms/frame   ({:.1}x lower)",
            lower(with_ratio)
        );
        println!(
            "  TAA on the indirect light   {with_indirect:.4}   {ms_ind:.0} ms/frame   ({:.1}x lower)",
            lower(with_indirect)
        );
    }
    Ok(())
}
