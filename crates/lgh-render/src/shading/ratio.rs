//! The ratio estimator (Heitz, Hill & McGuire 2018), as LGH 2019 section 3.3 uses it: the
//! shadow estimates S and U of [`crate::shading::shadow_pass`] are recombined if interleaved,
//! filtered by the same edge-avoiding a-trous filter, and
//! indirect = albedo / pi x A x D(S) / D(U) per channel, A being the analytic unshadowed sum
//! (ratio 1 where D(U) is zero).

use std::f32::consts::FRAC_1_PI;

use glam::Vec3;
use lgh_core::timing::Timings;
use rayon::prelude::*;

use crate::denoise::atrous::{AtrousParams, filter_ratio_pair_in_place};
use crate::memory::FrameMemory;
use crate::passes::gbuffer::GBuffer;
use crate::shading::interleave::{self, BlurParams};
use crate::shading::shadow_pass::ShadowEstimates;
use crate::world::World;

pub use crate::shading::reservoirs::MAX_SHADOW_SAMPLES;

/// How the shadow estimates are recombined and filtered.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RatioFilter {
    /// A-trous passes, 0 = no filter.
    pub passes: u32,
    /// Discontinuity-aware blur of A, S and U before the a-trous filter (interleaved
    /// sampling).
    pub interleave_blur: Option<BlurParams>,
    /// Largest ratio D(S) / D(U): 1 where S estimates a visible part of U
    /// ([`RATIO_VISIBILITY`]), more where it estimates a sum that A only approximates
    /// ([`RATIO_CORRECTION`]).
    pub max_ratio: f32,
    /// The a-trous colour weight c_phi of the first pass.
    pub c_phi: f32,
    /// The a-trous weight a_phi on the unshadowed sums A ([`AtrousParams::a_phi`]; 0: none).
    pub a_phi: f32,
}

/// [`RatioFilter::max_ratio`] of a visibility ratio.
pub const RATIO_VISIBILITY: f32 = 1.0;

/// [`RatioFilter::max_ratio`] of `lgh`'s unbiased estimate, whose ratio also corrects the
/// hierarchy's approximation A: a bound that only keeps runaway values out.
pub const RATIO_CORRECTION: f32 = 16.0;

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

/// The unshadowed sum A of the lighting loop, and what the pixels whose recombination
/// window misses sub-images shaded of those themselves ([`interleave::missed_sub_images`]).
#[derive(Clone, Debug, Default)]
pub struct Unshadowed {
    /// A per pixel, of the pixel's own sub-image (times n^2).
    pub a: Vec<Vec3>,
    /// The missed sub-images, if any pixel fills its window.
    pub fill: Option<WindowFill>,
}

impl From<Vec<Vec3>> for Unshadowed {
    fn from(a: Vec<Vec3>) -> Self {
        Self { a, fill: None }
    }
}

/// The sub-images that pixels shaded for their cut recombination windows
/// ([`interleave::recombine_filled`]).
#[derive(Clone, Debug, Default)]
pub struct WindowFill {
    /// Per pixel, the sub-images its window misses (bit s = sub-image s; 0: none).
    pub missed: Vec<u64>,
    /// Per pixel, the lights of those sub-images at the pixel (times n^2).
    pub filled: Vec<Vec3>,
}

/// A recombined by the narrowest blur of `p` ([`BlurParams::recombination`]), and where
/// pixels filled their windows, from what they shaded.
fn recombine(a: Unshadowed, g: &GBuffer, disc: &[u8], p: &BlurParams) -> Vec<Vec3> {
    let p = p.recombination();
    let Unshadowed { a, fill } = a;
    let raw = fill.as_ref().map(|_| a.clone());
    let [mut out] = interleave::blur_n([a], g, disc, &p);
    if let (Some(fill), Some(raw)) = (fill, raw) {
        interleave::recombine_filled(&mut out, &raw, &fill.filled, &fill.missed, g, disc, &p);
    }
    out
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

/// S / U per channel, clamped to [0, `max`]; 1 where U is zero.
#[must_use]
pub fn ratio_of(s: &[Vec3], u: &[Vec3], max: f32) -> Vec<Vec3> {
    s.par_iter()
        .zip(u)
        .map(|(&s, &u)| {
            Vec3::select(
                u.cmpgt(Vec3::splat(1e-20)),
                (s / u).clamp(Vec3::ZERO, Vec3::splat(max)),
                Vec3::ONE,
            )
        })
        .collect()
}

/// indirect = albedo / pi x A x ratio per pixel (in parallel: the viewer composites twice a
/// frame, once more after the temporal filter).
#[must_use]
pub fn composite(g: &GBuffer, a: &[Vec3], ratio: &[Vec3]) -> Vec<Vec3> {
    (0..g.len())
        .into_par_iter()
        .map(|i| g.albedo[i] * FRAC_1_PI * a[i] * ratio[i])
        .collect()
}

/// The blur's discontinuities of `g` with `p`'s thresholds, kept in `memory` while the view
/// stands still.
pub(crate) fn discontinuities<'m>(
    g: &GBuffer,
    p: &BlurParams,
    memory: &'m mut FrameMemory,
) -> &'m [u8] {
    let key = [
        p.z_diff.to_bits(),
        p.n_diff.to_bits(),
        p.a_n_diff.to_bits(),
        0,
    ];
    memory
        .discontinuities
        .get_or_insert_with(g, key, || interleave::discontinuities(g, p))
}

/// Recombines the unshadowed sum `a` and the shadow estimates if interleaved (timing
/// `interleave_blur`), filters the shadow estimates and composites: the indirect radiance
/// albedo / pi x A x D(S) / D(U), A, the ratio (filtered and raw) and the number of rays.
/// Timings `shadow_filter` and `composite` go to `t` too. The filter works in `memory`'s
/// planes, and the blur's discontinuities are kept there while the view stands still.
#[must_use]
pub fn shadowed_indirect(
    world: &World,
    g: &GBuffer,
    a: impl Into<Unshadowed>,
    estimates: ShadowEstimates,
    settings: &RatioFilter,
    t: &mut Timings,
    memory: &mut FrameMemory,
) -> Shadowed {
    shadowed_indirect_with(world, g, a, estimates, settings, t, memory, None)
}

/// An a-trous filter of S and U (with the unshadowed sums A where given) run elsewhere
/// (lgh-gpu's): filters them in place as [`filter_ratio_pair_in_place`] does and returns
/// true, or returns false (the GPU failed) and leaves them to the CPU's filter.
pub type AtrousBackend =
    fn(&mut [Vec3], &mut [Vec3], Option<&[Vec3]>, &GBuffer, &AtrousParams) -> bool;

/// [`shadowed_indirect`] with the a-trous filter of `atrous` where given.
#[must_use]
#[allow(clippy::too_many_arguments)]
pub fn shadowed_indirect_with(
    world: &World,
    g: &GBuffer,
    a: impl Into<Unshadowed>,
    estimates: ShadowEstimates,
    settings: &RatioFilter,
    t: &mut Timings,
    memory: &mut FrameMemory,
    atrous: Option<AtrousBackend>,
) -> Shadowed {
    let n_px = g.len();
    let a: Unshadowed = a.into();
    if estimates.k == 0 {
        let a = match &settings.interleave_blur {
            Some(p) => t.time("interleave_blur", || {
                let disc = discontinuities(g, p, memory);
                recombine(a, g, disc, p)
            }),
            None => a.a,
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
    // One discontinuity map. A, which needs no gathering of samples, over exactly the n x n
    // neighbourhood; S and U, whose ratio is a sample estimate, over the wide blur, which
    // gathers the samples of about 17 x 17 pixels before the a-trous filter (docs/design.md,
    // "Interleaved sampling").
    let [a, s_hat, u_hat] = match &settings.interleave_blur {
        Some(p) => t.time("interleave_blur", || {
            let disc = discontinuities(g, p, memory);
            let a = recombine(a, g, disc, p);
            // The walks of S and U stop where the recombined A, smoothed, changes.
            let stop = interleave::Stop::SmoothedA(&a);
            let [s, u] = interleave::blur_n_stopped([s_hat, u_hat], g, disc, p, stop);
            [a, s, u]
        }),
        None => [a.a, s_hat, u_hat],
    };
    let mut raw = Vec::new();
    let (s_f, u_f) = t.time("shadow_filter", || {
        raw = ratio_of(&s_hat, &u_hat, settings.max_ratio);
        if settings.passes > 0 {
            let params = AtrousParams {
                passes: settings.passes,
                c_phi: settings.c_phi,
                a_phi: settings.a_phi,
                ..AtrousParams::lgh_defaults(world.radius)
            };
            let (mut s, mut u) = (s_hat, u_hat);
            let guide = Some(&a[..]);
            if !atrous.is_some_and(|f| f(&mut s, &mut u, guide, g, &params)) {
                filter_ratio_pair_in_place(&mut s, &mut u, guide, g, &params, &mut memory.filter);
            }
            (s, u)
        } else {
            (s_hat, u_hat)
        }
    });
    let ratio = ShadowRatio {
        filtered: ratio_of(&s_f, &u_f, settings.max_ratio),
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
