//! `lgh render`: one frame, or a sequence of frames, to image files.

pub mod args;
pub mod piece;
mod stats;

use std::time::Instant;

use anyhow::{Result, bail};
use lgh_render::accumulate::render_accumulated;
use lgh_render::budget::MemoryEstimate;
use lgh_render::image::check_output_path;
use lgh_render::sequence::Sequence;
use lgh_render::{FrameMemory, RenderSettings, World, render_frame};

use args::frame_path;
pub use args::{RenderArgs, parse_size};
use stats::{FrameReport, ReportContext, write_json};

use crate::progress_bar::Bars;
use crate::scene_arg::load_scene;

/// Checks what the library's validation does not: the output files and the sequence flags.
fn check_args(args: &RenderArgs) -> Result<()> {
    if args.frames.is_some()
        && !args
            .out
            .file_name()
            .is_some_and(|n| n.to_string_lossy().contains('#'))
    {
        bail!(
            "{}: with --frames the file name needs #### for the frame number (e.g. frames/frame_####.png)",
            args.out.display()
        );
    }
    if args.frames.is_some() && args.accumulate > 1 {
        bail!("--accumulate and --frames cannot be combined (accumulation renders one view)");
    }
    args.temporal.validate()?;
    if !args.fps.is_finite() || args.fps <= 0.0 {
        bail!("--fps {}: must be a positive number", args.fps);
    }
    let out = if args.frames.is_some() {
        frame_path(&args.out, 0)
    } else {
        args.out.clone()
    };
    check_output_path(&out)?;
    let piece = args.piece.is_some() || args.region.is_some();
    let side = piece::side_path(&out);
    if piece {
        if lgh_render::image::ImageFormat::from_path(&out)? != lgh_render::image::ImageFormat::Exr {
            bail!(
                "{}: a piece of a frame (--tile, --region) is written as .exr (linear, for lgh merge)",
                out.display()
            );
        }
        if args.heatmap.is_some() {
            bail!("--heatmap and --tile/--region cannot be combined");
        }
    }
    let mut outputs = vec![("-o", out.as_path())];
    if piece {
        outputs.push(("the piece's side file", side.as_path()));
    }
    if let Some(h) = &args.heatmap {
        check_output_path(h)?;
        outputs.push(("--heatmap", h));
    }
    if let Some(s) = &args.stats {
        outputs.push(("--stats", s));
    }
    lgh_render::output::check_outputs(&outputs)?;
    Ok(())
}

/// Writes a frame: the whole image, or the piece of `s.region` with its side file.
fn save(
    args: &RenderArgs,
    image: &lgh_render::Image,
    path: &std::path::Path,
    s: &RenderSettings,
    exposure: f32,
    frame: Option<u32>,
) -> Result<()> {
    if s.region.is_some() {
        let scene = args.scene.as_ref().map_or_else(
            || "builtin:cornell".into(),
            |p| p.to_string_lossy().into_owned(),
        );
        // The seed of a sequence's frame is the base seed plus the frame number: the side
        // file records the base, so that every frame's pieces agree.
        let mut base = s.clone();
        base.seed = args.settings.seed;
        base.slc.frame_seed = 0;
        piece::write(path, image, &base, &scene, exposure, frame)
    } else {
        Ok(image.save(path, exposure)?)
    }
}

/// `--frames`: renders the sequence, one image per frame.
fn run_sequence(
    args: &RenderArgs,
    mut world: World,
    settings: &RenderSettings,
    (first, end): (u32, u32),
    exposure: f32,
    bars: &Bars,
) -> Result<()> {
    let mut seq = Sequence::new(args.taa.then_some(args.temporal));
    let mut per_frame = Vec::new();
    // The temporal filter's history: frames before `first`, rendered and not written.
    let warm = if args.taa {
        first.saturating_sub(args.warmup)
    } else {
        first
    };
    for f in warm..end {
        world
            .check_time(f as f32 / args.fps)
            .map_err(|e| anyhow::anyhow!("frame {f}: {e}"))?;
    }
    for f in warm..end {
        let update = Instant::now();
        world.set_time(f as f32 / args.fps)?;
        let update_ms = update.elapsed().as_secs_f64() * 1e3;
        let mut s = settings.clone();
        s.seed = settings.seed.wrapping_add(u64::from(f));
        s.slc.frame_seed = f;
        let frame = seq.render(&world, &s, bars)?;
        if f < first {
            seq.recycle(frame);
            continue;
        }
        let path = frame_path(&args.out, f);
        save(args, &frame.image, &path, &s, exposure, Some(f))?;
        let ms = frame.timings.get("total").unwrap_or(0.0);
        per_frame
            .push(serde_json::json!({"frame": f, "total_ms": ms, "scene_update_ms": update_ms}));
        if !args.quiet {
            eprintln!(
                "frame {f}: {ms:.0} ms (+ {update_ms:.0} ms moving the scene) -> {}",
                path.display()
            );
        }
        seq.recycle(frame);
    }
    if let Some(path) = &args.stats {
        let v = serde_json::json!({
            "scene": world.scene.name,
            "method": settings.method.name(),
            "frames": per_frame,
            "fps": args.fps,
            "taa": args.taa,
            "settings": settings,
        });
        write_json(path, &v)?;
    }
    Ok(())
}

pub fn run(args: &RenderArgs) -> Result<()> {
    check_args(args)?;
    let mut settings = args.render_settings().map_err(anyhow::Error::msg)?;
    settings.validate()?;
    let mut device = "cpu".to_owned();
    if args.device == args::Device::Gpu {
        let name = settings.method.name();
        settings.method = lgh_gpu::gpu_method(settings.method)
            .ok_or_else(|| lgh_gpu::GpuError::NotPorted(name.to_owned()))?;
        device = lgh_gpu::GpuContext::shared()?.adapter_name();
        if !args.quiet {
            eprintln!("GPU: {device}");
        }
    }
    for w in settings.warnings() {
        eprintln!("warning: {w}");
    }
    let threads = crate::set_threads(args.threads)?;
    let start = Instant::now();
    let scene = load_scene(args.scene.as_deref())?;
    let load_ms = start.elapsed().as_secs_f64() * 1e3;
    let frames_held = if args.accumulate > 1 || args.taa {
        2
    } else {
        1
    };
    let estimate = MemoryEstimate::new(&scene, &settings, frames_held);
    crate::sysmem::check(&estimate, args.max_memory)?;
    let exposure = settings.exposure_or(scene.exposure);
    let scene_name = scene.name.clone();

    let t = Instant::now();
    let world = World::with_accel(scene, args.accel.kind())?;
    let bvh_ms = t.elapsed().as_secs_f64() * 1e3;

    let bars = Bars::new(args.quiet);
    if let Some(frames) = args.frames {
        return run_sequence(args, world, &settings, frames, exposure, &bars);
    }
    let frame = if args.accumulate > 1 {
        let mut memory = FrameMemory::default();
        render_accumulated(&world, &settings, args.accumulate, &bars, &mut memory)?
    } else {
        render_frame(&world, &settings, &bars)?
    };
    save(args, &frame.image, &args.out, &settings, exposure, None)?;
    if let (Some(path), Some(counts)) = (&args.heatmap, &frame.method.lights_per_pixel) {
        let max = crate::heatmap::write(path, settings.width, settings.height, counts)?;
        if !args.quiet {
            eprintln!("heatmap: 0 (bottom of the bar) to {max} lights per pixel (top)");
        }
    }
    if let Some(path) = &args.stats {
        let context = ReportContext {
            scene: &scene_name,
            settings: &settings,
            threads,
            triangles: world.accel.len(),
            cut_out_triangles: world.accel.cut_out(),
            accel: world.accel.kind().name(),
            device: device.clone(),
            load_ms,
            bvh_ms,
            frames: args.accumulate,
            estimate,
        };
        write_json(path, &FrameReport::new(&frame, &context))?;
    }
    if !args.quiet {
        eprintln!(
            "{}: {}x{}, {} triangles{}, {} VPLs from {} light paths, {} in {:.0} ms ({} threads) -> {}",
            scene_name,
            settings.width,
            settings.height,
            world.accel.len(),
            match world.accel.cut_out() {
                0 => String::new(),
                n => format!(" ({n} with alpha cut-outs)"),
            },
            frame.vpls.len(),
            frame.vpls.paths,
            settings.method.name(),
            frame.timings.get("total").unwrap_or(0.0) + bvh_ms,
            threads,
            args.out.display()
        );
    }
    Ok(())
}
