//! Screen-space dithered strata for the stratified selection of shadow samples
//! (docs/design.md, "Dithered strata"; an extension of LGH 2019 Appendix A).
//!
//! The stratified selection draws a pixel's k samples at the points t_i = (i + u_i) / k of
//! its cumulative weight (`reservoirs::stratified_picks`). With u_i independent from pixel
//! to pixel, two neighbours of one sub-image, whose lights and weights are nearly the same,
//! often take the same lights, and the filters that average them afterwards (the
//! interleaving blur, the a-trous) average repeats. Here u_i follows a low-discrepancy
//! sequence over the screen instead: u_i(x, y) = frac(phi(x', y') + c + i g), with
//! phi = frac(a_1 x' + a_2 y') the R2 sequence (Roberts 2018, the plastic number's
//! a_1 = 1 / rho, a_2 = 1 / rho^2) over the pixel's coordinates (x', y') = (x, y) div n in
//! its sub-image of n x n interleaving, c a frame's random rotation and g the golden ratio's
//! fraction. Neighbouring pixels then spread their thresholds over the cumulative weight
//! jointly, so that the filtered estimate averages samples spread over the lights, as
//! screen-space blue-noise sampling does (Heitz and Belcour 2019).
//!
//! Each pixel's u_i alone is uniform over the frame's rotation c, so every sample alone is
//! still drawn in proportion to f_j: the estimate is unbiased as before. All arithmetic is
//! on 32-bit integers (the fractions in units of 2^-32), so the GPU's loop draws the same
//! numbers from the same key.

use lgh_core::rng::Rng;

/// Random-stream tag of the frame's rotation c.
const STREAM_STRATA: u64 = 0x5747;

/// a_1 = 1 / rho = 0.7548776662... in units of 2^-32 (rho the plastic number).
pub const R2_A1: u32 = 3_242_174_889;
/// a_2 = 1 / rho^2 = 0.5698402909... in units of 2^-32.
pub const R2_A2: u32 = 2_447_445_414;
/// g = frac of the golden ratio, 0.6180339887... in units of 2^-32: the step between a
/// pixel's strata.
pub const GOLDEN: u32 = 0x9E37_79B9;

/// The dithered strata of one frame: its rotation c and the interleaving n.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScreenStrata {
    /// c in units of 2^-32, from the frame's seed.
    pub key: u32,
    /// n of the n x n interleaving (1: none).
    pub phases: u32,
}

impl ScreenStrata {
    /// The strata of the frame with seed `seed` and `phases` x `phases` interleaving.
    #[must_use]
    pub fn new(seed: u64, phases: u32) -> Self {
        Self {
            key: Rng::new(&[seed, STREAM_STRATA]).next_u32(),
            phases: phases.max(1),
        }
    }

    /// The strata of pixel (x, y).
    #[inline]
    #[must_use]
    pub fn pixel(&self, x: u32, y: u32) -> PixelStrata {
        let (xs, ys) = (x / self.phases, y / self.phases);
        PixelStrata(
            xs.wrapping_mul(R2_A1)
                .wrapping_add(ys.wrapping_mul(R2_A2))
                .wrapping_add(self.key),
        )
    }
}

/// One pixel's dithered strata: frac(phi + c) in units of 2^-32.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelStrata(pub u32);

impl PixelStrata {
    /// u_i in [0, 1): the offset of stratum `i` (24 bits, as `Rng::next_f32`).
    #[inline]
    #[must_use]
    pub fn u(self, i: usize) -> f32 {
        let v = self.0.wrapping_add((i as u32).wrapping_mul(GOLDEN));
        (v >> 8) as f32 * (1.0 / 16_777_216.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The constants are the R2 sequence's and the golden ratio's fractions.
    #[test]
    fn constants_are_the_sequences() {
        let unit = 4_294_967_296.0f64;
        let rho = 1.324_717_957_244_746f64;
        for (c, x) in [
            (R2_A1, 1.0 / rho),
            (R2_A2, 1.0 / (rho * rho)),
            (GOLDEN, (5f64.sqrt() - 1.0) / 2.0),
        ] {
            assert!((f64::from(c) / unit - x).abs() < 1e-9, "{c} against {x}");
        }
    }

    /// Over frames (seeds), one pixel's u_i is uniform: each of 16 bins of [0, 1) gets its
    /// share of 16,000 frames within 5 standard deviations, for several pixels and strata.
    #[test]
    fn each_pixel_is_uniform_over_frames() {
        for (x, y, i) in [(0, 0, 0), (17, 3, 2), (1279, 719, 4)] {
            let mut bins = [0u32; 16];
            let frames = 16_000u64;
            for seed in 0..frames {
                let u = ScreenStrata::new(seed, 2).pixel(x, y).u(i);
                assert!((0.0..1.0).contains(&u));
                bins[(u * 16.0) as usize] += 1;
            }
            let (mean, sd) = (1000.0, (1000.0f64 * 15.0 / 16.0).sqrt());
            for b in bins {
                assert!((f64::from(b) - mean).abs() < 5.0 * sd, "{bins:?}");
            }
        }
    }

    /// Within a frame, the 16 pixels of a 4 x 4 block of one sub-image spread their u over
    /// [0, 1): no two fall closer than 1/64 apart, and the largest gap is under 3/16 (16
    /// independent numbers leave a gap over 3/16 about half the time).
    #[test]
    fn neighbours_spread_over_the_unit_interval() {
        for seed in 0..20 {
            let strata = ScreenStrata::new(seed, 2);
            for (bx, by) in [(0, 0), (40, 22), (300, 170)] {
                let mut u: Vec<f32> = (0..16)
                    .map(|k| strata.pixel(bx + 2 * (k % 4), by + 2 * (k / 4)).u(0))
                    .collect();
                u.sort_by(f32::total_cmp);
                let gaps: Vec<f32> = u
                    .windows(2)
                    .map(|w| w[1] - w[0])
                    .chain([u[0] + 1.0 - u[15]])
                    .collect();
                let (min, max) = gaps
                    .iter()
                    .fold((1.0f32, 0.0f32), |(a, b), &g| (a.min(g), b.max(g)));
                assert!(min > 1.0 / 64.0 && max < 3.0 / 16.0, "{u:?}");
            }
        }
    }

    /// What the dithering is for: 16 pixels of a 4 x 4 block of one sub-image share 40
    /// lights (weights 1 to 7) and see only the first 24 of them (a wall hides the rest).
    /// Each takes k = 2 samples and estimates its visible fraction of the weight (the
    /// ratio estimator's S / U), and a filter averages the 16. Over 4,000 frames the
    /// average is unbiased either way (within 4 standard errors of the exact fraction), and
    /// its variance with dithered strata is below a fifth of that with independent ones
    /// (the 32 thresholds then spread over the cumulative weight together).
    #[test]
    fn dithered_strata_lower_the_variance_of_a_filtered_estimate() {
        use crate::shading::reservoirs::stratified_picks;
        let f: Vec<f32> = (0..40).map(|j| 1.0 + (j * 5 % 7) as f32).collect();
        let chunks: Vec<f32> = f.chunks(4).map(|c| c.iter().sum()).collect();
        let lanes = |c: usize| {
            let mut w = [0.0f32; 4];
            w.copy_from_slice(&f[4 * c..4 * c + 4]);
            (w, c)
        };
        let exact = f64::from(f[..24].iter().sum::<f32>() / f.iter().sum::<f32>());
        let (k, frames) = (2usize, 4000u64);
        let mut rng = Rng::new(&[7]);
        let mut stats = Vec::new();
        for dithered in [false, true] {
            let (mut sum, mut sum2) = (0.0f64, 0.0f64);
            for frame in 0..frames {
                let strata = ScreenStrata::new(frame, 2);
                let mut mean = 0.0f64;
                for p in 0..16u32 {
                    let px = strata.pixel(100 + 2 * (p % 4), 50 + 2 * (p / 4));
                    let mut visible = 0.0f64;
                    let mut u = |i| if dithered { px.u(i) } else { rng.next_f32() };
                    stratified_picks(&chunks, lanes, k, &mut u, |_, l, &c, _, _| {
                        visible += f64::from(u8::from(4 * c + l < 24));
                    });
                    mean += visible / k as f64 / 16.0;
                }
                (sum, sum2) = (sum + mean, sum2 + mean * mean);
            }
            let m = sum / frames as f64;
            let var = sum2 / frames as f64 - m * m;
            let se = (var / frames as f64).sqrt();
            assert!(
                (m - exact).abs() < 4.0 * se + 1e-6,
                "mean {m}, exact {exact}"
            );
            stats.push(var);
        }
        assert!(stats[1] < 0.2 * stats[0], "variances {stats:?}");
    }

    /// Pixels of one n x n block (different sub-images, different lights) share their
    /// strata; the next block's differ.
    #[test]
    fn sub_image_coordinates() {
        let s = ScreenStrata::new(3, 4);
        assert_eq!(s.pixel(4, 8), s.pixel(7, 11));
        assert_ne!(s.pixel(4, 8), s.pixel(8, 8));
        assert_eq!(ScreenStrata::new(3, 0).phases, 1);
    }
}
