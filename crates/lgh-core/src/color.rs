//! RGB helpers shared by every pass.

use glam::Vec3;

/// Luminance weights used everywhere in lgh (ITU-R BT.601: 0.299, 0.587, 0.114).
///
/// These are the weights the LGH authors' code uses for the shadow-sample selection weight f_i
/// (docs/design.md, "Shadow sampling"); using one set of weights for selection, statistics and the `diff`
/// metrics keeps the numbers comparable.
pub const LUMINANCE_WEIGHTS: Vec3 = Vec3::new(0.299, 0.587, 0.114);

/// Luminance of a linear RGB value (see [`LUMINANCE_WEIGHTS`]).
#[inline]
#[must_use]
pub fn luminance(c: Vec3) -> f32 {
    c.dot(LUMINANCE_WEIGHTS)
}

/// Replaces NaN or infinite components by zero, so that no non-finite value reaches an image.
#[inline]
#[must_use]
pub fn finite_or_zero(c: Vec3) -> Vec3 {
    if c.is_finite() {
        c
    } else {
        Vec3::new(
            if c.x.is_finite() { c.x } else { 0.0 },
            if c.y.is_finite() { c.y } else { 0.0 },
            if c.z.is_finite() { c.z } else { 0.0 },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn luminance_of_white_is_one() {
        assert!((luminance(Vec3::ONE) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn non_finite_components_become_zero() {
        let c = finite_or_zero(Vec3::new(f32::NAN, 2.0, f32::INFINITY));
        assert_eq!(c, Vec3::new(0.0, 2.0, 0.0));
    }
}
