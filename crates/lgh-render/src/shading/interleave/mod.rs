//! Interleaved sampling (Keller & Heidrich 2001; Segovia et al. 2006), shared by the tiled
//! methods: LGH 2019 section 4.3 (2 x 2, 4 x 4) and stochastic light culling 2016 section 4.2
//! (8 x 8).
//!
//! With n x n interleaving, pixel (x, y) belongs to sub-image (x mod n, y mod n), where it
//! stands at (x div n, y div n); each sub-image is shaded with its own 1/n^2 of the lights,
//! whose intensities are scaled by n^2. Lights are dealt in order (light k to sub-image
//! k mod n^2). Afterwards the images are blurred with a discontinuity-aware filter, which
//! recombines the sub-images' estimates: the unshadowed sum over exactly the n x n
//! neighbourhood ([`BlurParams::recombination`]), the shadow estimates over 17 x 17 pixels,
//! gathering their samples.
//!
//! The shading passes do not copy the G-buffer into sub-images: a sub-image is a [`Lattice`]
//! of the full-resolution buffers (every n-th pixel from an offset), and its screen tiles are
//! n times wider in full-resolution pixels ([`crate::shading::tiles::TileBins::build_lattice`]). That
//! is the same computation as shading a swizzled sub-buffer, without the two copies.
//! [`split`] and [`merge`] are the explicit swizzle, for code that wants packed sub-images.

use glam::Vec3;
use rayon::prelude::*;

mod fill;
pub use fill::{DEFAULT_FILL_BELOW, missed_sub_images, recombine_filled};

use crate::denoise::atrous::unshadowed_key;
use crate::passes::gbuffer::GBuffer;
use crate::passes::par_filled;

/// One sub-image of n x n interleaving: the pixels (x, y) with x mod n = `sx` and
/// y mod n = `sy`. `n = 1` is the whole image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lattice {
    /// Interleaving factor n.
    pub n: u32,
    /// Column offset, 0..n.
    pub sx: u32,
    /// Row offset, 0..n.
    pub sy: u32,
}

impl Lattice {
    /// The whole image (no interleaving).
    pub const FULL: Self = Self { n: 1, sx: 0, sy: 0 };

    /// The n^2 sub-images of n x n interleaving, sub-image s = sy n + sx.
    #[must_use]
    pub fn all(n: u32) -> Vec<Self> {
        let n = n.max(1);
        (0..n * n)
            .map(|s| Self {
                n,
                sx: s % n,
                sy: s / n,
            })
            .collect()
    }

    /// True if pixel (x, y) belongs to this sub-image.
    #[inline]
    #[must_use]
    pub fn contains(&self, x: u32, y: u32) -> bool {
        x % self.n == self.sx && y % self.n == self.sy
    }
}

/// Index of the sub-image of pixel (x, y): (y mod n) n + (x mod n).
#[inline]
#[must_use]
pub fn sub_image_of(x: u32, y: u32, n: u32) -> usize {
    ((y % n) * n + x % n) as usize
}

/// Size of sub-image (sx, sy) of a `width` x `height` image.
#[must_use]
pub fn sub_image_size(width: u32, height: u32, n: u32, sx: u32, sy: u32) -> (u32, u32) {
    let len = |total: u32, offset: u32| {
        if offset >= total {
            0
        } else {
            (total - offset).div_ceil(n)
        }
    };
    (len(width, sx), len(height, sy))
}

/// Splits a row-major image into its n^2 packed sub-images (sub-image s = sy n + sx, row-major
/// in (x div n, y div n)).
#[must_use]
pub fn split<T: Copy>(data: &[T], width: u32, height: u32, n: u32) -> Vec<Vec<T>> {
    let n = n.max(1);
    Lattice::all(n)
        .iter()
        .map(|l| {
            let (w, h) = sub_image_size(width, height, n, l.sx, l.sy);
            let mut out = Vec::with_capacity((w * h) as usize);
            for v in 0..h {
                for u in 0..w {
                    let (x, y) = (u * n + l.sx, v * n + l.sy);
                    out.push(data[(y * width + x) as usize]);
                }
            }
            out
        })
        .collect()
}

/// The inverse of [`split`]: re-interleaves packed sub-images into one row-major image.
/// `fill` is used where a sub-image is missing or too short (never for [`split`]'s output).
#[must_use]
pub fn merge<T: Copy>(subs: &[Vec<T>], width: u32, height: u32, n: u32, fill: T) -> Vec<T> {
    let n = n.max(1);
    let mut out = vec![fill; width as usize * height as usize];
    for (s, sub) in subs.iter().enumerate() {
        let (sx, sy) = (s as u32 % n, s as u32 / n);
        let (w, _) = sub_image_size(width, height, n, sx, sy);
        for (k, &v) in sub.iter().enumerate() {
            let (u, vv) = (k as u32 % w.max(1), k as u32 / w.max(1));
            let (x, y) = (u * n + sx, vv * n + sy);
            if x < width && y < height {
                out[(y * width + x) as usize] = v;
            }
        }
    }
    out
}

/// Parameters of the discontinuity-aware blur (from the LGH demo; docs/design.md,
/// "Interleaved sampling").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlurParams {
    /// Taps on each side (8: a 17-tap kernel, the size Tokuyoshi & Harada use for 8 x 8).
    pub radius: u32,
    /// Gaussian standard deviation in pixels.
    pub sigma: f32,
    /// Depth discontinuity: |dz| / max(|depth gradient|, [`SLOPE_FLOOR`] x depth) above this
    /// (linear depth).
    pub z_diff: f32,
    /// Normal discontinuity: 1 - n . n' above this.
    pub n_diff: f32,
    /// The interleaving n the blur recombines: a walk that a discontinuity cuts short is
    /// averaged phase by phase (taps at offsets k with the same k mod n come from the same
    /// sub-image), so that every sub-image counts equally; 1 for a plain blur.
    pub phases: u32,
    /// Change of the unshadowed sum A: where the blur is given A ([`Stop::SmoothedA`]: its
    /// key ln lum A, A smoothed by this blur's own walks; [`blur_n_stopped`]), a walk stops
    /// before a pixel whose key differs from its centre's by more than this (0: no such
    /// stop). The shadow estimates S and U are summed, so a tap weighs by its U: without the
    /// stop, near a room's corner, where A climbs steeply, the taps of the open wall set the
    /// corner's ratio (docs/design.md, "Interleaved sampling").
    pub a_diff: f32,
    /// Normal discontinuity of the recombination of A: 1 - n . n' above this (at most
    /// `n_diff`). The unshadowed sum follows the normal closely (a cosine), so at a crease
    /// of 20-60 degrees, which `n_diff` lets the wide blur of S and U cross, the
    /// recombination would average two faces' light (docs/design.md, "Interleaved
    /// sampling").
    pub a_n_diff: f32,
    /// Walk to the jumps of [`BlurParams::a_n_diff`] ([`JUMP_X_A`], [`JUMP_Y_A`]) instead of
    /// those of `n_diff`: the recombination of A ([`BlurParams::recombination`]).
    pub creases: bool,
}

impl BlurParams {
    /// The demo's defaults: radius 8, sigma 3, ZDiff 8, NDiff 0.5.
    #[must_use]
    pub fn defaults() -> Self {
        Self {
            radius: 8,
            sigma: 3.0,
            z_diff: 8.0,
            n_diff: 0.5,
            phases: 1,
            a_diff: 0.05,
            a_n_diff: 0.05,
            creases: false,
        }
    }

    /// This blur for n x n interleaving: walks averaged over n phases.
    #[must_use]
    pub fn with_phases(self, n: u32) -> Self {
        Self { phases: n, ..self }
    }

    /// The narrowest blur that recombines the sub-images, for the unshadowed sum A: radius
    /// n / 2 (at least 1), whose phase-balanced weights give each of the n x n sub-images
    /// the same weight 1 / n^2 (at n = 4 the taps weigh (1/2, 1, 1, 1, 1/2) / 4 per axis).
    /// Every light then counts once, evaluated at the pixel of its own sub-image within the
    /// n x n window, and the image keeps its detail below the wide blur's 17 pixels
    /// (docs/design.md, "Interleaved sampling"). A itself is blurred without the stop on A,
    /// and its walks stop at the creases of [`BlurParams::a_n_diff`] as well.
    #[must_use]
    pub fn recombination(&self) -> Self {
        Self {
            radius: (self.phases / 2).max(1),
            a_diff: 0.0,
            creases: true,
            ..*self
        }
    }

    /// The normal threshold of the crease bits: [`BlurParams::a_n_diff`], at most `n_diff`
    /// (a jump for the wide blur is one for A's recombination too).
    #[must_use]
    pub fn crease_n_diff(&self) -> f32 {
        self.a_n_diff.min(self.n_diff)
    }

    /// The jump bits along x and y that this blur's walks stop at.
    fn jump_bits(&self) -> (u8, u8) {
        if self.creases {
            (JUMP_X_A, JUMP_Y_A)
        } else {
            (JUMP_X, JUMP_Y)
        }
    }
}

/// The least depth slope of the discontinuity test, relative to the pixel's depth (the
/// slope of a surface seen face-on is zero but for rounding). Relative, so that a scene finds
/// the same jumps in any units: an absolute 1e-4 hid real jumps in a scene in kilometres,
/// and in one in millimetres let rounding steps of a face-on wall's depth (two ulps of
/// 5,000) read as jumps (2e-5 x a depth of 5 is that 1e-4).
pub const SLOPE_FLOOR: f32 = 2e-5;

/// A jump between a pixel and its neighbour at (1, 0) ([`JUMP_X`]) and at (0, 1)
/// ([`JUMP_Y`]), one bit each per pixel: the depth jumps by more than `z_diff` times the local
/// depth gradient, or the normals differ by more than `n_diff` in 1 - n . n', or exactly one
/// of the two sees a surface; and the same with [`BlurParams::crease_n_diff`] for the
/// normals ([`JUMP_X_A`], [`JUMP_Y_A`], the recombination of A). Kept per axis, so that a
/// walk along an edge (between pixels on the same side) is not stopped by the jump across
/// it: a pixel on a vertical edge still blurs up and down, and every sub-image of the
/// interleaving reaches it (docs/design.md, "Interleaved sampling").
#[must_use]
pub fn discontinuities(g: &GBuffer, p: &BlurParams) -> Vec<u8> {
    let (w, h) = (g.width as usize, g.height as usize);
    let crease_n_diff = p.crease_n_diff();
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let hit = g.is_hit(i);
            // Local depth slope per axis: the smaller one-sided difference, which at an edge
            // is the one on this pixel's own surface (a screen-space derivative would
            // straddle the edge). The test scale is the larger of the two axes' slopes.
            let slope = |a: Option<usize>, b: Option<usize>| {
                [a, b]
                    .into_iter()
                    .flatten()
                    .filter(|&j| g.is_hit(j))
                    .map(|j| (g.depth[j] - g.depth[i]).abs())
                    .fold(f32::INFINITY, f32::min)
            };
            let scale = if hit {
                let gx = slope((x > 0).then(|| i - 1), (x + 1 < w).then_some(i + 1));
                let gy = slope((y > 0).then(|| i - w), (y + 1 < h).then_some(i + w));
                let finite = |v: f32| if v.is_finite() { v } else { 0.0 };
                finite(gx).max(finite(gy)).max(SLOPE_FLOOR * g.depth[i])
            } else {
                1.0
            };
            // The bits of the pair (i, j): [`JUMP_X`] or [`JUMP_Y`] (`wide`), and `crease`.
            let jump = |j: usize, wide: u8, crease: u8| {
                if hit != g.is_hit(j) {
                    return wide | crease;
                }
                if !hit {
                    return 0;
                }
                let dz = (g.depth[j] - g.depth[i]).abs() / scale;
                let dn = 1.0 - g.normal[i].dot(g.normal[j]);
                if dz > p.z_diff || dn > p.n_diff {
                    wide | crease
                } else if dn > crease_n_diff {
                    crease
                } else {
                    0
                }
            };
            let mut flags = 0;
            if x + 1 < w {
                flags |= jump(i + 1, JUMP_X, JUMP_X_A);
            }
            if y + 1 < h {
                flags |= jump(i + w, JUMP_Y, JUMP_Y_A);
            }
            flags
        })
        .collect()
}

/// Shortens the walks `[right, left, down, up]` of an image `w` pixels wide so that each
/// stops before the first pixel whose key differs from its centre's by more than `limit`.
fn stop_at_keys(keys: &[f32], w: usize, limit: f32, walks: [&mut [u8]; 4]) {
    let strides = [1, -1, w as isize, -(w as isize)];
    for (walk, stride) in walks.into_iter().zip(strides) {
        walk.par_iter_mut().enumerate().for_each(|(i, run)| {
            let centre = keys[i];
            let mut k = 0u8;
            while k < *run {
                let j = (i as isize + (isize::from(k) + 1) * stride) as usize;
                if (keys[j] - centre).abs() > limit {
                    break;
                }
                k += 1;
            }
            *run = k;
        });
    }
}

/// [`discontinuities`] bit: a jump to the neighbour at (1, 0).
pub const JUMP_X: u8 = 1;
/// [`discontinuities`] bit: a jump to the neighbour at (0, 1).
pub const JUMP_Y: u8 = 2;
/// [`discontinuities`] bit: a jump to the neighbour at (1, 0) for the recombination of A
/// (normals compared with [`BlurParams::crease_n_diff`]).
pub const JUMP_X_A: u8 = 4;
/// [`discontinuities`] bit: a jump to the neighbour at (0, 1) for the recombination of A.
pub const JUMP_Y_A: u8 = 8;

/// Separable Gaussian blur that walks outwards from each pixel and stops before the first
/// jump along its axis ([`discontinuities`]; the pixel itself always counts); weights are
/// renormalised over the taps used. Pixels that see nothing are left as they are.
#[must_use]
pub fn blur(img: &[Vec3], g: &GBuffer, disc: &[u8], p: &BlurParams) -> Vec<Vec3> {
    let [out] = blur_n([img.to_vec()], g, disc, p);
    out
}

/// [`blur`] of `N` images of the same G-buffer, in place: the walks are found once for all
/// of them (`runs`), and one scratch image serves every pass.
#[must_use]
pub fn blur_n<const N: usize>(
    imgs: [Vec<Vec3>; N],
    g: &GBuffer,
    disc: &[u8],
    p: &BlurParams,
) -> [Vec<Vec3>; N] {
    blur_n_stopped(imgs, g, disc, p, Stop::None)
}

/// Where the walks of [`blur_n_stopped`] stop besides the jumps ([`BlurParams::a_diff`]).
#[derive(Clone, Copy, Debug)]
pub enum Stop<'a> {
    /// Nowhere else.
    None,
    /// Where the key ln lum A of the recombined unshadowed sum A, smoothed by the blur's own
    /// walks (before this stop), moves from the centre's by more than `a_diff`.
    ///
    /// The keys of A as recombined carry the noise of the sub-images: under 4 x 4
    /// interleaving `lgh`'s differ by more than the stop's 5% from one pixel to the next on
    /// 15% of Sponza's steps (`slc`'s on 11%), so that most walks stopped within a few taps
    /// and S and U were hardly gathered. A corner's climb of A outlasts the smoothing
    /// (docs/design.md, "Interleaved sampling").
    SmoothedA(&'a [Vec3]),
    /// Where these keys (one per pixel) move from the centre's by more than `a_diff`.
    Keys(&'a [f32]),
}

/// [`blur_n`] whose walks also stop where `stop` says.
#[must_use]
pub fn blur_n_stopped<const N: usize>(
    mut imgs: [Vec<Vec3>; N],
    g: &GBuffer,
    disc: &[u8],
    p: &BlurParams,
    stop: Stop<'_>,
) -> [Vec<Vec3>; N] {
    let w = g.width as usize;
    let r = p.radius as usize;
    let weights: Vec<f32> = (0..=r)
        .map(|k| (-((k * k) as f32) / (2.0 * p.sigma * p.sigma)).exp())
        .collect();
    let phases = (p.phases as usize).clamp(1, MAX_PHASES);
    // A full walk covers every phase, but the Gaussian need not weigh them alike (at n = 8,
    // sigma 3, from 0.82 to 1.06: the 8 x 8 pattern of the sub-images shows through). Its
    // weights are divided by their phase's total, so that every sub-image counts equally
    // (at n = 4 they already agree within 0.6%).
    let full_weights: Vec<f32> = if phases > 1 {
        let mut total = vec![0.0f32; phases];
        for (k, &wk) in weights.iter().enumerate() {
            total[k % phases] += wk;
            if k > 0 {
                total[(phases - k % phases) % phases] += wk;
            }
        }
        weights
            .iter()
            .enumerate()
            .map(|(k, &wk)| wk / total[k % phases])
            .collect()
    } else {
        weights.clone()
    };
    let full_sum: f32 = full_weights[0] + 2.0 * full_weights[1..].iter().sum::<f32>();
    let cut = cut_walk_weights(&weights, phases, r);
    // One pass: out[i] = the weighted mean of src over the walk from i (stride `step`).
    let pass = |src: &[Vec3], out: &mut [Vec3], step: usize, fwd: &[u8], back: &[u8]| {
        let flat: &[f32] = bytemuck::cast_slice(src);
        out.par_chunks_mut(w.max(1))
            .enumerate()
            .for_each(|(y, out_row)| {
                let row = y * w;
                // A pixel whose walk is full both ways (most of them) has the same 2r + 1
                // weights as its neighbours: runs of such pixels are one convolution of the
                // row's floats, which vectorises ([`full_runs`]); the others walk alone.
                let full = |x: usize| {
                    let i = row + x;
                    usize::from(fwd[i]) == r && usize::from(back[i]) == r && g.is_hit(i)
                };
                let mut x = 0;
                while x < out_row.len() {
                    if full(x) {
                        let mut end = x + 1;
                        while end < out_row.len() && full(end) {
                            end += 1;
                        }
                        full_runs(
                            flat,
                            bytemuck::cast_slice_mut(&mut out_row[x..end]),
                            3 * (row + x),
                            3 * step,
                            &full_weights,
                            1.0 / full_sum,
                        );
                        x = end;
                        continue;
                    }
                    let i = row + x;
                    out_row[x] = if g.is_hit(i) {
                        let (f, b) = (usize::from(fwd[i]), usize::from(back[i]));
                        let taps = &cut[(f * (r + 1) + b) * (2 * r + 1)..][..2 * r + 1];
                        let mut sum = Vec3::ZERO;
                        for (k, &wk) in taps[r - b..=r + f].iter().enumerate() {
                            sum += src[i + k * step - b * step] * wk;
                        }
                        sum
                    } else {
                        src[i]
                    };
                    x += 1;
                }
            });
    };
    // How far the walk goes from each pixel, per direction: it stops before a step that
    // leaves the image, crosses a jump along its axis, or enters a pixel that sees nothing.
    // Known before the sums, the taps need no tests.
    let (bit_x, bit_y) = p.jump_bits();
    let (mut right, mut left) = runs(g, disc, r, bit_x, false);
    let (mut down, mut up) = runs(g, disc, r, bit_y, true);
    let mut scratch = par_filled(g.len(), Vec3::ZERO);
    let mut blur = |img: &mut Vec<Vec3>, walks: [&[u8]; 4]| {
        pass(img, &mut scratch, 1, walks[0], walks[1]);
        pass(&scratch, img, w, walks[2], walks[3]);
    };
    let stop = match stop {
        Stop::None => None,
        _ if p.a_diff <= 0.0 => None,
        Stop::Keys(keys) => Some(keys.to_vec()),
        Stop::SmoothedA(a) => {
            // A smoothed by the walks themselves, before the stop on it.
            let mut smooth = a.to_vec();
            blur(&mut smooth, [&right, &left, &down, &up]);
            Some(smooth.par_iter().map(|&c| unshadowed_key(c)).collect())
        }
    };
    if let Some(keys) = stop {
        stop_at_keys(
            &keys,
            w,
            p.a_diff,
            [&mut right, &mut left, &mut down, &mut up],
        );
    }
    for img in &mut imgs {
        blur(img, [&right, &left, &down, &up]);
    }
    imgs
}

/// The largest interleaving the phase-balanced walk handles.
const MAX_PHASES: usize = 16;

/// The tap weights of every walk that a discontinuity cut short, `fwd` and `back` in
/// `0..=r`: row (fwd (r + 1) + back) holds the weights of the taps at offsets -r..=r (zero
/// outside -back..=fwd), which sum to one. Each is a fixed mean of the taps, so it is found
/// once per blur, not per pixel.
///
/// With interleaving (`phases` > 1) the walk is averaged phase by phase: the taps at offsets
/// k with the same k mod `phases` come from the same sub-image; each phase's Gaussian-weighted
/// mean counts once, over the phases the walk reaches. A plain weighted mean would let the
/// sub-images near the pixel dominate, and along an edge the pixels would keep their own
/// sub-image's light: a comb of streaks with the period of the interleaving. Without, the
/// weights are the Gaussian's, renormalised over the taps.
fn cut_walk_weights(weights: &[f32], phases: usize, r: usize) -> Vec<f32> {
    let taps = 2 * r + 1;
    let mut table = vec![0.0f32; (r + 1) * (r + 1) * taps];
    for fwd in 0..=r {
        for back in 0..=r {
            let row = &mut table[(fwd * (r + 1) + back) * taps..][..taps];
            let phase = |k: isize| k.rem_euclid(phases as isize) as usize;
            let mut wsum = [0.0f32; MAX_PHASES];
            for k in -(back as isize)..=fwd as isize {
                wsum[phase(k)] += weights[k.unsigned_abs()];
            }
            let reached = wsum.iter().filter(|&&v| v > 0.0).count() as f32;
            for k in -(back as isize)..=fwd as isize {
                row[(k + r as isize) as usize] =
                    weights[k.unsigned_abs()] / wsum[phase(k)] / reached;
            }
        }
    }
    table
}

/// The blur of a run of consecutive pixels whose walks are all full (r steps both ways), on
/// their floats: `out[j] = inv_sum (w_0 src[at + j] + sum_k w_k (src[at + j + k d] +
/// src[at + j - k d]))`, with d = 3 x the pixel stride. Each tap is one pass over the run,
/// which the compiler turns into vector instructions.
fn full_runs(src: &[f32], out: &mut [f32], at: usize, d: usize, weights: &[f32], inv_sum: f32) {
    let len = out.len();
    for (o, &c) in out.iter_mut().zip(&src[at..at + len]) {
        *o = weights[0] * c;
    }
    for (k, &wk) in weights.iter().enumerate().skip(1) {
        let ahead = &src[at + k * d..at + k * d + len];
        let behind = &src[at - k * d..at - k * d + len];
        for ((o, &a), &b) in out.iter_mut().zip(ahead).zip(behind) {
            *o += wk * (a + b);
        }
    }
    for o in out.iter_mut() {
        *o *= inv_sum;
    }
}

/// Image rows per parallel block of the vertical [`runs`] (at least the blur radius).
const VERTICAL_BLOCK_ROWS: usize = 32;

/// Steps of the blur's walk from every pixel along x (`vertical` false) or y, at most `r`:
/// forwards and backwards. A step from i to j = i +- 1 pixel is allowed if j is in the image
/// and sees a surface and the pair has no jump along the axis (`bit` of the pair's first
/// pixel).
/// Each run extends its neighbour's by one step, so one sweep per direction finds them all.
fn runs(g: &GBuffer, disc: &[u8], r: usize, bit: u8, vertical: bool) -> (Vec<u8>, Vec<u8>) {
    let (w, h) = (g.width as usize, g.height as usize);
    let r = r.min(usize::from(u8::MAX)) as u8;
    let (mut fwd, mut back) = (vec![0u8; w * h], vec![0u8; w * h]);
    let step = |from: usize, to: usize, from_run: u8| -> u8 {
        if disc[from.min(to)] & bit == 0 && g.is_hit(to) {
            from_run.saturating_add(1).min(r)
        } else {
            0
        }
    };
    if vertical && w > 0 {
        // Along y each row follows from its neighbour, so the rows go in blocks: every block
        // in parallel as if the rows beyond it stopped the walks, then, block after block,
        // its r rows nearest the next block again from that block's final row (a run
        // reaches at most r rows, so the rows farther in are already right).
        let block = VERTICAL_BLOCK_ROWS.max(usize::from(r));
        fwd.par_chunks_mut(w * block)
            .zip(back.par_chunks_mut(w * block))
            .enumerate()
            .for_each(|(b, (fwd, back))| {
                let (first, rows) = (b * block * w, fwd.len() / w);
                for y in (0..rows.saturating_sub(1)).rev() {
                    for x in 0..w {
                        let (at, i) = (y * w + x, first + y * w + x);
                        fwd[at] = step(i, i + w, fwd[at + w]);
                    }
                }
                for y in 1..rows {
                    for x in 0..w {
                        let (at, i) = (y * w + x, first + y * w + x);
                        back[at] = step(i, i - w, back[at - w]);
                    }
                }
            });
        let fix = usize::from(r).min(block);
        for b0 in (block..h).step_by(block).rev() {
            for y in (b0.saturating_sub(fix)..b0).rev() {
                for i in y * w..(y + 1) * w {
                    fwd[i] = step(i, i + w, fwd[i + w]);
                }
            }
        }
        for b0 in (block..h).step_by(block) {
            for y in b0..(b0 + fix).min(h) {
                for i in y * w..(y + 1) * w {
                    back[i] = step(i, i - w, back[i - w]);
                }
            }
        }
    } else if !vertical {
        (fwd.par_chunks_mut(w.max(1)), back.par_chunks_mut(w.max(1)))
            .into_par_iter()
            .enumerate()
            .for_each(|(y, (fwd, back))| {
                let row = y * w;
                for x in (0..w.saturating_sub(1)).rev() {
                    fwd[x] = step(row + x, row + x + 1, fwd[x + 1]);
                }
                for x in 1..w {
                    back[x] = step(row + x, row + x - 1, back[x - 1]);
                }
            });
    }
    (fwd, back)
}

#[cfg(test)]
mod tests;
