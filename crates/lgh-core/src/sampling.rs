//! Sample warps and a discrete distribution.
//!
//! Each warp maps uniform numbers in [0, 1) to a sample of a known density, stated in its doc
//! comment, so that estimators can divide by it.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// An orthonormal basis (t, b, n) around a unit vector `n` (Duff et al. 2017, "Building an
/// Orthonormal Basis, Revisited"): no branch on a threshold, no singularity.
#[inline]
#[must_use]
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Cosine-weighted direction on the hemisphere around the unit normal `n`.
///
/// Density (solid angle): cos(theta) / pi. Uses Malley's method (a concentric disk sample
/// lifted to the hemisphere).
#[inline]
#[must_use]
pub fn cosine_hemisphere(n: Vec3, u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    let (t, b) = orthonormal_basis(n);
    (t * d.x + b * d.y + n * z).normalize()
}

/// Uniform point on the unit disk (Shirley & Chiu 1997 concentric map). Density: 1 / pi.
#[inline]
#[must_use]
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, (PI / 4.0) * (o.y / o.x))
    } else {
        (o.y, PI / 2.0 - (PI / 4.0) * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Uniform direction inside the cone of half-angle acos(`cos_max`) around the unit axis `n`.
///
/// Density (solid angle): 1 / (2 pi (1 - cos_max)).
#[inline]
#[must_use]
pub fn uniform_cone(n: Vec3, cos_max: f32, u: Vec2) -> Vec3 {
    let cos_t = 1.0 - u.x * (1.0 - cos_max);
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    let (t, b) = orthonormal_basis(n);
    (t * (sin_t * phi.cos()) + b * (sin_t * phi.sin()) + n * cos_t).normalize()
}

/// Uniform direction on the unit sphere. Density: 1 / (4 pi).
#[inline]
#[must_use]
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Barycentric coordinates (b1, b2) of a uniform point on a triangle: the point is
/// (1 - b1 - b2) v0 + b1 v1 + b2 v2. Density: 1 / area. (Square-root parameterisation.)
#[inline]
#[must_use]
pub fn uniform_triangle(u: Vec2) -> Vec2 {
    let s = u.x.sqrt();
    Vec2::new(1.0 - s, u.y * s)
}

/// A sample t in [-1, 1] of the raised-cosine density (1 + cos(pi t)) / 2, by rejection-free
/// folding: draw (x, y) uniform; if y > (1 + cos(pi x)) / 2 use x - 1, else x.
///
/// This is the per-axis jitter of a grid light's shadow-sample position (docs/design.md,
/// "Shadow sampling"): the offset t * deviation roughly reproduces the spread of the lights the grid
/// light stands for.
///
/// cos(pi x) is evaluated as -sin(pi (x - 1/2)) by its Taylor polynomial to degree 9
/// (absolute error below 4e-6 on [0, 1)): this runs for every shadow candidate of every pixel,
/// and the library cosine was a tenth of the LGH lighting pass.
#[inline]
#[must_use]
pub fn raised_cosine(u: Vec2) -> f32 {
    let x = u.x;
    let z = PI * (x - 0.5);
    let z2 = z * z;
    let sin_z = z * (1.0 - z2 / 6.0 * (1.0 - z2 / 20.0 * (1.0 - z2 / 42.0 * (1.0 - z2 / 72.0))));
    if u.y > 0.5 * (1.0 - sin_z) {
        x - 1.0
    } else {
        x
    }
}

/// The largest f32 below 1: uniform numbers are kept in [0, 1).
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// A discrete distribution over n items with probabilities proportional to non-negative
/// weights, sampled by binary search in its cumulative table.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    cdf: Vec<f64>,
    total: f64,
}

impl Distribution1D {
    /// Builds the distribution; weights that are negative or not finite count as zero.
    /// Returns `None` if no weight is positive.
    #[must_use]
    pub fn new(weights: &[f32]) -> Option<Self> {
        let mut cdf = Vec::with_capacity(weights.len());
        let mut total = 0.0f64;
        for &w in weights {
            if w.is_finite() && w > 0.0 {
                total += w as f64;
            }
            cdf.push(total);
        }
        (total > 0.0).then_some(Self { cdf, total })
    }

    /// Number of items.
    #[must_use]
    pub fn len(&self) -> usize {
        self.cdf.len()
    }

    /// True if there are no items (never the case for a built distribution).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.cdf.is_empty()
    }

    /// Sum of the weights.
    #[must_use]
    pub fn total(&self) -> f64 {
        self.total
    }

    /// The weights of items 0 to `i` over the total: the cumulative table a backend
    /// without `f64` keeps as two `f32`s (lgh-gpu's light table).
    #[must_use]
    pub fn cumulative(&self, i: usize) -> f64 {
        self.cdf[i] / self.total
    }

    /// Probability of item `i`.
    #[must_use]
    pub fn pmf(&self, i: usize) -> f32 {
        let prev = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        ((self.cdf[i] - prev) / self.total) as f32
    }

    /// Picks an item for the uniform number `u` in [0, 1); returns (index, probability).
    /// Items of zero weight are never picked.
    #[must_use]
    pub fn sample(&self, u: f32) -> (usize, f32) {
        let (i, _) = self.find(u);
        (i, self.pmf(i))
    }

    /// The item whose cumulative interval holds `u` times the total, and that point.
    #[inline]
    fn find(&self, u: f32) -> (usize, f64) {
        let target = u as f64 * self.total;
        let i = self
            .cdf
            .partition_point(|&c| c <= target)
            .min(self.cdf.len() - 1);
        (i, target)
    }

    /// Like [`Self::sample`], and also returns where `u` fell inside the picked item's
    /// interval, rescaled to [0, 1): a fresh uniform number that keeps the stratification of
    /// `u`, for the next choice (for example the point on the picked light).
    #[must_use]
    pub fn sample_remapped(&self, u: f32) -> (usize, f32, f32) {
        let (i, target) = self.find(u);
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let width = self.cdf[i] - lo;
        let rest = if width > 0.0 {
            ((target - lo) / width).clamp(0.0, 1.0) as f32
        } else {
            0.0
        };
        (i, self.pmf(i), rest.min(ONE_MINUS_EPSILON))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn basis_is_orthonormal() {
        let mut rng = Rng::new(&[7]);
        for _ in 0..1000 {
            let n = uniform_sphere(rng.next_2d());
            let (t, b) = orthonormal_basis(n);
            assert!(t.dot(n).abs() < 1e-5 && b.dot(n).abs() < 1e-5 && t.dot(b).abs() < 1e-5);
            assert!((t.length() - 1.0).abs() < 1e-5 && (b.length() - 1.0).abs() < 1e-5);
        }
    }

    /// E[cos theta] under the cosine density is 2/3; 200k samples give a standard error of
    /// about 0.0005, the tolerance is 0.003 (6 sigma).
    #[test]
    fn cosine_hemisphere_mean_cosine() {
        let mut rng = Rng::new(&[8]);
        let n = Vec3::new(0.3, -0.5, 0.8).normalize();
        let m = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..m {
            let d = cosine_hemisphere(n, rng.next_2d());
            let c = d.dot(n);
            assert!(c >= -1e-6);
            sum += c as f64;
        }
        assert!((sum / m as f64 - 2.0 / 3.0).abs() < 0.003);
    }

    /// The raised-cosine density has variance 1/3 - 2/pi^2 (about 0.1307); 200k samples,
    /// tolerance 0.002 (about 6 standard errors).
    #[test]
    fn raised_cosine_polynomial_matches_the_cosine() {
        for i in 0..=1000 {
            let x = i as f32 / 1000.0;
            let z = PI * (x - 0.5);
            let z2 = z * z;
            let p =
                z * (1.0 - z2 / 6.0 * (1.0 - z2 / 20.0 * (1.0 - z2 / 42.0 * (1.0 - z2 / 72.0))));
            assert!((-p - (PI * x).cos()).abs() < 4e-6, "x {x}");
        }
    }

    #[test]
    fn raised_cosine_variance() {
        let mut rng = Rng::new(&[9]);
        let m = 200_000;
        let (mut s1, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..m {
            let t = raised_cosine(rng.next_2d()) as f64;
            assert!((-1.0..=1.0).contains(&t));
            s1 += t;
            s2 += t * t;
        }
        let mean = s1 / m as f64;
        let var = s2 / m as f64 - mean * mean;
        let expected = 1.0 / 3.0 - 2.0 / (std::f64::consts::PI.powi(2));
        assert!(mean.abs() < 0.003, "mean {mean}");
        assert!((var - expected).abs() < 0.002, "var {var} vs {expected}");
    }

    /// Chi-square over 5 items (one of zero weight, never drawn): 4 degrees of freedom,
    /// 25 is beyond the 99.99th percentile.
    #[test]
    fn distribution_matches_weights() {
        let w = [1.0, 0.0, 3.0, 2.0, 4.0];
        let d = Distribution1D::new(&w).unwrap();
        let mut rng = Rng::new(&[10]);
        let n = 100_000;
        let mut counts = [0u32; 5];
        for _ in 0..n {
            let (i, p) = d.sample(rng.next_f32());
            assert!((p - w[i] / 10.0).abs() < 1e-6);
            counts[i] += 1;
        }
        assert_eq!(counts[1], 0);
        let chi2: f64 = [0, 2, 3, 4]
            .iter()
            .map(|&i| {
                let e = n as f64 * w[i] as f64 / 10.0;
                (counts[i] as f64 - e).powi(2) / e
            })
            .sum();
        assert!(chi2 < 25.0, "chi2 {chi2}");
        assert!(Distribution1D::new(&[0.0, f32::NAN]).is_none());
    }

    /// Evenly spaced u give evenly spaced remainders inside each picked item: the remainder is
    /// again uniform, and the item choice agrees with `sample`.
    #[test]
    fn remapped_remainder_is_uniform_within_each_item() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]).unwrap();
        let mut rests = [Vec::new(), Vec::new(), Vec::new()];
        for j in 0..4000 {
            let u = (j as f32 + 0.5) / 4000.0;
            let (i, p, rest) = d.sample_remapped(u);
            assert_eq!((i, p), d.sample(u));
            assert!((0.0..1.0).contains(&rest));
            rests[i].push(rest);
        }
        assert!(rests[1].is_empty());
        for r in [&rests[0], &rests[2]] {
            for (j, &v) in r.iter().enumerate() {
                let expected = (j as f32 + 0.5) / r.len() as f32;
                assert!((v - expected).abs() < 1e-3, "{v} vs {expected}");
            }
        }
    }
}
