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
//! light of one level whose blend is 1 everywhere), about four times the scalar loop's rate,
//! and groups of 64 VPLs (neighbours in Morton order) whose bounding box lies behind the
//! pixel's tangent plane are passed over whole: they give nothing.
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

use super::ShadowBatch;
use crate::methods::lgh::light_batch::{LANES, LightBatch, PackedLight};
use crate::passes::gbuffer::GBuffer;
use crate::passes::per_pixel_with;
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

/// VPLs in a group whose bounding box is tested against a pixel's tangent plane.
const GROUP: usize = 8 * LANES;

/// The VPLs as one [`LightBatch`] in Morton order of their positions, with the bounding box
/// of each [`GROUP`] of them in that order.
struct SortedVpls {
    batch: LightBatch,
    boxes: Vec<(Vec3, Vec3)>,
    /// The normal every VPL of the group has, if they share one (a flat wall's).
    normals: Vec<Option<Vec3>>,
}

impl SortedVpls {
    fn new(vpls: &Vpls) -> Self {
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
        let bounds = |points: &mut dyn Iterator<Item = Vec3>| {
            points.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p), hi.max(p))
            })
        };
        let (lo, hi) = bounds(&mut vpls.positions.iter().copied());
        let mut order: Vec<(u32, usize)> = vpls
            .positions
            .iter()
            .enumerate()
            .map(|(i, &p)| (morton(p, lo, hi - lo), i))
            .collect();
        order.sort_unstable();
        let mut batch = LightBatch::default();
        batch.fill((0, 0), &packed, order.into_iter().map(|(_, i)| i));
        let boxes = batch
            .index
            .chunks(GROUP)
            .map(|group| bounds(&mut group.iter().map(|&i| vpls.positions[i as usize])))
            .collect();
        let normals = batch
            .index
            .chunks(GROUP)
            .map(|group| {
                let m = vpls.normals[group[0] as usize];
                group
                    .iter()
                    .all(|&i| vpls.normals[i as usize] == m)
                    .then_some(m)
            })
            .collect();
        Self {
            batch,
            boxes,
            normals,
        }
    }

    /// Whether group `k` gives nothing at `x` with normal `n`: its box lies behind the
    /// tangent plane, or `x` behind the plane of its VPLs ([`SortedVpls::faces_away`]).
    fn dark(&self, k: usize, x: Vec3, n: Vec3) -> bool {
        self.behind(k, x, n) || self.faces_away(k, x)
    }

    /// The lower and upper corner of group `k`'s box relative to `x`, and the margin that
    /// covers the rounding of a dot product with them.
    fn corners(&self, k: usize, x: Vec3) -> (Vec3, Vec3, f32) {
        let (lo, hi) = self.boxes[k];
        let (a, b) = (lo - x, hi - x);
        (a, b, 1e-5 * (a.abs() + b.abs()).element_sum())
    }

    /// Group `k`'s box lies behind the tangent plane at `x` (max over the box of
    /// n . (p - x) < 0 by more than its rounding): every VPL's cos_x, and light, is 0.
    fn behind(&self, k: usize, x: Vec3, n: Vec3) -> bool {
        let (a, b, margin) = self.corners(k, x);
        (n * a).max(n * b).element_sum() < -margin
    }

    /// Group `k`'s VPLs share a normal m and `x` lies behind their plane (max over the box
    /// of m . (x - p) < 0 by more than its rounding): every VPL's emission cosine is 0.
    fn faces_away(&self, k: usize, x: Vec3) -> bool {
        let (a, b, margin) = self.corners(k, x);
        self.normals[k].is_some_and(|m| (-(m * a)).max(-(m * b)).element_sum() < -margin)
    }

    /// Appends to `cdf` the running sum `total` of the VPLs' luminances y_i at `x` with
    /// normal `n`, one entry a lane. A group that gives nothing ([`SortedVpls::dark`]) is
    /// not evaluated; the image is the same.
    fn cumulate(&self, x: Vec3, n: Vec3, eps2: f32, cdf: &mut Vec<f64>) -> f64 {
        let mut total = 0.0f64;
        let chunks = self.batch.chunks();
        for k in 0..self.boxes.len() {
            let first = k * GROUP / LANES;
            let last = (first + GROUP / LANES).min(chunks);
            if self.dark(k, x, n) {
                cdf.resize(cdf.len() + (last - first) * LANES, total);
                continue;
            }
            for c in first..last {
                for y in self.batch.eval(c, x, n, eps2).lum {
                    total += f64::from(y);
                    cdf.push(total);
                }
            }
        }
        total
    }
}

/// Indirect radiance towards the camera for every pixel, from all `vpls` with visibility
/// estimated from `rays` shadow rays per pixel (see the module's documentation); pixel i's
/// strata take their offsets from the stream (`seed`, i), so the image does not depend on
/// the thread count.
#[must_use]
pub fn render_brute_sampled(
    world: &World,
    g: &GBuffer,
    vpls: &Vpls,
    eps: f32,
    rays: u32,
    seed: u64,
    progress: &dyn Progress,
) -> Vec<Vec3> {
    let sorted = SortedVpls::new(vpls);
    progress.begin("indirect (brute force, sampled rays)", u64::from(g.height));
    let out = per_pixel_with(g.len(), g.width as usize, progress, Vec::new, |cdf, i| {
        if !g.is_hit(i) {
            return Vec3::ZERO;
        }
        let e = pixel(world, g, i, vpls, &sorted, eps * eps, rays, seed, cdf);
        g.albedo[i] * FRAC_1_PI * e
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
    sorted: &SortedVpls,
    eps2: f32,
    rays: u32,
    seed: u64,
    cdf: &mut Vec<f64>,
) -> Vec3 {
    let (x, n, ng) = (g.position[i], g.normal[i], g.geo_normal[i]);
    // The cumulative luminance, in f64 so that every VPL with light keeps an interval.
    cdf.clear();
    let total = sorted.cumulate(x, n, eps2, cdf);
    let batch = &sorted.batch;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Skipping the groups behind the tangent plane gives the cumulative sum of evaluating
    /// every VPL, bit for bit, and does skip (a cull that never culls would pass otherwise).
    #[test]
    fn skipped_groups_change_nothing() {
        let mut rng = Rng::new(&[3]);
        let mut u = || rng.next_f32();
        let mut vpls = Vpls::default();
        for _ in 0..1000 {
            // Most VPLs on a floor (y = 0), some on a wall (x = 0).
            let on_floor = u() < 0.7;
            let (p, n) = if on_floor {
                (Vec3::new(u(), 0.0, u()), Vec3::Y)
            } else {
                (Vec3::new(0.0, u(), u()), Vec3::X)
            };
            vpls.positions.push(p);
            vpls.normals.push(n);
            vpls.flux.push(Vec3::new(u(), u(), u()));
        }
        let sorted = SortedVpls::new(&vpls);
        let (mut fast, mut all) = (Vec::new(), Vec::new());
        let (mut skipped, mut by_normal) = (0, 0);
        for t in 0..400 {
            // Half the points on the floor's plane or the wall's, where the dot products
            // are near zero and only their rounding decides.
            let x = match t % 4 {
                0 => Vec3::new(u(), 0.0, u()),
                1 => Vec3::new(0.0, u(), u()),
                _ => Vec3::new(u() * 1.5 - 0.25, u() - 0.25, u()),
            };
            let n = Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize();
            fast.clear();
            all.clear();
            let total = sorted.cumulate(x, n, 1e-4, &mut fast);
            let mut sum = 0.0f64;
            for c in 0..sorted.batch.chunks() {
                for y in sorted.batch.eval(c, x, n, 1e-4).lum {
                    sum += f64::from(y);
                    all.push(sum);
                }
            }
            assert_eq!(fast, all);
            assert_eq!(total.to_bits(), sum.to_bits());
            skipped += (0..sorted.boxes.len())
                .filter(|&k| sorted.dark(k, x, n))
                .count();
            // Dark by the VPLs' own plane alone: the group faces away from x.
            by_normal += (0..sorted.boxes.len())
                .filter(|&k| sorted.faces_away(k, x) && !sorted.behind(k, x, n))
                .count();
        }
        assert!(skipped > 200, "{skipped} groups skipped");
        assert!(by_normal > 20, "{by_normal} groups skipped by their normal");
    }
}
