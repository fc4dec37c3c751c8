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

    /// The held rows, mutable and in parallel, each with its image row index; see
    /// [`ReservoirLayout::pixel_mut`].
    pub fn rows_mut(
        &mut self,
    ) -> impl IndexedParallelIterator<Item = (usize, &mut [Reservoir<ShadowSample>])> {
        let first = self.first_row;
        self.data
            .par_chunks_mut(self.width * self.slots)
            .enumerate()
            .map(move |(r, row)| (first + r, row))
    }

    /// Where a pixel's reservoirs lie in a row from [`ShadowReservoirs::rows_mut`].
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

    /// The k reservoirs of pixel `x` of a row from [`ShadowReservoirs::rows_mut`].
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

#[cfg(test)]
mod tests {
    use super::*;

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
