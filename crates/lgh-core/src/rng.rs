//! Counter-based random numbers.
//!
//! Every random decision in lgh is a pure function of a key (seed, pixel or path index, pass),
//! never of which thread ran the work: that is what makes images bit-identical with 1 or 2
//! threads. A [`Rng`] is a PCG32 generator (O'Neill 2014) whose state and stream are derived
//! from such a key by a strong 64-bit mixer. It is a few lines, and keeping it here (rather than
//! taking it from a crate) pins the streams: a dependency update can never change an image.

/// SplitMix64 finaliser (Steele et al. 2014): a bijective 64-bit mixer.
#[inline]
#[must_use]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Hashes a list of integers into 64 well-mixed bits.
#[inline]
#[must_use]
pub fn hash(keys: &[u64]) -> u64 {
    let mut h = 0x9e37_79b9_7f4a_7c15u64;
    for &k in keys {
        h = mix64(h ^ k.wrapping_add(0x9e37_79b9_7f4a_7c15));
    }
    h
}

/// A PCG32 (XSH-RR) random number generator seeded from a key.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

impl Rng {
    const MULT: u64 = 6_364_136_223_846_793_005;

    /// A generator for the stream named by `keys` (for example `[seed, pixel, pass]`).
    #[must_use]
    pub fn new(keys: &[u64]) -> Self {
        let h = hash(keys);
        let mut rng = Self {
            state: 0,
            inc: (mix64(h ^ 0xda94_2042_e4dd_58b5) << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(h);
        rng.next_u32();
        rng
    }

    /// The next 32 random bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// A uniform float in [0, 1) (24 random bits, so never exactly 1).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Two uniform floats in [0, 1).
    #[inline]
    pub fn next_2d(&mut self) -> glam::Vec2 {
        glam::Vec2::new(self.next_f32(), self.next_f32())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_key_same_stream_and_different_keys_differ() {
        let mut a = Rng::new(&[1, 2, 3]);
        let mut b = Rng::new(&[1, 2, 3]);
        let mut c = Rng::new(&[1, 2, 4]);
        let va: Vec<u32> = (0..8).map(|_| a.next_u32()).collect();
        let vb: Vec<u32> = (0..8).map(|_| b.next_u32()).collect();
        let vc: Vec<u32> = (0..8).map(|_| c.next_u32()).collect();
        assert_eq!(va, vb);
        assert_ne!(va, vc);
    }

    /// Chi-square test of uniformity over 64 bins, 640,000 draws: the statistic has 63 degrees
    /// of freedom, and 110 is beyond its 99.99th percentile.
    #[test]
    fn floats_are_uniform_chi_square() {
        let mut rng = Rng::new(&[42]);
        let bins = 64;
        let n = 640_000;
        let mut counts = vec![0u32; bins];
        for _ in 0..n {
            let u = rng.next_f32();
            assert!((0.0..1.0).contains(&u));
            counts[(u * bins as f32) as usize] += 1;
        }
        let expected = n as f64 / bins as f64;
        let chi2: f64 = counts
            .iter()
            .map(|&c| (c as f64 - expected).powi(2) / expected)
            .sum();
        assert!(chi2 < 110.0, "chi2 = {chi2}");
    }
}
