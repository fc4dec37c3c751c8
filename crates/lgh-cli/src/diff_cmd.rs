//! `lgh diff`: image metrics against a reference.

use std::path::PathBuf;

use anyhow::{Result, anyhow};
use clap::Args;
use glam::Vec3;
use lgh_core::color::luminance;
use lgh_render::Image;
use lgh_render::image::ImageFormat;
use lgh_render::image::metrics::{diff, display_bytes, flip_map, flip_picture, mean_luminance};

/// Compare image A against the reference B.
#[derive(Debug, Args)]
pub struct DiffArgs {
    /// The image to judge (.exr linear, or .png whose sRGB curve is undone).
    pub a: PathBuf,
    /// The reference image, same size.
    pub b: PathBuf,
    /// Print one JSON object {rmse, rel_rmse, rel_bias, max_abs, flip} instead of text.
    #[arg(long)]
    pub json: bool,
    /// Exposure applied to EXR inputs before tone mapping them for FLIP (PNG inputs are
    /// compared as they are); a positive number.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    /// Also write a signed error map to this PNG: per pixel (lum(A) - lum(B)) / mean lum(B),
    /// blue where A is darker, red where brighter, white where equal, saturated at +-0.5.
    #[arg(long)]
    pub map: Option<PathBuf>,
    /// Also write the per-pixel FLIP error to this PNG (FLIP's magma colour map: black where
    /// the images agree, yellow where they differ most).
    #[arg(long)]
    pub flip_map: Option<PathBuf>,
}

pub fn run(args: &DiffArgs) -> Result<()> {
    if !args.exposure.is_finite() || args.exposure <= 0.0 {
        anyhow::bail!("--exposure {}: must be a positive number", args.exposure);
    }
    let mut outputs = Vec::new();
    if let Some(p) = &args.map {
        lgh_render::image::check_output_path(p)?;
        outputs.push(("--map", p.as_path()));
    }
    if let Some(p) = &args.flip_map {
        lgh_render::image::check_output_path(p)?;
        outputs.push(("--flip-map", p.as_path()));
    }
    lgh_render::output::check_outputs(&outputs)?;
    let a = Image::load(&args.a)?;
    let b = Image::load(&args.b)?;
    let m =
        diff(&a, &b).map_err(|e| anyhow!("{} vs {}: {e}", args.a.display(), args.b.display()))?;
    let flip = flip_map(
        &display_bytes(&a, ImageFormat::from_path(&args.a)?, args.exposure),
        &display_bytes(&b, ImageFormat::from_path(&args.b)?, args.exposure),
        a.width,
        a.height,
    )
    .map_err(|e| anyhow!("{e}"))?;
    if let Some(path) = &args.flip_map {
        lgh_render::image::save_png(path, a.width, a.height, &flip_picture(&flip))?;
    }
    let flip = flip.iter().map(|&x| f64::from(x)).sum::<f64>() / flip.len() as f64;
    if let Some(path) = &args.map {
        error_map(&a, &b).save(path, 1.0)?;
    }
    if args.json {
        let v = serde_json::json!({
            "rmse": m.rmse,
            "rel_rmse": finite_or_null(m.rel_rmse),
            "rel_bias": finite_or_null(m.rel_bias),
            "max_abs": m.max_abs,
            "flip": flip,
        });
        println!("{v}");
    } else {
        println!("rmse      {:.6}", m.rmse);
        println!("rel_rmse  {:.6}", m.rel_rmse);
        println!("rel_bias  {:+.6}", m.rel_bias);
        println!("max_abs   {:.6}", m.max_abs);
        println!("flip      {flip:.6}  (LDR-FLIP mean, 0 = identical)");
    }
    Ok(())
}

/// The signed relative error map of `lgh diff --map` (same size as `a` and `b`).
fn error_map(a: &Image, b: &Image) -> Image {
    let mean = mean_luminance(b).max(1e-12) as f32;
    let pixels = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(&pa, &pb)| {
            let e = ((luminance(pa) - luminance(pb)) / mean * 2.0).clamp(-1.0, 1.0);
            // Linear RGB chosen so the PNG's tone map shows white at 0.
            let white = Vec3::splat(2.0);
            if e >= 0.0 {
                white.lerp(Vec3::new(2.0, 0.0, 0.0), e)
            } else {
                white.lerp(Vec3::new(0.0, 0.1, 2.0), -e)
            }
        })
        .collect();
    Image::from_pixels(a.width, a.height, pixels)
}

fn finite_or_null(x: f64) -> serde_json::Value {
    if x.is_finite() {
        serde_json::json!(x)
    } else {
        serde_json::Value::Null
    }
}
