//! `lgh render`.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use lgh_core::lighting_grid::{Construction, LevelCount};
use lgh_core::vpl::GridEmission;
use lgh_render::image::check_output_path;
use lgh_render::ism::IsmSettings;
use lgh_render::lgh::{JitterAt, LghSettings, MAX_SHADOW_SAMPLES, ShadowTarget};
use lgh_render::pt::PtSettings;
use lgh_render::sequence::Sequence;
use lgh_render::slc::SlcSettings;
use lgh_render::temporal::{TemporalSettings, TemporalTarget};
use lgh_render::vpl_gen::PathNumbers;
use lgh_render::{Component, Method, RenderSettings, World, render_frame};

use crate::progress_bar::Bars;
use crate::scene_arg::load_scene;

/// Indirect-lighting methods.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum MethodArg {
    /// Every pixel sums every VPL with an exact shadow ray (the reference).
    Brute,
    /// Every pixel sums every VPL without shadow rays.
    BruteUnshadowed,
    /// Lighting grid hierarchy (Lin & Yuksel 2019) with stochastic ray-traced shadows.
    Lgh,
    /// Lighting grid hierarchy without shadows.
    LghUnshadowed,
    /// Stochastic light culling (Tokuyoshi & Harada 2016): random unbiased light ranges,
    /// tiled lighting; shadows through the ratio estimator (--shadow-samples, 0 = none).
    Slc,
    /// Tiled lighting with light ranges clamped from the error bound (biased darker).
    SlcClamped,
    /// Path tracing (all bounces, not VPLs) whose light sampling uses stochastic light
    /// culling: bounding sphere tree, reservoir sampling, resampled importance sampling.
    PtSlc,
    /// Path tracing with uniform light sampling (baseline).
    PtUniform,
    /// Path tracing with clamped light ranges (biased baseline).
    PtClamped,
}

/// Numbers of the light paths that make the VPLs.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum PathNumbersArg {
    /// Path k uses point k of a per-frame scrambled Sobol sequence: the VPLs of one frame
    /// spread more evenly, so the indirect light changes less between frames.
    Sobol,
    /// Independent random numbers per path (plain Monte Carlo).
    Random,
}

/// Shadow filters.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum FilterArg {
    /// Edge-avoiding a-trous wavelet filter (Dammertz et al. 2010).
    Atrous,
    /// No filter.
    None,
}

/// When shadow targets are drawn.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum JitterArg {
    /// Every candidate, before selection (the demo code).
    Candidate,
    /// The selected samples, when their rays are traced.
    Ray,
}

/// Where shadow rays of grid lights go.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ShadowTargetArg {
    /// The grid light's centroid, jittered by its deviation (the paper and the demo).
    Centroid,
    /// One of the VPLs the grid light stands for, drawn in proportion to its share.
    Representative,
}

/// How the levels above S_1 are built.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ConstructionArg {
    /// Each level from the level below through the exact (1/2, 1, 1/2) restriction stencil:
    /// the all-scatter hierarchy at a fraction of the cost (an extension).
    Restrict,
    /// Each level gathered from the grid lights of S_1 (the paper, section 3.1).
    Gather,
    /// Each level splatted from all VPLs (the paper's Table 1 baseline).
    Scatter,
}

/// Directional emission models of grid lights.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum EmissionArg {
    /// max(0, m . w) with m the weighted mean normal, not renormalised (the authors' demo):
    /// clusters whose normals disagree lose light.
    MeanNormal,
    /// max(0, m . w) + (1 - |m|) / 4: the share lost by the mean normal is emitted uniformly,
    /// so every cluster keeps its VPLs' total flux (an extension of the paper).
    Energy,
}

/// What the temporal filter accumulates.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum TaaTargetArg {
    /// The filtered shadow ratio (lgh, slc).
    Ratio,
    /// The whole indirect light.
    Indirect,
}

/// Parts of the radiance to write.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ComponentArg {
    /// Emission + direct + indirect light.
    All,
    /// Emission + direct light only.
    Direct,
    /// Indirect light (from the VPLs) only.
    Indirect,
}

/// Render a scene to an image.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Scene file: .toml (scene file), .gltf, .glb or .obj, or a built-in scene:
    /// builtin:cornell (the default), builtin:cornell-moving-light (animated: a point light
    /// crosses the room in 2 s), builtin:cornell-moving-block (animated: the tall block turns
    /// 90 degrees and slides 10 cm in 2 s) or builtin:emitter-room (2688 emissive triangles,
    /// for the pt methods).
    pub scene: Option<PathBuf>,
    /// How the indirect light is computed (default: the lighting grid hierarchy; `brute` is
    /// the exact reference, slow).
    #[arg(long, value_enum, default_value = "lgh")]
    pub method: MethodArg,
    /// Number of virtual point lights (VPLs) to generate by light tracing.
    #[arg(long, default_value_t = 10_000)]
    pub vpls: usize,
    /// Maximum VPLs per light path, i.e. indirect bounces represented (1 = one bounce).
    #[arg(long, default_value_t = 3)]
    pub bounces: u32,
    /// Numbers that drive the light paths (both unbiased; `sobol` is stratified).
    #[arg(long, value_enum, default_value = "sobol")]
    pub path_numbers: PathNumbersArg,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Seed of all random choices; the same seed gives the same image on any thread count.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output image: .png (exposure, ACES filmic tone map, sRGB) or .exr (linear radiance).
    #[arg(long, short, default_value = "lgh.png")]
    pub out: PathBuf,
    /// Which part of the radiance to write.
    #[arg(long, value_enum, default_value = "all")]
    pub component: ComponentArg,
    /// Write statistics (sizes, counts, per-pass timings in ms) as JSON to this file.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Shadow-ray samples per pixel for area lights (emissive triangles) in the direct pass.
    #[arg(long, default_value_t = 16)]
    pub area_samples: u32,
    /// Exposure multiplier for PNG output (default: the scene file's, else 1).
    #[arg(long)]
    pub exposure: Option<f32>,
    /// lgh: alpha of the blending radii r_l = alpha h_l (larger = more accurate, slower).
    #[arg(long, default_value_t = 1.0)]
    pub alpha: f32,
    /// lgh: number of hierarchy levels, `auto` (largest with |S1| < VPLs/2) or 1..=10.
    #[arg(long, default_value = "auto")]
    pub levels: String,
    /// lgh, slc: shadow samples (shadow rays) per pixel, 0 = no shadows (at most 16).
    #[arg(long, default_value_t = 4)]
    pub shadow_samples: u32,
    /// lgh: lowest level whose lights are shadow candidates (2 skips S1, as the paper; 0 adds
    /// the VPLs when --start-level is 0).
    #[arg(long, default_value_t = 2)]
    pub shadow_from_level: u32,
    /// lgh, slc: filter applied to the shadow estimates.
    #[arg(long, value_enum, default_value = "atrous")]
    pub filter: FilterArg,
    /// lgh, slc: a-trous passes.
    #[arg(long, default_value_t = 5)]
    pub filter_passes: u32,
    /// lgh: lowest level shaded: 1 (S1, the paper's default) or 0 (the VPLs themselves).
    #[arg(long, default_value_t = 1)]
    pub start_level: u32,
    /// lgh: build six hierarchies, one per dominant normal direction of the VPLs (an extension
    /// of the paper: grid lights then average only normals that roughly agree). Better than
    /// one hierarchy with `--grid-emission mean-normal`, worse than the default emission:
    /// about 15% too bright on the Cornell box at 100K VPLs.
    #[arg(long)]
    pub normal_bins: bool,
    /// lgh: when a shadow sample's target (jittered centroid or representative VPL) is drawn:
    /// per candidate before selection, weighting it by its contribution there (the authors'
    /// demo), or only for the k selected samples when their rays are traced (the default;
    /// 13% faster lighting with representatives).
    #[arg(long, value_enum, default_value = "ray")]
    pub jitter_at: JitterArg,
    /// lgh: where the shadow ray of a selected grid light goes: one of the VPLs it stands for,
    /// drawn in proportion to its share (an extension, the default), or its jittered centroid
    /// (the paper; centroids inside objects or walls darken the image: -27% on the Cornell
    /// box).
    #[arg(long, value_enum, default_value = "representative")]
    pub shadow_target: ShadowTargetArg,
    /// lgh: how the levels above S_1 are built: `restrict` (exact, fastest; an extension),
    /// `gather` from S_1 (the paper) or `scatter` from all VPLs (the paper's baseline).
    #[arg(long, value_enum, default_value = "restrict")]
    pub construction: ConstructionArg,
    /// lgh: how a grid light's emission depends on direction.
    #[arg(long, value_enum, default_value = "energy")]
    pub grid_emission: EmissionArg,
    /// slc, pt-*: error bound epsilon_max of the light ranges (smaller = longer ranges, less
    /// noise, slower). Default: the paper's 0.0005 for slc, 0.125 for the path tracer. The
    /// ranges also use --exposure.
    #[arg(long)]
    pub error_bound: Option<f32>,
    /// pt-*: samples (passes) per pixel; every pass draws new light ranges.
    #[arg(long, default_value_t = 16)]
    pub spp: u32,
    /// lgh, slc: n x n interleaved sampling: each of the n^2 sub-images shades 1/n^2 of the
    /// lights (of each level, for lgh), then a discontinuity-aware blur recombines them.
    /// Default: 1 (none) for lgh, 8 for slc (the papers' settings).
    #[arg(long)]
    pub interleave: Option<u32>,
    /// lgh, slc: screen tile edge in sub-image pixels for light binning. Default: 16 full-
    /// resolution pixels for lgh (16 / n sub-image pixels with n x n interleaving, at least
    /// 4), 16 sub-image pixels for slc.
    #[arg(long)]
    pub tile: Option<u32>,
    /// slc: shadows from imperfect shadow maps, as the paper renders them (section 4.3): a
    /// 32x32 paraboloid depth map per VPL, splatted from a point cloud after the range-based
    /// culling of its Program 1. Replaces the ray-traced shadow samples.
    #[arg(long)]
    pub ism: bool,
    /// slc --ism: points splatted per map before culling (the paper uses 8192).
    #[arg(long, default_value_t = 1024)]
    pub ism_points: u32,
    /// slc: seed of the per-light random numbers xi_i that draw the light ranges.
    #[arg(long, default_value_t = 0)]
    pub frame_seed: u32,
    /// lgh: write the per-pixel overdraw (lights covering each pixel) as a colour map with a
    /// legend bar to this PNG (the paper's Fig. 5).
    #[arg(long)]
    pub heatmap: Option<PathBuf>,
    /// Render a sequence of frames A..B (B excluded, e.g. 0..48) of the scene's animation;
    /// --out must then contain #### (replaced by the zero-padded frame number). VPLs and all
    /// random numbers are new in every frame (seed + frame number).
    #[arg(long, value_parser = parse_frames)]
    pub frames: Option<(u32, u32)>,
    /// Frames per second of the sequence (frame f shows time f / fps).
    #[arg(long, default_value_t = 24.0)]
    pub fps: f32,
    /// Temporal filtering of the shadows across the frames of a sequence (LGH paper 4.3).
    #[arg(long)]
    pub taa: bool,
    /// Weight of the current frame in the temporal moving average.
    #[arg(long, default_value_t = 0.1)]
    pub taa_alpha: f32,
    /// What the temporal filter accumulates: the shadow ratio (the paper's choice) or the
    /// whole indirect light.
    #[arg(long, value_enum, default_value = "ratio")]
    pub taa_target: TaaTargetArg,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// No progress bars and no summary.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Parses `A..B` (frames A to B - 1).
pub fn parse_frames(s: &str) -> Result<(u32, u32), String> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| format!("'{s}' is not A..B (e.g. 0..48)"))?;
    let a: u32 = a
        .trim()
        .parse()
        .map_err(|_| format!("'{s}': A is not a number"))?;
    let b: u32 = b
        .trim()
        .parse()
        .map_err(|_| format!("'{s}': B is not a number"))?;
    if b <= a {
        return Err(format!("'{s}': B must be larger than A"));
    }
    Ok((a, b))
}

/// The output path of frame `f`: the run of '#' in `pattern` replaced by `f`, zero-padded to
/// the run's length.
#[must_use]
pub fn frame_path(pattern: &std::path::Path, f: u32) -> PathBuf {
    let text = pattern.to_string_lossy();
    let Some(start) = text.find('#') else {
        return pattern.to_path_buf();
    };
    let len = text[start..].chars().take_while(|&c| c == '#').count();
    let mut out = String::new();
    out.push_str(&text[..start]);
    out.push_str(&format!("{f:0len$}"));
    out.push_str(&text[start + len..]);
    PathBuf::from(out)
}

/// Parses `WIDTHxHEIGHT` with both sides positive.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}' is not WIDTHxHEIGHT (e.g. 640x360)"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("'{s}': width is not a number"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("'{s}': height is not a number"))?;
    if w == 0 || h == 0 {
        return Err(format!("'{s}': width and height must be at least 1"));
    }
    if u64::from(w) * u64::from(h) > 1 << 28 {
        return Err(format!("'{s}': image too large"));
    }
    Ok((w, h))
}

/// The LGH settings from the flags, validated.
fn lgh_settings(args: &RenderArgs) -> Result<LghSettings> {
    if !args.alpha.is_finite() || args.alpha <= 0.0 {
        bail!("--alpha {}: must be a positive number", args.alpha);
    }
    let levels = match args.levels.as_str() {
        "auto" => LevelCount::Auto,
        s => match s.parse::<u32>() {
            Ok(l) if (1..=10).contains(&l) => LevelCount::Fixed(l),
            _ => bail!("--levels {s}: expected 'auto' or a number from 1 to 10"),
        },
    };
    if args.shadow_samples > MAX_SHADOW_SAMPLES {
        bail!(
            "--shadow-samples {}: at most {MAX_SHADOW_SAMPLES}",
            args.shadow_samples
        );
    }
    if let Some(e) = args.error_bound
        && (!e.is_finite() || e <= 0.0)
    {
        bail!("--error-bound {e}: must be a positive number");
    }
    if args.spp == 0 || args.spp > 1 << 20 {
        bail!("--spp {}: expected 1 to 1048576", args.spp);
    }
    if let Some(n) = args.interleave
        && !(1..=16).contains(&n)
    {
        bail!("--interleave {n}: expected 1 to 16");
    }
    if let Some(t) = args.tile
        && !(1..=256).contains(&t)
    {
        bail!("--tile {t}: expected 1 to 256");
    }
    if args.start_level > 1 {
        bail!("--start-level {}: expected 0 or 1", args.start_level);
    }
    Ok(LghSettings {
        alpha: args.alpha,
        levels,
        shadow_samples: args.shadow_samples,
        shadow_from_level: args.shadow_from_level,
        start_level: args.start_level,
        filter_passes: match args.filter {
            FilterArg::Atrous => args.filter_passes,
            FilterArg::None => 0,
        },
        tile: args.tile,
        interleave: args.interleave.unwrap_or(1),
        normal_bins: args.normal_bins,
        jitter: match args.jitter_at {
            JitterArg::Candidate => JitterAt::Candidate,
            JitterArg::Ray => JitterAt::Ray,
        },
        shadow_target: match args.shadow_target {
            ShadowTargetArg::Centroid => ShadowTarget::Centroid,
            ShadowTargetArg::Representative => ShadowTarget::Representative,
        },
        construction: match args.construction {
            ConstructionArg::Restrict => Construction::Restrict,
            ConstructionArg::Gather => Construction::GatherFromS1,
            ConstructionArg::Scatter => Construction::ScatterAll,
        },
        emission: match args.grid_emission {
            EmissionArg::MeanNormal => GridEmission::MeanNormal,
            EmissionArg::Energy => GridEmission::EnergyConserving,
        },
        ..LghSettings::default()
    })
}

/// The SLC settings from the flags (sharing the shadow flags with lgh), validated.
fn slc_settings(args: &RenderArgs, lgh: &LghSettings, exposure: f32) -> Result<SlcSettings> {
    let interleave = args.interleave.unwrap_or(8);
    Ok(SlcSettings {
        error_bound: args.error_bound.unwrap_or(0.0005),
        exposure,
        interleave,
        tile: args.tile.unwrap_or(16),
        shadow_samples: lgh.shadow_samples,
        frame_seed: args.frame_seed,
        filter_passes: lgh.filter_passes,
        ism: args.ism.then(|| IsmSettings {
            points_per_map: args.ism_points,
            ..IsmSettings::default()
        }),
        ..SlcSettings::default()
    })
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
    let taa = args.taa.then_some(TemporalSettings {
        alpha: args.taa_alpha,
        target: match args.taa_target {
            TaaTargetArg::Ratio => TemporalTarget::ShadowRatio,
            TaaTargetArg::Indirect => TemporalTarget::Indirect,
        },
        ..TemporalSettings::default()
    });
    let mut seq = Sequence::new(taa);
    let mut per_frame = Vec::new();
    for f in first..end {
        let update = std::time::Instant::now();
        world.set_time(f as f32 / args.fps);
        let update_ms = update.elapsed().as_secs_f64() * 1e3;
        let mut s = settings.clone();
        s.seed = settings.seed.wrapping_add(u64::from(f));
        s.slc.frame_seed = f;
        let frame = seq.render(&world, &s, bars)?;
        let path = frame_path(&args.out, f);
        frame.image.save(&path, exposure)?;
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
        });
        std::fs::write(path, serde_json::to_string_pretty(&v)? + "\n")
            .with_context(|| format!("{}: cannot write statistics", path.display()))?;
    }
    Ok(())
}

pub fn run(args: &RenderArgs) -> Result<()> {
    if args.frames.is_some() && !args.out.to_string_lossy().contains('#') {
        bail!(
            "{}: with --frames the output name needs #### for the frame number (e.g. frames/frame_####.png)",
            args.out.display()
        );
    }
    if !args.taa_alpha.is_finite() || args.taa_alpha <= 0.0 || args.taa_alpha > 1.0 {
        bail!(
            "--taa-alpha {}: expected a number in (0, 1]",
            args.taa_alpha
        );
    }
    if !args.fps.is_finite() || args.fps <= 0.0 {
        bail!("--fps {}: must be a positive number", args.fps);
    }
    check_output_path(&frame_path(&args.out, 0))?;
    if let Some(stats) = &args.stats
        && let Some(dir) = stats.parent()
        && !dir.as_os_str().is_empty()
        && !dir.is_dir()
    {
        bail!(
            "{}: output folder {} does not exist",
            stats.display(),
            dir.display()
        );
    }
    if let Some(e) = args.exposure
        && (!e.is_finite() || e <= 0.0)
    {
        bail!("--exposure {e}: must be a positive number");
    }
    if let Some(h) = &args.heatmap {
        check_output_path(h)?;
    }
    let lgh = lgh_settings(args)?;
    let threads = crate::set_threads(args.threads)?;
    let start = Instant::now();
    let scene = load_scene(args.scene.as_deref())?;
    let load_ms = start.elapsed().as_secs_f64() * 1e3;
    let exposure = args.exposure.unwrap_or(scene.exposure);
    let scene_name = scene.name.clone();

    let t = Instant::now();
    let world = World::new(scene);
    let bvh_ms = t.elapsed().as_secs_f64() * 1e3;

    let settings = RenderSettings {
        width: args.size.0,
        height: args.size.1,
        vpls: args.vpls,
        bounces: args.bounces,
        seed: args.seed,
        path_numbers: match args.path_numbers {
            PathNumbersArg::Sobol => PathNumbers::Sobol,
            PathNumbersArg::Random => PathNumbers::Random,
        },
        area_samples: args.area_samples,
        method: match args.method {
            MethodArg::Brute => Method::Brute,
            MethodArg::BruteUnshadowed => Method::BruteUnshadowed,
            MethodArg::Lgh => Method::Lgh,
            MethodArg::LghUnshadowed => Method::LghUnshadowed,
            MethodArg::Slc => Method::Slc,
            MethodArg::SlcClamped => Method::SlcClamped,
            MethodArg::PtSlc => Method::PtSlc,
            MethodArg::PtUniform => Method::PtUniform,
            MethodArg::PtClamped => Method::PtClamped,
        },
        component: match args.component {
            ComponentArg::All => Component::All,
            ComponentArg::Direct => Component::Direct,
            ComponentArg::Indirect => Component::Indirect,
        },
        slc: slc_settings(args, &lgh, exposure)?,
        pt: PtSettings {
            spp: args.spp,
            error_bound: args.error_bound.unwrap_or(0.125),
            exposure,
            ..PtSettings::default()
        },
        lgh,
        ..RenderSettings::default()
    };
    let bars = Bars::new(args.quiet);
    if let Some(frames) = args.frames {
        return run_sequence(args, world, &settings, frames, exposure, &bars);
    }
    let frame = render_frame(&world, &settings, &bars)?;
    frame.image.save(&args.out, exposure)?;
    if let (Some(path), Some(stats)) = (&args.heatmap, &frame.lgh) {
        let max = crate::heatmap::write(path, settings.width, settings.height, &stats.overdraw)?;
        if !args.quiet {
            eprintln!("heatmap: 0 (bottom of the bar) to {max} lights per pixel (top)");
        }
    }

    let mut timings = serde_json::Map::new();
    timings.insert("scene_load".into(), load_ms.into());
    timings.insert("bvh_build".into(), bvh_ms.into());
    for (name, ms) in &frame.timings.0 {
        let ms = if name == "total" { ms + bvh_ms } else { *ms };
        timings.insert(name.clone(), ms.into());
    }
    if let Some(path) = &args.stats {
        let mut stats = serde_json::json!({
            "scene": scene_name,
            "width": settings.width,
            "height": settings.height,
            "vpls": frame.vpls.vpls.len(),
            "vpls_requested": settings.vpls,
            "light_paths": frame.vpls.paths,
            "bounces": settings.bounces,
            "path_numbers": format!("{:?}", settings.path_numbers).to_lowercase(),
            "method": settings.method.name(),
            "seed": settings.seed,
            "threads": threads,
            "triangles": world.accel.len(),
            "timings_ms": timings,
        });
        if let Some(l) = &frame.lgh {
            stats["grid_lights"] = l.grid_lights.into();
            stats["levels"] = l.levels.into();
            stats["avg_overdraw"] = l.avg_overdraw.into();
            stats["shadow_rays"] = l.shadow_rays.into();
            stats["alpha"] = f64::from(settings.lgh.alpha).into();
            stats["shadow_samples"] = settings.lgh.shadow_samples.into();
        }
        if let Some(p) = &frame.pt {
            stats["spp"] = p.spp.into();
            stats["emitters"] = p.emitters.into();
            stats["avg_overlapping_lights"] = p.avg_overlapping.into();
            stats["error_bound"] = f64::from(settings.pt.error_bound).into();
        }
        if let Some(l) = &frame.slc {
            stats["avg_lights_per_pixel"] = l.avg_lights_per_pixel.into();
            stats["shadow_rays"] = l.shadow_rays.into();
            stats["error_bound"] = f64::from(settings.slc.error_bound).into();
            stats["interleave"] = settings.slc.interleave.into();
            stats["frame_seed"] = settings.slc.frame_seed.into();
            stats["shadow_samples"] = settings.slc.shadow_samples.into();
            if let Some((tested, splatted)) = l.ism_points {
                stats["ism_points_tested"] = tested.into();
                stats["ism_points_splatted"] = splatted.into();
            }
        }
        let text = serde_json::to_string_pretty(&stats)?;
        std::fs::write(path, text + "\n")
            .with_context(|| format!("{}: cannot write statistics", path.display()))?;
    }
    if !args.quiet {
        eprintln!(
            "{}: {}x{}, {} triangles, {} VPLs from {} light paths, {} in {:.0} ms ({} threads) -> {}",
            scene_name,
            settings.width,
            settings.height,
            world.accel.len(),
            frame.vpls.vpls.len(),
            frame.vpls.paths,
            settings.method.name(),
            frame.timings.get("total").unwrap_or(0.0) + bvh_ms,
            threads,
            args.out.display()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::parse_size;

    #[test]
    fn sizes() {
        assert_eq!(parse_size("640x360"), Ok((640, 360)));
        assert!(parse_size("0x10").is_err());
        assert!(parse_size("640").is_err());
        assert!(parse_size("ax3").is_err());
    }
}
