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

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use lgh_core::reservoir::Reservoir;
use lgh_core::rng::Rng;
use lgh_core::sampling::raised_cosine;
use rayon::prelude::*;

use crate::atrous::{AtrousParams, filter_ratio_pair};
use crate::frame::Timings;
use crate::gbuffer::GBuffer;
use crate::interleave::{self, BlurParams};
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

/// k reservoirs per pixel in one flat buffer (memory fixed at k samples a pixel).
#[derive(Clone, Debug)]
pub struct ShadowReservoirs {
    k: usize,
    slots: usize,
    data: Vec<Reservoir<ShadowSample>>,
}

impl ShadowReservoirs {
    /// Empty reservoirs, `k` per pixel for `n_px` pixels.
    #[must_use]
    pub fn new(n_px: usize, k: usize) -> Self {
        // At least one slot a pixel so that row chunks line up when k = 0.
        let slots = k.max(1);
        // Filled in parallel: at 1280x720 and k = 4 this is 250 MB of fresh memory, whose
        // page faults cost about 100 ms on one thread.
        let mut data = Vec::new();
        (0..n_px * slots)
            .into_par_iter()
            .map(|_| Reservoir::new())
            .collect_into_vec(&mut data);
        Self { k, slots, data }
    }

    /// Shadow samples per pixel.
    #[must_use]
    pub fn k(&self) -> usize {
        self.k
    }

    /// Mutable rows of `width` pixels, for a parallel shading loop; see
    /// [`ReservoirLayout::pixel_mut`].
    pub fn rows_mut(
        &mut self,
        width: usize,
    ) -> rayon::slice::ChunksMut<'_, Reservoir<ShadowSample>> {
        self.data.par_chunks_mut(width * self.slots)
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

    /// The k reservoirs of pixel `i`.
    #[inline]
    #[must_use]
    pub fn pixel(&self, i: usize) -> &[Reservoir<ShadowSample>] {
        &self.data[i * self.slots..i * self.slots + self.k]
    }
}

/// Where a pixel's reservoirs lie within a row of [`ShadowReservoirs`].
#[derive(Clone, Copy, Debug)]
pub struct ReservoirLayout {
    k: usize,
    slots: usize,
}

impl ReservoirLayout {
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
    /// The filtered shadow ratio D(S) / D(U) per pixel and channel (1 without shadows).
    pub ratio: Vec<Vec3>,
    /// Shadow rays traced.
    pub rays: u64,
}

/// indirect = albedo / pi x A x ratio per pixel.
#[must_use]
pub fn composite(g: &GBuffer, a: &[Vec3], ratio: &[Vec3]) -> Vec<Vec3> {
    (0..g.len())
        .map(|i| g.albedo[i] * FRAC_1_PI * a[i] * ratio[i])
        .collect()
}

/// Recombines the unshadowed sum `a` if interleaved (timing `interleave_blur`), traces the
/// shadow rays, filters and composites: the indirect radiance albedo / pi x A x D(S) / D(U),
/// A, the ratio and the number of rays. Timings `shadow_rays`, `shadow_filter` and
/// `composite` go to `t` too.
#[must_use]
pub fn shadowed_indirect(
    world: &World,
    g: &GBuffer,
    a: Vec<Vec3>,
    reservoirs: &ShadowReservoirs,
    settings: &ShadowSettings,
    t: &mut Timings,
) -> Shadowed {
    let n_px = g.len();
    let k = reservoirs.k();
    let a = match &settings.interleave_blur {
        Some(p) => t.time("interleave_blur", || interleave::recombine(&a, g, p)),
        None => a,
    };
    if k == 0 {
        let ratio = vec![Vec3::ONE; n_px];
        let indirect = t.time("composite", || composite(g, &a, &ratio));
        return Shadowed {
            indirect,
            unshadowed: a,
            ratio,
            rays: 0,
        };
    }
    let (s_hat, u_hat): (Vec<Vec3>, Vec<Vec3>) = t.time("shadow_rays", || {
        (0..n_px)
            .into_par_iter()
            .map(|i| {
                if !g.is_hit(i) {
                    return (Vec3::ZERO, Vec3::ZERO);
                }
                let (xp, ng) = (g.position[i], g.geo_normal[i]);
                let (mut s, mut u) = (Vec3::ZERO, Vec3::ZERO);
                let mut rng = Rng::new(&[settings.seed, i as u64, STREAM_JITTER]);
                for r in reservoirs.pixel(i) {
                    let Some(sample) = r.sample else { continue };
                    let u_k = sample.f * (r.total / r.weight);
                    let q = if sample.jitter == Vec3::ZERO {
                        sample.q
                    } else {
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
                (s / k as f32, u / k as f32)
            })
            .unzip()
    });
    let rays = (0..n_px)
        .map(|i| {
            reservoirs
                .pixel(i)
                .iter()
                .filter(|r| r.sample.is_some())
                .count() as u64
        })
        .sum();
    let (s_f, u_f) = t.time("shadow_filter", || {
        let (s_hat, u_hat) = match &settings.interleave_blur {
            Some(p) => (
                interleave::recombine(&s_hat, g, p),
                interleave::recombine(&u_hat, g, p),
            ),
            None => (s_hat, u_hat),
        };
        if settings.filter_passes > 0 {
            let params = AtrousParams {
                passes: settings.filter_passes,
                ..AtrousParams::lgh_defaults(world.radius)
            };
            filter_ratio_pair(&s_hat, &u_hat, g, &params)
        } else {
            (s_hat, u_hat)
        }
    });
    let ratio: Vec<Vec3> = (0..n_px)
        .map(|i| {
            Vec3::select(
                u_f[i].cmpgt(Vec3::splat(1e-20)),
                (s_f[i] / u_f[i]).clamp(Vec3::ZERO, Vec3::ONE),
                Vec3::ONE,
            )
        })
        .collect();
    let indirect = t.time("composite", || composite(g, &a, &ratio));
    Shadowed {
        indirect,
        unshadowed: a,
        ratio,
        rays,
    }
}
