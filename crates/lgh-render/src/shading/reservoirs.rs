//! The k shadow-sample reservoirs a pixel keeps while it is shaded (LGH 2019 Appendix A):
//! every candidate light j is offered with weight f_j = luminance of its unshadowed
//! contribution, and each single-slot weighted reservoir keeps one candidate with probability
//! proportional to its weight. The reservoirs of one band of rows live in one flat buffer
//! ([`ShadowReservoirs`]), reused band after band by [`crate::shading::shadow_pass`].

use glam::{Vec2, Vec3};
use lgh_core::reservoir::Reservoir;
use lgh_core::rng::Rng;
use rayon::prelude::*;

/// Most shadow samples per pixel.
pub const MAX_SHADOW_SAMPLES: u32 = 16;

/// A held shadow sample: the point the ray goes to, the normal its end is moved off the
/// surface along (as for VPLs in the brute force), and the unshadowed contribution f.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowSample {
    /// Shadow-ray target.
    pub q: Vec3,
    /// Normal at the target (any length; zero for none).
    pub n: Vec3,
    /// Unshadowed RGB contribution of the light at the pixel.
    pub f: Vec3,
    /// Per-axis jitter extent drawn when the ray is traced: the ray goes to
    /// q + t * jitter, t raised-cosine per axis (zero: to q itself).
    pub jitter: Vec3,
    /// Index of the light in the method's own list, for a target drawn after selection.
    pub light: u32,
    /// Factor of the shadowed estimate per channel: S_k = V gain U_k (1 when S and U
    /// estimate the same sum; `lgh`'s unbiased estimate sets it, docs/design.md, "Unbiased
    /// estimate", and finishes it for a visible sample,
    /// [`crate::shading::shadow_pass::Targets::visible_gain`]). Zero: no ray, S_k = 0,
    /// U_k still counts.
    pub gain: Vec3,
}

impl Default for ShadowSample {
    fn default() -> Self {
        Self {
            q: Vec3::ZERO,
            n: Vec3::ZERO,
            f: Vec3::ZERO,
            jitter: Vec3::ZERO,
            light: 0,
            gain: Vec3::ONE,
        }
    }
}

/// k reservoirs per pixel for a band of image rows, in one flat buffer (memory fixed at k
/// samples a pixel of the band). Pixels and rows are addressed by their image index.
#[derive(Clone, Debug)]
pub struct ShadowReservoirs {
    k: usize,
    slots: usize,
    width: usize,
    first_row: usize,
    data: Vec<Reservoir<ShadowSample>>,
}

impl ShadowReservoirs {
    /// Empty reservoirs, `k` per pixel, for image rows `rows` of `width` pixels.
    #[must_use]
    pub fn new(width: usize, rows: std::ops::Range<usize>, k: usize) -> Self {
        let mut r = Self {
            // At least one slot a pixel so that row chunks line up when k = 0.
            k,
            slots: k.max(1),
            width,
            first_row: 0,
            data: Vec::new(),
        };
        r.reset(rows);
        r
    }

    /// Empties the reservoirs and moves them to image rows `rows`, reusing the buffer (its
    /// pages are already mapped: fresh memory costs a page fault per 4 KB).
    pub fn reset(&mut self, rows: std::ops::Range<usize>) {
        let kept = self.place(rows);
        self.data[..kept]
            .par_iter_mut()
            .for_each(|r| *r = Reservoir::new());
    }

    /// Moves the reservoirs to image rows `rows`, reusing the buffer, but empties only the
    /// part it had to add: returns how many reservoirs at the front still hold old samples
    /// (the caller empties each row before use, while it is in the cache).
    pub(crate) fn place(&mut self, rows: std::ops::Range<usize>) -> usize {
        self.first_row = rows.start;
        let len = rows.len() * self.width * self.slots;
        self.data.truncate(len);
        let kept = self.data.len();
        self.data
            .par_extend((0..len - kept).into_par_iter().map(|_| Reservoir::new()));
        kept
    }

    /// Shadow samples per pixel.
    #[must_use]
    pub fn k(&self) -> usize {
        self.k
    }

    /// Image rows held.
    #[must_use]
    pub fn rows(&self) -> std::ops::Range<usize> {
        let n = self.data.len() / (self.width * self.slots).max(1);
        self.first_row..self.first_row + n
    }

    /// The held rows in groups of `rows` (the last may be shorter), mutable and in
    /// parallel, each with the image index of its first row; see
    /// [`ReservoirLayout::pixel_mut`].
    pub fn groups_mut(
        &mut self,
        rows: usize,
    ) -> impl IndexedParallelIterator<Item = (usize, &mut [Reservoir<ShadowSample>])> {
        let (first, rows) = (self.first_row, rows.max(1));
        self.data
            .par_chunks_mut(self.width * self.slots * rows)
            .enumerate()
            .map(move |(r, group)| (first + r * rows, group))
    }

    /// Where a pixel's reservoirs lie in a row from [`ShadowReservoirs::groups_mut`].
    #[must_use]
    pub fn layout(&self) -> ReservoirLayout {
        ReservoirLayout {
            k: self.k,
            slots: self.slots,
        }
    }

    /// Slots per pixel (k, at least 1).
    #[must_use]
    pub fn slots(&self) -> usize {
        self.slots
    }

    /// The k reservoirs of image pixel `i` (in the held rows).
    #[inline]
    #[must_use]
    pub fn pixel(&self, i: usize) -> &[Reservoir<ShadowSample>] {
        let at = (i - self.first_row * self.width) * self.slots;
        &self.data[at..at + self.k]
    }
}

/// Where a pixel's reservoirs lie within a row of [`ShadowReservoirs`].
#[derive(Clone, Copy, Debug)]
pub struct ReservoirLayout {
    k: usize,
    slots: usize,
}

impl ReservoirLayout {
    /// The layout of `k` samples a pixel (at least one slot).
    #[must_use]
    pub fn new(k: usize) -> Self {
        Self { k, slots: k.max(1) }
    }

    /// The k reservoirs of pixel `x` of a row (or of pixel `x` counted from the first pixel
    /// of a group of rows) from [`ShadowReservoirs::groups_mut`].
    #[inline]
    #[must_use]
    pub fn pixel_mut<'a>(
        &self,
        row: &'a mut [Reservoir<ShadowSample>],
        x: usize,
    ) -> &'a mut [Reservoir<ShadowSample>] {
        &mut row[x * self.slots..x * self.slots + self.k]
    }
}

/// Two uniform numbers in (0, 1) from the halves of 32 random bits (16 bits each: ample for
/// a jitter or a reservoir decision, and half the generator calls of the hot loop).
#[inline]
#[must_use]
pub fn halves(x: u32) -> Vec2 {
    Vec2::new(
        ((x & 0xffff) as f32 + 0.5) / 65536.0,
        ((x >> 16) as f32 + 0.5) / 65536.0,
    )
}

/// Offers a sample with weight `lum` to every reservoir of a pixel (Appendix A), with
/// replacement thresholds ([`Reservoir::update_jump`]): random numbers from `rng` are drawn,
/// and `sample` is called, only when a reservoir takes it, not for every light.
#[inline]
pub fn offer(
    res: &mut [Reservoir<ShadowSample>],
    sample: impl Fn() -> ShadowSample,
    lum: f32,
    rng: &mut Rng,
) {
    for r in res {
        r.update_jump(&sample, lum, || rng.next_f32());
    }
}

/// Passes over lights of total weight `sum` that no reservoir of the pixel would take: if
/// adding `sum` leaves every reservoir's total below its replacement threshold
/// ([`Reservoir::update_jump`]), the totals grow by `sum` and true is returned; otherwise
/// nothing changes and the lights must be offered one by one with [`offer`]. Taking a run
/// of lights at once is the same decision as offering them in turn, up to the rounding of
/// the total.
#[inline]
pub fn pass_over(res: &mut [Reservoir<ShadowSample>], sum: f32) -> bool {
    if !(sum >= 0.0 && sum.is_finite()) {
        return false;
    }
    if res.iter().any(|r| r.total + sum >= r.threshold) {
        return false;
    }
    for r in res {
        r.total += sum;
    }
    true
}

/// Selects `k` lights of a pixel in proportion to their weights f_j by inverting the
/// cumulative weight with stratified numbers: sample i takes the light where the running
/// total reaches t_i = (i + u_i) / k * F, u_i = `u(i)` uniform in [0, 1) (independent
/// numbers, or the screen's dithered strata of [`crate::shading::strata`]), F = sum of
/// f_j. The lights come in
/// chunks of `N`: `chunk_weights[c]` is the sum of chunk c's weights (in any order), and
/// `lanes(c)` gives chunk c's lights' weights (kept by the loop, or evaluated again) and a payload for
/// `take(i, lane, &payload, f_j, F)`, called once per sample in order of i.
///
/// Each sample alone is the draw of Appendix A (LGH 2019): light j with probability
/// f_j / F, the distribution of one of the paper's streaming reservoirs. Jointly the k
/// samples are stratified over the cumulative weight instead of independent, so that they
/// spread over the pixel's lights (fewer repeats of one bright light; docs/design.md,
/// "Stratified selection"). The cost is one pass over the chunk sums and one evaluation of
/// at most k chunks, instead of k reservoir updates for every light the streaming
/// selection cannot pass over.
pub fn stratified_picks<const N: usize, V>(
    chunk_weights: &[f32],
    mut lanes: impl FnMut(usize) -> ([f32; N], V),
    k: usize,
    mut u: impl FnMut(usize) -> f32,
    mut take: impl FnMut(usize, usize, &V, f32, f32),
) {
    let total: f32 = chunk_weights.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return;
    }
    let Some(last) = chunk_weights.iter().rposition(|&w| w > 0.0) else {
        return;
    };
    // `below` is the sum of the chunks before chunk `c`, in the order `total` was summed.
    let (mut c, mut below) = (0, 0.0f32);
    let mut cached: Option<(usize, [f32; N], V)> = None;
    for i in 0..k {
        let t = (i as f32 + u(i)) / k as f32 * total;
        while c < last && below + chunk_weights[c] <= t {
            below += chunk_weights[c];
            c += 1;
        }
        if cached.as_ref().is_none_or(|(at, ..)| *at != c) {
            let (w, v) = lanes(c);
            cached = Some((c, w, v));
        }
        let Some((_, w, v)) = &cached else { return };
        // The lane where the running total passes t; the last positive lane if rounding
        // leaves t beyond the chunk's sum.
        let (mut acc, mut pick) = (below, None);
        for (l, &f) in w.iter().enumerate() {
            if f > 0.0 {
                pick = Some(l);
                acc += f;
                if acc > t {
                    break;
                }
            }
        }
        if let Some(l) = pick {
            take(i, l, v, w[l], total);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::strata::ScreenStrata;

    /// Chi-square statistic of `counts` against expected shares `p` (which sum to 1) of
    /// `n` draws, over the entries with p > 0; and whether an entry with p = 0 was drawn.
    fn chi_square(counts: &[u32], p: &[f64], n: u32) -> (f64, bool) {
        let mut chi = 0.0;
        let mut impossible = false;
        for (&c, &pj) in counts.iter().zip(p) {
            if pj > 0.0 {
                let e = pj * f64::from(n);
                chi += (f64::from(c) - e).powi(2) / e;
            } else {
                impossible |= c > 0;
            }
        }
        (chi, impossible)
    }

    /// Every sample of [`stratified_picks`] alone draws light j with probability f_j / F:
    /// 23 lights in chunks of 4 (zeros, a zero chunk, weights over two decades), k = 1, 3
    /// and 4, 100,000 pixels (and k = 3 and 4 for one pixel's dithered strata over 100,000
    /// frames, `crate::shading::strata`); chi-square per sample below the 0.999 quantile for its 17
    /// degrees of freedom (40.8), never a light of weight 0. And sample i lies in stratum i:
    /// its light's cumulative interval meets [i F / k, (i + 1) F / k].
    #[test]
    fn each_stratified_pick_is_drawn_in_proportion_to_its_weight() {
        const N: usize = 4;
        let f: Vec<f32> = vec![
            0.0, 2.0, 0.5, 0.0, /**/ 0.0, 0.0, 0.0, 0.0, /**/ 4.0, 1.0, 3.0,
            0.25, /**/
            0.05, 0.0, 7.0, 0.1, /**/ 1.5, 0.3, 0.0, 2.5, /**/ 0.7, 0.2, 0.04,
        ];
        let lanes = |c: usize| {
            let mut w = [0.0f32; N];
            for (l, x) in w.iter_mut().enumerate() {
                *x = f.get(c * N + l).copied().unwrap_or(0.0);
            }
            (w, c)
        };
        let chunks: Vec<f32> = (0..f.len().div_ceil(N))
            .map(|c| lanes(c).0.iter().sum())
            .collect();
        let sum: f64 = f.iter().map(|&x| f64::from(x)).sum();
        let p: Vec<f64> = f.iter().map(|&x| f64::from(x) / sum).collect();
        let cdf: Vec<f64> = p
            .iter()
            .scan(0.0, |a, &x| {
                *a += x;
                Some(*a)
            })
            .collect();
        let n = 100_000u32;
        // Independent offsets, and one pixel's dithered strata over n frames.
        for (k, dithered) in [
            (1usize, false),
            (3, false),
            (4, false),
            (3, true),
            (4, true),
        ] {
            let mut counts = vec![vec![0u32; f.len()]; k];
            let mut rng = Rng::new(&[k as u64, 99]);
            for frame in 0..n {
                let mut seen = 0;
                let strata = ScreenStrata::new(u64::from(frame), 2).pixel(37, 11);
                let mut u = |i| {
                    if dithered {
                        strata.u(i)
                    } else {
                        rng.next_f32()
                    }
                };
                stratified_picks(&chunks, lanes, k, &mut u, |i, l, &c, w, total| {
                    let j = c * N + l;
                    assert_eq!(i, seen, "samples in order");
                    seen += 1;
                    assert_eq!(w, f[j]);
                    assert!((f64::from(total) - sum).abs() < 1e-5 * sum);
                    let (lo, hi) = (cdf[j] - p[j], cdf[j]);
                    let (s0, s1) = (i as f64 / k as f64, (i + 1) as f64 / k as f64);
                    assert!(
                        lo <= s1 + 1e-6 && hi >= s0 - 1e-6,
                        "light {j} outside stratum {i}"
                    );
                    counts[i][j] += 1;
                });
                assert_eq!(seen, k);
            }
            for (i, c) in counts.iter().enumerate() {
                // Sample i is uniform over its stratum: light j's share of stratum i.
                let (s0, s1) = (i as f64 / k as f64, (i + 1) as f64 / k as f64);
                let q: Vec<f64> = cdf
                    .iter()
                    .zip(&p)
                    .map(|(&hi, &pj)| ((hi.min(s1) - (hi - pj).max(s0)).max(0.0)) * k as f64)
                    .collect();
                let (chi, impossible) = chi_square(c, &q, n);
                let dof = q.iter().filter(|&&x| x > 0.0).count();
                assert!(
                    !impossible,
                    "k = {k}, sample {i}: a light of weight 0 drawn"
                );
                assert!(
                    chi < 40.8,
                    "k = {k}, sample {i}: chi-square {chi} over {dof} lights"
                );
            }
            // Over the k samples, each light's count is k n f_j / F.
            let all: Vec<u32> = (0..f.len())
                .map(|j| counts.iter().map(|c| c[j]).sum())
                .collect();
            let (chi, _) = chi_square(&all, &p, n * k as u32);
            assert!(chi < 40.8, "k = {k}: chi-square {chi} over all samples");
        }
    }

    /// Nothing is drawn when every weight is zero or the total is not finite.
    #[test]
    fn stratified_picks_draw_nothing_without_weight() {
        let mut rng = Rng::new(&[1]);
        for chunks in [
            vec![0.0f32; 3],
            vec![],
            vec![1.0, f32::INFINITY],
            vec![f32::NAN],
        ] {
            stratified_picks(
                &chunks,
                |_| ([1.0f32; 2], ()),
                4,
                |_| rng.next_f32(),
                |_, _, _, _, _| panic!("nothing to draw from {chunks:?}"),
            );
        }
    }

    /// Offering a stream of lights in chunks of 8, each chunk passed over at once where
    /// [`pass_over`] allows and offered light by light otherwise, makes the same selections as
    /// offering every light in turn with the same random numbers (a replacement draws a
    /// number only when it happens, so both consume the stream alike): 4 reservoirs, 2,000
    /// pixels of 200 lights with weights over three decades. Allowed: a differing selection
    /// in at most 0.1% of the reservoirs, where the rounding of a chunk's sum crosses a
    /// threshold the one-by-one total does not.
    #[test]
    fn passing_chunks_over_selects_as_offering_each_light() {
        let sample = |j: u32| ShadowSample {
            light: j,
            ..ShadowSample::default()
        };
        let (mut differ, mut total) = (0, 0);
        for pixel in 0..2000u64 {
            let mut weights = Rng::new(&[77, pixel]);
            let f: Vec<f32> = (0..200)
                .map(|_| 10f32.powf(3.0 * weights.next_f32() - 3.0))
                .collect();
            let (mut each, mut chunked) = ([Reservoir::new(); 4], [Reservoir::new(); 4]);
            let (mut rng_a, mut rng_b) = (Rng::new(&[5, pixel]), Rng::new(&[5, pixel]));
            for (j, &fj) in f.iter().enumerate() {
                offer(&mut each, || sample(j as u32), fj, &mut rng_a);
            }
            for (c, chunk) in f.chunks(8).enumerate() {
                if pass_over(&mut chunked, chunk.iter().sum()) {
                    continue;
                }
                for (l, &fj) in chunk.iter().enumerate() {
                    let j = (c * 8 + l) as u32;
                    offer(&mut chunked, || sample(j), fj, &mut rng_b);
                }
            }
            for (a, b) in each.iter().zip(&chunked) {
                total += 1;
                let (a, b) = (a.sample.map(|s| s.light), b.sample.map(|s| s.light));
                assert!(a.is_some() && b.is_some());
                differ += usize::from(a != b);
            }
        }
        assert!(
            differ * 1000 <= total,
            "{differ} of {total} selections differ"
        );
    }
}
