//! The LGH lighting loop (Lin & Yuksel 2019 section 3.2 and Appendix A): per pixel, the
//! unshadowed sum A over its tile's lights and the k shadow samples drawn among them.

use glam::Vec3;
use lgh_core::blending::blend;
use lgh_core::color::luminance;
use lgh_core::lighting_grid::representative::SLOTS;
use lgh_core::reservoir::Reservoir;
use lgh_core::rng::Rng;
use lgh_core::sampling::raised_cosine;
use lgh_core::vpl::light_irradiance;

use crate::methods::lgh::light_batch::{LANES, LaneResult, LightBatch, PackedLight, lane_sum};
use crate::methods::lgh::lights::ShadeLights;
use crate::methods::lgh::settings::{JitterAt, LghSettings};
use crate::passes::gbuffer::GBuffer;
use crate::shading::reservoirs::{
    ReservoirLayout, ShadowSample, halves, offer, pass_over, stratified_picks,
};
use crate::shading::strata::ScreenStrata;
use crate::shading::tiles::InterleavedBins;

/// Random-stream tag of the LGH lighting pass.
const STREAM_LGH: u64 = 0x161;

/// What the lighting loop of a group of rows reads.
pub(super) struct RowContext<'a> {
    pub(super) g: &'a GBuffer,
    pub(super) bins: &'a InterleavedBins,
    pub(super) packed: &'a [PackedLight],
    pub(super) lights: &'a ShadeLights,
    pub(super) settings: &'a LghSettings,
    pub(super) layout: ReservoirLayout,
    pub(super) k: usize,
    pub(super) representative: bool,
    pub(super) eps2: f32,
    pub(super) seed: u64,
    /// Interleaving n: pixels of a row cycle through n sub-images.
    pub(super) phases: usize,
    /// The frame's dithered strata, where the selection is [`Selection::Dithered`].
    pub(super) strata: Option<ScreenStrata>,
    /// Per pixel, the sub-images its recombination window misses, which it shades as a
    /// guest of theirs ([`crate::shading::interleave::missed_sub_images`]).
    pub(super) missed: Option<&'a [u64]>,
}

/// What the lighting loop gives a pixel: A of its own sub-image, the overdraw, and the
/// lights of the sub-images it shades as a guest (all times n^2).
pub(super) type Shaded = (Vec3, u32, Vec3);

impl RowContext<'_> {
    /// The shadow sample of light `j` with unshadowed contribution `bc` at the pixel, whose
    /// target is drawn when its ray is traced ([`JitterAt::Ray`]).
    #[inline]
    fn ray_sample(&self, j: usize, bc: Vec3) -> ShadowSample {
        let pl = &self.packed[j];
        ShadowSample {
            q: pl.position,
            n: pl.normal,
            f: bc,
            jitter: if self.representative {
                Vec3::ZERO
            } else {
                self.lights.deviation[j] * self.settings.dev_scale
            },
            light: j as u32,
            gain: Vec3::ONE,
        }
    }
}

/// A chunk's index and its lights' B_l(d) f_j (RGB planes), as stratified selection
/// reads it.
type ChunkValues = (usize, [[f32; LANES]; 3]);

/// What a task of the lighting loop keeps from pixel to pixel.
#[derive(Default)]
pub(super) struct RowScratch {
    /// The lights of the current (sub-image, tile).
    batch: LightBatch,
    /// The selection weight of each chunk of the pixel's batch (stratified selection).
    chunk_weights: Vec<f32>,
    /// Each chunk's lanes as the loop evaluated them, its selection weights and
    /// B_l(d) f_j: the picks read them instead of evaluating their chunks again.
    chunk_lanes: Vec<([f32; LANES], [[f32; LANES]; 3])>,
    /// The guests of the current tile: (x, y, the sub-images each shades).
    guests: Vec<(usize, usize, u64)>,
}

/// The selection weights f_j of a chunk's lights: the luminance of their contributions,
/// zero below the first candidate level and where not finite.
#[inline(always)]
fn candidate_weights(
    batch: &LightBatch,
    chunk: usize,
    lanes: &LaneResult,
    candidates_from: u32,
) -> [f32; LANES] {
    let mut lum = lanes.lum.map(|y| if y.is_finite() { y } else { 0.0 });
    if candidates_from > 0 {
        let levels = &batch.level[chunk * LANES..((chunk + 1) * LANES).min(batch.len())];
        for (f, &l) in lum.iter_mut().zip(levels) {
            if u32::from(l) < candidates_from {
                *f = 0.0;
            }
        }
    }
    lum
}

/// The lighting loop over the image rows `y0..` held by `rows` (and their reservoirs
/// `res`; LGH 2019 section 3.2 and Appendix A): per pixel, the sum A of B_l(d) f_j over its
/// tile's lights, the overdraw, and the k reservoirs of shadow candidates; and for the
/// pixels that fill their recombination window ([`RowContext::missed`]), the lights of the
/// sub-images they miss, with those sub-images' batches (A only: no candidates).
///
/// The pixels are visited tile by tile and, within a tile, sub-image by sub-image, so that
/// the light batch of a (sub-image, tile) is filled once for all its pixels in the rows, not
/// once per row (a batch fill costs about as much as shading a few pixels with it). Every
/// pixel's result depends on its own random stream and light list only, so the order does
/// not change the image. Compiled for AVX2 as well, chosen at run time (the light batches
/// then evaluate 8 lanes at once instead of 4).
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub(super) fn shade_rows(
    ctx: &RowContext,
    y0: usize,
    rows: &mut [Shaded],
    res: &mut [Reservoir<ShadowSample>],
    scratch: &mut RowScratch,
) {
    let w = ctx.g.width as usize;
    let y1 = y0 + rows.len() / w.max(1);
    let n = ctx.phases.max(1);
    let tile = ctx.bins.tile_pixels().max(1) as usize;
    for x0 in (0..w).step_by(tile) {
        let x1 = (x0 + tile).min(w);
        scratch.guests.clear();
        if let Some(missed) = ctx.missed {
            for y in y0..y1 {
                for x in x0..x1 {
                    let m = missed[y * w + x];
                    if m != 0 {
                        scratch.guests.push((x, y, m));
                    }
                }
            }
        }
        for (sy, sx) in (0..n).flat_map(|sy| (0..n).map(move |sx| (sy, sx))) {
            let first_y = y0 + (sy + n - y0 % n) % n;
            let first_x = x0 + (sx + n - x0 % n) % n;
            for y in (first_y..y1).step_by(n) {
                for x in (first_x..x1).step_by(n) {
                    let at = (y - y0) * w + x;
                    let px = &mut rows[at];
                    shade_pixel(ctx, x, y, px, ctx.layout.pixel_mut(res, at), scratch);
                }
            }
            // The tile's guests that miss this sub-image, with its light batch (the tile's
            // pixels of the sub-image share it: the same key as its first pixel's; where the
            // image ends inside the tile before the sub-image has a pixel there, the key of
            // the pixel it would have, in the same tile).
            let bit = 1u64 << (sy * n + sx);
            if scratch.guests.iter().any(|g| g.2 & bit != 0) {
                let key = ctx.bins.tile_key(first_x as u32, first_y as u32);
                if scratch.batch.key != Some(key) {
                    let lights = ctx.bins.lights_at(first_x as u32, first_y as u32);
                    scratch.batch.fill(key, ctx.packed, lights);
                }
                for &(x, y, m) in &scratch.guests {
                    if m & bit != 0 {
                        let i = y * w + x;
                        rows[(y - y0) * w + x].2 += guest_sum(&scratch.batch, ctx.g, i, ctx.eps2);
                    }
                }
            }
        }
    }
}

/// The sum of a batch's lights at pixel `i`: what a guest shades of the sub-image.
#[inline(always)]
fn guest_sum(batch: &LightBatch, g: &GBuffer, i: usize, eps2: f32) -> Vec3 {
    let (xp, n) = (g.position[i], g.normal[i]);
    let mut sum = [[0.0f32; LANES]; 3];
    for chunk in 0..batch.chunks() {
        add_lanes(&mut sum, &batch.eval(chunk, xp, n, eps2).value);
    }
    Vec3::from(sum.map(|s| lane_sum(&s)))
}

/// Adds a chunk's lane values (RGB planes) to `sum`, lane by lane.
#[inline(always)]
fn add_lanes(sum: &mut [[f32; LANES]; 3], value: &[[f32; LANES]; 3]) {
    for (s, v) in sum.iter_mut().zip(value) {
        for l in 0..LANES {
            s[l] += v[l];
        }
    }
}

/// The lighting loop of pixel (x, y): A and the overdraw into `px`, the shadow candidates
/// into its reservoirs `res`.
#[inline(always)]
fn shade_pixel(
    ctx: &RowContext,
    x: usize,
    y: usize,
    px: &mut Shaded,
    res: &mut [Reservoir<ShadowSample>],
    scratch: &mut RowScratch,
) {
    let RowContext {
        g,
        bins,
        packed,
        lights,
        settings,
        k,
        representative,
        eps2,
        seed,
        ..
    } = *ctx;
    let candidates_from = settings.candidates_from();
    let RowScratch {
        batch,
        chunk_weights,
        chunk_lanes,
        ..
    } = scratch;
    // Stratified selection applies where targets are drawn after selection.
    let stratified =
        k > 0 && settings.jitter == JitterAt::Ray && settings.selection.is_stratified();
    let i = y * g.width as usize + x;
    if !g.is_hit(i) {
        return;
    }
    let (xp, n) = (g.position[i], g.normal[i]);
    let mut rng = Rng::new(&[seed, i as u64, STREAM_LGH]);
    let (a, overdraw, _) = px;
    let key = bins.tile_key(x as u32, y as u32);
    if batch.key != Some(key) {
        batch.fill(key, packed, bins.lights_at(x as u32, y as u32));
    }
    let batch = &*batch;
    // A summed lane by lane over the chunks, reduced once per pixel.
    let mut sum = [[0.0f32; LANES]; 3];
    let chunks = batch.chunks();
    if stratified {
        // Each chunk's selection weights f_j (zero below the first candidate level) and
        // their sum are kept; the samples are drawn after the loop. The scratch arrays
        // only grow: every entry below `chunks` is written before the picks read it, and
        // writing through slices keeps their lengths out of the loop.
        if chunk_lanes.len() < chunks {
            chunk_lanes.resize(chunks, ([0.0; LANES], [[0.0; LANES]; 3]));
            chunk_weights.resize(chunks, 0.0);
        }
        let kept = chunk_weights[..chunks]
            .iter_mut()
            .zip(&mut chunk_lanes[..chunks]);
        for (chunk, (weight, lanes_kept)) in kept.enumerate() {
            let lanes = shade_chunk(batch, chunk, (xp, n, eps2), overdraw, &mut sum);
            let lum = candidate_weights(batch, chunk, &lanes, candidates_from);
            *weight = lane_sum(&lum);
            *lanes_kept = (lum, lanes.value);
        }
        *a += Vec3::from(sum.map(|s| lane_sum(&s)));
        let lanes = |c: usize| {
            let (lum, value) = chunk_lanes[c];
            (lum, (c, value))
        };
        let take = |slot: usize, lane: usize, &(c, value): &ChunkValues, f, total| {
            let j = batch.index[c * LANES + lane] as usize;
            let bc = Vec3::new(value[0][lane], value[1][lane], value[2][lane]);
            res[slot] = Reservoir {
                total,
                weight: f,
                sample: Some(ctx.ray_sample(j, bc)),
                threshold: 0.0,
            };
        };
        let weights = &chunk_weights[..chunks];
        match ctx.strata {
            Some(strata) => {
                let px = strata.pixel(x as u32, y as u32);
                stratified_picks(weights, lanes, k, |i| px.u(i), take);
            }
            None => stratified_picks(weights, lanes, k, |_| rng.next_f32(), take),
        }
        return;
    }
    for chunk in 0..chunks {
        let lanes = shade_chunk(batch, chunk, (xp, n, eps2), overdraw, &mut sum);
        if k == 0 {
            continue;
        }
        // The selection weights f_j of the chunk's candidates (zero below the first
        // candidate level). Streaming: when no reservoir's replacement threshold is
        // reached by the chunk's total, none takes any of its lights: the totals grow by
        // the sum and the lights are passed over without a look (the common case once
        // the reservoirs hold a sample; Reservoir::update_jump).
        let lum = candidate_weights(batch, chunk, &lanes, candidates_from);
        if settings.jitter == JitterAt::Ray && pass_over(res, lane_sum(&lum)) {
            continue;
        }
        for (lane, &f) in lum.iter().enumerate() {
            if f == 0.0 {
                continue;
            }
            let bc = Vec3::new(
                lanes.value[0][lane],
                lanes.value[1][lane],
                lanes.value[2][lane],
            );
            let e = chunk * LANES + lane;
            let j = batch.index[e] as usize;
            let pl = &packed[j];
            if settings.jitter == JitterAt::Ray {
                // The target is drawn after selection; the light is read only if a
                // reservoir takes it.
                offer(res, || ctx.ray_sample(j, bc), f, &mut rng);
                continue;
            }
            let (p, nj, iso, ij) = (pl.position, pl.normal, pl.iso, pl.intensity);
            let b = || blend(pl.role, (p - xp).length(), pl.radius);
            let sample = if representative {
                let s = rng.next_u32() as usize % SLOTS;
                let Some((q, nq)) = lights.representative(j, s) else {
                    continue;
                };
                ShadowSample {
                    q,
                    n: nq,
                    f: b() * light_irradiance(xp, n, q, nq, 0.0, ij, eps2),
                    jitter: Vec3::ZERO,
                    light: j as u32,
                    gain: Vec3::ONE,
                }
            } else {
                let t = Vec3::new(
                    raised_cosine(halves(rng.next_u32())),
                    raised_cosine(halves(rng.next_u32())),
                    raised_cosine(halves(rng.next_u32())),
                );
                let dev = lights.deviation[j] * settings.dev_scale;
                let q = p + t * dev;
                ShadowSample {
                    q,
                    n: nj,
                    f: b() * light_irradiance(xp, n, q, nj, iso, ij, eps2),
                    jitter: Vec3::ZERO,
                    light: j as u32,
                    gain: Vec3::ONE,
                }
            };
            offer(res, || sample, luminance(sample.f), &mut rng);
        }
    }
    *a += Vec3::from(sum.map(|s| lane_sum(&s)));
}

/// Evaluates chunk `chunk` of `batch` at the pixel (position, normal, eps^2): adds the
/// lights it reaches to `overdraw` and B_l(d) f_j to `sum`, lane by lane.
#[inline(always)]
fn shade_chunk(
    batch: &LightBatch,
    chunk: usize,
    (xp, n, eps2): (Vec3, Vec3, f32),
    overdraw: &mut u32,
    sum: &mut [[f32; LANES]; 3],
) -> LaneResult {
    let lanes = batch.eval(chunk, xp, n, eps2);
    *overdraw += lanes.reached.iter().map(|&r| u32::from(r)).sum::<u32>();
    add_lanes(sum, &lanes.value);
    lanes
}
