//! Image comparison metrics for `lgh diff` and the tests.

use lgh_core::color::luminance;

use crate::image::Image;

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
}
