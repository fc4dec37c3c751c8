//! Pixels whose recombination window misses sub-images shade them themselves (an extension
//! of the interleaved sampling of LGH 2019 section 4.3; docs/design.md, "Interleaved
//! sampling", "Filling cut windows").
//!
//! The unshadowed sum A is recombined over the n x n window around a pixel
//! ([`BlurParams::recombination`]): each of the n^2 sub-images holds 1/n^2 of the lights,
//! and the window averages their estimates phase by phase. On thin or folded geometry (a
//! chair leg one pixel wide, a column's curve) the window's walks stop at the edges and
//! reach only a few sub-images, whose estimates of A, each n^2 times a subset of the
//! lights, differ by a factor of 2 or more from each other: the window is a poor estimate
//! there, and under 4 x 4 interleaving such pixels held two thirds of `lgh`'s squared error
//! on Sponza.
//!
//! Such a pixel shades the sub-images its window misses during the lighting loop (their
//! light batches are at hand, one tile at a time), and its A becomes
//!
//! A(x) = (sum over the reached sub-images s of m_s + sum over the missed s of A_s(x)) / n^2,
//!
//! m_s the Gaussian-weighted mean of sub-image s's values over the window's taps (as the
//! recombination weighs them), A_s(x) the missed sub-image's lights (times n^2) evaluated at
//! the pixel itself. Every light thus counts once, as in a complete window.

use glam::Vec3;
use rayon::prelude::*;

use super::{BlurParams, runs, sub_image_of};
use crate::passes::gbuffer::GBuffer;

/// The default of [`crate::methods::lgh::LghSettings::fill_below`]: a pixel whose window
/// reaches fewer than 0.3 n^2 sub-images (at most 4 of 16 under 4 x 4 interleaving, 1 of 4
/// under 2 x 2) fills the others (docs/design.md, "Filling cut windows").
pub const DEFAULT_FILL_BELOW: f32 = 0.3;

/// The most sub-images the masks hold (n <= 8).
const MAX_SUB_IMAGES: usize = 64;

/// The walks of the recombination window of every pixel: per axis the steps forwards and
/// backwards (x: right, left; y: down, up), as the blur takes them.
struct Walks {
    right: Vec<u8>,
    left: Vec<u8>,
    down: Vec<u8>,
    up: Vec<u8>,
}

impl Walks {
    fn new(g: &GBuffer, disc: &[u8], p: &BlurParams) -> Self {
        let r = p.radius as usize;
        let (bit_x, bit_y) = p.jump_bits();
        let (right, left) = runs(g, disc, r, bit_x, false);
        let (down, up) = runs(g, disc, r, bit_y, true);
        Self {
            right,
            left,
            down,
            up,
        }
    }

    /// Whether pixel `i`'s window spans n rows, each n pixels wide: it reaches every
    /// sub-image (most pixels; no bits needed).
    fn full(&self, i: usize, w: usize, n: usize) -> bool {
        let wide = |f: u8, b: u8| usize::from(f) + usize::from(b) + 1 >= n;
        wide(self.down[i], self.up[i])
            && (-isize::from(self.up[i])..=isize::from(self.down[i])).all(|dy| {
                let j = (i as isize + dy * w as isize) as usize;
                wide(self.right[j], self.left[j])
            })
    }

    /// The taps of pixel `i`'s window as the separable blur visits them: down its column
    /// to each row it reaches, then along that row. Calls `f(tap, dx, dy)`.
    fn taps(&self, i: usize, w: usize, mut f: impl FnMut(usize, isize, isize)) {
        for dy in -isize::from(self.up[i])..=isize::from(self.down[i]) {
            let j = (i as isize + dy * w as isize) as usize;
            for dx in -isize::from(self.left[j])..=isize::from(self.right[j]) {
                f((j as isize + dx) as usize, dx, dy);
            }
        }
    }
}

/// The sub-image of pixel `i` of an image `w` pixels wide ([`sub_image_of`]).
#[inline]
fn sub_image(i: usize, w: usize, n: usize) -> usize {
    sub_image_of((i % w) as u32, (i / w) as u32, n as u32)
}

/// Per pixel, the sub-images its recombination window misses (bit s = sy n + sx), where it
/// reaches fewer than `below` n^2 of them; zero elsewhere (and where the pixel sees nothing).
/// `p` is the recombination's blur ([`BlurParams::recombination`]), `disc` the G-buffer's
/// jumps ([`super::discontinuities`]). `None` where no pixel misses any (or n is 1, or n^2
/// is more than the 64 bits hold).
#[must_use]
pub fn missed_sub_images(g: &GBuffer, disc: &[u8], p: &BlurParams, below: f32) -> Option<Vec<u64>> {
    let n = p.phases as usize;
    if n <= 1 || n * n > MAX_SUB_IMAGES || below <= 0.0 {
        return None;
    }
    let w = g.width as usize;
    let all = u64::MAX >> (MAX_SUB_IMAGES - n * n);
    let limit = below * (n * n) as f32;
    let walks = Walks::new(g, disc, p);
    let missed: Vec<u64> = (0..g.len())
        .into_par_iter()
        .map(|i| {
            if !g.is_hit(i) || walks.full(i, w, n) {
                return 0;
            }
            let mut reached = 0u64;
            walks.taps(i, w, |j, _, _| reached |= 1 << sub_image(j, w, n));
            if (reached.count_ones() as f32) < limit {
                all & !reached
            } else {
                0
            }
        })
        .collect();
    missed.iter().any(|&m| m != 0).then_some(missed)
}

/// A of the pixels that fill their window ([`missed_sub_images`] non-zero): the reached
/// sub-images' Gaussian-weighted means of `raw` (the loop's A, before the recombination)
/// over the window, plus `filled` (the missed sub-images' lights at the pixel, each times
/// n^2), over n^2; written into `a` (the recombined A), other pixels left as they are.
pub fn recombine_filled(
    a: &mut [Vec3],
    raw: &[Vec3],
    filled: &[Vec3],
    missed: &[u64],
    g: &GBuffer,
    disc: &[u8],
    p: &BlurParams,
) {
    let n = p.phases as usize;
    let w = g.width as usize;
    let n2 = (n * n) as f32;
    let weight = |d: isize| (-((d * d) as f32) / (2.0 * p.sigma * p.sigma)).exp();
    let walks = Walks::new(g, disc, p);
    a.par_iter_mut().enumerate().for_each(|(i, out)| {
        if missed[i] == 0 {
            return;
        }
        let mut sum = [Vec3::ZERO; MAX_SUB_IMAGES];
        let mut wsum = [0.0f32; MAX_SUB_IMAGES];
        walks.taps(i, w, |j, dx, dy| {
            let s = sub_image(j, w, n);
            let wt = weight(dx) * weight(dy);
            sum[s] += raw[j] * wt;
            wsum[s] += wt;
        });
        let mut total = filled[i];
        for (s, v) in sum.iter().enumerate().take(n * n) {
            if wsum[s] > 0.0 {
                total += *v / wsum[s];
            }
        }
        *out = total / n2;
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::interleave::{discontinuities, sub_image_of};

    /// A wall at depth 3 facing the camera with a pole one pixel wide in front of it
    /// (column `pole`, depth 1, its visible side facing +x: a one-pixel pole has no depth
    /// slope of its own, so the normals tell it from the wall).
    fn pole(w: u32, h: u32, pole: u32) -> GBuffer {
        let n = (w * h) as usize;
        let depth: Vec<f32> = (0..n)
            .map(|i| if i as u32 % w == pole { 1.0 } else { 3.0 })
            .collect();
        let position = (0..n)
            .map(|i| Vec3::new((i as u32 % w) as f32, (i as u32 / w) as f32, -depth[i]))
            .collect();
        let normal: Vec<Vec3> = (0..n)
            .map(|i| {
                if i as u32 % w == pole {
                    Vec3::X
                } else {
                    Vec3::Z
                }
            })
            .collect();
        GBuffer::from_planes((w, h), position, normal, depth)
    }

    /// Under 4 x 4 interleaving the pole's pixels reach only the 4 sub-images of their
    /// column and fill the other 12; the wall's pixels beside it still reach 12 of 16 and
    /// fill none. With sub-image s holding n^2 v_s everywhere (the loop's A of a light set
    /// split into 16 parts v_s), the pole's recombined A is then exactly the sum of all v_s,
    /// where the plain recombination gives 4 times its own column's four.
    #[test]
    fn a_pole_one_pixel_wide_fills_the_sub_images_it_misses() {
        let (w, h, x_pole, n) = (24u32, 16u32, 9u32, 4u32);
        let g = pole(w, h, x_pole);
        let p = BlurParams::defaults().with_phases(n).recombination();
        let disc = discontinuities(&g, &p);
        let missed = missed_sub_images(&g, &disc, &p, DEFAULT_FILL_BELOW).unwrap();
        let column: u64 = (0..n).map(|sy| 1u64 << (sy * n + x_pole % n)).sum();
        for y in 0..h {
            for x in 0..w {
                let m = missed[(y * w + x) as usize];
                if x != x_pole {
                    assert_eq!(m, 0, "({x}, {y})");
                } else if (2..h - 2).contains(&y) {
                    assert_eq!(m, 0xffff & !column, "({x}, {y})");
                } else {
                    // The border cuts the column's walk too.
                    assert_eq!(m & !column, 0xffff & !column, "({x}, {y})");
                }
            }
        }
        let n2 = (n * n) as f32;
        let v = |s: usize| 1.0 + 0.37 * s as f32;
        let raw: Vec<Vec3> = (0..(w * h) as usize)
            .map(|i| Vec3::splat(n2 * v(sub_image_of(i as u32 % w, i as u32 / w, n))))
            .collect();
        let filled: Vec<Vec3> = missed
            .iter()
            .map(|&m| {
                let total: f32 = (0..16).filter(|s| m >> s & 1 == 1).map(v).sum();
                Vec3::splat(n2 * total)
            })
            .collect();
        let total: f32 = (0..16).map(v).sum();
        let [plain] = super::super::blur_n([raw.clone()], &g, &disc, &p);
        let mut a = plain.clone();
        recombine_filled(&mut a, &raw, &filled, &missed, &g, &disc, &p);
        for y in 0..h {
            let i = (y * w + x_pole) as usize;
            assert!(
                (a[i].x - total).abs() < 1e-5 * total,
                "row {y}: {} vs {total}",
                a[i].x
            );
            if (2..h - 2).contains(&y) {
                let own: f32 = (0..n as usize).map(|sy| v(sy * n as usize + 1)).sum();
                assert!(
                    (plain[i].x - 4.0 * own).abs() < 1e-4 * total,
                    "{}",
                    plain[i].x
                );
            }
        }
        // Elsewhere the recombination is left as it was.
        for (i, (&x, &y)) in a.iter().zip(&plain).enumerate() {
            if missed[i] == 0 {
                assert_eq!(x, y);
            }
        }
        // Off: no masks.
        assert!(missed_sub_images(&g, &disc, &p, 0.0).is_none());
    }
}
