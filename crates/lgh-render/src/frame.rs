//! One frame, pass by pass: the recipe the command line and library users follow.
//!
//! ```text
//! scene --World::new--> BVH + light tables
//!        camera --GBuffer::render_into--> G-buffer (position, normal, albedo, depth, emission)
//!        lights --generate_vpls--> VPLs (light tracing)
//!        G-buffer + lights --render_direct--> direct radiance (exact shadow rays)
//!        G-buffer + VPLs --settings.method--> indirect radiance (crate::methods)
//!        G-buffer + sub-pixel rays --EdgeResolve--> anti-aliased edges of every part
//!        emission + direct + indirect --> image (the chosen component)
//! ```
//!
//! A method that computes all reflected light itself (a path tracer,
//! [`Illumination::AllReflected`]) skips the VPLs and the direct pass. A method may run the
//! G-buffer, the VPLs, the direct pass and the edge resolve on its own backend (the hooks
//! of [`crate::methods::IndirectMethod`]; lgh-gpu's methods run them on the GPU); where it
//! does not, the passes above run here. Nothing below this module imports it.

use std::time::Instant;

use glam::Vec3;
use lgh_core::timing::Timings;
use lgh_scene::camera::CameraFrame;
use rayon::prelude::*;

use crate::direct::render_direct;
use crate::image::Image;
use crate::memory::FrameMemory;
use crate::methods::{Illumination, MethodInputs, MethodOutput, MethodStats};
use crate::passes::edge_aa::EdgeResolve;
use crate::passes::gbuffer::GBuffer;
use crate::passes::vpl_gen::{VplSet, generate_vpls};
use crate::progress::Progress;
use crate::settings::{Component, RenderError, RenderSettings};
use crate::shading::ratio::ShadowRatio;
use crate::world::World;

/// A rendered frame with its parts.
#[derive(Clone, Debug)]
pub struct Frame {
    /// The requested component (see [`RenderSettings::component`]).
    pub image: Image,
    /// Emitted radiance seen directly.
    pub emission: Image,
    /// Direct lighting (zero, and not computed, when the component is
    /// [`Component::Indirect`] or the method computes all reflected light).
    pub direct: Image,
    /// Indirect lighting from the VPLs (all reflected light for a path tracer).
    pub indirect: Image,
    /// The VPLs used.
    pub vpls: VplSet,
    /// Per-pass times: `gbuffer`, `vpl_generation`, `direct`, `indirect`, `total`, and the
    /// method's own passes (parts of `indirect`).
    pub timings: Timings,
    /// What the method reported besides its radiance (`radiance` is moved to `indirect`).
    pub method: MethodOutput,
    /// The G-buffer the frame was shaded from.
    pub gbuffer: GBuffer,
    /// The camera of the frame.
    pub camera: CameraFrame,
}

/// The output image of `component` from a frame's parts.
fn compose(component: Component, emission: &Image, direct: &Image, indirect: &Image) -> Image {
    let pixels = (0..emission.pixels.len())
        .into_par_iter()
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

    /// The method's statistics as their own type (`LghStats`, `SlcStats`, `PtStats`, ...).
    #[must_use]
    pub fn stats<T: MethodStats>(&self) -> Option<&T> {
        self.method.stats()
    }

    /// The unshadowed sum A per pixel, for methods with the ratio estimator.
    #[must_use]
    pub fn unshadowed(&self) -> Option<&[Vec3]> {
        self.method.unshadowed.as_deref()
    }

    /// The shadow ratio per pixel, for methods with the ratio estimator.
    #[must_use]
    pub fn shadow_ratio(&self) -> Option<&ShadowRatio> {
        self.method.shadow_ratio.as_ref()
    }
}

/// Renders one frame of `world` (see the module docs for the passes).
///
/// # Errors
/// The settings are out of range ([`RenderSettings::validate`]), or the method cannot render
/// (the `lgh` methods fail if the VPLs cannot form a hierarchy).
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
    s.validate()?;
    let start = Instant::now();
    let mut t = Timings::default();
    let (w, h) = (s.width, s.height);
    let camera = world.scene.camera().frame(w, h).with_jitter(s.jitter);
    // A piece of a frame shades its rectangle and the guard band its filters reach.
    let keep = s
        .region
        .map(|r| r.grown(crate::region::guard_band(s), w, h));
    let g = t.time("gbuffer", || {
        let mut g = memory.gbuffer.take().unwrap_or_default();
        if !g.shows(world, &camera, w, h)
            && !s
                .method
                .get()
                .trace_gbuffer(world, &camera, (w, h), &mut g)?
        {
            g.render_into(world, &camera, w, h);
        }
        if let Some(r) = &keep {
            g.clear_outside(r);
        }
        Ok::<_, RenderError>(g)
    })?;
    let all_reflected = s.method.illumination() == Illumination::AllReflected;
    let vpls = if all_reflected {
        VplSet::default()
    } else {
        t.time("vpl_generation", || {
            Ok::<_, RenderError>(match s.method.get().generate_vpls(world, s)? {
                Some(set) => set,
                None => generate_vpls(world, s.vpls, s.bounces, s.seed, s.path_numbers),
            })
        })?
    };
    // The indirect component alone does not need the direct pass (about a third of a
    // 1280x720 frame), and a path tracer computes it itself.
    let direct = if s.component == Component::Indirect || all_reflected {
        vec![Vec3::ZERO; g.len()]
    } else {
        let out = t.time("direct", || match s.method.get().direct(world, &g, s) {
            Ok(Some(out)) => Ok(out),
            Ok(None) => Ok(render_direct(
                world,
                &g,
                s.seed,
                s.area_samples,
                s.direct,
                &mut memory.direct_filter,
                progress,
            )),
            Err(e) => Err(e),
        })?;
        t.0.extend(out.timings.0);
        out.radiance
    };
    let inputs = MethodInputs {
        world,
        gbuffer: &g,
        camera: &camera,
        vpls: &vpls.vpls,
        vpl_count: vpls.len(),
        vpl_bins: vpls.kept_bins,
        settings: s,
        progress,
    };
    let name = if all_reflected {
        "path_tracing"
    } else {
        "indirect"
    };
    let mut out = t.time(name, || s.method.get().render(&inputs, memory))?;
    let mut emission = g.emission.clone();
    let mut direct = direct;
    let mut indirect = std::mem::take(&mut out.radiance);
    if s.edge_samples > 1 {
        t.time("edge_aa", || {
            let mut apply = |resolve: &EdgeResolve| {
                for image in [&mut emission, &mut direct, &mut indirect] {
                    resolve.apply(image);
                }
            };
            let make = || EdgeResolve::new(world, &camera, &g, s.edge_samples, keep.as_ref());
            match keep {
                // A piece of a frame resolves its own rectangle.
                Some(_) => apply(&make()),
                // The method's backend may find it (kept while the view stands still).
                None => {
                    let cache = &mut memory.edge_resolve;
                    let params = [s.edge_samples, 0, 0, 0];
                    if !cache.holds(&g, params) {
                        let method = s.method.get();
                        match method.edge_resolve(world, &camera, &g, s.edge_samples)? {
                            Some(r) if g.view.is_some() => cache.insert(&g, params, r),
                            Some(r) => {
                                apply(&r);
                                return Ok(());
                            }
                            None => {}
                        }
                    }
                    apply(cache.get_or_insert_with(&g, params, make));
                }
            }
            Ok::<_, RenderError>(())
        })?;
    }
    let emission = Image::from_pixels(w, h, emission);
    let direct = Image::from_pixels(w, h, direct);
    let indirect = Image::from_pixels(w, h, indirect);
    let image = compose(s.component, &emission, &direct, &indirect);
    t.0.extend(std::mem::take(&mut out.timings.0));
    t.0.push(("total".into(), start.elapsed().as_secs_f64() * 1e3));
    Ok(Frame {
        image,
        emission,
        direct,
        indirect,
        vpls,
        timings: t,
        method: out,
        gbuffer: g,
        camera,
    })
}
