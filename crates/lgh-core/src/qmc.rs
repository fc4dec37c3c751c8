//! Randomised quasi-Monte Carlo numbers for light paths, and the [`Sampler`] trait that lets a
//! sampling routine take either them or a plain [`Rng`].
//!
//! Light tracing (Keller 1997, "Instant Radiosity", used Halton points for the same reason)
//! draws every path from a few uniform numbers: which light, where on it, which direction,
//! then a roulette number and a direction per bounce. With independent random numbers the
//! VPLs clump and leave holes, so the unshadowed light A = sum of VPL contributions changes
//! visibly from one VPL set to the next: that change is the flicker of LGH 2019 section 4.3
//! when VPLs are regenerated every frame. [`PathSampler`] gives path `k` the `k`-th point of an
//! Owen-scrambled Sobol sequence instead (Burley 2020, "Practical Hash-based Owen Scrambling",
//! through the `sobol_burley` crate), so the paths of one frame stratify the light's position
//! and direction. The scrambling seed changes with the frame seed, so each frame's point set
//! is an independent random one and every estimate stays unbiased.
//!
//! The dimensions are consumed in groups of four, each group a separately seeded 4D sequence
//! ("padding", Burley 2020 section 4), which keeps every 4D projection well stratified. The
//! sequence supports 2^16 points; path `k` uses point `k mod 2^16` of block `k / 2^16`, and
//! blocks are scrambled independently of each other.

use glam::Vec2;

use crate::rng::{Rng, hash};

/// A source of uniform numbers in [0, 1) for sampling routines.
pub trait Sampler {
    /// The next uniform number in [0, 1).
    fn next_f32(&mut self) -> f32;

    /// The next two uniform numbers, as one 2D point in [0, 1)^2.
    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        let x = self.next_f32();
        Vec2::new(x, self.next_f32())
    }
}

impl Sampler for Rng {
    #[inline]
    fn next_f32(&mut self) -> f32 {
        Rng::next_f32(self)
    }

    #[inline]
    fn next_2d(&mut self) -> Vec2 {
        Rng::next_2d(self)
    }
}

/// Points per scrambled block (the longest sequence `sobol_burley` supports).
pub const BLOCK: u64 = 1 << 16;

/// The scrambling seed of block `block` of the point set of `seed` ([`PathSampler`]).
#[inline]
#[must_use]
pub fn block_seed(seed: u64, block: u64) -> u64 {
    hash(&[seed, block, 0x50b0])
}

/// The seed of the 4D sequence of dimension group `group` in a block of seed `block_seed`
/// (`sobol_burley::sample_4d`'s seed): what a backend that draws the same numbers needs.
#[inline]
#[must_use]
pub fn group_seed(block_seed: u64, group: u32) -> u32 {
    hash(&[block_seed, u64::from(group)]) as u32
}

/// The Owen-scrambled Sobol point of one light path: its dimensions, four at a time.
#[derive(Clone, Debug)]
pub struct PathSampler {
    /// Index of the point within its block.
    index: u32,
    /// Seed of the block (from the frame seed and the block number).
    block_seed: u64,
    /// Next 4D group to draw.
    group: u32,
    /// The current group's four numbers and how many are used.
    values: [f32; 4],
    used: usize,
}

impl PathSampler {
    /// The sampler of path `path` in the point set of `seed`.
    #[must_use]
    pub fn new(seed: u64, path: u64) -> Self {
        Self {
            index: (path % BLOCK) as u32,
            block_seed: block_seed(seed, path / BLOCK),
            group: 0,
            values: [0.0; 4],
            used: 4,
        }
    }
}

impl Sampler for PathSampler {
    #[inline]
    fn next_f32(&mut self) -> f32 {
        if self.used == 4 {
            let seed = group_seed(self.block_seed, self.group);
            self.values = sobol_burley::sample_4d(self.index, 0, seed);
            self.group += 1;
            self.used = 0;
        }
        let v = self.values[self.used];
        self.used += 1;
        v
    }
}

/// The direction vectors of the first four Sobol dimensions that [`PathSampler`]'s 4D groups
/// use, bit-reversed as `sobol_burley` keeps them: entry b holds, per dimension, what bit b
/// (from the top) of the bit-reversed, index-scrambled point index contributes. A backend
/// that draws the same numbers (lgh-gpu) XORs these over the set bits of the top 16.
#[must_use]
pub fn direction_vectors_4d() -> [[u32; 4]; 16] {
    std::array::from_fn(|b| {
        std::array::from_fn(|d| sobol_burley::parts::sobol_rev(0x8000_0000 >> b, d as u32))
    })
}

/// Point `index` of the 2D Owen-scrambled Sobol set of `seed` (the first two dimensions of
/// its 4D sequence): the points of one seed are stratified, and sets of different seeds are
/// independent. Beyond 2^16 points the set continues with independently scrambled blocks.
#[inline]
#[must_use]
pub fn stratified_2d(seed: u64, index: u64) -> Vec2 {
    let block = index / BLOCK;
    let s = if block == 0 {
        seed as u32 ^ (seed >> 32) as u32
    } else {
        hash(&[seed, block, 0x2d]) as u32
    };
    let v = sobol_burley::sample_4d((index % BLOCK) as u32, 0, s);
    Vec2::new(v[0], v[1])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Counts of 2D points in an n x n grid of cells.
    fn cell_counts(points: &[Vec2], n: usize) -> Vec<u32> {
        let mut counts = vec![0u32; n * n];
        for p in points {
            let (x, y) = ((p.x * n as f32) as usize, (p.y * n as f32) as usize);
            counts[y.min(n - 1) * n + x.min(n - 1)] += 1;
        }
        counts
    }

    #[test]
    fn every_dimension_is_in_the_unit_interval_and_deterministic() {
        for path in [0u64, 1, 65_535, 65_536, 1_000_003] {
            let mut a = PathSampler::new(7, path);
            let mut b = PathSampler::new(7, path);
            for _ in 0..20 {
                let (x, y) = (a.next_f32(), b.next_f32());
                assert!((0.0..1.0).contains(&x));
                assert_eq!(x.to_bits(), y.to_bits());
            }
        }
    }

    /// 1024 paths put exactly 4 points in each of the 16 x 16 cells of the 2D projection of
    /// the first two dimensions of a group (the Sobol (0, 2)-net property, kept by Owen
    /// scrambling), in the first and in a later group. Independent random numbers, for
    /// comparison, give a chi-square near its mean of 255.
    #[test]
    fn the_paths_of_one_frame_are_stratified() {
        for (dims_before, seed) in [(0usize, 3u64), (4, 11), (8, 5)] {
            let points: Vec<Vec2> = (0..1024)
                .map(|k| {
                    let mut s = PathSampler::new(seed, k);
                    for _ in 0..dims_before {
                        s.next_f32();
                    }
                    s.next_2d()
                })
                .collect();
            let counts = cell_counts(&points, 16);
            assert!(counts.iter().all(|&c| c == 4), "{dims_before}: {counts:?}");
        }
        let mut rng = Rng::new(&[1]);
        let points: Vec<Vec2> = (0..1024).map(|_| Rng::next_2d(&mut rng)).collect();
        let chi2: f64 = cell_counts(&points, 16)
            .iter()
            .map(|&c| (f64::from(c) - 4.0).powi(2) / 4.0)
            .sum();
        assert!(chi2 > 150.0, "random chi2 {chi2}");
    }

    /// Unbiased: over independent seeds, the mean of a smooth integrand over 100 points is its
    /// integral (x y z w over [0,1]^4 = 1/16), within 4 standard errors.
    #[test]
    fn scrambled_points_integrate_without_bias() {
        let estimates: Vec<f64> = (0..200u64)
            .map(|seed| {
                (0..100u64)
                    .map(|k| {
                        let mut s = PathSampler::new(seed, k);
                        (0..4).map(|_| f64::from(s.next_f32())).product::<f64>()
                    })
                    .sum::<f64>()
                    / 100.0
            })
            .collect();
        let n = estimates.len() as f64;
        let mean = estimates.iter().sum::<f64>() / n;
        let var = estimates.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let se = (var / n).sqrt();
        assert!(
            (mean - 1.0 / 16.0).abs() < 4.0 * se + 1e-6,
            "{mean} +- {se}"
        );
    }
}
