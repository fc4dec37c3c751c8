//! Shading in bands of rows with one shadow ray per selected sample (LGH 2019 section 3.3),
//! shared by the LGH and stochastic-light-culling passes.
//!
//! A band's reservoirs are filled by the method's shading of its rows, its shadow rays
//! traced, and the same buffer serves the next band. One shadow ray per reservoir gives
//! U_k = f_j* W / w_j* (an unbiased estimate of the candidates' unshadowed sum; W is the
//! reservoir's weight total) and S_k = V U_k, both averaged over k ([`ShadowEstimates`]).
//! Reservoir memory is thus k samples a pixel of one band (32 MB) instead of the whole image
//! (250 MB at 1280x720 and k = 4; 2.2 GB at 3840x2160), and only that much fresh memory is
//! mapped (page-faulted) per frame.

use glam::Vec3;
use lgh_core::reservoir::Reservoir;
use lgh_core::rng::Rng;
use lgh_core::sampling::raised_cosine;
use rayon::prelude::*;

use crate::passes::gbuffer::GBuffer;
use crate::passes::par_filled;
use crate::shading::reservoirs::{ShadowReservoirs, ShadowSample, halves};
use crate::world::World;

/// Random-stream tag of the ray-time jitter.
const STREAM_JITTER: u64 = 0x717;

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

/// How a method finishes the samples its reservoirs selected, when their targets are drawn
/// after selection (`lgh`'s representatives and unbiased estimate).
pub trait Targets: Sync {
    /// Sets the shadow-ray target of every held sample of a band, and the factors of its
    /// gain that the ray needs (a zero gain: no ray).
    fn resolve(&self, reservoirs: &mut ShadowReservoirs);

    /// The gain of a sample of pixel `pixel` whose ray found its target visible. Factors
    /// that only a visible sample needs are computed here, not for every sample (an
    /// occluded sample adds nothing to S whatever its gain). By default the sample's gain.
    fn visible_gain(&self, pixel: usize, sample: &ShadowSample) -> Vec3 {
        let _ = pixel;
        sample.gain
    }
}

/// Wall times of [`ShadowPass::shade_in_bands`], summed over the bands, in milliseconds.
#[derive(Clone, Copy, Debug, Default)]
pub struct BandTimes {
    /// The shading of the rows (reservoir selection included).
    pub shade_ms: f64,
    /// The targets' [`Targets::resolve`] step.
    pub resolve_ms: f64,
    /// The shadow rays, with the visible samples' [`Targets::visible_gain`].
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
    /// Image rows shaded together by one call of the shading function (1: row by row);
    /// bands are rounded up to whole groups.
    pub group_rows: usize,
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
            group_rows: 1,
        }
    }

    /// The same passes, shading `rows` image rows per call (at least 1): a method whose
    /// lights are listed per screen tile shades a whole row of tiles at once.
    #[must_use]
    pub fn with_group_rows(self, rows: usize) -> Self {
        Self {
            group_rows: rows.max(1),
            ..self
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
        targets: Option<&dyn Targets>,
    ) -> (ShadowEstimates, BandTimes) {
        let Self {
            g,
            k,
            band_rows,
            group_rows,
            ..
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
        let group = group_rows.max(1);
        let rows = band_rows
            .unwrap_or_else(|| default_band_rows(w, k.max(1)))
            .div_ceil(group)
            * group;
        let mut reservoirs = ShadowReservoirs::new(w, 0..0, k);
        for y0 in (0..h).step_by(rows) {
            let band = y0..(y0 + rows).min(h);
            let px = band.start * w..band.end * w;
            let start = std::time::Instant::now();
            // Each row's reservoirs are emptied just before it is shaded (in the cache),
            // not in a pass of their own over the whole band (250 MB at k = 4, 1280x720).
            reservoirs.place(band.clone());
            shaded[px.clone()]
                .par_chunks_mut(w * group)
                .zip(reservoirs.groups_mut(group))
                .for_each_init(&init, |state, (rows, (y, res))| {
                    res.fill(Reservoir::new());
                    shade(state, y, rows, res);
                });
            times.shade_ms += start.elapsed().as_secs_f64() * 1e3;
            if k == 0 {
                continue;
            }
            if let Some(targets) = targets {
                let start = std::time::Instant::now();
                targets.resolve(&mut reservoirs);
                times.resolve_ms += start.elapsed().as_secs_f64() * 1e3;
            }
            let start = std::time::Instant::now();
            est.rays += trace_band(
                self,
                &reservoirs,
                targets,
                px.start,
                &mut est.s[px.clone()],
                &mut est.u[px],
            );
            times.rays_ms += start.elapsed().as_secs_f64() * 1e3;
        }
        (est, times)
    }
}

/// Pixels whose shadow rays are traced as one batch ([`crate::world::accel::Accel::occluded_many`]).
const RAY_BATCH_PIXELS: usize = 32;

/// One traced sample of a batch: the pixel (in the batch), its U_k and the sample.
struct Traced<'a> {
    pixel: usize,
    u_k: Vec3,
    sample: &'a ShadowSample,
}

/// One shadow ray per held sample of the pixels `first..first + s.len()`: writes their S and
/// U and returns the number of rays. A visible sample adds its U_k times its gain
/// ([`Targets::visible_gain`] if the method has targets) to S. The rays of
/// `RAY_BATCH_PIXELS` pixels are traced as one batch (Embree traces it as a stream); each
/// pixel's S is summed in its samples' order, so the image does not depend on the batching.
fn trace_band(
    pass: &ShadowPass,
    reservoirs: &ShadowReservoirs,
    targets: Option<&dyn Targets>,
    first: usize,
    s_out: &mut [Vec3],
    u_out: &mut [Vec3],
) -> u64 {
    let ShadowPass { world, g, seed, .. } = *pass;
    let k = reservoirs.k();
    s_out
        .par_chunks_mut(RAY_BATCH_PIXELS)
        .zip(u_out.par_chunks_mut(RAY_BATCH_PIXELS))
        .enumerate()
        .map_init(
            || (Vec::new(), Vec::new(), Vec::new()),
            |(traced, segments, blocked), (c, (s_px, u_px))| {
                traced.clear();
                segments.clear();
                let i0 = first + c * RAY_BATCH_PIXELS;
                for (j, u_px) in u_px.iter_mut().enumerate() {
                    let i = i0 + j;
                    *u_px = Vec3::ZERO;
                    if !g.is_hit(i) {
                        continue;
                    }
                    let (xp, ng) = (g.position[i], g.geo_normal[i]);
                    let mut u = Vec3::ZERO;
                    // Created on first use: representatives need no jitter (and no hashing).
                    let mut rng: Option<Rng> = None;
                    for r in reservoirs.pixel(i) {
                        let Some(sample) = &r.sample else { continue };
                        let u_k = sample.f * (r.total / r.weight);
                        u += u_k;
                        // No VPL of the sample lights the pixel: nothing to trace.
                        if sample.gain == Vec3::ZERO {
                            continue;
                        }
                        let q = if sample.jitter == Vec3::ZERO {
                            sample.q
                        } else {
                            let rng = rng
                                .get_or_insert_with(|| Rng::new(&[seed, i as u64, STREAM_JITTER]));
                            let t = Vec3::new(
                                raised_cosine(halves(rng.next_u32())),
                                raised_cosine(halves(rng.next_u32())),
                                raised_cosine(halves(rng.next_u32())),
                            );
                            sample.q + t * sample.jitter
                        };
                        traced.push(Traced {
                            pixel: j,
                            u_k,
                            sample,
                        });
                        // Points too close for anything between them: a ray that hits nothing.
                        segments.push(
                            world
                                .shadow_segment(xp, ng, q, sample.n.normalize_or_zero())
                                .unwrap_or_default(),
                        );
                    }
                    *u_px = u / k as f32;
                }
                blocked.clear();
                blocked.resize(segments.len(), false);
                world.accel.occluded_many(segments, blocked);
                s_px.fill(Vec3::ZERO);
                for (t, &hidden) in traced.iter().zip(blocked.iter()) {
                    if !hidden {
                        let gain = targets
                            .map_or(t.sample.gain, |tg| tg.visible_gain(i0 + t.pixel, t.sample));
                        s_px[t.pixel] += t.u_k * gain;
                    }
                }
                for s in s_px.iter_mut() {
                    *s /= k as f32;
                }
                traced.len() as u64
            },
        )
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::reservoirs::{ReservoirLayout, offer};

    /// The banded passes over the Cornell box at 40 x 30 with 3 samples a pixel, chosen
    /// among 7 point lights spread through the box (some hidden behind the blocks), in bands
    /// of `rows` rows shaded `group` rows per call: the shaded sums A and the shadow
    /// estimates.
    fn seven_lights(
        rows: Option<usize>,
        group: usize,
        targets: Option<&dyn Targets>,
    ) -> (Vec<Vec3>, ShadowEstimates) {
        let world = World::new(lgh_scene::cornell::cornell_box());
        let (w, h) = (40u32, 30u32);
        let g = GBuffer::render(&world, &world.scene.camera().frame(w, h), w, h);
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
            |_: &mut (), y0: usize, rows: &mut [Vec3], res: &mut [Reservoir<ShadowSample>]| {
                let layout = ReservoirLayout::new(3);
                for (at, a) in rows.iter_mut().enumerate() {
                    let i = y0 * w as usize + at;
                    if !g.is_hit(i) {
                        continue;
                    }
                    let mut rng = Rng::new(&[9, i as u64]);
                    let slots = layout.pixel_mut(res, at);
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
                        offer(slots, || sample, f.x, &mut rng);
                    }
                }
            };
        let mut shaded = vec![Vec3::ZERO; g.len()];
        let pass = ShadowPass {
            world: &world,
            g: &g,
            k: 3,
            seed: 5,
            band_rows: rows,
            group_rows: group,
        };
        let (est, _) = pass.shade_in_bands(&mut shaded, || (), shade, targets);
        (shaded, est)
    }

    /// Shading in bands of 3 rows, row by row or in groups of 2 or 7 rows (bands rounded up
    /// to whole groups, the last group short), gives what one band for the whole image
    /// gives: the same shaded values, shadow estimates and ray count (pixels and random
    /// streams are indexed by image position), with occluded samples among them.
    #[test]
    fn bands_and_groups_do_not_change_the_result() {
        let (a1, one) = seven_lights(Some(30), 1, None);
        for group in [2, 7] {
            let (a, grouped) = seven_lights(Some(3), group, None);
            assert_eq!(a1, a, "groups of {group}");
            assert_eq!(
                (&one.s, &one.u, one.rays),
                (&grouped.s, &grouped.u, grouped.rays),
                "groups of {group}"
            );
        }
        let (a3, three) = seven_lights(Some(3), 1, None);
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

    /// Targets whose visible gain is 2 (the samples' own gain is 1) and that count the
    /// samples they are asked about.
    struct Doubling(std::sync::atomic::AtomicU64);

    impl Targets for Doubling {
        fn resolve(&self, _: &mut ShadowReservoirs) {}

        fn visible_gain(&self, _: usize, _: &ShadowSample) -> Vec3 {
            self.0.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            Vec3::splat(2.0)
        }
    }

    /// A method's visible gain scales exactly the visible samples' share of S (twice the
    /// S of the samples' own gain, the same U), and is asked only for visible samples:
    /// fewer times than rays are traced, since some samples are occluded.
    #[test]
    fn the_visible_gain_is_asked_for_visible_samples_only() {
        let (_, plain) = seven_lights(None, 1, None);
        let doubling = Doubling(0.into());
        let (_, doubled) = seven_lights(None, 1, Some(&doubling));
        assert_eq!(plain.u, doubled.u);
        assert_eq!(plain.rays, doubled.rays);
        for (s, s2) in plain.s.iter().zip(&doubled.s) {
            assert_eq!(*s * 2.0, *s2);
        }
        let asked = doubling.0.into_inner();
        assert!(
            asked > 0 && asked < plain.rays,
            "{asked} of {} rays",
            plain.rays
        );
    }
}
