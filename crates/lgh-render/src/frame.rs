//! One frame, pass by pass: the recipe the command line and library users follow.
//!
//! ```text
//! scene --World::new--> BVH + light tables
//!        camera --GBuffer::render--> G-buffer (position, normal, albedo, depth, emission)
//!        lights --generate_vpls--> VPLs (light tracing)
//!        G-buffer + lights --render_direct--> direct radiance (exact shadow rays)
//!        G-buffer + VPLs --method--> indirect radiance
//!        emission + direct + indirect --> image (the chosen component)
//! ```

use std::time::Instant;

use glam::Vec3;

use lgh_core::lighting_grid::{GridBuilder, GridError};

use crate::atrous::AtrousBuffers;
use crate::brute::render_brute;
use crate::direct::render_direct;
use crate::gbuffer::GBuffer;
use crate::image::Image;
use crate::lgh::{LghSettings, render_lgh};
use crate::progress::Progress;
use crate::pt::{LightSampling, PtSettings, render_pt};
use crate::ratio::ShadowRatio;
use crate::slc::{RangeMode, SlcSettings, render_slc};
use crate::vpl_gen::{PathNumbers, VplSet, generate_vpls};
use crate::world::World;
use lgh_scene::camera::CameraFrame;

/// How the indirect light (the VPLs' contribution) is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Every pixel sums every VPL with an exact shadow ray (the reference).
    Brute,
    /// Every pixel sums every VPL, no shadow rays.
    BruteUnshadowed,
    /// Lighting grid hierarchy with stochastic ray-traced shadows (Lin & Yuksel 2019).
    Lgh,
    /// Lighting grid hierarchy without shadows.
    LghUnshadowed,
    /// Stochastic tiled lighting (Tokuyoshi & Harada 2016); shadowed through the ratio
    /// estimator when `slc.shadow_samples > 0`.
    Slc,
    /// Tiled lighting with clamped light ranges (the biased baseline of the same paper).
    SlcClamped,
    /// Path tracing with stochastic light culling for many area lights (SLC section 5); the
    /// image holds the path-traced radiance, not VPL lighting.
    PtSlc,
    /// Path tracing with uniform light sampling.
    PtUniform,
    /// Path tracing with clamped light ranges.
    PtClamped,
}

impl Method {
    /// The name used on the command line and in statistics.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Method::Brute => "brute",
            Method::BruteUnshadowed => "brute-unshadowed",
            Method::Lgh => "lgh",
            Method::LghUnshadowed => "lgh-unshadowed",
            Method::Slc => "slc",
            Method::SlcClamped => "slc-clamped",
            Method::PtSlc => "pt-slc",
            Method::PtUniform => "pt-uniform",
            Method::PtClamped => "pt-clamped",
        }
    }

    /// The path-tracing methods, which need no VPLs.
    #[must_use]
    pub fn is_path_tracer(self) -> bool {
        matches!(self, Method::PtSlc | Method::PtUniform | Method::PtClamped)
    }
}

/// Which part of the radiance the output image holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Component {
    /// Emission + direct + indirect.
    All,
    /// Emission + direct light from the primary lights.
    Direct,
    /// Indirect light only (the VPLs), to compare methods on what differs between them.
    Indirect,
}

/// Everything that defines a frame besides the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Number of VPLs to generate (at least; whole light paths).
    pub vpls: usize,
    /// Maximum VPLs per light path (indirect bounces represented).
    pub bounces: u32,
    /// Seed of every random choice.
    pub seed: u64,
    /// Numbers of the light paths that make the VPLs (stratified by default).
    pub path_numbers: PathNumbers,
    /// Shadow-ray samples per pixel for area lights in the direct pass.
    pub area_samples: u32,
    /// Indirect-lighting method.
    pub method: Method,
    /// What the output image holds.
    pub component: Component,
    /// eps of the 1/(d^2 + eps^2) clamp, as a fraction of the scene's bounding-sphere radius
    /// (LGH design notes 4.3: 0.01).
    pub clamp_fraction: f32,
    /// Settings of the `lgh` methods.
    pub lgh: LghSettings,
    /// Settings of the `slc` methods.
    pub slc: SlcSettings,
    /// Settings of the `pt` methods.
    pub pt: PtSettings,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 640,
            height: 360,
            vpls: 10_000,
            bounces: 3,
            seed: 0,
            path_numbers: PathNumbers::Sobol,
            area_samples: 16,
            method: Method::Brute,
            component: Component::All,
            clamp_fraction: 0.01,
            lgh: LghSettings::default(),
            slc: SlcSettings::default(),
            pt: PtSettings::default(),
        }
    }
}

pub use lgh_core::timing::Timings;

/// A rendered frame with its parts.
#[derive(Clone, Debug)]
pub struct Frame {
    /// The requested component (see [`RenderSettings::component`]).
    pub image: Image,
    /// Emitted radiance seen directly.
    pub emission: Image,
    /// Direct lighting (zero, and not computed, when the component is
    /// [`Component::Indirect`]).
    pub direct: Image,
    /// Indirect lighting from the VPLs.
    pub indirect: Image,
    /// The VPLs used.
    pub vpls: VplSet,
    /// Per-pass times: `gbuffer`, `vpl_generation`, `direct`, `indirect`, `total`; the `lgh`
    /// methods add `lgh_build`, `lighting`, `shadow_rays`, `shadow_filter`, `composite`
    /// (parts of `indirect`).
    pub timings: Timings,
    /// Statistics of the `lgh` methods.
    pub lgh: Option<LghStats>,
    /// Statistics of the `slc` methods.
    pub slc: Option<SlcStats>,
    /// Statistics of the `pt` methods.
    pub pt: Option<PtStats>,
    /// The G-buffer the frame was shaded from.
    pub gbuffer: GBuffer,
    /// The camera of the frame.
    pub camera: CameraFrame,
    /// `lgh` and `slc`: the unshadowed sum A per pixel (before albedo / pi).
    pub unshadowed: Option<Vec<Vec3>>,
    /// `lgh` and `slc`: the shadow ratio per pixel, filtered and raw (1 without shadows).
    pub shadow_ratio: Option<ShadowRatio>,
}

/// The output image of `component` from a frame's parts.
fn compose(component: Component, emission: &Image, direct: &Image, indirect: &Image) -> Image {
    let pixels = (0..emission.pixels.len())
        .map(|i| {
            let e = emission.pixels[i];
            match component {
                Component::All => e + direct.pixels[i] + indirect.pixels[i],
                Component::Direct => e + direct.pixels[i],
                Component::Indirect => indirect.pixels[i],
            }
        })
        .collect();
    Image::from_pixels(emission.width, emission.height, pixels)
}

impl Frame {
    /// Replaces the indirect light (after a temporal filter, say) and rebuilds `image` for
    /// `component`.
    pub fn set_indirect(&mut self, indirect: Vec<Vec3>, component: Component) {
        self.indirect = Image::from_pixels(self.indirect.width, self.indirect.height, indirect);
        self.image = compose(component, &self.emission, &self.direct, &self.indirect);
    }
}

/// Statistics of a `pt` frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PtStats {
    /// Samples per pixel.
    pub spp: u32,
    /// Emissive triangles.
    pub emitters: usize,
    /// Mean number of lights whose influence sphere held a shading point.
    pub avg_overlapping: f64,
}

/// Statistics of an `slc` frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SlcStats {
    /// Mean number of lights evaluated (within range) per pixel that sees a surface.
    pub avg_lights_per_pixel: f64,
    /// Shadow rays traced.
    pub shadow_rays: u64,
    /// With imperfect shadow maps: points tested by the culling, and points splatted.
    pub ism_points: Option<(u64, u64)>,
}

/// Statistics of an `lgh` frame (the paper's Table 3 and Fig. 5).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LghStats {
    /// Grid lights in the hierarchy.
    pub grid_lights: usize,
    /// l_max.
    pub levels: u32,
    /// Mean overdraw over pixels that see a surface.
    pub avg_overdraw: f64,
    /// Per-pixel overdraw.
    pub overdraw: Vec<u32>,
    /// Shadow rays traced.
    pub shadow_rays: u64,
}

/// A frame that could not be rendered.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The VPLs could not form a lighting grid hierarchy.
    #[error("lighting grid hierarchy: {0}")]
    Grid(#[from] GridError),
}

/// Working memory that frames reuse: the hierarchy builder's and the shadow filter's (about
/// 90 MB at 1280x720), and the G-buffer of a frame handed back with
/// [`FrameMemory::recycle`]. A renderer of frame after frame keeps one
/// ([`render_frame_with`]), so that no frame pays for paging in fresh memory. A clone is
/// empty: it is only a cache.
#[derive(Debug, Default)]
pub struct FrameMemory {
    /// The lighting grid hierarchy builder.
    pub grid: GridBuilder,
    /// The a-trous filter's planes.
    pub filter: AtrousBuffers,
    /// Planes for the next frame's G-buffer (1280x720: 57 MB, 13 ms of first touches).
    pub gbuffer: Option<GBuffer>,
}

impl FrameMemory {
    /// Takes back a frame that is no longer needed, so that the next frame renders its
    /// G-buffer into the same planes.
    pub fn recycle(&mut self, frame: Frame) {
        self.gbuffer = Some(frame.gbuffer);
    }
}

impl Clone for FrameMemory {
    fn clone(&self) -> Self {
        Self::default()
    }
}

/// Renders one frame of `world` (see the module docs for the passes).
///
/// # Errors
/// The `lgh` methods fail if the VPLs cannot form a hierarchy (non-finite values).
pub fn render_frame(
    world: &World,
    s: &RenderSettings,
    progress: &dyn Progress,
) -> Result<Frame, RenderError> {
    render_frame_with(world, s, progress, &mut FrameMemory::default())
}

/// [`render_frame`] in the working memory `memory`, reused from frame to frame.
///
/// # Errors
/// As [`render_frame`].
pub fn render_frame_with(
    world: &World,
    s: &RenderSettings,
    progress: &dyn Progress,
    memory: &mut FrameMemory,
) -> Result<Frame, RenderError> {
    let start = Instant::now();
    let mut t = Timings::default();
    let mut sub_timings = Vec::new();
    let (w, h) = (s.width, s.height);
    let camera = world.scene.camera().frame(w, h);
    let g = t.time("gbuffer", || {
        let mut g = memory.gbuffer.take().unwrap_or_default();
        g.render_into(world, &camera, w, h);
        g
    });
    if s.method.is_path_tracer() {
        return Ok(path_traced_frame(world, s, g, t, start, progress));
    }
    let vpls = t.time("vpl_generation", || {
        generate_vpls(world, s.vpls, s.bounces, s.seed, s.path_numbers)
    });
    // The indirect component alone does not need the direct pass (about a third of a
    // 1280x720 frame).
    let direct = if s.component == Component::Indirect {
        vec![Vec3::ZERO; g.len()]
    } else {
        t.time("direct", || {
            render_direct(world, &g, s.seed, s.area_samples, progress)
        })
    };
    let eps = s.clamp_fraction * world.radius;
    let mut lgh_stats = None;
    let mut slc_stats = None;
    let (mut unshadowed, mut shadow_ratio) = (None, None);
    let indirect = t.time("indirect", || -> Result<Vec<Vec3>, RenderError> {
        Ok(match s.method {
            Method::Brute => render_brute(world, &g, &vpls.vpls, eps, true, progress),
            Method::BruteUnshadowed => render_brute(world, &g, &vpls.vpls, eps, false, progress),
            Method::Lgh | Method::LghUnshadowed => {
                let out = render_lgh(
                    world,
                    &g,
                    &camera,
                    &vpls.vpls,
                    eps,
                    &s.lgh,
                    s.seed,
                    s.method == Method::Lgh,
                    memory,
                )?;
                lgh_stats = Some(LghStats {
                    grid_lights: out.grid_lights,
                    levels: out.levels,
                    avg_overdraw: out.avg_overdraw(&g),
                    overdraw: out.overdraw,
                    shadow_rays: out.shadow_rays,
                });
                sub_timings = out.timings.0;
                unshadowed = Some(out.unshadowed);
                shadow_ratio = Some(out.ratio);
                out.indirect
            }
            Method::Slc | Method::SlcClamped => {
                let mode = if s.method == Method::Slc {
                    RangeMode::Stochastic
                } else {
                    RangeMode::Clamped
                };
                let out = render_slc(
                    world,
                    &g,
                    &camera,
                    &vpls.vpls,
                    eps,
                    mode,
                    &s.slc,
                    s.seed,
                    s.slc.shadow_samples > 0 && s.slc.ism.is_none(),
                );
                slc_stats = Some(SlcStats {
                    avg_lights_per_pixel: out.avg_lights_per_pixel(&g),
                    shadow_rays: out.shadow_rays,
                    ism_points: out.ism_points,
                });
                sub_timings = out.timings.0;
                unshadowed = Some(out.unshadowed);
                shadow_ratio = Some(out.ratio);
                out.indirect
            }
            Method::PtSlc | Method::PtUniform | Method::PtClamped => Vec::new(),
        })
    })?;
    let emission = Image::from_pixels(w, h, g.emission.clone());
    let direct = Image::from_pixels(w, h, direct);
    let indirect = Image::from_pixels(w, h, indirect);
    let image = compose(s.component, &emission, &direct, &indirect);
    t.0.extend(sub_timings);
    t.0.push(("total".into(), start.elapsed().as_secs_f64() * 1e3));
    Ok(Frame {
        image,
        emission,
        direct,
        indirect,
        vpls,
        timings: t,
        lgh: lgh_stats,
        slc: slc_stats,
        pt: None,
        gbuffer: g,
        camera,
        unshadowed,
        shadow_ratio,
    })
}

/// A `pt` frame: emission from the G-buffer, and everything reflected (direct and indirect,
/// every bounce) path traced into `indirect`; `direct` is zero and there are no VPLs.
fn path_traced_frame(
    world: &World,
    s: &RenderSettings,
    g: GBuffer,
    mut t: Timings,
    start: Instant,
    progress: &dyn Progress,
) -> Frame {
    let (w, h) = (s.width, s.height);
    let mode = match s.method {
        Method::PtUniform => LightSampling::Uniform,
        Method::PtClamped => LightSampling::Clamped,
        _ => LightSampling::Slc,
    };
    let out = t.time("path_tracing", || {
        render_pt(world, &g, mode, &s.pt, s.seed, progress)
    });
    let emission = Image::from_pixels(w, h, g.emission.clone());
    let indirect = Image::from_pixels(w, h, out.radiance);
    let direct = Image::new(w, h);
    let image = compose(s.component, &emission, &direct, &indirect);
    t.0.push(("total".into(), start.elapsed().as_secs_f64() * 1e3));
    Frame {
        image,
        emission,
        direct,
        indirect,
        vpls: VplSet::default(),
        timings: t,
        lgh: None,
        slc: None,
        pt: Some(PtStats {
            spp: s.pt.spp,
            emitters: world.lights.emitters.len(),
            avg_overlapping: out.avg_overlapping,
        }),
        gbuffer: g,
        camera: world.scene.camera().frame(w, h),
        unshadowed: None,
        shadow_ratio: None,
    }
}
