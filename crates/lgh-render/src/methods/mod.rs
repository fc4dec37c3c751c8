//! Indirect-lighting methods: one folder each, one contract.
//!
//! A method turns the frame's inputs ([`MethodInputs`]: the G-buffer, the camera, the VPLs and
//! the settings) into a [`MethodOutput`]: the radiance it adds to the image, and what it can
//! tell about it (the unshadowed sum and shadow ratio of the ratio estimator, lights per
//! pixel, rays, pass timings, its own statistics as serde data). The frame recipe
//! ([`crate::frame`]) runs whichever [`Method`] the settings name; it knows no method by name.
//!
//! | folder | methods | paper |
//! | --- | --- | --- |
//! | [`brute`] | `brute`, `brute-unshadowed` | the exact reference |
//! | [`lgh`] | `lgh`, `lgh-unshadowed` | Lin & Yuksel 2019 |
//! | [`slc`] | `slc`, `slc-clamped` | Tokuyoshi & Harada 2016, sections 3-4 |
//! | [`pt`] | `pt-slc`, `pt-uniform`, `pt-clamped` | Tokuyoshi & Harada 2016, section 5 |
//!
//! # Adding a method
//! Write a type implementing [`IndirectMethod`] in a folder of its own, give it a
//! [`Method`] constant there, and add one line for the folder to the `register!` list in
//! this file: the command line, the statistics and the benchmarks find it through
//! [`METHODS`]. ARCHITECTURE.md shows the smallest example.

use std::any::Any;
use std::fmt;
use std::sync::Arc;

use glam::Vec3;
use lgh_core::timing::Timings;
use lgh_core::vpl::Vpls;
use lgh_scene::camera::CameraFrame;

use crate::memory::FrameMemory;
use crate::passes::gbuffer::GBuffer;
use crate::progress::Progress;
use crate::settings::{RenderError, RenderSettings};
use crate::shading::ratio::ShadowRatio;
use crate::world::World;

// The method folders, declared outside the registry macro so that rustfmt (which does not
// look inside macro calls) formats them.
pub mod brute;
pub mod lgh;
pub mod pt;
pub mod slc;

/// Lists the methods of each folder in [`METHODS`].
macro_rules! register {
    ($($folder:ident => [$($method:ident),+],)+) => {
        /// Every method, in the order `--help` lists them.
        pub static METHODS: &[Method] = &[$($($folder::$method,)+)+];
    };
}

// The registry: one line per method folder.
register! {
    brute => [BRUTE, BRUTE_UNSHADOWED, BRUTE_SAMPLED],
    lgh => [LGH, LGH_UNSHADOWED],
    slc => [SLC, SLC_CLAMPED],
    pt => [PT_SLC, PT_UNIFORM, PT_CLAMPED],
}

/// What every method shades from.
#[derive(Clone, Copy)]
pub struct MethodInputs<'a> {
    /// The scene with its BVH and lights.
    pub world: &'a World,
    /// The frame's primary visibility.
    pub gbuffer: &'a GBuffer,
    /// The camera the G-buffer was rendered with.
    pub camera: &'a CameraFrame,
    /// The frame's VPLs (empty for methods that do not use them, and where the method's
    /// backend keeps them on its device: `vpl_count` says how many there are).
    pub vpls: &'a Vpls,
    /// How many VPLs the frame has: `vpls.len()`, or where the method's backend keeps
    /// them ([`crate::passes::vpl_gen::VplSet::kept`]) their number.
    pub vpl_count: usize,
    /// Where the backend keeps the VPLs split by normal bin
    /// ([`crate::passes::vpl_gen::VplSet::kept_bins`]), the number in each bin.
    pub vpl_bins: Option<[usize; lgh::NORMAL_BINS]>,
    /// All settings of the frame; a method reads the part that is its own.
    pub settings: &'a RenderSettings,
    /// Progress of long passes.
    pub progress: &'a dyn Progress,
}

impl MethodInputs<'_> {
    /// eps of the 1/(d^2 + eps^2) clamp in scene units: R max(f, min(C / sqrt(N), 0.05)),
    /// with R the scene's bounding-sphere radius, f [`RenderSettings::clamp_fraction`], C
    /// [`RenderSettings::vpl_clamp`] and N the frame's VPLs.
    #[must_use]
    pub fn eps(&self) -> f32 {
        clamp_eps(self.settings, self.vpl_count, self.world.radius)
    }
}

/// [`MethodInputs::eps`] for `vpls` VPLs in a scene of radius `radius`.
#[must_use]
pub fn clamp_eps(s: &RenderSettings, vpls: usize, radius: f32) -> f32 {
    let by_count = if vpls == 0 {
        0.0
    } else {
        (s.vpl_clamp / (vpls as f32).sqrt()).min(crate::settings::MAX_VPL_CLAMP_FRACTION)
    };
    s.clamp_fraction.max(by_count) * radius
}

/// What the frame needs from a method besides its radiance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Illumination {
    /// The method shades the frame's VPLs: its radiance is the indirect light, added to the
    /// exact direct light.
    FromVpls,
    /// The method computes all reflected light itself (a path tracer): the frame makes no
    /// VPLs and no direct pass, and the method's radiance is everything but the emission.
    AllReflected,
}

/// Statistics of a method, serialisable and readable back as their own type
/// ([`MethodOutput::stats`]). Implemented for every `Serialize + Debug` type.
pub trait MethodStats: Any + fmt::Debug + Send + Sync {
    /// The statistics as a JSON object (merged into `lgh render --stats`).
    fn to_json(&self) -> serde_json::Value;
}

impl<T: serde::Serialize + Any + fmt::Debug + Send + Sync> MethodStats for T {
    fn to_json(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or(serde_json::Value::Null)
    }
}

/// What a method produces for one frame.
#[derive(Clone, Debug, Default)]
pub struct MethodOutput {
    /// Radiance towards the camera per pixel: the indirect light, or all reflected light for
    /// [`Illumination::AllReflected`].
    pub radiance: Vec<Vec3>,
    /// Methods with the ratio estimator: the unshadowed sum A per pixel (before albedo / pi).
    pub unshadowed: Option<Vec<Vec3>>,
    /// Methods with the ratio estimator: the shadow ratio per pixel, filtered and raw.
    pub shadow_ratio: Option<ShadowRatio>,
    /// Lights evaluated per pixel (the LGH paper's overdraw, Fig. 5; SLC's lights per pixel).
    pub lights_per_pixel: Option<Vec<u32>>,
    /// Shadow rays traced, by the methods that count them (the ratio estimator's).
    pub shadow_rays: u64,
    /// Per-pass times (parts of the frame's `indirect`).
    pub timings: Timings,
    /// The method's own statistics.
    pub stats: Option<Arc<dyn MethodStats>>,
}

impl MethodOutput {
    /// The method's statistics as their own type `T`, if they are of that type.
    #[must_use]
    pub fn stats<T: MethodStats>(&self) -> Option<&T> {
        let any: &dyn Any = self.stats.as_deref()?;
        any.downcast_ref()
    }
}

/// The contract of an indirect-lighting method.
pub trait IndirectMethod: Sync + Send {
    /// Name on the command line and in statistics (kebab-case).
    fn name(&self) -> &'static str;
    /// One line for `--help`.
    fn about(&self) -> &'static str;
    /// Whether the method shades the VPLs or computes all reflected light itself.
    fn illumination(&self) -> Illumination {
        Illumination::FromVpls
    }
    /// Shadow samples per pixel when `--shadow-samples` is not given (for the methods that
    /// trace shadow samples through the ratio estimator).
    fn default_shadow_samples(&self) -> u32 {
        0
    }
    /// Renders one frame's share of the method. `memory` holds buffers that frames reuse.
    ///
    /// # Errors
    /// The method cannot render these inputs (for example VPLs that form no hierarchy).
    fn render(
        &self,
        inputs: &MethodInputs,
        memory: &mut FrameMemory,
    ) -> Result<MethodOutput, RenderError>;
    /// The frame's direct light ([`crate::direct::render_direct`]'s output for `g` with the
    /// settings `s`) computed by this method's own backend, or `Ok(None)`, the default, for
    /// the CPU's pass. lgh-gpu's methods run it on the GPU.
    ///
    /// # Errors
    /// The backend failed.
    fn direct(
        &self,
        _world: &World,
        _g: &GBuffer,
        _s: &RenderSettings,
    ) -> Result<Option<crate::direct::DirectOutput>, RenderError> {
        Ok(None)
    }
    /// The frame's VPLs (`generate_vpls(world, s.vpls, s.bounces, s.seed,
    /// s.path_numbers)`'s set) generated on this method's own backend, or `Ok(None)`, the
    /// default, for the CPU's pass. lgh-gpu's methods trace the light paths on the GPU; a
    /// method whose every later pass runs there may keep them there
    /// ([`crate::passes::vpl_gen::VplSet::kept`]): its [`IndirectMethod::render`] then
    /// gets an empty [`MethodInputs::vpls`].
    ///
    /// # Errors
    /// The backend failed.
    fn generate_vpls(
        &self,
        _world: &World,
        _s: &RenderSettings,
    ) -> Result<Option<crate::passes::vpl_gen::VplSet>, RenderError> {
        Ok(None)
    }
    /// The frame's edge resolve (`EdgeResolve::new(world, camera, g, samples, None)`)
    /// found on this method's own backend, or `Ok(None)`, the default, for the CPU's pass.
    /// lgh-gpu's methods trace the sub-pixel samples on the GPU.
    ///
    /// # Errors
    /// The backend failed.
    fn edge_resolve(
        &self,
        _world: &World,
        _camera: &CameraFrame,
        _g: &GBuffer,
        _samples: u32,
    ) -> Result<Option<crate::passes::edge_aa::EdgeResolve>, RenderError> {
        Ok(None)
    }
    /// Renders the frame's indirect light and, where `show.direct`, its direct light, and
    /// shows the frame on this method's own backend without bringing its parts back: the
    /// emission (where `show.emission`), direct and indirect light composed, `show.edges`
    /// applied, added to the backend's running mean and tone-mapped as `show.request`
    /// asks ([`crate::display`]). `Ok(None)`, the default: the recipe renders the frame
    /// and the caller shows it on the CPU. lgh-gpu's `lgh` shows frames on the GPU; its
    /// output then holds no images (`radiance` and the planes empty, no rays counted).
    ///
    /// # Errors
    /// The method cannot render these inputs, or the backend failed.
    fn render_shown(
        &self,
        _inputs: &MethodInputs,
        _show: &crate::display::ShowInputs,
        _memory: &mut FrameMemory,
    ) -> Result<Option<(MethodOutput, crate::display::Displayed)>, RenderError> {
        Ok(None)
    }

    /// Traces the frame's primary rays into `g` (`world` seen by `camera` at `width` x
    /// `height`, every plane and [`GBuffer::view`] set as [`GBuffer::render_into`] sets
    /// them) on this method's own backend and returns `Ok(true)`, or returns `Ok(false)`,
    /// the default, for the CPU's pass. lgh-gpu's methods trace them on the GPU. Where
    /// `keep_on_device` (a frame the backend may show itself, whose caller reads the planes
    /// through [`GBuffer::planes`] or [`GBuffer::read_deferred`]), the backend may leave
    /// the planes on its device ([`GBuffer::defer_planes`]).
    ///
    /// # Errors
    /// The backend failed.
    fn trace_gbuffer(
        &self,
        _world: &World,
        _camera: &CameraFrame,
        _size: (u32, u32),
        _g: &mut GBuffer,
        _keep_on_device: bool,
    ) -> Result<bool, RenderError> {
        Ok(false)
    }
}

/// A registered method: a handle to a `'static` [`IndirectMethod`], compared by name.
#[derive(Clone, Copy)]
pub struct Method(&'static dyn IndirectMethod);

impl Method {
    /// The handle of `method` (for the constants the method folders define).
    #[must_use]
    pub const fn new(method: &'static dyn IndirectMethod) -> Self {
        Self(method)
    }

    /// The method behind the handle.
    #[must_use]
    pub fn get(self) -> &'static dyn IndirectMethod {
        self.0
    }

    /// Name on the command line and in statistics.
    #[must_use]
    pub fn name(self) -> &'static str {
        self.0.name()
    }

    /// Whether the method shades VPLs or computes all reflected light itself.
    #[must_use]
    pub fn illumination(self) -> Illumination {
        self.0.illumination()
    }

    /// The registered method called `name`.
    #[must_use]
    pub fn by_name(name: &str) -> Option<Self> {
        METHODS.iter().copied().find(|m| m.name() == name)
    }
}

impl PartialEq for Method {
    fn eq(&self, other: &Self) -> bool {
        self.name() == other.name()
    }
}

impl Eq for Method {}

impl std::hash::Hash for Method {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.name().hash(state);
    }
}

impl fmt::Debug for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Method {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::by_name(s).ok_or_else(|| {
            let names: Vec<&str> = METHODS.iter().map(|m| m.name()).collect();
            format!(
                "unknown method '{s}' (expected one of {})",
                names.join(", ")
            )
        })
    }
}

impl serde::Serialize for Method {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

#[cfg(feature = "clap")]
impl clap::ValueEnum for Method {
    fn value_variants<'a>() -> &'a [Self] {
        METHODS
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.name()).help(self.0.about()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Names are unique and round-trip through `FromStr`.
    #[test]
    fn registry_names_are_unique() {
        for (i, m) in METHODS.iter().enumerate() {
            assert_eq!(m.name().parse::<Method>(), Ok(*m));
            assert!(METHODS[..i].iter().all(|o| o.name() != m.name()));
        }
        assert!("nope".parse::<Method>().is_err());
    }
}
