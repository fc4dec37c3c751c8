//! The brute force with sampled visibility (`brute-sampled`): every pixel sums every VPL's
//! unshadowed light, as [`super::BRUTE`] does, but estimates their visibility from
//! `--brute-rays` shadow rays instead of tracing one per VPL.
//!
//! For pixel x with VPL contributions c_i (the brute force's summand without V) and their
//! luminances y_i, Y = sum y_i, the M rays go to VPLs drawn by stratified inversion of the
//! cumulative y: ray s takes the VPL j_s whose interval of the cumulative sum holds
//! t_s = (s + u_s) Y / M, u_s uniform in [0, 1). Each draw alone picks VPL i with
//! p_i = y_i / Y, so
//!
//!   L(x) = albedo / pi x (1 / M) sum_s V(x, p_{j_s}) c_{j_s} / p_{j_s}
//!
//! is an unbiased estimate of the brute force's sum over the same VPLs, whose mean over
//! frames converges to the same limit (docs/design.md, "Equal time"). The VPLs are visited
//! in Morton order of their positions, so that the strata are regions of space and the rays
//! of a pixel spread over the scene's light; a VPL drawn by consecutive strata is traced
//! once. The unshadowed sums go eight VPLs at a time through [`LightBatch`] (a VPL is a
//! light of one level whose blend is 1 everywhere), about four times the scalar loop's rate.
//!
//! Where the brute force's cost is one ray per (pixel, VPL) pair, this one's is an unshadowed
//! evaluation per pair and M rays per pixel: the references of `lgh bench quality
//! --equal-time` afford many more VPL sets in the same time, and the noise the sets leave is
//! what the references must average away (VPL noise, not visibility noise, set their
//! convergence on the scenes lit through a doorway).

use std::f32::consts::FRAC_1_PI;

use glam::Vec3;
use lgh_core::blending::LevelRole;
use lgh_core::rng::Rng;
use lgh_core::vpl::Vpls;
use rayon::prelude::*;

use super::ShadowBatch;
use crate::methods::lgh::light_batch::{LANES, LightBatch, PackedLight};
use crate::passes::gbuffer::GBuffer;
use crate::passes::par_filled;
use crate::progress::Progress;
use crate::world::World;

/// The default of `--brute-rays`.
pub const DEFAULT_BRUTE_RAYS: u32 = 256;

/// The most rays `--brute-rays` takes.
pub const MAX_BRUTE_RAYS: u32 = 1 << 16;

/// Random stream of the strata's offsets.
const STREAM_STRATA: u64 = 0x6272_7574_6573;

/// The Morton code of `p`'s cell in a 1024^3 grid over `[lo, lo + extent]`.
fn morton(p: Vec3, lo: Vec3, extent: Vec3) -> u32 {
    let spread = |v: f32| -> u32 {
        // 10 bits, each moved to every third place.
        let mut x = (v.clamp(0.0, 1.0) * 1023.0) as u32;
        x = (x | (x << 16)) & 0x0300_00ff;
        x = (x | (x << 8)) & 0x0300_f00f;
        x = (x | (x << 4)) & 0x030c_30c3;
        (x | (x << 2)) & 0x0924_9249
    };
    let q = (p - lo) / extent.max(Vec3::splat(f32::MIN_POSITIVE));
    spread(q.x) | (spread(q.y) << 1) | (spread(q.z) << 2)
}

/// The VPLs as one [`LightBatch`] in Morton order of their positions.
fn vpl_batch(vpls: &Vpls) -> LightBatch {
    let packed: Vec<PackedLight> = (0..vpls.len())
        .map(|i| PackedLight {
            position: vpls.positions[i],
            reach2: f32::INFINITY,
            normal: vpls.normals[i],
            iso: 0.0,
            intensity: vpls.flux[i],
            radius: 1.0,
            role: LevelRole::Only,
            level: 0,
        })
        .collect();
    let (lo, hi) = vpls
        .positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let mut order: Vec<(u32, usize)> = vpls
        .positions
        .iter()
        .enumerate()
        .map(|(i, &p)| (morton(p, lo, hi - lo), i))
        .collect();
    order.sort_unstable();
    let mut batch = LightBatch::default();
    batch.fill((0, 0), &packed, order.into_iter().map(|(_, i)| i));
    batch
}

/// Indirect radiance towards the camera for every pixel, from all `vpls` with visibility
/// estimated from `rays` shadow rays per pixel (see the module's documentation); pixel i's
/// strata take their offsets from the stream (`seed`, i), so the image does not depend on
/// the thread count.
#[must_use]
#[allow(clippy::too_many_arguments)]
pub fn render_brute_sampled(
    world: &World,
    g: &GBuffer,
    vpls: &Vpls,
    eps: f32,
    rays: u32,
    seed: u64,
    progress: &dyn Progress,
) -> Vec<Vec3> {
    let batch = vpl_batch(vpls);
    let width = (g.width as usize).max(1);
    let mut out = par_filled(g.len(), Vec3::ZERO);
    progress.begin("indirect (brute force, sampled rays)", u64::from(g.height));
    out.par_chunks_mut(width)
        .enumerate()
        .for_each_init(Vec::new, |cdf, (y, row)| {
            for (x, v) in row.iter_mut().enumerate() {
                let i = y * width + x;
                if g.is_hit(i) {
                    let e = pixel(world, g, i, vpls, &batch, eps * eps, rays, seed, cdf);
                    *v = g.albedo[i] * FRAC_1_PI * e;
                }
            }
            progress.advance(1);
        });
    progress.end();
    out
}

/// The estimate of sum_i V_i c_i at pixel `i` ([`render_brute_sampled`]); `cdf` is scratch.
#[allow(clippy::too_many_arguments)]
fn pixel(
    world: &World,
    g: &GBuffer,
    i: usize,
    vpls: &Vpls,
    batch: &LightBatch,
    eps2: f32,
    rays: u32,
    seed: u64,
    cdf: &mut Vec<f64>,
) -> Vec3 {
    let (x, n, ng) = (g.position[i], g.normal[i], g.geo_normal[i]);
    // The cumulative luminance, in f64 so that every VPL with light keeps an interval.
    cdf.clear();
    let mut total = 0.0f64;
    for c in 0..batch.chunks() {
        let r = batch.eval(c, x, n, eps2);
        for y in r.lum {
            total += f64::from(y);
            cdf.push(total);
        }
    }
    if total <= 0.0 || rays == 0 {
        return Vec3::ZERO;
    }
    let mut rng = Rng::new(&[seed, i as u64, STREAM_STRATA]);
    let mut pending = ShadowBatch::default();
    let mut e = Vec3::ZERO;
    let mut last = None;
    let scale = total / f64::from(rays);
    for s in 0..rays {
        let t = (f64::from(s) + f64::from(rng.next_f32())) * scale;
        let j = cdf.partition_point(|&v| v <= t).min(cdf.len() - 1);
        let mass = cdf[j] - if j == 0 { 0.0 } else { cdf[j - 1] };
        let r = batch.eval(j / LANES, x, n, eps2);
        let lane = j % LANES;
        let c = Vec3::new(r.value[0][lane], r.value[1][lane], r.value[2][lane]);
        // c_j / (M p_j) with p_j = mass / total.
        let w = c * (scale / mass) as f32;
        if last == Some(j) {
            // The same VPL as the stratum before: the same ray, counted again.
            pending.add_to_last(w);
            continue;
        }
        last = Some(j);
        let v = batch.index[j] as usize;
        let segment = world.shadow_segment(x, ng, vpls.positions[v], vpls.normals[v]);
        if pending.push(w, segment) {
            pending.flush(world, &mut e);
            last = None;
        }
    }
    pending.flush(world, &mut e);
    e
}
