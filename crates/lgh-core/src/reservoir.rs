//! Streaming selection of shadow samples (Lin & Yuksel 2019, section 3.3 and Appendix A).
//!
//! A pixel sees its lights one at a time, in any order, with selection weights f_i >= 0 (the
//! luminance of the light's unshadowed contribution). A single-slot reservoir keeps a running
//! total f^_i = sum_{j <= i} f_j and replaces its sample by light i with probability
//! p~_i = f_i / f^_i. After the stream, light i is held with probability p_i = f_i / sum_j f_j
//! (Appendix A's induction), whatever the order, with memory fixed at one slot. A pixel keeps
//! k independent reservoirs (k shadow samples), each with its own random numbers.
//!
//! [`Reservoir::update_jump`] draws the same decisions with one random number per
//! *replacement* instead of one per light: the chance that no light replaces the sample while
//! the total grows from f^ to F is the telescoping product of (1 - f_i / f^_i) = f^ / F, so
//! after each replacement at total f^ a threshold T = f^ / u (u uniform in (0, 1]) is drawn,
//! and the next replacement is the light whose addition makes the total reach T.

/// One single-slot weighted reservoir holding a sample of type `T`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Reservoir<T> {
    /// Running total f^ of the weights seen so far.
    pub total: f32,
    /// Weight f of the held sample.
    pub weight: f32,
    /// The held sample (`None` until a light of positive weight is seen).
    pub sample: Option<T>,
    /// Total at which [`Reservoir::update_jump`] replaces the sample next.
    pub threshold: f32,
}

impl<T> Reservoir<T> {
    /// An empty reservoir.
    #[must_use]
    pub fn new() -> Self {
        Self {
            total: 0.0,
            weight: 0.0,
            sample: None,
            threshold: 0.0,
        }
    }

    /// Offers a light with weight `f` (ignored unless positive and finite), building the
    /// sample only if it is taken; `u` gives a uniform number in [0, 1) and is called once per
    /// replacement (see the module docs: the same distribution as [`Reservoir::update`],
    /// with no random number for the lights that are passed over). Returns true if taken.
    #[inline]
    pub fn update_jump(
        &mut self,
        sample: impl FnOnce() -> T,
        f: f32,
        u: impl FnOnce() -> f32,
    ) -> bool {
        if !(f > 0.0 && f.is_finite()) {
            return false;
        }
        self.total += f;
        if self.total >= self.threshold {
            self.weight = f;
            self.sample = Some(sample());
            // T = f^ / u with u in (0, 1].
            self.threshold = self.total / (1.0 - u());
            true
        } else {
            false
        }
    }

    /// Offers a light with weight `f` (ignored unless positive and finite) and uniform random
    /// number `u` in [0, 1): it replaces the held sample with probability f / f^. Returns true
    /// if it was taken.
    #[inline]
    pub fn update(&mut self, sample: T, f: f32, u: f32) -> bool {
        if !(f > 0.0 && f.is_finite()) {
            return false;
        }
        self.total += f;
        if u * self.total < f {
            self.weight = f;
            self.sample = Some(sample);
            true
        } else {
            false
        }
    }

    /// The probability with which the held sample was chosen, f / f^ (0 if empty).
    #[must_use]
    pub fn probability(&self) -> f32 {
        if self.total > 0.0 {
            self.weight / self.total
        } else {
            0.0
        }
    }
}

/// Uniform reservoir sampling of k items from a stream of unknown length m (Vitter 1985, as
/// Tokuyoshi & Harada 2016 use it in Algorithm 3): the first k items fill the slots; item m
/// (counting from 1) then replaces a random slot with probability k/m. After the stream every
/// item is held with probability min(k/m, 1), with memory fixed at k items.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UniformReservoir<T> {
    /// The held items (at most k).
    pub items: Vec<T>,
    k: usize,
    seen: usize,
}

impl<T> UniformReservoir<T> {
    /// An empty reservoir of `k` slots.
    #[must_use]
    pub fn new(k: usize) -> Self {
        Self {
            items: Vec::with_capacity(k),
            k,
            seen: 0,
        }
    }

    /// Offers `item` with a uniform random number `u` in [0, 1).
    #[inline]
    pub fn offer(&mut self, item: T, u: f32) {
        self.seen += 1;
        if self.items.len() < self.k {
            self.items.push(item);
        } else {
            let r = (u * self.seen as f32) as usize;
            if r < self.k {
                self.items[r] = item;
            }
        }
    }

    /// Items offered so far (m).
    #[must_use]
    pub fn seen(&self) -> usize {
        self.seen
    }

    /// The probability min(k/m, 1) with which each offered item is held.
    #[must_use]
    pub fn keep_probability(&self) -> f32 {
        if self.seen > self.k {
            self.k as f32 / self.seen as f32
        } else {
            1.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// Over 200k trials, light i is picked with probability f_i / sum f, for k = 1 and for each
    /// of k = 4 independent reservoirs, with zero weights (never picked) in the stream. Chi-square
    /// with 5 degrees of freedom (6 positive weights): 30 is beyond the 99.99th percentile;
    /// with 10 tests the family-wise false-alarm rate stays below 1e-3.
    /// The same for [`Reservoir::update_jump`] (thresholds instead of a decision per light).
    #[test]
    fn appendix_a_selection_probabilities() {
        selection_probabilities(false);
        selection_probabilities(true);
    }

    fn selection_probabilities(jump: bool) {
        let f = [0.0f32, 2.0, 0.5, 0.0, 4.0, 1.0, 3.0, 0.25];
        let sum: f32 = f.iter().sum();
        for k in [1usize, 4] {
            let trials = 200_000;
            let mut counts = vec![vec![0u32; f.len()]; k];
            let mut rng = Rng::new(&[k as u64, 77]);
            for _ in 0..trials {
                let mut rs = vec![Reservoir::new(); k];
                for (i, &fi) in f.iter().enumerate() {
                    for r in &mut rs {
                        if jump {
                            r.update_jump(|| i, fi, || rng.next_f32());
                        } else {
                            r.update(i, fi, rng.next_f32());
                        }
                    }
                }
                for (slot, r) in rs.iter().enumerate() {
                    let i = r.sample.unwrap();
                    assert!((r.total - sum).abs() < 1e-4);
                    counts[slot][i] += 1;
                }
            }
            for c in &counts {
                assert_eq!(c[0] + c[3], 0, "a zero-weight light was picked");
                let chi2: f64 = (0..f.len())
                    .filter(|&i| f[i] > 0.0)
                    .map(|i| {
                        let e = trials as f64 * f64::from(f[i] / sum);
                        (f64::from(c[i]) - e).powi(2) / e
                    })
                    .sum();
                assert!(
                    chi2 < 30.0,
                    "k = {k}, jump {jump}: chi2 {chi2}, counts {c:?}"
                );
            }
        }
    }

    #[test]
    fn empty_and_degenerate_streams() {
        let mut r: Reservoir<u32> = Reservoir::new();
        assert!(!r.update(1, 0.0, 0.5));
        assert!(!r.update(2, f32::NAN, 0.5));
        assert!(r.sample.is_none() && r.probability() == 0.0);
        assert!(r.update(3, 1.0, 0.999));
        assert_eq!(r.sample, Some(3));
    }

    /// Algorithm 3 keeps each of m = 20 items with probability k/m = 8/20: chi-square over
    /// the 20 items' hold counts in 20,000 trials (19 degrees of freedom, 99.9% point 43.8).
    #[test]
    fn uniform_reservoir_keeps_each_item_with_probability_k_over_m() {
        let (k, m, trials) = (8usize, 20usize, 20_000u32);
        let mut held = vec![0u32; m];
        let mut rng = crate::rng::Rng::new(&[5]);
        for _ in 0..trials {
            let mut r = UniformReservoir::new(k);
            for i in 0..m {
                r.offer(i, rng.next_f32());
            }
            assert_eq!(r.items.len(), k);
            assert!((r.keep_probability() - 0.4).abs() < 1e-6);
            for &i in &r.items {
                held[i] += 1;
            }
        }
        let e = f64::from(trials) * k as f64 / m as f64;
        let chi2: f64 = held.iter().map(|&h| (f64::from(h) - e).powi(2) / e).sum();
        assert!(chi2 < 43.8, "chi2 {chi2}: {held:?}");
        // Fewer items than slots: all kept.
        let mut r = UniformReservoir::new(4);
        r.offer(1, 0.3);
        r.offer(2, 0.9);
        assert_eq!(r.items, vec![1, 2]);
        assert_eq!(r.keep_probability(), 1.0);
    }
}
