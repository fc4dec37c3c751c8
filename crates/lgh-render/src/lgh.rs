//! Rendering with the lighting grid hierarchy (Lin & Yuksel 2019, sections 3.2, 3.3, 4.1).
//!
//! 1. **Hierarchy** of the VPLs ([`lgh_core::lighting_grid`], section 3.1).
//! 2. **Lighting computation** (3.2): the grid lights of levels l_min..=l_max (l_min = 1 by
//!    default, 4.1; 0 adds the VPLs themselves as S_0 with h_0 = h_1 / 2) are binned into
//!    screen tiles as spheres of radius 2 r_l, r_l = alpha h_l (the top level covers the whole
//!    screen), the CPU counterpart of rasterising light volumes. Each pixel x sums, over its
//!    tile's lights j, B_l(d_j) x Phi_j e_j(w) max(0, n_x . w) / (pi (d^2 + eps^2))
//!    (the unshadowed sum A), skipping lights whose blending weight is zero. The emission
//!    cosine e_j is max(0, -m_j . w) + (1 - |m_j|) / 4 for the mean normal m_j by default
//!    ([`GridEmission`]; max(0, -m_j . w) alone is the demo's, which loses light where normals
//!    disagree). The number of lights whose sphere covers the pixel is its overdraw (Fig. 5).
//!    With n x n interleaved sampling (4.3, `interleave` > 1), the lights of each level are
//!    dealt to the n^2 sub-images (light k to k mod n^2), each pixel sums only its
//!    sub-image's lights with n^2 times their intensity, and A, S and U are recombined by the
//!    discontinuity-aware blur of [`crate::interleave`] before the shadow filter.
//! 3. **Shadow sample selection** (3.3, Appendix A): while shading, each pixel keeps k
//!    single-slot reservoirs; every light of level >= the shadow level (2 by default, 4.1,
//!    Fig. 3) is offered with weight f_j = luminance of its unshadowed contribution at its
//!    shadow target q. By default q is one of the VPLs the light stands for, drawn in
//!    proportion to its share ([`ShadowTarget::Representative`], an extension that removes
//!    the darkening of centroids inside objects); the paper's target is the centroid jittered
//!    by its deviation (q = p_j + 0.5 t * deviation, t raised-cosine per axis; design notes
//!    5).
//! 4. **Shadow rays and the ratio estimator** (Heitz et al. 2018): one ray per reservoir;
//!    U_k = f^ f_j / lum(f_j) (an unbiased estimate of the candidates' sum), S_k = V U_k;
//!    both are averaged over k, filtered by the same edge-avoiding a-trous filter
//!    ([`crate::atrous`]), and indirect = albedo / pi x A x D(S) / D(U) per channel (ratio 1
//!    where D(U) is zero).

use std::time::Instant;

use glam::Vec3;
use lgh_core::blending::{LevelRole, blend};
use lgh_core::color::luminance;
use lgh_core::lighting_grid::representative::{NONE, SLOTS, representatives};
use lgh_core::lighting_grid::{Construction, GridError, InputLights, LevelCount, LightingGrid};
use lgh_core::reservoir::Reservoir;
use lgh_core::rng::Rng;
use lgh_core::sampling::raised_cosine;
use lgh_core::vpl::{GridEmission, Vpls, light_irradiance};
use lgh_scene::camera::CameraFrame;
use rayon::prelude::*;

use crate::frame::{FrameMemory, Timings};
use crate::gbuffer::GBuffer;
use crate::interleave::BlurParams;
use crate::light_batch::{LANES, LightBatch, PackedLight};
use crate::passes::par_filled;
use crate::ratio::{
    ReservoirLayout, ShadowPass, ShadowRatio, ShadowReservoirs, ShadowSample, ShadowSettings,
    halves, offer, shadowed_indirect,
};
use crate::tiles::InterleavedBins;
use crate::world::World;

/// Random-stream tag of the LGH lighting pass.
const STREAM_LGH: u64 = 0x161;
/// Random-stream tag of the shadow targets drawn after selection.
const STREAM_TARGET: u64 = 0x162;
pub use crate::ratio::MAX_SHADOW_SAMPLES;

/// Settings of the LGH method (command-line flags in brackets).
#[derive(Clone, Debug, PartialEq)]
pub struct LghSettings {
    /// alpha of r_l = alpha h_l (`--alpha`, default 1).
    pub alpha: f32,
    /// Number of levels (`--levels auto|N`).
    pub levels: LevelCount,
    /// Shadow samples k per pixel, 0 = no shadows (`--shadow-samples`, default 4).
    pub shadow_samples: u32,
    /// Lowest level whose lights are shadow candidates (`--shadow-from-level`, default 2).
    pub shadow_from_level: u32,
    /// Lowest level shaded: 1 (S_1, default) or 0 (the VPLs) (`--start-level`).
    pub start_level: u32,
    /// A-trous passes on the shadow estimates, 0 = no filter (`--filter`, `--filter-passes`).
    pub filter_passes: u32,
    /// Screen tile edge in sub-image pixels for light binning (`--tile`); `None`:
    /// [`auto_tile`] of the interleaving.
    pub tile: Option<u32>,
    /// n of n x n interleaved sampling, 1 = none (`--interleave`; paper 4.3: 2 or 4).
    pub interleave: u32,
    /// The discontinuity-aware blur after interleaved shading.
    pub blur: BlurParams,
    /// Scale of the shadow-sample jitter (the demo's DevScale, 0.5).
    pub dev_scale: f32,
    /// Construction of levels >= 2 (default: the exact restriction, an extension; the paper
    /// gathers from S_1).
    pub construction: Construction,
    /// Build six hierarchies, one per dominant normal direction of the VPLs, instead of one
    /// (`--normal-bins`; an extension, not in the paper: grid lights then average only
    /// normals that roughly agree). It helps the mean-normal emission, which loses light in
    /// rooms, but not the default one: Cornell box, 640x360, 100K VPLs, alpha 1, unshadowed,
    /// rel_rmse 0.32 (bias +15%) with six hierarchies against 0.155 with one.
    pub normal_bins: bool,
    /// Directional emission model of grid lights (`--grid-emission`).
    pub emission: GridEmission,
    /// When the shadow-sample position is jittered (`--jitter-at`).
    pub jitter: JitterAt,
    /// Where shadow rays go (`--shadow-target`).
    pub shadow_target: ShadowTarget,
}

/// Where the shadow ray of a selected grid light goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadowTarget {
    /// The grid light's centroid jittered by its deviation (the paper and the demo). Centroids
    /// that fall inside objects (VPLs on a box's top and on the floor around it) or walls
    /// (VPLs on both sides) report their light as occluded: measured 27 % too dark on the
    /// Cornell box and 40 % on Sponza against brute force.
    Centroid,
    /// One of the VPLs the light stands for, drawn in proportion to its share
    /// ([`lgh_core::lighting_grid::representative`]; an extension, the default), then among
    /// the light's [`SLOTS`] representatives by contribution (see [`JitterAt`]): -0.4 % on
    /// the Cornell box, -8 % on Sponza.
    Representative,
}

/// When a shadow sample's target is drawn: the jittered point of [`ShadowTarget::Centroid`],
/// or the VPL of [`ShadowTarget::Representative`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JitterAt {
    /// Every candidate draws its target before it is offered, and its weight f_j is its
    /// contribution there (the authors' demo code): a second evaluation and more random
    /// numbers per candidate, and targets that do not light the receiver get no weight.
    Candidate,
    /// Candidates are offered with the contribution A already computed (the paper's text:
    /// f_i "based on the illumination contribution of each light"); each of the k selected
    /// samples draws its target afterwards (the default). For representatives: among the
    /// light's representatives in proportion to their contributions, dropping the sample if
    /// none lights the pixel; measured at 1280x720, 100K VPLs: lighting 1923 -> 1671 ms, and
    /// against brute force (320x180, 10K) rel_bias -0.4 % / -8.4 % / +2.5 % on Cornell,
    /// Sponza, conference (candidate: +1.5 % / -4.6 % / +3.3 %). For centroids, 3-5 % darker
    /// than candidate jitter, since points behind the receiver's horizon get a weight.
    Ray,
}

impl Default for LghSettings {
    fn default() -> Self {
        Self {
            alpha: 1.0,
            levels: LevelCount::Auto,
            shadow_samples: 4,
            shadow_from_level: 2,
            start_level: 1,
            filter_passes: 5,
            tile: None,
            interleave: 1,
            blur: BlurParams::defaults(),
            dev_scale: 0.5,
            construction: Construction::Restrict,
            normal_bins: false,
            emission: GridEmission::EnergyConserving,
            jitter: JitterAt::Ray,
            shadow_target: ShadowTarget::Representative,
        }
    }
}

/// What the LGH passes produced besides the image.
#[derive(Clone, Debug, Default)]
pub struct LghOutput {
    /// Indirect radiance towards the camera.
    pub indirect: Vec<Vec3>,
    /// The unshadowed sum A per pixel (without albedo / pi; recombined if interleaved).
    pub unshadowed: Vec<Vec3>,
    /// The shadow ratio per pixel, filtered and raw (1 without shadows).
    pub ratio: ShadowRatio,
    /// Per-pixel overdraw: lights whose sphere covers the pixel.
    pub overdraw: Vec<u32>,
    /// Grid lights in the hierarchy (all levels).
    pub grid_lights: usize,
    /// l_max.
    pub levels: u32,
    /// Lights shaded (grid lights of the shaded levels, plus VPLs when starting at 0).
    pub shaded_lights: usize,
    /// Shadow rays traced.
    pub shadow_rays: u64,
    /// Per-pass times: `lgh_build`, `lighting`, `shadow_rays`, `shadow_filter`, `composite`.
    pub timings: Timings,
}

impl LghOutput {
    /// Mean overdraw over the pixels of `g` that see a surface.
    #[must_use]
    pub fn avg_overdraw(&self, g: &GBuffer) -> f64 {
        g.mean_over_hits(&self.overdraw)
    }
}

/// The lights a pixel may see, structure-of-arrays, each with its level's radius r_l,
/// blending role and reach (2 r_l, or infinite for the top level).
#[derive(Default)]
struct ShadeLights {
    position: Vec<Vec3>,
    normal: Vec<Vec3>,
    /// Isotropic share of the emission cosine ([`GridEmission::isotropic`]).
    iso: Vec<f32>,
    intensity: Vec<Vec3>,
    deviation: Vec<Vec3>,
    level: Vec<u8>,
    /// Sub-image of interleaved sampling: within each level, light k goes to k mod n^2.
    sub: Vec<u16>,
    radius: Vec<f32>,
    role: Vec<LevelRole>,
    reach: Vec<f32>,
    /// The [`SLOTS`] representative VPLs of each light (shadow target `Representative`;
    /// empty otherwise).
    reps: Vec<RepSet>,
}

/// The [`SLOTS`] representative VPLs of one light, structure of arrays (positions and
/// normals per axis), so that weighing all of them for a pixel is a few vector operations on
/// three cache lines. A zero normal marks an empty slot.
#[derive(Clone, Copy, Debug, Default)]
#[repr(align(64))]
struct RepSet {
    position: [[f32; SLOTS]; 3],
    normal: [[f32; SLOTS]; 3],
}

impl RepSet {
    /// Slot `s`: position and normal.
    fn get(&self, s: usize) -> (Vec3, Vec3) {
        let [px, py, pz] = self.position;
        let [nx, ny, nz] = self.normal;
        (
            Vec3::new(px[s], py[s], pz[s]),
            Vec3::new(nx[s], ny[s], nz[s]),
        )
    }

    /// Sets slot `s`.
    fn set(&mut self, s: usize, p: Vec3, n: Vec3) {
        for a in 0..3 {
            self.position[a][s] = p[a];
            self.normal[a][s] = n[a];
        }
    }

    /// [`representative_weight`] of every slot for the pixel at `x` with normal `n_x`.
    #[inline]
    fn weights(&self, x: Vec3, n_x: Vec3, eps2: f32) -> [f32; SLOTS] {
        let [px, py, pz] = &self.position;
        let [nx, ny, nz] = &self.normal;
        // A plain loop over the lanes, not `array::from_fn`: in some builds its closure was
        // compiled as an out-of-line call, and the shadow-target pass took 44 ms instead of
        // 33 (1280x720, k = 4).
        let mut w = [0.0; SLOTS];
        for (s, w) in w.iter_mut().enumerate() {
            *w = representative_weight(
                x,
                n_x,
                Vec3::new(px[s], py[s], pz[s]),
                Vec3::new(nx[s], ny[s], nz[s]),
                eps2,
            );
        }
        w
    }
}

impl ShadeLights {
    /// Adds levels `lowest..=l_max` of `grid` (level 0 = the VPLs `vpls` it was built from).
    fn add_hierarchy(
        &mut self,
        grid: &LightingGrid,
        vpls: &Vpls,
        lowest: u32,
        alpha: f32,
        emission: GridEmission,
        n2: usize,
    ) {
        let geom = grid.geometry;
        let l_max = geom.l_max;
        for l in lowest..=l_max {
            let r = if l == 0 { 0..0 } else { grid.level_range(l) };
            let (p, n, i, d) = if l == 0 {
                (&vpls.positions[..], &vpls.normals[..], &vpls.flux[..], None)
            } else {
                (
                    &grid.position[r.clone()],
                    &grid.normal[r.clone()],
                    &grid.intensity[r.clone()],
                    Some(&grid.deviation[r]),
                )
            };
            let radius = geom.radius(l, alpha);
            let role = LevelRole::of(l, lowest, l_max);
            self.position.extend_from_slice(p);
            self.normal.extend_from_slice(n);
            self.iso.extend(n.iter().map(|&m| emission.isotropic(m)));
            self.intensity.extend_from_slice(i);
            match d {
                Some(d) => self.deviation.extend_from_slice(d),
                None => self
                    .deviation
                    .extend(std::iter::repeat_n(Vec3::ZERO, p.len())),
            }
            self.level.extend(std::iter::repeat_n(l as u8, p.len()));
            self.sub.extend((0..p.len()).map(|k| (k % n2) as u16));
            self.radius.extend(std::iter::repeat_n(radius, p.len()));
            self.role.extend(std::iter::repeat_n(role, p.len()));
            self.reach
                .extend(std::iter::repeat_n(role.reach(radius), p.len()));
        }
    }

    /// Adds the representatives of the lights that [`ShadeLights::add_hierarchy`] added for
    /// the same `grid` and `lowest` level: [`SLOTS`] per light, drawn for the shadow
    /// candidates (levels >= `from_level`; a VPL of level 0 is its own), empty slots
    /// elsewhere.
    fn add_representatives(
        &mut self,
        grid: &LightingGrid,
        vpls: &Vpls,
        lowest: u32,
        from_level: u32,
        construction: Construction,
        seed: u64,
    ) {
        let input = InputLights {
            positions: &vpls.positions,
            intensity: &vpls.flux,
            normals: Some(&vpls.normals),
        };
        let reps = representatives(grid, &input, from_level, construction, seed);
        if lowest == 0 {
            // A VPL stands for itself.
            self.reps
                .extend(vpls.positions.iter().zip(&vpls.normals).map(|(&p, &n)| {
                    let mut set = RepSet::default();
                    for s in 0..SLOTS {
                        set.set(s, p, n);
                    }
                    set
                }));
        }
        let first = grid.level_range(1).start;
        self.reps
            .extend(reps[SLOTS * first..].chunks(SLOTS).map(|slots| {
                let mut set = RepSet::default();
                for (s, &r) in slots.iter().enumerate() {
                    if r != NONE {
                        set.set(s, vpls.positions[r as usize], vpls.normals[r as usize]);
                    }
                }
                set
            }));
    }

    /// Representative `s` of light `j`: its position and normal, or `None` for an empty slot.
    fn representative(&self, j: usize, s: usize) -> Option<(Vec3, Vec3)> {
        let (q, nq) = self.reps[j].get(s);
        (nq != Vec3::ZERO).then_some((q, nq))
    }

    /// Draws the shadow target of every selected sample among its light's representatives in
    /// proportion to their unshadowed contributions at the pixel (as VPLs of the light's
    /// intensity); drops the sample if none contributes.
    fn resolve_representatives(
        &self,
        reservoirs: &mut ShadowReservoirs,
        g: &GBuffer,
        seed: u64,
        eps2: f32,
    ) {
        let w = g.width as usize;
        let layout = reservoirs.layout();
        reservoirs.rows_mut().for_each(|(y, row)| {
            for x in 0..w {
                let i = y * w + x;
                if g.is_hit(i) {
                    self.resolve_pixel(layout.pixel_mut(row, x), g, i, seed, eps2);
                }
            }
        });
    }

    /// [`ShadeLights::resolve_representatives`] for the reservoirs of pixel `i`.
    fn resolve_pixel(
        &self,
        reservoirs: &mut [Reservoir<ShadowSample>],
        g: &GBuffer,
        i: usize,
        seed: u64,
        eps2: f32,
    ) {
        let (xp, nx) = (g.position[i], g.normal[i]);
        let mut rng = Rng::new(&[seed, i as u64, STREAM_TARGET]);
        for r in reservoirs {
            let Some(j) = r.sample.map(|s| s.light as usize) else {
                continue;
            };
            // The representatives' contributions (an empty slot has n_q = 0).
            let weights = self.reps[j].weights(xp, nx, eps2);
            let total: f32 = weights.iter().sum();
            if total <= 0.0 {
                // None of the VPLs the light stands for lights the pixel: its contribution
                // is an artefact of the mean normal, with no visibility to estimate.
                // Dropped, as a zero weight drops it at candidate time.
                r.sample = None;
                continue;
            }
            let mut u = rng.next_f32() * total;
            let mut pick = SLOTS - 1;
            for (s, &wt) in weights.iter().enumerate() {
                if u < wt {
                    pick = s;
                    break;
                }
                u -= wt;
            }
            if let Some(sample) = r.sample.as_mut() {
                (sample.q, sample.n) = self.reps[j].get(pick);
            }
        }
    }

    /// The lights packed for the lighting loop, intensities times `scale`.
    fn packed(&self, scale: f32) -> Vec<PackedLight> {
        (0..self.position.len())
            .into_par_iter()
            .map(|j| PackedLight {
                position: self.position[j],
                reach2: self.reach[j] * self.reach[j],
                normal: self.normal[j],
                iso: self.iso[j],
                intensity: self.intensity[j] * scale,
                radius: self.radius[j],
                role: self.role[j],
                level: self.level[j],
            })
            .collect()
    }
}

/// The default tile edge, in sub-image pixels, for n x n interleaving: 16 full-resolution
/// pixels (16 / n sub-image pixels, at least 4). A sub-image tile of 16 sub-image pixels
/// spans 16 n pixels of the screen, so at n = 4 its lights cover far more than a pixel's;
/// measured at 1280x720, 100K VPLs, k = 4 (lighting ms): n = 2, tile 8 / 16: 268 / 292;
/// n = 4, tile 4 / 16: 130 / 150.
#[must_use]
pub fn auto_tile(n: u32) -> u32 {
    (16 / n.max(1)).max(4)
}

/// The contribution at x (normal n_x) of a representative VPL at q (normal n_q) as a VPL
/// of its light's intensity I, up to the factor luminance(I) / pi that a light's
/// representatives share: cos_x cos_q / (d^2 + eps^2) = max(0, n_x . d) max(0, -n_q . d) /
/// (d^2 (d^2 + eps^2)), d = q - x, without a branch or a square root (the shadow targets
/// weigh 8 of them per selected sample). Zero where d = 0.
#[inline]
fn representative_weight(x: Vec3, n_x: Vec3, q: Vec3, n_q: Vec3, eps2: f32) -> f32 {
    let d = q - x;
    let d2 = d.length_squared();
    let w = n_x.dot(d).max(0.0) * (-n_q.dot(d)).max(0.0) / (d2 * (d2 + eps2));
    if w.is_finite() { w } else { 0.0 }
}

/// What the lighting loop of one row reads.
struct RowContext<'a> {
    g: &'a GBuffer,
    bins: &'a InterleavedBins,
    packed: &'a [PackedLight],
    lights: &'a ShadeLights,
    settings: &'a LghSettings,
    layout: ReservoirLayout,
    k: usize,
    representative: bool,
    eps2: f32,
    seed: u64,
    /// Interleaving n: pixels of a row cycle through n sub-images.
    phases: usize,
}

/// The lighting loop over row `y` (LGH 2019 section 3.2 and Appendix A): per pixel, the sum
/// A of B_l(d) f_j over its tile's lights, the overdraw, and the k reservoirs of shadow
/// candidates.
fn shade_row(
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
        for chunk in 0..batch.chunks() {
            let lanes = batch.eval(chunk, xp, n, eps2);
            for lane in 0..LANES {
                if !lanes.reached[lane] {
                    continue;
                }
                *overdraw += 1;
                let bc = Vec3::new(
                    lanes.value[0][lane],
                    lanes.value[1][lane],
                    lanes.value[2][lane],
                );
                if bc == Vec3::ZERO {
                    continue;
                }
                let e = chunk * LANES + lane;
                let (j, l) = (batch.index[e] as usize, batch.level[e]);
                *a += bc;
                if k > 0 && l as u32 >= settings.shadow_from_level {
                    let pl = &packed[j];
                    let (p, nj, iso, ij) = (pl.position, pl.normal, pl.iso, pl.intensity);
                    let b = || blend(pl.role, (p - xp).length(), pl.radius);
                    let sample = match (settings.jitter, representative) {
                        // The target is drawn after selection.
                        (JitterAt::Ray, _) => ShadowSample {
                            q: p,
                            n: nj,
                            f: bc,
                            jitter: if representative {
                                Vec3::ZERO
                            } else {
                                lights.deviation[j] * settings.dev_scale
                            },
                            light: j as u32,
                        },
                        (JitterAt::Candidate, true) => {
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
                            }
                        }
                        (JitterAt::Candidate, false) => {
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
                            }
                        }
                    };
                    offer(res, sample, luminance(sample.f), &mut rng);
                }
            }
        }
    }
}

/// Splits VPLs into six groups by the dominant axis and sign of their normal (+x, -x, +y,
/// -y, +z, -z), so that each hierarchy only averages normals that roughly agree.
fn split_by_normal(vpls: &Vpls) -> Vec<Vpls> {
    let mut groups = vec![Vpls::default(); 6];
    for i in 0..vpls.len() {
        let n = vpls.normals[i];
        let a = n.abs();
        let axis = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let bin = 2 * axis + usize::from(n[axis] < 0.0);
        groups[bin].push(vpls.positions[i], n, vpls.flux[i]);
    }
    groups
}

/// Renders the indirect light of `vpls` with the lighting grid hierarchy. With
/// `shadows == false` (method `lgh-unshadowed`) no sample is selected and no ray traced.
///
/// # Errors
/// The VPLs cannot form a hierarchy (non-finite values).
#[allow(clippy::too_many_arguments)]
pub fn render_lgh(
    world: &World,
    g: &GBuffer,
    frame: &CameraFrame,
    vpls: &Vpls,
    eps: f32,
    settings: &LghSettings,
    seed: u64,
    shadows: bool,
    memory: &mut FrameMemory,
) -> Result<LghOutput, GridError> {
    let builder = &mut memory.grid;
    let mut t = Timings::default();
    let n_px = g.len();
    if vpls.is_empty() {
        return Ok(LghOutput {
            indirect: par_filled(n_px, Vec3::ZERO),
            overdraw: par_filled(n_px, 0),
            ..LghOutput::default()
        });
    }
    // Every image of the output is set by the passes below.
    let mut out = LghOutput::default();
    // One hierarchy, or one per dominant normal direction (--normal-bins).
    let split;
    let groups: Vec<&Vpls> = if settings.normal_bins {
        split = split_by_normal(vpls);
        split.iter().collect()
    } else {
        vec![vpls]
    };
    let lowest = settings.start_level.min(1);
    let n = settings.interleave.max(1);
    let n2 = (n * n) as usize;
    let scale = n2 as f32;
    let mut lights = ShadeLights::default();
    let mut build_ms = 0.0;
    let mut lighting_ms = 0.0;
    let mut reps_ms = 0.0;
    for group in groups.iter().filter(|g| !g.is_empty()) {
        let input = InputLights {
            positions: &group.positions,
            intensity: &group.flux,
            normals: Some(&group.normals),
        };
        let start = Instant::now();
        builder.build(&input, settings.levels, settings.construction)?;
        build_ms += start.elapsed().as_secs_f64() * 1e3;
        let Some(grid) = builder.grid() else { continue };
        let start = Instant::now();
        out.grid_lights += grid.len();
        out.levels = out.levels.max(grid.l_max());
        lights.add_hierarchy(grid, group, lowest, settings.alpha, settings.emission, n2);
        lighting_ms += start.elapsed().as_secs_f64() * 1e3;
        if shadows && settings.shadow_target == ShadowTarget::Representative {
            let start = Instant::now();
            lights.add_representatives(
                grid,
                group,
                lowest,
                settings.shadow_from_level,
                settings.construction,
                seed,
            );
            reps_ms += start.elapsed().as_secs_f64() * 1e3;
        }
    }
    t.push("lgh_build", build_ms);
    if reps_ms > 0.0 {
        t.push("representatives", reps_ms);
    }
    let lighting_start = Instant::now();
    out.shaded_lights = lights.position.len();
    let bins = InterleavedBins::build(
        g,
        frame,
        settings.tile.unwrap_or_else(|| auto_tile(n)),
        n,
        &lights.position,
        &lights.reach,
        &lights.sub,
    );

    let k = if shadows {
        settings.shadow_samples.min(MAX_SHADOW_SAMPLES) as usize
    } else {
        0
    };
    let eps2 = eps * eps;
    let representative = settings.shadow_target == ShadowTarget::Representative;
    let packed = lights.packed(scale);
    // Per pixel: A and overdraw; and k reservoirs.
    let mut shaded: Vec<(Vec3, u32)> = par_filled(n_px, (Vec3::ZERO, 0));
    let layout = ReservoirLayout::new(k);
    let ctx = RowContext {
        g,
        bins: &bins,
        packed: &packed,
        lights: &lights,
        settings,
        layout,
        k,
        representative,
        eps2,
        seed,
        phases: n as usize,
    };
    let resolve = |r: &mut ShadowReservoirs| lights.resolve_representatives(r, g, seed, eps2);
    let (estimates, times) = ShadowPass::new(world, g, k, seed).shade_in_bands(
        &mut shaded,
        || vec![LightBatch::default(); ctx.phases],
        |batches, y, row, row_res| shade_row(&ctx, y, row, row_res, batches),
        (representative && settings.jitter == JitterAt::Ray)
            .then_some(&resolve as &(dyn Fn(&mut ShadowReservoirs) + Sync)),
    );
    out.overdraw = shaded.par_iter().map(|p| p.1).collect();
    t.push(
        "lighting",
        lighting_ms
            + (lighting_start.elapsed().as_secs_f64() * 1e3 - times.resolve_ms - times.rays_ms),
    );
    if times.resolve_ms > 0.0 {
        t.push("shadow_targets", times.resolve_ms);
    }
    if k > 0 {
        t.push("shadow_rays", times.rays_ms);
    }
    let a: Vec<Vec3> = shaded.par_iter().map(|p| p.0).collect();
    let shadow = ShadowSettings {
        filter_passes: settings.filter_passes,
        interleave_blur: (n > 1).then_some(settings.blur),
        seed,
    };
    let shadowed = shadowed_indirect(world, g, a, estimates, &shadow, &mut t, &mut memory.filter);
    (out.indirect, out.unshadowed, out.ratio, out.shadow_rays) = (
        shadowed.indirect,
        shadowed.unshadowed,
        shadowed.ratio,
        shadowed.rays,
    );
    out.timings = t;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use lgh_core::rng::Rng;

    /// The representatives' weight is their VPL contribution divided by luminance(I) / pi,
    /// for random positions and normals (both sides of both surfaces), and zero at d = 0.
    #[test]
    fn representative_weight_is_the_vpl_contribution() {
        let mut rng = Rng::new(&[17, 3]);
        let mut v = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
        let intensity = Vec3::new(0.7, 1.3, 0.4);
        let eps2 = 1e-4;
        let mut lit = 0;
        for _ in 0..2000 {
            let (x, q) = (v(), v());
            let (n_x, n_q) = (v().normalize(), v().normalize());
            let exact = luminance(light_irradiance(x, n_x, q, n_q, 0.0, intensity, eps2));
            let w = representative_weight(x, n_x, q, n_q, eps2) * luminance(intensity)
                / std::f32::consts::PI;
            assert!(
                (w - exact).abs() <= 1e-4 * exact.max(1e-3),
                "{w} vs {exact}"
            );
            lit += usize::from(exact > 0.0);
        }
        assert!(lit > 300, "{lit}");
        assert_eq!(
            representative_weight(Vec3::ONE, Vec3::Y, Vec3::ONE, -Vec3::Y, eps2),
            0.0
        );
    }
}
