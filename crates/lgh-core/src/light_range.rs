//! Stochastic and clamped light ranges (Tokuyoshi & Harada 2016, "Stochastic Light Culling",
//! sections 3.1-3.2 and Appendix A).
//!
//! A point light with fall-off f(l) reaches everywhere. Stochastic light culling keeps it with
//! the Russian-roulette probability p_i(l) = min(f(l) / alpha_i, 1) (Eq. 1) and, when kept,
//! weights it by f / p_i = max(alpha_i, f(l)) (Eq. 2), which is unbiased. One random number
//! xi_i per light and frame (not per shading point) turns the roulette into a finite range:
//! the light is kept where p_i(l) > xi_i, that is for l < r_i with p_i(r_i) = xi_i (Eq. 3).
//! alpha_i comes from the user's error bound epsilon_max and the camera exposure E (Eq. 6 for
//! point lights, Eq. 7 for area lights). The clamped baseline (Appendix A) uses a fixed range
//! from the same error bound and drops the light beyond it, which biases the image darker.
//!
//! The fall-off here is f(l) = 1 / (l^2 + eps^2), the renderer's clamped inverse square (docs/design.md,
//! "Clamps"); eps = 0 gives the paper's 1 / l^2. With eps > 0 a range can be 0: the
//! light is then culled everywhere, which Eq. 1 allows (p_i(0) = f(0) / alpha_i < xi_i).

use std::f32::consts::PI;

/// The fall-off f(l) = 1 / (l^2 + eps^2) at squared distance `l2`.
#[inline]
#[must_use]
pub fn falloff(l2: f32, eps2: f32) -> f32 {
    1.0 / (l2 + eps2)
}

/// The distance at which the fall-off equals `value`: f^-1(value), 0 if f never gets that
/// large and infinite for `value` = 0.
#[inline]
#[must_use]
pub fn falloff_inverse(value: f32, eps2: f32) -> f32 {
    if value <= 0.0 {
        return f32::INFINITY;
    }
    (1.0 / value - eps2).max(0.0).sqrt()
}

/// alpha_i of Eq. 6: `2 pi epsilon_max / (E max_w I_i(w))`, for a light whose largest radiant
/// intensity (over directions and colour channels) is `max_intensity`. Infinite for a black
/// light (it is then culled everywhere).
#[inline]
#[must_use]
pub fn alpha_point(error_bound: f32, exposure: f32, max_intensity: f32) -> f32 {
    2.0 * PI * error_bound / (exposure * max_intensity)
}

/// alpha_i of Eq. 7 for an area light: `2 pi epsilon_max / (E L_i A_i)` with `mean_radiance`
/// L_i (largest channel) and `area` A_i.
#[inline]
#[must_use]
pub fn alpha_area(error_bound: f32, exposure: f32, mean_radiance: f32, area: f32) -> f32 {
    alpha_point(error_bound, exposure, mean_radiance * area)
}

/// The stochastic range r_i = f^-1(alpha_i xi_i) of Eq. 3 (1 / sqrt(alpha_i xi_i) for
/// eps = 0): where p_i(r_i) = xi_i.
#[inline]
#[must_use]
pub fn stochastic_range(alpha: f32, xi: f32, eps2: f32) -> f32 {
    falloff_inverse(alpha * xi, eps2)
}

/// The Russian-roulette probability p_i(l) = min(f(l) / alpha_i, 1) of Eq. 1.
#[inline]
#[must_use]
pub fn keep_probability(alpha: f32, l2: f32, eps2: f32) -> f32 {
    (falloff(l2, eps2) / alpha).min(1.0)
}

/// The stochastic fall-off of Eq. 2 for a light with range `range` (from
/// [`stochastic_range`]): max(alpha_i, f(l)) inside the range, 0 outside.
#[inline]
#[must_use]
pub fn stochastic_falloff(alpha: f32, range: f32, l2: f32, eps2: f32) -> f32 {
    if l2 < range * range {
        falloff(l2, eps2).max(alpha)
    } else {
        0.0
    }
}

/// The clamped range of Appendix A: f(r_i) = pi epsilon_max / (E N max_w I_i(w)), so that the
/// summed bias of `n_lights` lights stays below the error bound; for eps = 0 it is
/// sqrt(E N I_i / (pi epsilon_max)).
#[inline]
#[must_use]
pub fn clamped_range(
    error_bound: f32,
    exposure: f32,
    n_lights: usize,
    max_intensity: f32,
    eps2: f32,
) -> f32 {
    falloff_inverse(
        PI * error_bound / (exposure * n_lights as f32 * max_intensity),
        eps2,
    )
}

/// The clamped fall-off: f(l) inside the range, 0 outside (the biased baseline).
#[inline]
#[must_use]
pub fn clamped_falloff(range: f32, l2: f32, eps2: f32) -> f32 {
    if l2 < range * range {
        falloff(l2, eps2)
    } else {
        0.0
    }
}

/// The tiny encryption algorithm (Wheeler & Needham 1994) used as a hash, as the paper does
/// for xi_i (after Zafar et al. 2010): `rounds` Feistel rounds on the pair (v0, v1) with a
/// fixed key; returns the first word.
#[must_use]
pub fn tea(mut v0: u32, mut v1: u32, rounds: u32) -> u32 {
    const KEY: [u32; 4] = [0xa341_316c, 0xc801_3ea4, 0xad90_777d, 0x7e95_761e];
    const DELTA: u32 = 0x9e37_79b9;
    let mut sum = 0u32;
    for _ in 0..rounds {
        sum = sum.wrapping_add(DELTA);
        v0 = v0.wrapping_add(
            (v1 << 4).wrapping_add(KEY[0]) ^ v1.wrapping_add(sum) ^ (v1 >> 5).wrapping_add(KEY[1]),
        );
        v1 = v1.wrapping_add(
            (v0 << 4).wrapping_add(KEY[2]) ^ v0.wrapping_add(sum) ^ (v0 >> 5).wrapping_add(KEY[3]),
        );
    }
    v0
}

/// xi_i in [0, 1) for light `light` in frame `frame_seed`: TEA with 16 rounds of (index,
/// seed), 24 bits.
#[inline]
#[must_use]
pub fn light_xi(light: u32, frame_seed: u32) -> f32 {
    (tea(light, frame_seed, 16) >> 8) as f32 * (1.0 / 16_777_216.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn the_range_is_where_the_keep_probability_equals_xi() {
        for eps2 in [0.0, 1e-4] {
            for (alpha, xi) in [(0.5, 0.3), (20.0, 0.01), (3.0, 0.999), (1e3, 0.5)] {
                let r = stochastic_range(alpha, xi, eps2);
                if r > 0.0 {
                    let p = keep_probability(alpha, r * r, eps2);
                    assert!((p - xi).abs() < 1e-4 * xi.max(1e-3), "{alpha} {xi}: {p}");
                    // Inside it is kept, outside not.
                    assert!(keep_probability(alpha, (r * 0.99).powi(2), eps2) > xi);
                    assert!(keep_probability(alpha, (r * 1.01).powi(2), eps2) < xi);
                } else {
                    assert!(keep_probability(alpha, 0.0, eps2) <= xi);
                }
            }
        }
        // The paper's closed form for eps = 0.
        let r = stochastic_range(4.0, 0.25, 0.0);
        assert!((r - 1.0).abs() < 1e-6);
    }

    /// Monte Carlo over xi: the stochastic fall-off averages to f(l) (unbiased) and its
    /// variance is (1 / p - 1) f^2 (Eq. 4). 400,000 draws; tolerance 4 standard errors.
    #[test]
    fn the_stochastic_falloff_is_unbiased_with_the_variance_of_eq_4() {
        let eps2 = 1e-3;
        // p = 1 at l = 0.2 (no roulette), 0.41 at 0.7, 0.09 at 1.5.
        let alpha = 5.0;
        for l in [0.2f32, 0.7, 1.5] {
            let l2 = l * l;
            let f = f64::from(falloff(l2, eps2));
            let p = f64::from(keep_probability(alpha, l2, eps2));
            let n = 400_000;
            let mut rng = Rng::new(&[7, l.to_bits() as u64]);
            let (mut s, mut s2) = (0.0f64, 0.0f64);
            for _ in 0..n {
                let xi = rng.next_f32();
                let v = f64::from(stochastic_falloff(
                    alpha,
                    stochastic_range(alpha, xi, eps2),
                    l2,
                    eps2,
                ));
                s += v;
                s2 += v * v;
            }
            let mean = s / f64::from(n);
            let var = s2 / f64::from(n) - mean * mean;
            let expected_var = (1.0 / p - 1.0) * f * f;
            let se = (expected_var / f64::from(n)).sqrt().max(1e-9);
            assert!(
                (mean - f).abs() < 4.0 * se + 1e-6 * f,
                "l {l}: mean {mean} vs {f}"
            );
            // The variance of a Bernoulli-scaled value: relative s.e. about sqrt(2 / n) / p.
            let tol = 0.05 * expected_var + 1e-6 * f * f;
            assert!(
                (var - expected_var).abs() < tol,
                "l {l}: var {var} vs {expected_var}"
            );
        }
    }

    #[test]
    fn the_clamped_range_meets_its_error_bound_and_the_stochastic_one_is_bounded() {
        // Appendix A: N lights each losing at most f(r) E I / pi sum to epsilon_max.
        let (eb, e, n, i) = (0.0005, 1.0, 10_000, 0.02);
        let r = clamped_range(eb, e, n, i, 0.0);
        let total = n as f32 * falloff(r * r, 0.0) * e * i / PI;
        assert!((total - eb).abs() < 1e-4 * eb, "{total}");
        // Eq. 6: max_l sigma_i = alpha / 2, so the per-light error bound is alpha E I / (2 pi).
        let alpha = alpha_point(eb, e, i);
        assert!((alpha * e * i / (2.0 * PI) - eb).abs() < 1e-6 * eb);
    }

    #[test]
    fn xi_is_uniform_and_depends_on_the_frame_seed() {
        // Chi-square over 16 bins of 64,000 lights: 15 degrees of freedom, 99.9% point 37.7.
        let n = 64_000u32;
        let mut bins = [0u32; 16];
        for i in 0..n {
            bins[(light_xi(i, 3) * 16.0) as usize] += 1;
        }
        let e = f64::from(n) / 16.0;
        let chi2: f64 = bins.iter().map(|&b| (f64::from(b) - e).powi(2) / e).sum();
        assert!(chi2 < 37.7, "{chi2}");
        assert_ne!(light_xi(5, 0), light_xi(5, 1));
        assert_eq!(light_xi(5, 1), light_xi(5, 1));
    }
}
