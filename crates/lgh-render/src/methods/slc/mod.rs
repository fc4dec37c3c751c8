//! Stochastic tiled lighting of VPLs (Tokuyoshi & Harada 2016, "Stochastic Light Culling",
//! Algorithm 1, sections 4.1-4.2), and the clamped tiled lighting it is compared with
//! (Appendix A).
//!
//! 1. **Light ranges** (in parallel): alpha_i from the error bound epsilon_max and the
//!    exposure E (Eq. 6, with the intensity each light is shaded with), one xi_i per light and
//!    frame from TEA of (light index, frame seed), r_i = f^-1(alpha_i xi_i) (Eq. 3). Clamped:
//!    r_i from Appendix A.
//! 2. **Culling**: n x n interleaved sampling ([`crate::shading::interleave`], 8 x 8 in the paper): light
//!    i belongs to sub-image i mod n^2 and is shaded there with n^2 times its flux; each
//!    sub-image bins its lights' spheres (c_i, r_i) into 16 x 16-pixel tiles with per-tile
//!    depth bounds ([`crate::shading::tiles`], shared with LGH).
//! 3. **Shading**: each pixel sums its tile's lights with the stochastic fall-off
//!    max(alpha_i, f(l)) inside r_i (Eq. 2) or, clamped, f(l) inside r_i. Lights with l < r_i
//!    are the pixel's "lights per pixel".
//! 4. With n > 1, the discontinuity-aware blur recombines the sub-images (section 4.4's
//!    geometry-aware filter).
//!
//! The paper shadows the VPLs with imperfect shadow maps: with [`SlcSettings::ism`] each light
//! is tested against its map ([`crate::methods::slc::ism`], with the range-based point-cloud culling of
//! section 4.3). Otherwise the `slc` methods are either unshadowed or shadowed through the
//! same k-sample ratio estimator as LGH ([`crate::shading::ratio`]), with each light offered with its
//! stochastic contribution as weight.

use std::sync::Arc;

use glam::Vec3;
use lgh_core::color::luminance;
use lgh_core::light_range::{alpha_point, clamped_range, light_xi, stochastic_range};
use lgh_core::rng::Rng;
use lgh_core::timing::Timings;
use lgh_core::vpl::{Vpls, vpl_irradiance};
use rayon::prelude::*;

use crate::memory::FrameMemory;
use crate::methods::{IndirectMethod, Method, MethodInputs, MethodOutput};
use crate::passes::par_filled;
use crate::settings::{ErrorBound, RenderError};
use crate::shading::ratio::shadowed_indirect;
use crate::shading::reservoirs::{ReservoirLayout, ShadowSample, offer};
use crate::shading::shadow_pass::ShadowPass;
use crate::shading::tiles::{BinLights, InterleavedBins};

pub mod ism;

use ism::{IsmSettings, PointCloud, ShadowMaps};

/// Stochastic light culling: random unbiased light ranges, tiled lighting.
pub const SLC: Method = Method::new(&Slc(RangeMode::Stochastic));
/// Tiled lighting with light ranges clamped from the error bound (biased darker).
pub const SLC_CLAMPED: Method = Method::new(&Slc(RangeMode::Clamped));

/// Random-stream tag of the SLC shading pass.
const STREAM_SLC: u64 = 0x51c;

/// The error bound epsilon_max of the light ranges when none is set (the paper's 0.0005).
pub const DEFAULT_ERROR_BOUND: f32 = 0.0005;
/// Shadow samples per pixel when `--shadow-samples` is not given.
pub const DEFAULT_SHADOW_SAMPLES: u32 = 4;
/// Interleaving n of n x n sub-images when none is set (the paper's 8).
pub const DEFAULT_INTERLEAVE: u32 = 8;
/// Screen tile edge in sub-image pixels when none is set.
pub const DEFAULT_TILE: u32 = 16;

/// How light ranges are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RangeMode {
    /// Random ranges with the stochastic fall-off (unbiased; `--method slc`).
    Stochastic,
    /// Fixed ranges from the error bound, light dropped beyond (biased darker;
    /// `--method slc-clamped`).
    Clamped,
}

/// Settings of the SLC methods. The error bound and exposure
/// ([`crate::settings::RenderSettings::error_bound`], default [`DEFAULT_ERROR_BOUND`]), the
/// shadow samples and filter, and the interleaving ([`crate::settings::Tiling`], default
/// [`DEFAULT_INTERLEAVE`]) are shared with other methods.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct SlcSettings {
    /// slc: seed of the per-light random numbers xi_i that draw the light ranges.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = SlcSettings::default().frame_seed))]
    pub frame_seed: u32,
    /// slc: shadows from imperfect shadow maps, as the paper renders them (section 4.3): a
    /// 32x32 paraboloid depth map per VPL, splatted from a point cloud after the range-based
    /// culling of its Program 1. Replaces the ray-traced shadow samples.
    #[cfg_attr(feature = "clap", arg(long))]
    pub ism: bool,
    /// slc --ism: points splatted per map before culling (the paper uses 8192).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = SlcSettings::default().ism_points))]
    pub ism_points: u32,
}

impl Default for SlcSettings {
    fn default() -> Self {
        Self {
            frame_seed: 0,
            ism: false,
            ism_points: IsmSettings::default().points_per_map,
        }
    }
}

impl SlcSettings {
    /// The imperfect shadow maps' settings, if they are on.
    #[must_use]
    pub fn ism_settings(&self) -> Option<IsmSettings> {
        self.ism.then(|| IsmSettings {
            points_per_map: self.ism_points,
            ..IsmSettings::default()
        })
    }
}

/// The `slc` methods, by their range mode.
struct Slc(RangeMode);

impl IndirectMethod for Slc {
    fn name(&self) -> &'static str {
        match self.0 {
            RangeMode::Stochastic => "slc",
            RangeMode::Clamped => "slc-clamped",
        }
    }

    fn about(&self) -> &'static str {
        match self.0 {
            RangeMode::Stochastic => {
                "Stochastic light culling (Tokuyoshi & Harada 2016): random unbiased light ranges, tiled lighting; shadows through the ratio estimator (--shadow-samples, 0 = none)"
            }
            RangeMode::Clamped => {
                "Tiled lighting with light ranges clamped from the error bound (biased darker)"
            }
        }
    }

    fn default_shadow_samples(&self) -> u32 {
        DEFAULT_SHADOW_SAMPLES
    }

    fn render(
        &self,
        inputs: &MethodInputs,
        memory: &mut FrameMemory,
    ) -> Result<MethodOutput, RenderError> {
        Ok(render_slc(inputs, self.0, memory))
    }
}

/// Statistics of an `slc` frame.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct SlcStats {
    /// Mean number of lights evaluated (within range) per pixel that sees a surface.
    pub avg_lights_per_pixel: f64,
    /// Shadow rays traced.
    pub shadow_rays: u64,
    /// Error bound epsilon_max of the light ranges.
    pub error_bound: f32,
    /// n of the n x n interleaving.
    pub interleave: u32,
    /// Seed of the light ranges' random numbers.
    pub frame_seed: u32,
    /// Shadow samples per pixel used (0 without ray-traced shadows).
    pub shadow_samples: u32,
    /// With imperfect shadow maps: points tested by the culling.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ism_points_tested: Option<u64>,
    /// With imperfect shadow maps: points splatted.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ism_points_splatted: Option<u64>,
}

/// Per-light data of a frame: the range r_i and alpha_i (0 for clamped ranges, where the
/// fall-off is not raised).
struct Ranges {
    range: Vec<f32>,
    alpha: Vec<f32>,
}

/// Step 1 of Algorithm 1: every light's range, from the flux it is shaded with
/// (`scale` x flux). A VPL's largest radiant intensity is its flux / pi (largest channel).
fn light_ranges(
    vpls: &Vpls,
    mode: RangeMode,
    s: ErrorBound,
    frame_seed: u32,
    scale: f32,
    eps2: f32,
) -> Ranges {
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
                    let alpha = alpha_point(s.epsilon_max, s.exposure, intensity);
                    let xi = light_xi(i as u32, frame_seed);
                    (stochastic_range(alpha, xi, eps2), alpha)
                }
                RangeMode::Clamped => (
                    clamped_range(s.epsilon_max, s.exposure, n, intensity, eps2),
                    0.0,
                ),
            }
        })
        .unzip();
    Ranges { range, alpha }
}

/// Renders the indirect light of the VPLs with stochastic (or clamped) tiled lighting,
/// shadowed through the ratio estimator, by imperfect shadow maps ([`SlcSettings::ism`]), or
/// not at all (no shadow samples). The statistics are an [`SlcStats`].
#[must_use]
pub fn render_slc(
    inputs: &MethodInputs,
    mode: RangeMode,
    memory: &mut FrameMemory,
) -> MethodOutput {
    let (world, g, vpls, all) = (inputs.world, inputs.gbuffer, inputs.vpls, inputs.settings);
    let (settings, seed) = (&all.slc, all.seed);
    let bound = all.error_bound_or(DEFAULT_ERROR_BOUND, world.scene.exposure);
    let ism = settings.ism_settings();
    let mut t = Timings::default();
    let n_px = g.len();
    let n = all.tiling.interleave.unwrap_or(DEFAULT_INTERLEAVE).max(1);
    let n2 = (n * n) as usize;
    let scale = n2 as f32;
    let eps2 = inputs.eps() * inputs.eps();
    let ranges = t.time("light_ranges", || {
        light_ranges(vpls, mode, bound, settings.frame_seed, scale, eps2)
    });
    // Step 2: per sub-image, its lights (i = s mod n^2) binned into its tiles.
    let bins = t.time("culling", || {
        let sub: Vec<u16> = (0..vpls.len()).map(|i| (i % n2) as u16).collect();

        InterleavedBins::build(
            g,
            inputs.camera,
            all.tiling.tile.unwrap_or(DEFAULT_TILE),
            n,
            BinLights {
                // A VPL emits nothing behind its plane.
                facing: &vpls.normals,
                ..BinLights::spheres(&vpls.positions, &ranges.range)
            },
            &sub,
        )
    });
    // Imperfect shadow maps replace the ray-traced shadow samples.
    let k = all.shadows.k(ism.is_none(), DEFAULT_SHADOW_SAMPLES);
    let maps = ism.map(|ism| {
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
                        let sample = || ShadowSample {
                            q: p,
                            n: vpls.normals[j],
                            f: c,
                            jitter: Vec3::ZERO,
                            light: j as u32,
                            gain: Vec3::ONE,
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
    let lights_per_pixel: Vec<u32> = shaded.par_iter().map(|p| p.1).collect();
    let a: Vec<Vec3> = shaded.into_par_iter().map(|p| p.0).collect();
    let filter = all.ratio_filter(n);
    let shadowed = shadowed_indirect(world, g, a, estimates, &filter, &mut t, memory);
    let stats = SlcStats {
        avg_lights_per_pixel: g.mean_over_hits(&lights_per_pixel),
        shadow_rays: shadowed.rays,
        error_bound: bound.epsilon_max,
        interleave: n,
        frame_seed: settings.frame_seed,
        shadow_samples: k as u32,
        ism_points_tested: maps.as_ref().map(|m| m.points_tested),
        ism_points_splatted: maps.as_ref().map(|m| m.points_splatted),
    };
    MethodOutput {
        radiance: shadowed.indirect,
        unshadowed: Some(shadowed.unshadowed),
        shadow_ratio: Some(shadowed.ratio),
        lights_per_pixel: Some(lights_per_pixel),
        shadow_rays: shadowed.rays,
        timings: t,
        stats: Some(Arc::new(stats)),
    }
}
