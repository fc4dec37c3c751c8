//! Tone mapping for PNG output.
//!
//! Radiance is multiplied by the exposure, mapped by the ACES filmic curve as fitted by
//! Narkowicz (2015), `x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)` per channel, clamped to
//! [0, 1], encoded with the sRGB transfer function and rounded to 8 bits. EXR output skips all
//! of this and keeps linear radiance.

use glam::Vec3;
use lgh_core::color::finite_or_zero;
use rayon::prelude::*;

/// The ACES filmic curve (Narkowicz 2015 fit) for one channel; result in [0, 1]. It
/// saturates: the input is clamped to [0, 10^4] (where the curve is already 1), so that
/// `x * x` cannot overflow to inf / inf = NaN (radiance above 1.8e19 turned black).
#[inline]
#[must_use]
pub fn aces(x: f32) -> f32 {
    // NaN to 0 (`clamp` would keep it).
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1e4) };
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// sRGB transfer function (linear in [0, 1] to encoded).
#[inline]
#[must_use]
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Tone-maps one linear pixel to 8-bit sRGB (R, G, B).
#[inline]
#[must_use]
pub fn tonemap_pixel(p: Vec3, exposure: f32) -> [u8; 3] {
    let p = finite_or_zero(p) * exposure;
    [p.x, p.y, p.z].map(|c| (linear_to_srgb(aces(c)) * 255.0 + 0.5) as u8)
}

/// Tone-maps linear pixels to 8-bit sRGB bytes (RGB, 3 bytes a pixel).
#[must_use]
pub fn tonemap_to_srgb8(pixels: &[Vec3], exposure: f32) -> Vec<u8> {
    let mut out = vec![0u8; 3 * pixels.len()];
    out.par_chunks_exact_mut(3)
        .zip(pixels.par_iter())
        .for_each(|(o, &p)| o.copy_from_slice(&tonemap_pixel(p, exposure)));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_is_monotonic_and_bounded() {
        let mut prev = -1.0;
        for i in 0..1000 {
            let y = aces(i as f32 * 0.05);
            assert!((0.0..=1.0).contains(&y) && y >= prev);
            prev = y;
        }
        assert_eq!(
            tonemap_to_srgb8(&[Vec3::new(f32::NAN, -1.0, 1e9)], 1.0),
            vec![0, 0, 255]
        );
        // Radiance past 1.8e19 (x * x overflows) and products that overflow stay white.
        assert_eq!(
            tonemap_to_srgb8(&[Vec3::new(2e19, f32::MAX, 1e30)], 4.0),
            vec![255, 255, 255]
        );
    }
}
