//! Image comparison metrics for `lgh diff` and the tests.

use lgh_core::color::luminance;

use crate::image::tonemap::{linear_to_srgb, tonemap_to_srgb8};
use crate::image::{Image, ImageFormat};

/// How far an image A is from a reference B.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffMetrics {
    /// Root-mean-square difference over all pixels and the three channels.
    pub rmse: f64,
    /// `rmse` divided by the reference's mean luminance.
    pub rel_rmse: f64,
    /// (mean luminance of A - mean luminance of B) / mean luminance of B (signed).
    pub rel_bias: f64,
    /// Largest absolute difference of any channel of any pixel.
    pub max_abs: f64,
}

/// Mean luminance of an image.
#[must_use]
pub fn mean_luminance(img: &Image) -> f64 {
    img.pixels.iter().map(|&p| luminance(p) as f64).sum::<f64>() / img.pixels.len().max(1) as f64
}

/// Compares `a` against the reference `b`. The relative metrics are 0 when both are black
/// and infinite when only the reference is.
///
/// # Errors
/// The sizes differ.
pub fn diff(a: &Image, b: &Image) -> Result<DiffMetrics, String> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(format!(
            "the images differ in size: {}x{} and {}x{}",
            a.width, a.height, b.width, b.height
        ));
    }
    let mut se = 0.0f64;
    let mut max_abs = 0.0f64;
    for (pa, pb) in a.pixels.iter().zip(&b.pixels) {
        let d = (*pa - *pb).abs();
        se += d.as_dvec3().length_squared();
        max_abs = max_abs.max(d.max_element() as f64);
    }
    let n = (3 * a.pixels.len()).max(1) as f64;
    let rmse = (se / n).sqrt();
    let (la, lb) = (mean_luminance(a), mean_luminance(b));
    let rel = |x: f64| {
        if lb > 0.0 {
            x / lb
        } else if x == 0.0 {
            0.0
        } else {
            f64::INFINITY
        }
    };
    Ok(DiffMetrics {
        rmse,
        rel_rmse: rel(rmse),
        rel_bias: rel(la - lb),
        max_abs,
    })
}

/// The 8-bit sRGB picture a person sees of an image read from a file of `format`: a PNG's own
/// bytes (its sRGB curve re-applied), or an EXR after `exposure` and the same tone map as PNG
/// output (ACES filmic, sRGB).
#[must_use]
pub fn display_bytes(img: &Image, format: ImageFormat, exposure: f32) -> Vec<u8> {
    match format {
        ImageFormat::Png => img
            .pixels
            .iter()
            .flat_map(|p| [p.x, p.y, p.z].map(|c| (linear_to_srgb(c) * 255.0 + 0.5) as u8))
            .collect(),
        ImageFormat::Exr => tonemap_to_srgb8(&img.pixels, exposure),
    }
}

/// Mean of NVIDIA's LDR-FLIP error map (Andersson et al. 2020, via the `nv-flip` crate, at
/// its default 67 pixels per degree) between two 8-bit sRGB pictures of `width` x `height`;
/// `b` is the reference. 0 = identical, 1 = as different as black and white.
///
/// # Errors
/// The byte buffers do not hold `width` x `height` RGB pixels.
pub fn flip_mean(a: &[u8], b: &[u8], width: u32, height: u32) -> Result<f64, String> {
    let v = flip_map(a, b, width, height)?;
    Ok(v.iter().map(|&x| f64::from(x)).sum::<f64>() / v.len() as f64)
}

/// NVIDIA's LDR-FLIP error per pixel (row-major, in [0, 1]) between two 8-bit sRGB pictures;
/// see [`flip_mean`].
///
/// # Errors
/// The byte buffers do not hold `width` x `height` RGB pixels.
pub fn flip_map(a: &[u8], b: &[u8], width: u32, height: u32) -> Result<Vec<f32>, String> {
    let n = 3 * width as usize * height as usize;
    if a.len() != n || b.len() != n || n == 0 {
        return Err("FLIP needs two RGB images of the same, non-zero size".into());
    }
    let test = nv_flip::FlipImageRgb8::with_data(width, height, a);
    let reference = nv_flip::FlipImageRgb8::with_data(width, height, b);
    Ok(nv_flip::flip(reference, test, nv_flip::DEFAULT_PIXELS_PER_DEGREE).to_vec())
}

/// A FLIP error map as a picture: 8-bit sRGB through FLIP's own magma colour map (black: no
/// error, yellow: as different as black and white).
#[must_use]
pub fn flip_picture(map: &[f32]) -> Vec<u8> {
    let lut = nv_flip::magma_lut().to_vec();
    let last = lut.len() / 3 - 1;
    map.iter()
        .flat_map(|&e| {
            let k = ((e.clamp(0.0, 1.0) * last as f32) + 0.5) as usize;
            [lut[3 * k], lut[3 * k + 1], lut[3 * k + 2]]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn metrics_of_a_scaled_image() {
        let b = Image::from_pixels(2, 1, vec![Vec3::ONE, Vec3::splat(3.0)]);
        let a = Image::from_pixels(2, 1, vec![Vec3::splat(1.1), Vec3::splat(3.3)]);
        let m = diff(&a, &b).unwrap();
        assert!((m.rel_bias - 0.1).abs() < 1e-6);
        assert!((m.max_abs - 0.3).abs() < 1e-6);
        assert!((m.rmse - ((0.01 + 0.09) / 2.0f64).sqrt()).abs() < 1e-6);
        assert_eq!(diff(&b, &b).unwrap().rmse, 0.0);
        assert!(diff(&a, &Image::new(1, 1)).is_err());
    }

    #[test]
    fn flip_is_zero_for_equal_images_and_large_for_black_and_white() {
        let w = 32;
        let grey = vec![128u8; 3 * w * w];
        let white = vec![255u8; 3 * w * w];
        let black = vec![0u8; 3 * w * w];
        assert!(flip_mean(&grey, &grey, w as u32, w as u32).unwrap() < 1e-6);
        let bw = flip_mean(&black, &white, w as u32, w as u32).unwrap();
        assert!(bw > 0.5, "{bw}");
        let gw = flip_mean(&grey, &white, w as u32, w as u32).unwrap();
        assert!(gw > 0.0 && gw < bw);
        assert!(flip_mean(&grey, &white[3..], w as u32, w as u32).is_err());
    }
}
