//! Direct lighting from the primary lights.
//!
//! Point, spot and directional lights are evaluated exactly (one shadow ray each): their
//! shadows are hard and exact, and no filter touches them. A scene with more than
//! [`EXACT_PUNCTUAL`] of them samples [`PUNCTUAL_SAMPLES`] per pixel by power instead
//! ([`punctual_irradiance`]).
//!
//! Area lights (emissive triangles) take `area_samples` points per pixel, each chosen in
//! proportion to radiance x area and then uniformly on its triangle, from the frame's
//! Owen-scrambled Sobol point set ([`frame_points`]) under a random digital shift per pixel
//! (stratified; [`area_samples`]). Two
//! estimators ([`DirectMode`]):
//!
//! - **Analytic** (the default): the ratio estimator of Heitz, Hill & McGuire 2018 ("Combining
//!   Analytic Direct Illumination and Stochastic Shadows"), the LGH paper's own idea applied
//!   to direct light. The unshadowed irradiance U_a of the analytic emitters has a closed form
//!   ([`polygon`], Lambert's formula); the same samples give S = mean of f V / p and
//!   U = mean of f / p for them; S and U are filtered by the same edge-avoiding a-trous filter
//!   ([`crate::denoise::atrous`], [`direct_filter`]) and E = U_a x D(S) / D(U) per channel (ratio 1 where D(U) is
//!   zero). Where the whole emitter is visible S = U sample by sample, the ratio is exactly 1
//!   and the result is exact and noise-free. Which emitters are analytic: [`analytic_emitters`]
//!   (docs/design.md, "Direct light"); the others are sampled as below, from the same points.
//! - **Sampled**: E = mean of f V / p over the samples (unbiased, noisy).

pub mod polygon;

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use lgh_core::color::luminance;
use lgh_core::qmc::stratified_2d;
use lgh_core::rng::{Rng, hash};
use lgh_core::sampling::ONE_MINUS_EPSILON;
use lgh_core::timing::Timings;
use lgh_scene::Light;
use rayon::prelude::*;

use crate::denoise::atrous::{AtrousBuffers, AtrousParams, filter_ratio_pair_in_place};
use crate::passes::gbuffer::GBuffer;
use crate::passes::par_filled;
use crate::progress::Progress;
use crate::shading::ratio::{RATIO_VISIBILITY, ratio_of};
use crate::world::World;
use crate::world::lights::LightSet;

/// Random-stream tag of the direct-lighting pass.
const STREAM_DIRECT: u64 = 0xd1;
/// Random stream of the choice of punctual lights.
const STREAM_PUNCTUAL: u64 = 0xd2;

/// How the direct light of area lights is estimated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum DirectMode {
    /// Analytic unshadowed irradiance times the filtered ratio of shadowed to unshadowed
    /// sample sums (Heitz et al. 2018): exact where the light is wholly visible, noise only in
    /// the penumbrae, which the shadow filter smooths.
    #[default]
    Analytic,
    /// The mean of the shadowed samples (unbiased, grainy).
    Sampled,
}

/// The most emitters that get the analytic term: its cost per pixel is about that of one
/// shadow ray per 8 emitters.
pub const MAX_ANALYTIC: usize = 16;

/// Share of the area lights' power the analytic emitters must hold when not all of them can
/// be analytic: the ratio estimator needs most samples to land on them.
pub const ANALYTIC_POWER_SHARE: f32 = 0.9;

/// Which emitters get the analytic term: all if there are at most [`MAX_ANALYTIC`]; else the
/// [`MAX_ANALYTIC`] most powerful if they emit at least [`ANALYTIC_POWER_SHARE`] of the
/// power; else none (the sampled estimator for all, as for a room of many small lights,
/// where the few analytic ones would rarely be sampled and their ratio would be noise).
#[must_use]
pub fn analytic_emitters(lights: &LightSet) -> Vec<bool> {
    let n = lights.emitters.len();
    if n <= MAX_ANALYTIC {
        return vec![true; n];
    }
    let power: Vec<f32> = lights
        .emitters
        .iter()
        .map(|e| luminance(e.radiance) * e.area)
        .collect();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| power[b].total_cmp(&power[a]).then(a.cmp(&b)));
    let total: f32 = power.iter().sum();
    let top: f32 = order[..MAX_ANALYTIC].iter().map(|&i| power[i]).sum();
    let mut chosen = vec![false; n];
    if total > 0.0 && top >= ANALYTIC_POWER_SHARE * total {
        for &i in &order[..MAX_ANALYTIC] {
            chosen[i] = true;
        }
    }
    chosen
}

/// Up to this many point, spot and directional lights are evaluated exactly at every pixel,
/// one shadow ray each; a scene with more samples [`PUNCTUAL_SAMPLES`] of them per pixel in
/// proportion to their power (unbiased, and the cost stays that of 64 lights: 10^4 lights
/// took 13 s a frame when each pixel traced a ray to every one).
pub const EXACT_PUNCTUAL: usize = 64;

/// Punctual lights sampled per pixel where there are more than [`EXACT_PUNCTUAL`].
pub const PUNCTUAL_SAMPLES: usize = 64;

/// Irradiance (RGB, W/m^2) arriving at surface point `p` (shading normal `n`, geometric normal
/// `ng`) from the point, spot and directional lights, shadows included: exactly for up to
/// [`EXACT_PUNCTUAL`] lights, else by [`PUNCTUAL_SAMPLES`] lights chosen by power with
/// stratified (systematic) sampling of the power's CDF from the offset `u` in [0, 1): the
/// estimate sum_s E_i(s) / (S p_i(s)) has the exact sum as its mean.
#[must_use]
pub fn punctual_irradiance(world: &World, p: Vec3, n: Vec3, ng: Vec3, u: f32) -> Vec3 {
    let lights = &world.lights;
    match &lights.punctual_by_power {
        Some(cdf) if lights.punctual.len() > EXACT_PUNCTUAL => {
            let scale = 1.0 / PUNCTUAL_SAMPLES as f32;
            (0..PUNCTUAL_SAMPLES)
                .map(|s| {
                    let (i, pmf) = cdf.sample(((s as f32 + u) * scale).min(ONE_MINUS_EPSILON));
                    punctual_one(world, &lights.punctual[i], p, n, ng) * (scale / pmf)
                })
                .sum()
        }
        _ => lights
            .punctual
            .iter()
            .map(|l| punctual_one(world, l, p, n, ng))
            .sum(),
    }
}

/// Irradiance at `p` from one punctual light, its shadow ray included.
fn punctual_one(world: &World, light: &Light, p: Vec3, n: Vec3, ng: Vec3) -> Vec3 {
    match light {
        Light::Point {
            position,
            intensity,
        }
        | Light::Spot {
            position,
            intensity,
            ..
        } => {
            let d = *position - p;
            let d2 = d.length_squared();
            let w = d / d2.sqrt();
            let cos = n.dot(w);
            if cos <= 0.0 || ng.dot(w) <= 0.0 {
                return Vec3::ZERO;
            }
            let f = light.falloff(-w);
            if f <= 0.0 {
                return Vec3::ZERO;
            }
            let o = world.offset(p, ng, w);
            let len = (*position - o).length();
            if world.accel.occluded(o, w, len * (1.0 - 1e-4)) {
                Vec3::ZERO
            } else {
                *intensity * (f * cos / d2)
            }
        }
        Light::Directional {
            direction,
            irradiance,
        } => {
            let w = -*direction;
            let cos = n.dot(w);
            if cos <= 0.0 || ng.dot(w) <= 0.0 {
                return Vec3::ZERO;
            }
            let o = world.offset(p, ng, w);
            if world.accel.occluded(o, w, 4.0 * world.radius) {
                Vec3::ZERO
            } else {
                *irradiance * cos
            }
        }
    }
}

/// The offset of pixel (or point) `i`'s stratified choice of punctual lights.
fn punctual_offset(seed: u64, i: usize) -> f32 {
    Rng::new(&[seed, i as u64, STREAM_PUNCTUAL]).next_f32()
}

/// The area-light samples of one pixel: for the analytic emitters the shadowed and
/// unshadowed means S and U, for the others the shadowed mean (`rest`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AreaSamples {
    /// Mean of f V / p over the samples on analytic emitters (zero elsewhere).
    pub s: Vec3,
    /// Mean of f / p over the samples on analytic emitters.
    pub u: Vec3,
    /// Mean of f V / p over the samples on the other emitters.
    pub rest: Vec3,
}

/// The area-light samples at `p` (normals `n`, `ng`) for the stratified 2D `points` (32-bit
/// fixed point) under the digital shift `shift` (XOR per coordinate: a digitally shifted
/// (0, m, 2)-net is still one, so every pixel's set stays stratified in every elementary
/// interval, and a random shift per pixel makes each pixel's estimate unbiased and
/// independent of its neighbours'); `analytic[j]` says which sums emitter j's samples go to.
#[must_use]
pub fn area_samples(
    world: &World,
    p: Vec3,
    n: Vec3,
    ng: Vec3,
    points: &[[u32; 2]],
    shift: [u32; 2],
    analytic: &[bool],
) -> AreaSamples {
    let mut out = AreaSamples::default();
    if points.is_empty() || world.lights.emitters.is_empty() {
        return out;
    }
    for &[a, b] in points {
        let u = Vec2::new(unit(a ^ shift[0]), unit(b ^ shift[1]));
        let Some((j, s)) = world.lights.sample_emitter(u) else {
            break;
        };
        let d = s.position - p;
        let d2 = d.length_squared();
        let w = d / d2.sqrt();
        let cos_x = n.dot(w);
        let cos_l = -s.normal.dot(w);
        if cos_x <= 0.0 || cos_l <= 0.0 || ng.dot(w) <= 0.0 {
            continue;
        }
        let f = s.radiance * (cos_x * cos_l / (d2 * s.pdf_area));
        if !f.is_finite() {
            continue;
        }
        let visible = !world.occluded_between(p, ng, s.position, s.normal);
        let shadowed = if visible { f } else { Vec3::ZERO };
        if analytic.get(j).copied().unwrap_or(false) {
            out.u += f;
            out.s += shadowed;
        } else {
            out.rest += shadowed;
        }
    }
    let inv = 1.0 / points.len() as f32;
    AreaSamples {
        s: out.s * inv,
        u: out.u * inv,
        rest: out.rest * inv,
    }
}

/// The indices of the emitters marked in `analytic` (found once per frame, so that the
/// per-pixel closed form visits only them).
#[must_use]
pub fn analytic_indices(analytic: &[bool]) -> Vec<usize> {
    (0..analytic.len()).filter(|&j| analytic[j]).collect()
}

/// The unshadowed irradiance at `x` (normal `n`) of the emitters `indices`
/// ([`analytic_indices`]), in closed form: L_j times the projected solid angle of each
/// triangle that faces x.
#[must_use]
pub fn analytic_irradiance(lights: &LightSet, indices: &[usize], x: Vec3, n: Vec3) -> Vec3 {
    let mut e = Vec3::ZERO;
    for em in indices.iter().filter_map(|&j| lights.emitters.get(j)) {
        // One-sided: the front is the counter-clockwise normal.
        if em.normal.dot(x - em.v0) <= 0.0 {
            continue;
        }
        e += em.radiance * polygon::projected_solid_angle(x, n, em.vertices());
    }
    e
}

/// The shadow filter of the analytic estimator: one a-trous pass with a tight colour weight
/// (c_phi 0.05). Sixteen stratified samples leave little noise in the ratio, and every
/// further pass or a looser weight blurs penumbrae more than it removes noise
/// (docs/design.md, "Direct light").
#[must_use]
pub fn direct_filter(radius: f32) -> AtrousParams {
    AtrousParams {
        passes: 1,
        c_phi: 0.05,
        ..AtrousParams::lgh_defaults(radius)
    }
}

/// A 32-bit fixed-point number in [0, 1) as an f32 (its top 24 bits).
#[inline]
fn unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// The stratified 2D point set of a frame: the first `count` points of the Owen-scrambled
/// Sobol sequence of `seed`, in 32-bit fixed point.
#[must_use]
pub fn frame_points(seed: u64, count: u32) -> Vec<[u32; 2]> {
    let s = hash(&[seed, STREAM_DIRECT]);
    let fixed = |v: f32| (v * (1u64 << 32) as f32) as u32;
    (0..u64::from(count))
        .map(|k| {
            let p = stratified_2d(s, k);
            [fixed(p.x), fixed(p.y)]
        })
        .collect()
}

/// The random digital shift of pixel `i`'s copy of the frame's point set.
fn pixel_shift(seed: u64, i: usize) -> [u32; 2] {
    let mut rng = Rng::new(&[seed, i as u64, STREAM_DIRECT]);
    [rng.next_u32(), rng.next_u32()]
}

/// Irradiance at one surface point by the sampled estimator: punctual lights exactly, area
/// lights by `count` stratified samples (the point set of `seed`, shifted for point `i`).
#[must_use]
pub fn direct_irradiance(world: &World, p: Vec3, n: Vec3, ng: Vec3, seed: u64, count: u32) -> Vec3 {
    let points = frame_points(seed, count);
    punctual_irradiance(world, p, n, ng, punctual_offset(seed, 0))
        + area_samples(world, p, n, ng, &points, pixel_shift(seed, 0), &[]).rest
}

/// One pixel's direct light before the shadow filter.
#[derive(Clone, Copy, Debug, Default)]
struct PixelDirect {
    /// Punctual lights and the sampled emitters (shadowed).
    base: Vec3,
    /// Closed-form unshadowed irradiance of the analytic emitters.
    analytic: Vec3,
    /// Shadowed and unshadowed sample means of the analytic emitters.
    s: Vec3,
    u: Vec3,
}

/// What the direct pass produced.
#[derive(Clone, Debug, Default)]
pub struct DirectOutput {
    /// Direct radiance towards the camera per pixel (albedo / pi x irradiance).
    pub radiance: Vec<Vec3>,
    /// Per-pass times: `direct_samples`, and for the analytic estimator `direct_filter` and
    /// `direct_composite`.
    pub timings: Timings,
}

/// Direct-lighting radiance towards the camera for every pixel (albedo / pi x irradiance),
/// with `area_samples` samples per pixel for the area lights and the estimator `mode`. The
/// shadow filter of the analytic estimator works in `buffers`.
#[must_use]
pub fn render_direct(
    world: &World,
    g: &GBuffer,
    seed: u64,
    area_samples_per_pixel: u32,
    mode: DirectMode,
    buffers: &mut AtrousBuffers,
    progress: &dyn Progress,
) -> DirectOutput {
    let mut timings = Timings::default();
    let analytic = match mode {
        DirectMode::Analytic if area_samples_per_pixel > 0 => analytic_emitters(&world.lights),
        _ => Vec::new(),
    };
    let indices = analytic_indices(&analytic);
    let any_analytic = !indices.is_empty();
    progress.begin("direct", u64::from(g.height));
    let w = g.width as usize;
    let points = frame_points(seed, area_samples_per_pixel);
    // Per pixel: punctual + the sampled rest; and the analytic emitters' closed-form
    // irradiance with their S and U.
    let mut px: Vec<PixelDirect> = par_filled(g.len(), PixelDirect::default());
    timings.time("direct_samples", || {
        px.par_chunks_mut(w.max(1))
            .enumerate()
            .for_each(|(y, row)| {
                for (x, out) in row.iter_mut().enumerate() {
                    let i = y * w + x;
                    if !g.is_hit(i) {
                        continue;
                    }
                    let (p, n, ng) = (g.position[i], g.normal[i], g.geo_normal[i]);
                    let shift = pixel_shift(seed, i);
                    let a = area_samples(world, p, n, ng, &points, shift, &analytic);
                    *out = PixelDirect {
                        base: punctual_irradiance(world, p, n, ng, punctual_offset(seed, i))
                            + a.rest,
                        analytic: if any_analytic {
                            analytic_irradiance(&world.lights, &indices, p, n)
                        } else {
                            Vec3::ZERO
                        },
                        s: a.s,
                        u: a.u,
                    };
                }
                progress.advance(1);
            });
    });
    progress.end();
    let irradiance: Vec<Vec3> = if any_analytic {
        let (mut s, mut u): (Vec<Vec3>, Vec<Vec3>) = px.par_iter().map(|p| (p.s, p.u)).unzip();
        timings.time("direct_filter", || {
            filter_ratio_pair_in_place(
                &mut s,
                &mut u,
                None,
                g,
                &direct_filter(world.radius),
                buffers,
            );
        });
        timings.time("direct_composite", || {
            px.par_iter()
                .zip(ratio_of(&s, &u, RATIO_VISIBILITY))
                .map(|(p, r)| p.base + p.analytic * r)
                .collect()
        })
    } else {
        px.into_par_iter().map(|p| p.base).collect()
    };
    let radiance = irradiance
        .par_iter()
        .zip(&g.albedo)
        .map(|(e, &albedo)| albedo * FRAC_1_PI * *e)
        .collect();
    DirectOutput { radiance, timings }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 16 points of the frame set under any digital shift put exactly one point in each cell
    /// of the 4 x 4, 2 x 8, 8 x 2, 1 x 16 and 16 x 1 grids (the (0, 4, 2)-net property).
    #[test]
    fn shifted_frame_points_are_stratified() {
        let points = frame_points(9, 16);
        for shift in [[0, 0], [0xdead_beef, 0x1234_5678], [u32::MAX, 7]] {
            let p: Vec<Vec2> = points
                .iter()
                .map(|&[a, b]| Vec2::new(unit(a ^ shift[0]), unit(b ^ shift[1])))
                .collect();
            for (nx, ny) in [(4, 4), (2, 8), (8, 2), (1, 16), (16, 1)] {
                let mut cells = vec![0; nx * ny];
                for q in &p {
                    let (x, y) = ((q.x * nx as f32) as usize, (q.y * ny as f32) as usize);
                    cells[y * nx + x] += 1;
                }
                assert!(
                    cells.iter().all(|&c| c == 1),
                    "{nx}x{ny} {shift:?}: {cells:?}"
                );
            }
        }
    }
}
