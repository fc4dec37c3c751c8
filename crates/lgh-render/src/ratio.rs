//! Ray-traced shadows through the ratio estimator (Heitz, Hill & McGuire 2018), as LGH 2019
//! section 3.3 uses them; shared by the LGH and stochastic-light-culling passes so that both
//! methods are compared with the same shadow machinery.
//!
//! While shading, each pixel keeps k single-slot weighted reservoirs (LGH Appendix A): every
//! candidate light j is offered with weight f_j = luminance of its unshadowed contribution.
//! Afterwards one shadow ray per reservoir gives U_k = f_j* W / w_j* (an unbiased estimate of
//! the candidates' unshadowed sum; W is the reservoir's weight total) and S_k = V U_k. Both
//! are averaged over k, filtered by the same edge-avoiding a-trous filter, and
//! indirect = albedo / pi x A x D(S) / D(U) per channel, A being the analytic unshadowed sum
//! (ratio 1 where D(U) is zero).
//!
//! The image is shaded in bands of rows ([`ShadowPass::shade_in_bands`]): a band's
//! reservoirs are filled, its shadow rays traced, and the same buffer serves the next band.
//! Reservoir memory is thus k samples a pixel of one band (32 MB) instead of the whole image
//! (250 MB at 1280x720 and k = 4; 2.2 GB at 3840x2160), and only that much fresh memory is
//! mapped (page-faulted) per frame.

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use lgh_core::reservoir::Reservoir;
use lgh_core::rng::Rng;
use lgh_core::sampling::raised_cosine;
use rayon::prelude::*;

use crate::atrous::{AtrousBuffers, AtrousParams, filter_ratio_pair_in_place};
use crate::frame::Timings;
use crate::gbuffer::GBuffer;
use crate::interleave::{self, BlurParams};
use crate::passes::par_filled;
use crate::world::World;

/// Most shadow samples per pixel.
pub const MAX_SHADOW_SAMPLES: u32 = 16;

/// A held shadow sample: the point the ray goes to, the normal its end is moved off the
/// surface along (as for VPLs in the brute force), and the unshadowed contribution f.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
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
    fn place(&mut self, rows: std::ops::Range<usize>) -> usize {
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

/// Offers `sample` with weight `lum` to every reservoir of a pixel (Appendix A), with
/// replacement thresholds ([`Reservoir::update_jump`]): random numbers from `rng` are drawn
/// only when a reservoir takes the sample, not for every light.
#[inline]
pub fn offer(res: &mut [Reservoir<ShadowSample>], sample: ShadowSample, lum: f32, rng: &mut Rng) {
    for r in res {
        r.update_jump(|| sample, lum, || rng.next_f32());
    }
}

/// Settings of the shadow passes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowSettings {
    /// A-trous passes, 0 = no filter.
    pub filter_passes: u32,
    /// Discontinuity-aware blur of S and U before the a-trous filter (interleaved sampling).
    pub interleave_blur: Option<BlurParams>,
    /// Seed of the ray-time jitter.
    pub seed: u64,
}

/// Random-stream tag of the ray-time jitter.
const STREAM_JITTER: u64 = 0x717;

/// What the shadow passes produce.
#[derive(Clone, Debug, Default)]
pub struct Shadowed {
    /// Indirect radiance albedo / pi x A x ratio.
    pub indirect: Vec<Vec3>,
    /// The unshadowed sum A, recombined if interleaved.
    pub unshadowed: Vec<Vec3>,
    /// The shadow ratio, filtered and raw.
    pub ratio: ShadowRatio,
    /// Shadow rays traced.
    pub rays: u64,
}

/// The shadow ratio per pixel and channel (1 where nothing is shadowed or sampled).
#[derive(Clone, Debug, Default)]
pub struct ShadowRatio {
    /// D(S) / D(U): the ratio of the filtered estimates, used for compositing.
    pub filtered: Vec<Vec3>,
    /// S / U before filtering: noisy, it shows how far the ratio may plausibly lie from the
    /// filtered one (the temporal filter clamps its history to its neighbourhood).
    pub raw: Vec<Vec3>,
}

impl ShadowRatio {
    /// Ratio 1 everywhere (no shadows).
    #[must_use]
    pub fn unshadowed(n: usize) -> Self {
        let ones = vec![Vec3::ONE; n];
        Self {
            filtered: ones.clone(),
            raw: ones,
        }
    }
}

/// S / U per channel, clamped to [0, 1]; 1 where U is zero.
fn ratio_of(s: &[Vec3], u: &[Vec3]) -> Vec<Vec3> {
    s.par_iter()
        .zip(u)
        .map(|(&s, &u)| {
            Vec3::select(
                u.cmpgt(Vec3::splat(1e-20)),
                (s / u).clamp(Vec3::ZERO, Vec3::ONE),
                Vec3::ONE,
            )
        })
        .collect()
}

/// indirect = albedo / pi x A x ratio per pixel.
#[must_use]
pub fn composite(g: &GBuffer, a: &[Vec3], ratio: &[Vec3]) -> Vec<Vec3> {
    (0..g.len())
        .map(|i| g.albedo[i] * FRAC_1_PI * a[i] * ratio[i])
        .collect()
}

/// The per-pixel shadow estimates of the ratio estimator: S = mean of V U_k and U = mean of
/// U_k over the k samples (zero without samples), and the number of rays traced.
#[derive(Clone, Debug, Default)]
pub struct ShadowEstimates {
    /// Samples per pixel.
    pub k: usize,
    /// S per pixel.
    pub s: Vec<Vec3>,
    /// U per pixel.
    pub u: Vec<Vec3>,
    /// Shadow rays traced.
    pub rays: u64,
}

/// Wall times of [`ShadowPass::shade_in_bands`], summed over the bands, in milliseconds.
#[derive(Clone, Copy, Debug, Default)]
pub struct BandTimes {
    /// The shading of the rows (reservoir selection included).
    pub shade_ms: f64,
    /// The `resolve` step.
    pub resolve_ms: f64,
    /// The shadow rays.
    pub rays_ms: f64,
}

/// Image rows per band: reservoirs of about [`BAND_BYTES`] (at least 8 rows).
fn default_band_rows(width: usize, slots: usize) -> usize {
    let per_row = width * slots * std::mem::size_of::<Reservoir<ShadowSample>>();
    (BAND_BYTES / per_row.max(1)).max(8)
}

/// Memory of the reservoirs of one band: 32 MB, 92 rows at 1280 pixels and k = 4, instead
/// of 250 MB for the whole image.
pub const BAND_BYTES: usize = 32 << 20;

/// The fixed inputs of the banded shading and shadow passes
/// ([`ShadowPass::shade_in_bands`]).
#[derive(Clone, Copy)]
pub struct ShadowPass<'a> {
    /// Scene (for the shadow rays).
    pub world: &'a World,
    /// G-buffer of the frame.
    pub g: &'a GBuffer,
    /// Shadow samples per pixel (0: no rays).
    pub k: usize,
    /// Seed of the ray-time jitter.
    pub seed: u64,
    /// Image rows per band; `None`: reservoirs of about [`BAND_BYTES`].
    pub band_rows: Option<usize>,
}

impl<'a> ShadowPass<'a> {
    /// The passes for `k` samples a pixel, with the default band size.
    #[must_use]
    pub fn new(world: &'a World, g: &'a GBuffer, k: usize, seed: u64) -> Self {
        Self {
            world,
            g,
            k,
            seed,
            band_rows: None,
        }
    }

    /// Runs the shading pass and the shadow rays band of rows by band of rows, so that the
    /// k reservoirs a pixel holds (LGH Appendix A) need memory for one band only, reused
    /// band after band. Per band: every row is shaded in parallel by `shade(state, y, row of
    /// P, row of reservoirs)` (`state` from `init`, per task), `resolve` (if any) finishes
    /// the selected samples, and one shadow ray per sample gives the pixel's S and U. Pixels
    /// and random streams are indexed by image position, so the result does not depend on
    /// the band size.
    pub fn shade_in_bands<P: Send, St>(
        &self,
        shaded: &mut [P],
        init: impl Fn() -> St + Sync + Send,
        shade: impl Fn(&mut St, usize, &mut [P], &mut [Reservoir<ShadowSample>]) + Sync + Send,
        resolve: Option<&(dyn Fn(&mut ShadowReservoirs) + Sync)>,
    ) -> (ShadowEstimates, BandTimes) {
        let Self {
            world,
            g,
            k,
            seed,
            band_rows,
        } = *self;
        let (w, h) = (g.width as usize, g.height as usize);
        let n_px = g.len();
        let mut est = ShadowEstimates {
            k,
            s: par_filled(if k > 0 { n_px } else { 0 }, Vec3::ZERO),
            u: par_filled(if k > 0 { n_px } else { 0 }, Vec3::ZERO),
            rays: 0,
        };
        let mut times = BandTimes::default();
        let rows = band_rows.unwrap_or_else(|| default_band_rows(w, k.max(1)));
        let mut reservoirs = ShadowReservoirs::new(w, 0..0, k);
        for y0 in (0..h).step_by(rows) {
            let band = y0..(y0 + rows).min(h);
            let px = band.start * w..band.end * w;
            let start = std::time::Instant::now();
            // Each row's reservoirs are emptied just before it is shaded (in the cache),
            // not in a pass of their own over the whole band (250 MB at k = 4, 1280x720).
            reservoirs.place(band.clone());
            shaded[px.clone()]
                .par_chunks_mut(w)
                .zip(reservoirs.rows_mut())
                .for_each_init(&init, |state, (row, (y, row_res))| {
                    row_res.fill(Reservoir::new());
                    shade(state, y, row, row_res);
                });
            times.shade_ms += start.elapsed().as_secs_f64() * 1e3;
            if k == 0 {
                continue;
            }
            if let Some(resolve) = resolve {
                let start = std::time::Instant::now();
                resolve(&mut reservoirs);
                times.resolve_ms += start.elapsed().as_secs_f64() * 1e3;
            }
            let start = std::time::Instant::now();
            est.rays += trace_band(
                world,
                g,
                &reservoirs,
                seed,
                px.start,
                &mut est.s[px.clone()],
                &mut est.u[px],
            );
            times.rays_ms += start.elapsed().as_secs_f64() * 1e3;
        }
        (est, times)
    }
}

/// One shadow ray per held sample of the pixels `first..first + s.len()`: writes their S and
/// U and returns the number of rays.
fn trace_band(
    world: &World,
    g: &GBuffer,
    reservoirs: &ShadowReservoirs,
    seed: u64,
    first: usize,
    s_out: &mut [Vec3],
    u_out: &mut [Vec3],
) -> u64 {
    let k = reservoirs.k();
    s_out
        .par_iter_mut()
        .zip(u_out.par_iter_mut())
        .enumerate()
        .map(|(j, (s_px, u_px))| {
            let i = first + j;
            if !g.is_hit(i) {
                return 0;
            }
            let (xp, ng) = (g.position[i], g.geo_normal[i]);
            let (mut s, mut u) = (Vec3::ZERO, Vec3::ZERO);
            // Created on first use: representatives need no jitter (and no hashing).
            let mut rng: Option<Rng> = None;
            let mut rays = 0;
            for r in reservoirs.pixel(i) {
                let Some(sample) = r.sample else { continue };
                rays += 1;
                let u_k = sample.f * (r.total / r.weight);
                let q = if sample.jitter == Vec3::ZERO {
                    sample.q
                } else {
                    let rng = rng.get_or_insert_with(|| Rng::new(&[seed, i as u64, STREAM_JITTER]));
                    let t = Vec3::new(
                        raised_cosine(halves(rng.next_u32())),
                        raised_cosine(halves(rng.next_u32())),
                        raised_cosine(halves(rng.next_u32())),
                    );
                    sample.q + t * sample.jitter
                };
                let visible = !world.occluded_between(xp, ng, q, sample.n.normalize_or_zero());
                u += u_k;
                if visible {
                    s += u_k;
                }
            }
            (*s_px, *u_px) = (s / k as f32, u / k as f32);
            rays
        })
        .sum()
}

/// Recombines the unshadowed sum `a` and the shadow estimates if interleaved (timing
/// `interleave_blur`), filters the shadow estimates and composites: the indirect radiance
/// albedo / pi x A x D(S) / D(U), A, the ratio (filtered and raw) and the number of rays.
/// Timings `shadow_filter` and `composite` go to `t` too. The filter works in `buffers`.
#[must_use]
pub fn shadowed_indirect(
    world: &World,
    g: &GBuffer,
    a: Vec<Vec3>,
    estimates: ShadowEstimates,
    settings: &ShadowSettings,
    t: &mut Timings,
    buffers: &mut AtrousBuffers,
) -> Shadowed {
    let n_px = g.len();
    if estimates.k == 0 {
        let a = match &settings.interleave_blur {
            Some(p) => t.time("interleave_blur", || interleave::recombine(a, g, p)),
            None => a,
        };
        let ratio = ShadowRatio::unshadowed(n_px);
        let indirect = t.time("composite", || composite(g, &a, &ratio.filtered));
        return Shadowed {
            indirect,
            unshadowed: a,
            ratio,
            rays: 0,
        };
    }
    let ShadowEstimates {
        s: s_hat,
        u: u_hat,
        rays,
        ..
    } = estimates;
    // A, S and U recombined together: one discontinuity map, one walk per pixel.
    let [a, s_hat, u_hat] = match &settings.interleave_blur {
        Some(p) => t.time("interleave_blur", || {
            interleave::recombine_n([a, s_hat, u_hat], g, p)
        }),
        None => [a, s_hat, u_hat],
    };
    let mut raw = Vec::new();
    let (s_f, u_f) = t.time("shadow_filter", || {
        raw = ratio_of(&s_hat, &u_hat);
        if settings.filter_passes > 0 {
            let params = AtrousParams {
                passes: settings.filter_passes,
                ..AtrousParams::lgh_defaults(world.radius)
            };
            let (mut s, mut u) = (s_hat, u_hat);
            filter_ratio_pair_in_place(&mut s, &mut u, g, &params, buffers);
            (s, u)
        } else {
            (s_hat, u_hat)
        }
    });
    let ratio = ShadowRatio {
        filtered: ratio_of(&s_f, &u_f),
        raw,
    };
    let indirect = t.time("composite", || composite(g, &a, &ratio.filtered));
    Shadowed {
        indirect,
        unshadowed: a,
        ratio,
        rays,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Shading in bands of 3 rows gives what one band for the whole image gives: the same
    /// shaded values, shadow estimates and ray count (pixels and random streams are indexed
    /// by image position), with occluded samples among them.
    #[test]
    fn bands_do_not_change_the_result() {
        let world = World::new(lgh_scene::cornell::cornell_box());
        let (w, h) = (40u32, 30u32);
        let g = GBuffer::render(&world, &world.scene.camera().frame(w, h), w, h);
        // Candidate lights spread through the box (some hidden behind the blocks).
        let lights: Vec<Vec3> = (0..7)
            .map(|j| {
                let t = j as f32 / 7.0;
                Vec3::new(
                    0.1 + 0.8 * t,
                    0.05 + 0.9 * (1.0 - t),
                    0.1 + 0.8 * (t * 3.0).fract(),
                ) * world.radius
                    + world.centre
                    - Vec3::splat(0.5 * world.radius)
            })
            .collect();
        let shade =
            |_: &mut (), y: usize, row: &mut [Vec3], res: &mut [Reservoir<ShadowSample>]| {
                let layout = ReservoirLayout::new(3);
                for (x, a) in row.iter_mut().enumerate() {
                    let i = y * w as usize + x;
                    if !g.is_hit(i) {
                        continue;
                    }
                    let mut rng = Rng::new(&[9, i as u64]);
                    let slots = layout.pixel_mut(res, x);
                    for (j, &q) in lights.iter().enumerate() {
                        let f = Vec3::splat(1.0 + j as f32)
                            / (1.0 + (q - g.position[i]).length_squared());
                        *a += f;
                        let sample = ShadowSample {
                            q,
                            f,
                            light: j as u32,
                            ..ShadowSample::default()
                        };
                        offer(slots, sample, f.x, &mut rng);
                    }
                }
            };
        let run = |rows: Option<usize>| {
            let mut shaded = vec![Vec3::ZERO; g.len()];
            let pass = ShadowPass {
                world: &world,
                g: &g,
                k: 3,
                seed: 5,
                band_rows: rows,
            };
            let (est, _) = pass.shade_in_bands(&mut shaded, || (), shade, None);
            (shaded, est)
        };
        let (a1, one) = run(Some(h as usize));
        let (a3, three) = run(Some(3));
        assert_eq!(a1, a3);
        assert_eq!(
            (one.s, one.u, one.rays),
            (three.s.clone(), three.u.clone(), three.rays)
        );
        assert!(three.rays > 0);
        let occluded = three
            .s
            .iter()
            .zip(&three.u)
            .filter(|(s, u)| s.x < u.x)
            .count();
        assert!(occluded > 0, "some samples are shadowed");
    }
}
