//! The LGH lighting loop (Lin & Yuksel 2019 section 3.2 and Appendix A): per pixel, the
//! unshadowed sum A over its tile's lights and the k reservoirs of shadow candidates.

use glam::Vec3;
use lgh_core::blending::blend;
use lgh_core::color::luminance;
use lgh_core::lighting_grid::representative::SLOTS;
use lgh_core::reservoir::Reservoir;
use lgh_core::rng::Rng;
use lgh_core::sampling::raised_cosine;
use lgh_core::vpl::light_irradiance;

use crate::methods::lgh::light_batch::{LANES, LightBatch, PackedLight};
use crate::methods::lgh::lights::ShadeLights;
use crate::methods::lgh::settings::{JitterAt, LghSettings};
use crate::passes::gbuffer::GBuffer;
use crate::shading::reservoirs::{ReservoirLayout, ShadowSample, halves, offer, pass_over};
use crate::shading::tiles::InterleavedBins;

/// Random-stream tag of the LGH lighting pass.
const STREAM_LGH: u64 = 0x161;

/// What the lighting loop of one row reads.
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
}

/// The lighting loop over row `y` (LGH 2019 section 3.2 and Appendix A): per pixel, the sum
/// A of B_l(d) f_j over its tile's lights, the overdraw, and the k reservoirs of shadow
/// candidates.
pub(super) fn shade_row(
    ctx: &RowContext,
    y: usize,
    row: &mut [(Vec3, u32)],
    row_res: &mut [Reservoir<ShadowSample>],
    batches: &mut [LightBatch],
) {
    let RowContext {
        g,
        bins,
        packed,
        lights,
        settings,
        layout,
        k,
        representative,
        eps2,
        seed,
        ..
    } = *ctx;
    let candidates_from = settings.candidates_from();
    let w = g.width as usize;
    let keys = bins.row_keys(y as u32, w as u32);
    for ((x, px), (phase, key)) in row.iter_mut().enumerate().zip(keys) {
        let i = y * w + x;
        if !g.is_hit(i) {
            continue;
        }
        let (xp, n) = (g.position[i], g.normal[i]);
        let mut rng = Rng::new(&[seed, i as u64, STREAM_LGH]);
        let (a, overdraw) = px;
        let res = layout.pixel_mut(row_res, x);
        // The batch of this pixel's tile (one per sub-image column phase).
        let batch = &mut batches[phase];
        if batch.key != Some(key) {
            batch.fill(key, packed, bins.lights_at(x as u32, y as u32));
        }
        let batch = &*batch;
        // A summed lane by lane over the chunks, reduced once per pixel.
        let mut sum = [[0.0f32; LANES]; 3];
        for chunk in 0..batch.chunks() {
            let lanes = batch.eval(chunk, xp, n, eps2);
            *overdraw += lanes.reached.iter().map(|&r| u32::from(r)).sum::<u32>();
            for (s, v) in sum.iter_mut().zip(&lanes.value) {
                for l in 0..LANES {
                    s[l] += v[l];
                }
            }
            if k == 0 {
                continue;
            }
            // The selection weights f_j of the chunk's candidates (zero below the first
            // candidate level). When no reservoir's replacement threshold is reached by the
            // chunk's total, none takes any of its lights: the totals grow by the sum and
            // the lights are passed over without a look (the common case once the
            // reservoirs hold a sample; Reservoir::update_jump).
            let mut lum = [0.0f32; LANES];
            for (l, f) in lum.iter_mut().enumerate() {
                let c = Vec3::new(lanes.value[0][l], lanes.value[1][l], lanes.value[2][l]);
                *f = luminance(c);
            }
            if candidates_from > 0 {
                let levels = &batch.level[chunk * LANES..((chunk + 1) * LANES).min(batch.len())];
                for (f, &l) in lum.iter_mut().zip(levels) {
                    if u32::from(l) < candidates_from {
                        *f = 0.0;
                    }
                }
            }
            if settings.jitter == JitterAt::Ray && pass_over(res, lum.iter().sum()) {
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
                    let sample = || ShadowSample {
                        q: pl.position,
                        n: pl.normal,
                        f: bc,
                        jitter: if representative {
                            Vec3::ZERO
                        } else {
                            lights.deviation[j] * settings.dev_scale
                        },
                        light: j as u32,
                        gain: Vec3::ONE,
                    };
                    offer(res, sample, f, &mut rng);
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
        *a += Vec3::from(sum.map(|s| s.iter().sum::<f32>()));
    }
}
