//! Stochastic tiled lighting of VPLs (Tokuyoshi & Harada 2016, "Stochastic Light Culling",
//! Algorithm 1, sections 4.1-4.2), and the clamped tiled lighting it is compared with
//! (Appendix A).
//!
//! 1. **Light ranges** (in parallel): alpha_i from the error bound epsilon_max and the
//!    exposure E (Eq. 6, with the intensity each light is shaded with), one xi_i per light and
//!    frame from TEA of (light index, frame seed), r_i = f^-1(alpha_i xi_i) (Eq. 3). Clamped:
//!    r_i from Appendix A.
//! 2. **Culling**: n x n interleaved sampling ([`crate::interleave`], 8 x 8 in the paper): light
//!    i belongs to sub-image i mod n^2 and is shaded there with n^2 times its flux; each
//!    sub-image bins its lights' spheres (c_i, r_i) into 16 x 16-pixel tiles with per-tile
//!    depth bounds ([`crate::tiles`], shared with LGH).
//! 3. **Shading**: each pixel sums its tile's lights with the stochastic fall-off
//!    max(alpha_i, f(l)) inside r_i (Eq. 2) or, clamped, f(l) inside r_i. Lights with l < r_i
//!    are the pixel's "lights per pixel".
//! 4. With n > 1, the discontinuity-aware blur recombines the sub-images (section 4.4's
//!    geometry-aware filter).
//!
//! The paper shadows the VPLs with imperfect shadow maps: with [`SlcSettings::ism`] each light
//! is tested against its map ([`crate::ism`], with the range-based point-cloud culling of
//! section 4.3). Otherwise the `slc` methods are either unshadowed or shadowed through the
//! same k-sample ratio estimator as LGH ([`crate::ratio`]), with each light offered with its
//! stochastic contribution as weight.

use glam::Vec3;
use lgh_core::color::luminance;
use lgh_core::light_range::{alpha_point, clamped_range, light_xi, stochastic_range};
use lgh_core::rng::Rng;
use lgh_core::vpl::{Vpls, vpl_irradiance};
use lgh_scene::camera::CameraFrame;
use rayon::prelude::*;

use crate::atrous::AtrousBuffers;
use crate::frame::Timings;
use crate::gbuffer::GBuffer;
use crate::interleave::BlurParams;
use crate::ism::{IsmSettings, PointCloud, ShadowMaps};
use crate::passes::par_filled;
use crate::ratio::{
    ReservoirLayout, ShadowPass, ShadowRatio, ShadowSample, ShadowSettings, offer,
    shadowed_indirect,
};
use crate::tiles::InterleavedBins;
use crate::world::World;

/// Random-stream tag of the SLC shading pass.
const STREAM_SLC: u64 = 0x51c;

/// How light ranges are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RangeMode {
    /// Random ranges with the stochastic fall-off (unbiased; `--method slc`).
    Stochastic,
    /// Fixed ranges from the error bound, light dropped beyond (biased darker;
    /// `--method slc-clamped`).
    Clamped,
}

/// Settings of the SLC methods (command-line flags in brackets).
#[derive(Clone, Debug, PartialEq)]
pub struct SlcSettings {
    /// User error bound epsilon_max (`--error-bound`, default 0.0005 as in the paper).
    pub error_bound: f32,
    /// Camera exposure E of the error bound (`--exposure`, default 1).
    pub exposure: f32,
    /// Interleaving n of n x n sub-images (`--interleave`, default 8 as in the paper).
    pub interleave: u32,
    /// Screen tile edge in sub-image pixels (`--tile`, default 16).
    pub tile: u32,
    /// Shadow samples k per pixel, 0 = no shadows (`--shadow-samples`).
    pub shadow_samples: u32,
    /// Seed of the per-light random numbers xi_i (`--frame-seed`, default 0).
    pub frame_seed: u32,
    /// A-trous passes on the shadow estimates (`--filter-passes`).
    pub filter_passes: u32,
    /// The discontinuity-aware blur after interleaved shading.
    pub blur: BlurParams,
    /// Shadows from imperfect shadow maps (`--ism`) instead of the ratio estimator.
    pub ism: Option<IsmSettings>,
}

impl Default for SlcSettings {
    fn default() -> Self {
        Self {
            error_bound: 0.0005,
            exposure: 1.0,
            interleave: 8,
            tile: 16,
            shadow_samples: 4,
            frame_seed: 0,
            filter_passes: 5,
            blur: BlurParams::defaults(),
            ism: None,
        }
    }
}

/// What the SLC passes produced besides the image.
#[derive(Clone, Debug, Default)]
pub struct SlcOutput {
    /// Indirect radiance towards the camera.
    pub indirect: Vec<Vec3>,
    /// The unshadowed sum A per pixel (without albedo / pi; recombined if interleaved).
    pub unshadowed: Vec<Vec3>,
    /// The shadow ratio per pixel, filtered and raw (1 without shadows).
    pub ratio: ShadowRatio,
    /// Per pixel: lights evaluated (within their range) by the pixel's sub-image.
    pub lights_per_pixel: Vec<u32>,
    /// Shadow rays traced.
    pub shadow_rays: u64,
    /// With imperfect shadow maps: points tested by the culling, and points splatted.
    pub ism_points: Option<(u64, u64)>,
    /// Per-pass times: `light_ranges`, `culling`, `shading`, `interleave_blur`, then the
    /// shadow passes.
    pub timings: Timings,
}

impl SlcOutput {
    /// Mean lights per pixel over the pixels of `g` that see a surface.
    #[must_use]
    pub fn avg_lights_per_pixel(&self, g: &GBuffer) -> f64 {
        g.mean_over_hits(&self.lights_per_pixel)
    }
}

/// Per-light data of a frame: the range r_i and alpha_i (0 for clamped ranges, where the
/// fall-off is not raised).
struct Ranges {
    range: Vec<f32>,
    alpha: Vec<f32>,
}

/// Step 1 of Algorithm 1: every light's range, from the flux it is shaded with
/// (`scale` x flux). A VPL's largest radiant intensity is its flux / pi (largest channel).
fn light_ranges(vpls: &Vpls, mode: RangeMode, s: &SlcSettings, scale: f32, eps2: f32) -> Ranges {
    let n = vpls.len();
    let max_intensity = |i: usize| scale * vpls.flux[i].max_element() * std::f32::consts::FRAC_1_PI;
    let (range, alpha) = (0..n)
        .into_par_iter()
        .map(|i| {
            let intensity = max_intensity(i);
            if intensity <= 0.0 {
                return (0.0, 0.0);
            }
            match mode {
                RangeMode::Stochastic => {
                    let alpha = alpha_point(s.error_bound, s.exposure, intensity);
                    let xi = light_xi(i as u32, s.frame_seed);
                    (stochastic_range(alpha, xi, eps2), alpha)
                }
                RangeMode::Clamped => (
                    clamped_range(s.error_bound, s.exposure, n, intensity, eps2),
                    0.0,
                ),
            }
        })
        .unzip();
    Ranges { range, alpha }
}

/// Renders the indirect light of `vpls` with stochastic (or clamped) tiled lighting. With
/// `shadows == false` no sample is selected and no ray traced (imperfect shadow maps, if
/// set, still apply).
#[allow(clippy::too_many_arguments)]
#[must_use]
pub fn render_slc(
    world: &World,
    g: &GBuffer,
    frame: &CameraFrame,
    vpls: &Vpls,
    eps: f32,
    mode: RangeMode,
    settings: &SlcSettings,
    seed: u64,
    shadows: bool,
) -> SlcOutput {
    let mut t = Timings::default();
    let n_px = g.len();
    let n = settings.interleave.max(1);
    let n2 = (n * n) as usize;
    let scale = n2 as f32;
    let eps2 = eps * eps;
    let ranges = t.time("light_ranges", || {
        light_ranges(vpls, mode, settings, scale, eps2)
    });
    // Step 2: per sub-image, its lights (i = s mod n^2) binned into its tiles.
    let bins = t.time("culling", || {
        let sub: Vec<u16> = (0..vpls.len()).map(|i| (i % n2) as u16).collect();
        InterleavedBins::build(
            g,
            frame,
            settings.tile,
            n,
            &vpls.positions,
            &ranges.range,
            &sub,
        )
    });
    let k = if shadows {
        settings
            .shadow_samples
            .min(crate::ratio::MAX_SHADOW_SAMPLES) as usize
    } else {
        0
    };
    let maps = settings.ism.map(|ism| {
        t.time("ism", || {
            let cloud = PointCloud::sample(world, ism.cloud_points as usize, seed);
            ShadowMaps::build(
                &cloud,
                &vpls.positions,
                &vpls.normals,
                &ranges.range,
                &ism,
                seed,
            )
        })
    });
    // Step 3: shading.
    let w = g.width as usize;
    let mut shaded: Vec<(Vec3, u32)> = par_filled(n_px, (Vec3::ZERO, 0));
    let layout = ReservoirLayout::new(k);
    let (estimates, times) = ShadowPass::new(world, g, k, seed).shade_in_bands(
        &mut shaded,
        || (),
        |(), y, row, row_res| {
            for (x, px) in row.iter_mut().enumerate() {
                let i = y * w + x;
                if !g.is_hit(i) {
                    continue;
                }
                let (xp, nx) = (g.position[i], g.normal[i]);
                let mut rng = Rng::new(&[seed, i as u64, STREAM_SLC]);
                let res = layout.pixel_mut(row_res, x);
                let (a, count) = px;
                for j in bins.lights_at(x as u32, y as u32) {
                    let p = vpls.positions[j];
                    let d2 = (p - xp).length_squared();
                    let r = ranges.range[j];
                    if d2 >= r * r {
                        continue;
                    }
                    *count += 1;
                    if maps.as_ref().is_some_and(|m| !m.visible(j, xp)) {
                        continue;
                    }
                    // vpl_irradiance carries f(l) = 1 / (l^2 + eps^2); the stochastic
                    // fall-off max(alpha, f) is f x max(1, alpha / f).
                    let raise = (ranges.alpha[j] * (d2 + eps2)).max(1.0);
                    let c = vpl_irradiance(xp, nx, p, vpls.normals[j], vpls.flux[j], eps2)
                        * (scale * raise);
                    if c == Vec3::ZERO {
                        continue;
                    }
                    *a += c;
                    if k > 0 {
                        let sample = ShadowSample {
                            q: p,
                            n: vpls.normals[j],
                            f: c,
                            jitter: Vec3::ZERO,
                            light: j as u32,
                        };
                        offer(res, sample, luminance(c), &mut rng);
                    }
                }
            }
        },
        None,
    );
    t.push("shading", times.shade_ms);
    if k > 0 {
        t.push("shadow_rays", times.rays_ms);
    }
    let lights_per_pixel = shaded.par_iter().map(|p| p.1).collect();
    let a: Vec<Vec3> = shaded.into_par_iter().map(|p| p.0).collect();
    let shadow = ShadowSettings {
        filter_passes: settings.filter_passes,
        interleave_blur: (n > 1).then_some(settings.blur),
        seed,
    };
    let shadowed = shadowed_indirect(
        world,
        g,
        a,
        estimates,
        &shadow,
        &mut t,
        &mut AtrousBuffers::default(),
    );
    SlcOutput {
        indirect: shadowed.indirect,
        unshadowed: shadowed.unshadowed,
        ratio: shadowed.ratio,
        lights_per_pixel,
        shadow_rays: shadowed.rays,
        ism_points: maps.map(|m| (m.points_tested, m.points_splatted)),
        timings: t,
    }
}
