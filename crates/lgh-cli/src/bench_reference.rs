//! The converged references of `lgh bench quality --equal-time`: the mean of many
//! brute-force frames, each with its own VPL set and sub-pixel position, cached as EXR
//! (`--reference-dir`, or one file per scene with `--reference`) with the mean of the first
//! half of their frames beside them (`NAME.half.exr`): the FLIP between the two says how
//! far the reference is from converged. `--references-only` makes (or loads) them and
//! stops, so that a machine with a GPU can make them for a sweep that runs elsewhere.

use std::path::{Path, PathBuf};

use anyhow::{Result, anyhow, bail};
use lgh_render::methods::brute::{BRUTE, BRUTE_SAMPLED};
use lgh_render::{Image, RenderSettings, World};

use crate::bench_quality::{QualityBenchArgs, indirect_only, measure, prefix_means};
use crate::render_cmd::args::Device;

/// A converged reference and what is known of its convergence.
pub struct Reference {
    /// The mean of every frame.
    pub image: Image,
    /// FLIP of the mean of the first half of the frames against the whole mean, if that
    /// half is known.
    pub half_flip: Option<f64>,
    /// The file it was read from or written to.
    pub path: PathBuf,
}

/// A short fingerprint of the scene file (path, size, modification time), so that a cached
/// reference of an edited scene is not reused.
fn fingerprint(path: &Path) -> u64 {
    let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    let meta = std::fs::metadata(&canonical).ok();
    let modified = meta
        .as_ref()
        .and_then(|m| m.modified().ok())
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_secs());
    let text = canonical.to_string_lossy();
    let mut words: Vec<u64> = text.bytes().map(u64::from).collect();
    words.push(meta.map_or(0, |m| m.len()));
    words.push(modified);
    lgh_core::rng::hash(&words)
}

/// Where the reference of `scene` is cached by default.
fn cached_path(args: &QualityBenchArgs, name: &str, scene: &Path) -> PathBuf {
    let (w, h) = args.size;
    // Sampled rays name themselves; one ray per VPL keeps the name it always had.
    let rays = match sampled_rays(args) {
        0 => String::new(),
        r => format!("-r{r}"),
    };
    args.reference_dir.join(format!(
        "{name}-{:08x}-{w}x{h}-{}x{}{rays}.exr",
        fingerprint(scene) as u32,
        args.reference_frames,
        args.reference_vpls
    ))
}

/// The file beside `reference` that holds the mean of its first half.
fn half_path(reference: &Path) -> PathBuf {
    reference.with_extension("half.exr")
}

/// Loads the reference at `path` (with its half, if there), checking its size.
fn load(path: &Path, size: (u32, u32), exposure: f32) -> Result<Reference> {
    let image = Image::load(path).map_err(|e| anyhow!("reference {}: {e}", path.display()))?;
    if (image.width, image.height) != size {
        bail!(
            "reference {}: {}x{}, the benchmark renders {}x{} (--size)",
            path.display(),
            image.width,
            image.height,
            size.0,
            size.1
        );
    }
    let half = Image::load(&half_path(path))
        .ok()
        .filter(|h| (h.width, h.height) == size);
    let half_flip = match half {
        Some(h) => Some(measure(&h, &image, exposure)?.1),
        None => None,
    };
    Ok(Reference {
        image,
        half_flip,
        path: path.to_path_buf(),
    })
}

/// The shadow rays per pixel of a reference frame drawn by `brute-sampled`, or 0 where
/// every VPL has its own (`brute`, and the GPU's brute force).
fn sampled_rays(args: &QualityBenchArgs) -> u32 {
    match args.reference_device {
        Device::Cpu => args.reference_rays,
        Device::Gpu => 0,
    }
}

/// What a reference is the mean of, e.g. "48 brute-force frames of 20000 VPLs, 256 rays a
/// pixel".
pub fn describe(args: &QualityBenchArgs) -> String {
    let rays = match sampled_rays(args) {
        0 => "a ray per VPL".to_string(),
        r => format!("{r} rays a pixel"),
    };
    format!(
        "{} brute-force frames of {} VPLs, {rays}",
        args.reference_frames, args.reference_vpls
    )
}

/// Renders the converged reference: the mean of `--reference-frames` brute-force frames of
/// `--reference-vpls` VPLs each, every frame with its own VPLs and sub-pixel position, and
/// the fixed 1/d^2 clamp of many VPLs (`--vpl-clamp 0`).
fn compute(world: &World, args: &QualityBenchArgs, name: &str) -> Result<(Image, Image)> {
    let frames = args.reference_frames;
    let method = match args.reference_device {
        Device::Cpu if args.reference_rays > 0 => BRUTE_SAMPLED,
        Device::Cpu => BRUTE,
        Device::Gpu => {
            let gpu = lgh_gpu::gpu_method(BRUTE)
                .ok_or_else(|| lgh_gpu::GpuError::NotPorted("brute".into()))?;
            if !args.options.json {
                eprintln!("GPU: {}", lgh_gpu::GpuContext::shared()?.adapter_name());
            }
            gpu
        }
    };
    // The limit of many VPLs: the fixed clamp, whatever the VPLs of a frame.
    let base = RenderSettings {
        method,
        brute_rays: args.reference_rays.max(1),
        vpl_clamp: 0.0,
        ..indirect_only(args.size, args.reference_vpls)
    };
    let bar = crate::progress_bar::counter(
        args.options.json,
        u64::from(frames),
        &format!("{name}: reference"),
    );
    let mut means = prefix_means(world, &base, frames, &[frames / 2, frames], || bar.inc(1))?;
    bar.finish_and_clear();
    let whole = means.pop().map(|(_, m)| m);
    let half = means.pop().map(|(_, m)| m);
    let whole = whole.ok_or_else(|| anyhow!("no reference frame rendered"))?;
    Ok((half.unwrap_or_else(|| whole.clone()), whole))
}

/// The reference of one scene: the file `--reference` names for it, else the cache; loaded
/// if there, else rendered and written there (with its half).
pub fn reference(
    world: &World,
    args: &QualityBenchArgs,
    name: &str,
    scene: &Path,
    index: usize,
) -> Result<Reference> {
    let exposure = world.scene.exposure;
    let path = match args.reference.get(index) {
        Some(p) => p.clone(),
        None => cached_path(args, name, scene),
    };
    if path.exists() {
        if !args.options.json {
            eprintln!("{name}: reference {}", path.display());
        }
        return load(&path, args.size, exposure);
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| anyhow!("reference folder {}: {e}", dir.display()))?;
    }
    if !args.options.json {
        eprintln!(
            "{name}: converged reference, {} -> {}",
            describe(args),
            path.display()
        );
    }
    let (half, image) = compute(world, args, name)?;
    half.save(&half_path(&path), exposure)?;
    image.save(&path, exposure)?;
    let half_flip = (args.reference_frames >= 2)
        .then(|| measure(&half, &image, exposure).map(|m| m.1))
        .transpose()?;
    Ok(Reference {
        image,
        half_flip,
        path,
    })
}

/// The benchmark's image size and reference settings, the head of its JSON output.
pub fn settings_json(args: &QualityBenchArgs) -> serde_json::Map<String, serde_json::Value> {
    let mut v = serde_json::Map::new();
    v.insert("width".into(), args.size.0.into());
    v.insert("height".into(), args.size.1.into());
    v.insert("reference_frames".into(), args.reference_frames.into());
    v.insert("reference_vpls".into(), args.reference_vpls.into());
    v.insert("reference_rays".into(), sampled_rays(args).into());
    v
}

/// `--references-only`: each scene's reference file and how converged it is, as text or
/// JSON.
pub fn print_references(
    args: &QualityBenchArgs,
    convergence: &[(String, Option<f64>)],
    paths: &[PathBuf],
) -> Result<()> {
    if args.options.json {
        let list: Vec<_> = convergence
            .iter()
            .zip(paths)
            .map(|((scene, flip), path)| {
                serde_json::json!({"scene": scene, "reference": path, "half_flip": flip})
            })
            .collect();
        // The adapter that made them (only where the GPU rendered any this run).
        let adapter = (args.reference_device == Device::Gpu)
            .then(|| lgh_gpu::GpuContext::shared().map(|c| c.adapter_name()).ok())
            .flatten();
        let mut v = settings_json(args);
        v.insert("device".into(), serde_json::json!(args.reference_device));
        v.insert("adapter".into(), serde_json::json!(adapter));
        v.insert("references".into(), serde_json::json!(list));
        println!("{}", serde_json::Value::Object(v));
        return Ok(());
    }
    for ((scene, flip), path) in convergence.iter().zip(paths) {
        let flip = flip.map_or_else(|| "unknown".into(), |f| format!("{f:.4}"));
        println!(
            "{scene}: {} (FLIP of its first half against it: {flip})",
            path.display()
        );
    }
    Ok(())
}
