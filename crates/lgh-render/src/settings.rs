//! Everything that defines a frame besides the scene: one settings model for the library and
//! the command line.
//!
//! [`RenderSettings`] holds the settings every frame has, the settings shared by several
//! methods once ([`ShadowSettings`], [`Tiling`]), and one struct per method folder
//! ([`LghSettings`], [`SlcSettings`], [`PtSettings`]). With the `clap` feature every struct is
//! a `clap::Args` and every enum a `clap::ValueEnum`: the field docs are the `--help` text
//! and the defaults come from the `Default` impls, so the command line mirrors nothing by
//! hand. [`RenderSettings::validate`] checks the values a type cannot.

use lgh_core::lighting_grid::{GridError, LevelCount};

use crate::direct::DirectMode;
use crate::methods::lgh::LghSettings;
use crate::methods::pt::PtSettings;
use crate::methods::slc::SlcSettings;
use crate::methods::{Illumination, Method, lgh};
use crate::passes::vpl_gen::PathNumbers;
use crate::shading::interleave::BlurParams;
use crate::shading::ratio::{MAX_SHADOW_SAMPLES, RATIO_VISIBILITY, RatioFilter};

/// Which part of the radiance the output image holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Component {
    /// Emission + direct + indirect light.
    All,
    /// Emission + direct light from the primary lights only.
    Direct,
    /// Indirect light (the VPLs) only, to compare methods on what differs between them.
    Indirect,
}

/// Where a frame's indirect light is computed: the renderer runs on the CPU; a backend
/// crate (lgh-gpu) supplies GPU methods under the same names, which the command line and
/// the viewer pick with `--device gpu`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Device {
    /// The CPU (every method).
    #[default]
    Cpu,
    /// The GPU through wgpu (the methods and passes ported so far).
    Gpu,
}

/// A backend's stand-in for the method of a frame with these settings: the GPU method of the
/// same name, or `None` where the method, or its GPU version with these settings, has not
/// been ported (lgh-gpu's `gpu_method_for`).
pub type MethodMap = fn(&RenderSettings) -> Option<crate::Method>;

/// Filters of the shadow estimates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum ShadowFilter {
    /// Edge-avoiding a-trous wavelet filter (Dammertz et al. 2010).
    Atrous,
    /// No filter.
    None,
}

/// Ray-traced shadows through the ratio estimator, shared by the methods that use it (`lgh`,
/// `slc`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct ShadowSettings {
    /// lgh, slc: shadow samples (shadow rays) per pixel, 0 = no shadows (at most 16).
    /// Default: the method's own (lgh 5, slc 4; docs/design.md, "Defaults").
    #[cfg_attr(feature = "clap", arg(long = "shadow-samples"))]
    pub samples: Option<u32>,
    /// lgh, slc: filter applied to the shadow estimates.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = ShadowSettings::default().filter))]
    pub filter: ShadowFilter,
    /// lgh, slc: a-trous passes (0 to 12; pass i steps 2^i pixels).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = ShadowSettings::default().filter_passes))]
    pub filter_passes: u32,
    /// lgh, slc: the a-trous filter's colour weight c_phi of its first pass (Dammertz et al.
    /// 2010; halved every pass): larger smooths the shadow ratio more across its own edges.
    /// The demo's is 0.5 ([`DEMO_FILTER_COLOR`]); 0.1 measured more accurate for both methods
    /// (docs/design.md, "Defaults").
    #[cfg_attr(feature = "clap", arg(long, default_value_t = ShadowSettings::default().filter_color))]
    pub filter_color: f32,
    /// lgh, slc: the a-trous filter's weight a_phi on the unshadowed sums A: taps whose
    /// ln lum(A) differ by d weigh exp(-d^2 / a_phi), so that the ratio is not smoothed across
    /// a place where A changes fast (a room's corners, which came out too bright); 0 = no
    /// such weight (docs/design.md, "A-trous filter").
    #[cfg_attr(feature = "clap", arg(long, default_value_t = ShadowSettings::default().filter_unshadowed))]
    pub filter_unshadowed: f32,
}

/// The LGH demo's colour weight of the a-trous filter (its c_phi).
pub const DEMO_FILTER_COLOR: f32 = 0.5;

impl Default for ShadowSettings {
    fn default() -> Self {
        Self {
            samples: None,
            filter: ShadowFilter::Atrous,
            filter_passes: 5,
            filter_color: 0.1,
            filter_unshadowed: 0.01,
        }
    }
}

impl ShadowSettings {
    /// Shadow samples k per pixel for a method that is `shadowed` (0 if not) and takes
    /// `default` unless `samples` is given, at most [`MAX_SHADOW_SAMPLES`].
    #[must_use]
    pub fn k(&self, shadowed: bool, default: u32) -> usize {
        if shadowed {
            self.samples.unwrap_or(default).min(MAX_SHADOW_SAMPLES) as usize
        } else {
            0
        }
    }

    /// A-trous passes, 0 without the filter.
    #[must_use]
    pub fn passes(&self) -> u32 {
        match self.filter {
            ShadowFilter::Atrous => self.filter_passes,
            ShadowFilter::None => 0,
        }
    }
}

/// Interleaved sampling and light binning, shared by the tiled methods (`lgh`, `slc`); each
/// has its own defaults.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct Tiling {
    /// lgh, slc: n x n interleaved sampling: each of the n^2 sub-images shades 1/n^2 of the
    /// lights (of each level, for lgh), then a discontinuity-aware blur recombines them.
    /// Default: 2 for lgh renders, 4 in the viewer (the paper: none), 8 for slc (the
    /// paper's).
    #[cfg_attr(feature = "clap", arg(long))]
    pub interleave: Option<u32>,
    /// lgh, slc: screen tile edge in sub-image pixels for light binning. Default: 16
    /// full-resolution pixels for lgh (16 / n sub-image pixels with n x n interleaving, at least
    /// 4), 16 sub-image pixels for slc. (`--tile` renders one piece of the frame.)
    #[cfg_attr(feature = "clap", arg(long = "tile-size"))]
    pub tile: Option<u32>,
    /// The discontinuity-aware blur that recombines interleaved sub-images.
    #[cfg_attr(feature = "clap", arg(skip = BlurParams::defaults()))]
    #[serde(skip)]
    pub blur: BlurParams,
}

impl Default for Tiling {
    fn default() -> Self {
        Self {
            interleave: None,
            tile: None,
            blur: BlurParams::defaults(),
        }
    }
}

/// Default C of [`RenderSettings::vpl_clamp`]: eps = 0.04 R at 10,000 VPLs, the fixed
/// 0.01 R from 160,000 on (docs/design.md, "Clamps").
pub const DEFAULT_VPL_CLAMP: f32 = 4.0;

/// Largest eps of [`RenderSettings::vpl_clamp`], as a fraction of the scene's radius.
pub const MAX_VPL_CLAMP_FRACTION: f32 = 0.05;

/// Everything that defines a frame besides the scene.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct RenderSettings {
    /// Image width in pixels.
    #[cfg_attr(feature = "clap", arg(skip = RenderSettings::default().width))]
    pub width: u32,
    /// Image height in pixels.
    #[cfg_attr(feature = "clap", arg(skip = RenderSettings::default().height))]
    pub height: u32,
    /// How the indirect light is computed (`brute` is the exact reference, slow).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = RenderSettings::default().method))]
    pub method: Method,
    /// Render only this rectangle of the frame (and the guard band its filters need): its
    /// pixels equal the whole frame's ([`crate::region`]); `None` renders the whole frame.
    #[cfg_attr(feature = "clap", arg(skip))]
    #[serde(skip)]
    pub region: Option<crate::region::Region>,
    /// Offset of every pixel's primary ray from the pixel centre, in pixels (each component
    /// in [-0.5, 0.5)); zero for a single frame, set per frame by an accumulation so that
    /// the mean is anti-aliased ([`crate::accumulate::subpixel_jitter`]).
    #[cfg_attr(feature = "clap", arg(skip))]
    #[serde(skip)]
    pub jitter: glam::Vec2,
    /// Primary rays per pixel at geometric edges (silhouettes, creases; 1 = pixel centres
    /// only, at most 64): edge pixels take the shading of the neighbours their sub-pixel
    /// samples land on, so that edges are anti-aliased at the cost of a few primary rays
    /// ([`crate::passes::edge_aa`]). An accumulation jitters whole frames instead.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = RenderSettings::default().edge_samples))]
    pub edge_samples: u32,
    /// Number of virtual point lights (VPLs) to generate by light tracing.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = RenderSettings::default().vpls))]
    pub vpls: usize,
    /// Maximum VPLs per light path, i.e. indirect bounces represented (1 = one bounce; at
    /// most 64).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = RenderSettings::default().bounces))]
    pub bounces: u32,
    /// Numbers that drive the light paths (both unbiased; `sobol` is stratified).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = RenderSettings::default().path_numbers))]
    pub path_numbers: PathNumbers,
    /// Seed of all random choices; the same seed gives the same image on any thread count.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = RenderSettings::default().seed))]
    pub seed: u64,
    /// Which part of the radiance to write.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = RenderSettings::default().component))]
    pub component: Component,
    /// Shadow-ray samples per pixel for area lights (emissive triangles) in the direct pass
    /// (stratified; at most 1024).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = RenderSettings::default().area_samples))]
    pub area_samples: u32,
    /// How the direct light of area lights is estimated: `analytic` (closed-form unshadowed
    /// light times a filtered shadow ratio; noise-free where the light is wholly visible) or
    /// `sampled` (the plain mean of the shadowed samples).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = RenderSettings::default().direct))]
    pub direct: DirectMode,
    /// Camera exposure E: the multiplier of PNG output, and the E of the error bounds of the
    /// light ranges (slc, pt-*). Default: the scene file's, else 1.
    #[cfg_attr(feature = "clap", arg(long))]
    pub exposure: Option<f32>,
    /// slc, pt-*: error bound epsilon_max of the light ranges (smaller = longer ranges, less
    /// noise, slower). Default: the paper's 0.0005 for slc, 0.125 for the path tracer.
    #[cfg_attr(feature = "clap", arg(long))]
    pub error_bound: Option<f32>,
    /// eps of the 1/(d^2 + eps^2) clamp, as a fraction of the scene's bounding-sphere radius
    /// (0.01, as the LGH authors' code; docs/design.md, "Clamps").
    #[cfg_attr(feature = "clap", arg(skip = RenderSettings::default().clamp_fraction))]
    pub clamp_fraction: f32,
    /// C of the clamp that grows as VPLs get fewer: eps = R max(0.01, min(C / sqrt(VPLs),
    /// 0.05)) with R the scene's bounding-sphere radius. A VPL stands for a patch of
    /// surface whose size shrinks like 1 / sqrt(VPLs); near corners, where a VPL on one wall
    /// lights the other from up close, a smaller clamp draws bright dots. 0 = the LGH
    /// authors' fixed 0.01 R (docs/design.md, "Clamps").
    #[cfg_attr(feature = "clap", arg(long, default_value_t = RenderSettings::default().vpl_clamp))]
    pub vpl_clamp: f32,
    /// brute-sampled: shadow rays per pixel, drawn in proportion to each VPL's unshadowed
    /// light (stratified), at most 65536. More rays, less visibility noise; the VPLs' own
    /// noise is the same as brute's.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = RenderSettings::default().brute_rays))]
    pub brute_rays: u32,
    /// Ray-traced shadows of the methods that use the ratio estimator.
    #[cfg_attr(feature = "clap", command(flatten))]
    pub shadows: ShadowSettings,
    /// Interleaving and light binning of the tiled methods.
    #[cfg_attr(feature = "clap", command(flatten))]
    pub tiling: Tiling,
    /// Settings of the `lgh` methods.
    #[cfg_attr(feature = "clap", command(flatten))]
    pub lgh: LghSettings,
    /// Settings of the `slc` methods.
    #[cfg_attr(feature = "clap", command(flatten))]
    pub slc: SlcSettings,
    /// Settings of the `pt` methods.
    #[cfg_attr(feature = "clap", command(flatten))]
    pub pt: PtSettings,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 640,
            height: 360,
            region: None,
            jitter: glam::Vec2::ZERO,
            edge_samples: crate::passes::edge_aa::DEFAULT_EDGE_SAMPLES,
            method: lgh::LGH,
            vpls: 10_000,
            bounces: 3,
            path_numbers: PathNumbers::Sobol,
            seed: 0,
            component: Component::All,
            area_samples: 8,
            direct: DirectMode::Analytic,
            exposure: None,
            error_bound: None,
            clamp_fraction: 0.01,
            vpl_clamp: DEFAULT_VPL_CLAMP,
            brute_rays: crate::methods::brute::sampled::DEFAULT_BRUTE_RAYS,
            shadows: ShadowSettings::default(),
            tiling: Tiling::default(),
            lgh: LghSettings::default(),
            slc: SlcSettings::default(),
            pt: PtSettings::default(),
        }
    }
}

/// A setting out of its range: names the setting (as its command-line flag), the value and
/// what is expected.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("--{name} {value}: {expected}")]
pub struct SettingsError {
    /// The setting, as its command-line flag without the dashes.
    pub name: &'static str,
    /// The value given.
    pub value: String,
    /// What the value must be.
    pub expected: String,
}

/// Most VPLs a frame: 2^24 (about 4 GB with their hierarchy).
pub const MAX_VPLS: usize = 1 << 24;

/// The most VPLs per light path (`--bounces`): 64, where a path's throughput has long
/// vanished in any scene whose albedos are below one.
pub const MAX_BOUNCES: u32 = 64;

/// The most area-light samples per pixel (`--area-samples`): 1024, far past where the
/// analytic estimator's filtered ratio stops improving.
pub const MAX_AREA_SAMPLES: u32 = 1024;

/// Parses `WIDTHxHEIGHT` with both sides positive.
///
/// # Errors
/// Not of that form, a side of zero, or more than [`MAX_PIXELS`] pixels.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}' is not WIDTHxHEIGHT (e.g. 640x360)"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("'{s}': width is not a number"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("'{s}': height is not a number"))?;
    if w == 0 || h == 0 {
        return Err(format!("'{s}': width and height must be at least 1"));
    }
    if u64::from(w) * u64::from(h) > MAX_PIXELS {
        return Err(format!(
            "'{s}': image too large (at most {} pixels)",
            MAX_PIXELS
        ));
    }
    Ok((w, h))
}

/// Largest image: 2^28 pixels (16384 x 16384).
pub const MAX_PIXELS: u64 = 1 << 28;

/// The error bound of stochastic light ranges (Tokuyoshi & Harada 2016, Eqs. 6 and 7):
/// epsilon_max and the camera exposure E it is relative to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorBound {
    /// epsilon_max.
    pub epsilon_max: f32,
    /// Camera exposure E.
    pub exposure: f32,
}

impl RenderSettings {
    /// The shadow samples per pixel of the chosen method: `--shadow-samples`, or the
    /// method's default ([`crate::methods::IndirectMethod::default_shadow_samples`]).
    #[must_use]
    pub fn shadow_samples(&self) -> u32 {
        self.shadows
            .samples
            .unwrap_or_else(|| self.method.get().default_shadow_samples())
    }

    /// Settings that are valid but probably not what was meant, one line each (the image
    /// of a VPL method with no VPLs has no indirect light).
    #[must_use]
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.method.illumination() == Illumination::FromVpls {
            if self.vpls == 0 {
                out.push("--vpls 0: no VPLs, so the image has no indirect light".to_string());
            }
            if self.bounces == 0 {
                out.push("--bounces 0: no VPLs, so the image has no indirect light".to_string());
            }
        }
        let lgh = &self.lgh;
        if self.method == crate::methods::lgh::LGH
            && lgh.estimator == crate::methods::lgh::Estimator::Paper
            && lgh.start_level == 0
            && lgh.shadow_from_level > 0
        {
            out.push(format!(
                "--estimator paper with --start-level 0 and --shadow-from-level {}: the VPLs \
                 shaded near each pixel take the shadow ratio of the levels from {} up (the \
                 two rooms come out 17% dark); add --start-level 1 or --shadow-from-level 0",
                lgh.shadow_from_level, lgh.shadow_from_level
            ));
        }
        out
    }

    /// The exposure E: [`RenderSettings::exposure`], else the scene's.
    #[must_use]
    pub fn exposure_or(&self, scene_exposure: f32) -> f32 {
        self.exposure.unwrap_or(scene_exposure)
    }

    /// The error bound of a method's light ranges: [`RenderSettings::error_bound`], else the
    /// method's `default`, with [`RenderSettings::exposure_or`] the scene's exposure.
    #[must_use]
    pub fn error_bound_or(&self, default: f32, scene_exposure: f32) -> ErrorBound {
        ErrorBound {
            epsilon_max: self.error_bound.unwrap_or(default),
            exposure: self.exposure_or(scene_exposure),
        }
    }

    /// How the methods with the ratio estimator recombine and filter their shadow estimates
    /// under n x n interleaving (`n` = 1: none).
    #[must_use]
    pub fn ratio_filter(&self, n: u32) -> RatioFilter {
        RatioFilter {
            passes: self.shadows.passes(),
            interleave_blur: (n > 1).then_some(self.tiling.blur.with_phases(n)),
            max_ratio: RATIO_VISIBILITY,
            c_phi: self.shadows.filter_color,
            a_phi: self.shadows.filter_unshadowed,
        }
    }

    /// Checks every value a type does not restrict.
    ///
    /// # Errors
    /// The first setting out of its range.
    pub fn validate(&self) -> Result<(), SettingsError> {
        let err = |name: &'static str, value: &dyn std::fmt::Display, expected: &str| {
            Err(SettingsError {
                name,
                value: value.to_string(),
                expected: expected.to_string(),
            })
        };
        let positive = |name: &'static str, v: f32| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                err(name, &v, "must be a positive number")
            }
        };
        let in_range = |name: &'static str, v: u32, lo: u32, hi: u32| {
            if (lo..=hi).contains(&v) {
                Ok(())
            } else {
                err(name, &v, &format!("expected {lo} to {hi}"))
            }
        };
        if self.width == 0 || self.height == 0 {
            let size = format!("{}x{}", self.width, self.height);
            return err("size", &size, "width and height must be at least 1");
        }
        if u64::from(self.width) * u64::from(self.height) > MAX_PIXELS {
            let size = format!("{}x{}", self.width, self.height);
            return err("size", &size, &format!("at most {MAX_PIXELS} pixels"));
        }
        if let Some(e) = self.exposure {
            positive("exposure", e)?;
        }
        if let Some(e) = self.error_bound {
            positive("error-bound", e)?;
        }
        if let Some(r) = &self.region
            && let Err(e) = r.check(self.width, self.height)
        {
            return err(
                "region",
                &format!("{},{},{},{}", r.x0, r.y0, r.x1, r.y1),
                &e,
            );
        }
        if self.vpls > MAX_VPLS {
            return err(
                "vpls",
                &self.vpls,
                &format!(
                    "at most {MAX_VPLS} (each VPL needs up to {} bytes with its hierarchy)",
                    crate::budget::BYTES_PER_VPL
                ),
            );
        }
        positive("alpha", self.lgh.alpha)?;
        positive("filter-color", self.shadows.filter_color)?;
        let a_phi = self.shadows.filter_unshadowed;
        if !(a_phi.is_finite() && a_phi >= 0.0) {
            return err("filter-unshadowed", &a_phi, "expected a finite number >= 0");
        }
        positive("clamp-fraction", self.clamp_fraction)?;
        if !(self.vpl_clamp.is_finite() && (0.0..=1000.0).contains(&self.vpl_clamp)) {
            return err("vpl-clamp", &self.vpl_clamp, "expected 0 to 1000");
        }
        if !(0.0..=1.0).contains(&self.lgh.fill_below) {
            return err("fill-below", &self.lgh.fill_below, "expected 0 to 1");
        }
        if let Some(k) = self.shadows.samples {
            in_range("shadow-samples", k, 0, MAX_SHADOW_SAMPLES)?;
        }
        in_range("spp", self.pt.spp, 1, 1 << 20)?;
        in_range(
            "brute-rays",
            self.brute_rays,
            1,
            crate::methods::brute::sampled::MAX_BRUTE_RAYS,
        )?;
        in_range(
            "filter-passes",
            self.shadows.filter_passes,
            0,
            crate::denoise::atrous::MAX_PASSES,
        )?;
        in_range("area-samples", self.area_samples, 0, MAX_AREA_SAMPLES)?;
        in_range("bounces", self.bounces, 0, MAX_BOUNCES)?;
        in_range(
            "edge-samples",
            self.edge_samples,
            1,
            crate::passes::edge_aa::MAX_EDGE_SAMPLES,
        )?;
        if let Some(n) = self.tiling.interleave {
            in_range("interleave", n, 1, 16)?;
        }
        if let Some(t) = self.tiling.tile {
            in_range("tile-size", t, 1, 256)?;
        }
        in_range("start-level", self.lgh.start_level, 0, 1)?;
        if let Some(l) = self.lgh.only_level {
            in_range("only-level", l, 0, lgh_core::lighting_grid::MAX_LEVELS)?;
        }
        if let Some((name, expected)) = self.lgh.unbiased_conflict() {
            let value = match name {
                "shadow-target" => format!("{:?}", self.lgh.shadow_target).to_lowercase(),
                "jitter-at" => format!("{:?}", self.lgh.jitter).to_lowercase(),
                _ => self.lgh.construction.name().to_string(),
            };
            return err(name, &value, expected);
        }
        if let LevelCount::Fixed(l) = self.lgh.levels {
            in_range("levels", l, 1, lgh_core::lighting_grid::MAX_LEVELS)?;
        }
        Ok(())
    }
}

/// A frame that could not be rendered.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// A setting is out of its range.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// The VPLs could not form a lighting grid hierarchy.
    #[error("lighting grid hierarchy: {0}")]
    Grid(#[from] GridError),
    /// An animation puts the scene where it cannot be rendered at a time (a camera keyframe
    /// pair that passes through its own look-at point, geometry moved out of range).
    #[error("at time {time} s: {message}")]
    Animation {
        /// The scene's time, in seconds.
        time: f32,
        /// What is wrong.
        message: String,
    },
    /// A backend outside this crate (the GPU) could not run the method, with its message.
    #[error("{0}")]
    Backend(String),
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The defaults are valid, and each check names its setting.
    #[test]
    fn validation_names_the_setting() {
        assert_eq!(RenderSettings::default().validate(), Ok(()));
        let mut s = RenderSettings::default();
        s.lgh.alpha = -1.0;
        let e = s.validate().unwrap_err();
        assert_eq!(e.to_string(), "--alpha -1: must be a positive number");
        let mut s = RenderSettings::default();
        s.shadows.samples = Some(17);
        assert_eq!(s.validate().unwrap_err().name, "shadow-samples");
        let mut s = RenderSettings::default();
        s.tiling.interleave = Some(0);
        assert_eq!(s.validate().unwrap_err().name, "interleave");
        let mut s = RenderSettings::default();
        s.shadows.filter_passes = 13;
        assert_eq!(
            s.validate().unwrap_err().to_string(),
            "--filter-passes 13: expected 0 to 12"
        );
        let s = RenderSettings {
            width: 0,
            ..RenderSettings::default()
        };
        assert_eq!(s.validate().unwrap_err().name, "size");
    }

    /// The paper's estimate with the VPLs shaded near the pixel but not shadow candidates
    /// gets a warning; the paper's own levels and the unbiased estimate do not.
    #[test]
    fn paper_estimate_with_unshadowed_vpls_warns() {
        use crate::methods::lgh::{Estimator, LGH};
        let mut s = RenderSettings {
            method: LGH,
            ..RenderSettings::default()
        };
        assert!(s.warnings().is_empty());
        s.lgh.estimator = Estimator::Paper;
        assert_eq!(s.warnings().len(), 1, "{:?}", s.warnings());
        s.lgh.start_level = 1;
        assert!(s.warnings().is_empty());
    }

    /// The shadow sample count is the method's default unless given, clamped, and zero for
    /// unshadowed methods; no filter means no passes.
    #[test]
    fn shadow_settings_resolve() {
        let s = ShadowSettings {
            samples: Some(40),
            filter: ShadowFilter::None,
            ..ShadowSettings::default()
        };
        assert_eq!(s.k(true, 5), MAX_SHADOW_SAMPLES as usize);
        assert_eq!(s.k(false, 5), 0);
        assert_eq!(s.passes(), 0);
        let d = ShadowSettings::default();
        assert_eq!((d.k(true, 5), d.k(true, 4)), (5, 4));
        let mut r = RenderSettings::default();
        assert_eq!(r.shadow_samples(), lgh::DEFAULT_SHADOW_SAMPLES);
        r.method = crate::methods::slc::SLC;
        assert_eq!(
            r.shadow_samples(),
            crate::methods::slc::DEFAULT_SHADOW_SAMPLES
        );
        r.shadows.samples = Some(2);
        assert_eq!(r.shadow_samples(), 2);
    }
}
