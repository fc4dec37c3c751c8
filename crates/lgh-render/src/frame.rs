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
use crate::display::{DisplayRequest, Displayed, ShowEdges, ShowInputs};
use crate::image::Image;
use crate::memory::{FrameMemory, ViewCache};
use crate::methods::{Illumination, MethodInputs, MethodOutput, MethodStats};
use crate::passes::edge_aa::EdgeResolve;
use crate::passes::gbuffer::GBuffer;
use crate::passes::vpl_gen::{VplSet, generate_vpls};
use crate::progress::Progress;
use crate::region::Region;
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
    /// The frame as its method's backend showed it ([`render_frame_shown`]); its images
    /// are then empty (their sizes kept).
    pub shown: Option<Displayed>,
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
    recipe(world, s, progress, memory, None)
}

/// [`render_frame_with`] for a viewer that shows the frame as `request` asks: where the
/// method's backend shows frames itself
/// ([`crate::methods::IndirectMethod::render_shown`]: lgh-gpu's `lgh`, for the components
/// [`Component::All`] and [`Component::Indirect`]), the frame is composed, added to that
/// backend's running mean and tone-mapped there, and comes back as [`Frame::shown`] with
/// its images empty (their sizes kept): only the packed pixels cross from the device. Else
/// the frame is rendered as [`render_frame_with`] renders it, `shown` is `None`, and the
/// caller shows it ([`crate::display::RunningMean`]).
///
/// # Errors
/// As [`render_frame`].
pub fn render_frame_shown(
    world: &World,
    s: &RenderSettings,
    progress: &dyn Progress,
    memory: &mut FrameMemory,
    request: DisplayRequest,
) -> Result<Frame, RenderError> {
    recipe(world, s, progress, memory, Some(request))
}

fn recipe(
    world: &World,
    s: &RenderSettings,
    progress: &dyn Progress,
    memory: &mut FrameMemory,
    request: Option<DisplayRequest>,
) -> Result<Frame, RenderError> {
    s.validate()?;
    let start = Instant::now();
    let mut t = Timings::default();
    let (w, h) = (s.width, s.height);
    let camera = world.scene.camera().frame(w, h).with_jitter(s.jitter);
    // A piece of a frame shades its rectangle and the guard band its filters reach.
    let keep = crate::region::shaded_rect(s);
    let all_reflected = s.method.illumination() == Illumination::AllReflected;
    // A frame its method's backend may show (`show`) leaves the G-buffer's planes on that
    // backend's device until a pass here reads them: a moving camera's frame then moves
    // no planes (80 bytes a pixel) across.
    let may_show =
        request.is_some() && keep.is_none() && !all_reflected && s.component != Component::Direct;
    let (mut g, still) = t.time("gbuffer", || {
        let mut g = memory.gbuffer.take().unwrap_or_default();
        let still = g.shows(world, &camera, w, h);
        if !still
            && !s
                .method
                .get()
                .trace_gbuffer(world, &camera, (w, h), &mut g, may_show)?
        {
            g.render_into(world, &camera, w, h);
        }
        if !may_show {
            g.read_deferred()?;
        }
        if let Some(r) = &keep {
            g.clear_outside(r);
        }
        Ok::<_, RenderError>((g, still))
    })?;
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
    if let Some(request) = request.filter(|_| may_show) {
        let view = View {
            camera: &camera,
            g: &g,
            still,
        };
        let shown = show(world, s, progress, memory, &view, &vpls, request);
        if let Some((out, displayed, shown_t)) = shown? {
            t.0.extend(shown_t.0);
            return Ok(shown_frame(s, start, t, g, vpls, out, displayed, camera));
        }
        // Not shown there: the passes here read the planes.
        t.time("gbuffer_read_back", || g.read_deferred())?;
    }
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
    let inputs = method_inputs(world, &g, &camera, &vpls, s, progress);
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
            let resolve = find_edges(
                world,
                &camera,
                &g,
                s,
                keep.as_ref(),
                &mut memory.edge_resolve,
            )?;
            for image in [&mut emission, &mut direct, &mut indirect] {
                resolve.get().apply(image);
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
        shown: None,
    })
}

/// What the frame's method gets: the frame's world, G-buffer, camera, VPLs (or their number
/// where its backend keeps them), settings and progress.
fn method_inputs<'a>(
    world: &'a World,
    g: &'a GBuffer,
    camera: &'a CameraFrame,
    vpls: &'a VplSet,
    s: &'a RenderSettings,
    progress: &'a dyn Progress,
) -> MethodInputs<'a> {
    MethodInputs {
        world,
        gbuffer: g,
        camera,
        vpls: &vpls.vpls,
        vpl_count: vpls.len(),
        vpl_bins: vpls.kept_bins,
        settings: s,
        progress,
    }
}

/// The edge resolve of a frame: made for it, or kept in the frame memory.
enum Resolve<'m> {
    Made(EdgeResolve),
    Kept(&'m EdgeResolve),
}

impl Resolve<'_> {
    fn get(&self) -> &EdgeResolve {
        match self {
            Self::Made(r) => r,
            Self::Kept(r) => r,
        }
    }
}

/// The resolve of the edges of `g` with `s.edge_samples` sub-pixel rays: a piece of a
/// frame (`keep`) resolves its own rectangle; a whole frame's is found by the method's
/// backend where it can, and kept in `cache` while the view stands still.
fn find_edges<'m>(
    world: &World,
    camera: &CameraFrame,
    g: &GBuffer,
    s: &RenderSettings,
    keep: Option<&Region>,
    cache: &'m mut ViewCache<EdgeResolve>,
) -> Result<Resolve<'m>, RenderError> {
    if keep.is_some() {
        let made = EdgeResolve::new(world, camera, g.planes()?, s.edge_samples, keep);
        return Ok(Resolve::Made(made));
    }
    let params = [s.edge_samples, 0, 0, 0];
    if !cache.holds(g, params) {
        match s
            .method
            .get()
            .edge_resolve(world, camera, g, s.edge_samples)?
        {
            Some(r) if g.view.is_some() => cache.insert(g, params, r),
            Some(r) => return Ok(Resolve::Made(r)),
            None => {}
        }
    }
    // Made here: from the planes, read back if the backend kept them.
    let planes = if cache.holds(g, params) {
        g
    } else {
        g.planes()?
    };
    let make = || EdgeResolve::new(world, camera, planes, s.edge_samples, None);
    Ok(Resolve::Kept(cache.get_or_insert_with(g, params, make)))
}

/// The view of a frame: its camera and G-buffer, and whether the G-buffer is the last
/// frame's (the camera stood still).
struct View<'a> {
    camera: &'a CameraFrame,
    g: &'a GBuffer,
    still: bool,
}

/// The frame's direct and indirect light rendered and shown by the method's backend
/// ([`crate::methods::IndirectMethod::render_shown`]), with the edges resolved there;
/// `None` where the backend does not show frames. The edges of a still view are found
/// here and kept; a moving view's are found by the backend in the frame's own work
/// ([`ShowEdges::Find`]). The timings: `edge_aa` (finding the edges here) and `indirect`
/// (all the rest), with the method's own.
fn show(
    world: &World,
    s: &RenderSettings,
    progress: &dyn Progress,
    memory: &mut FrameMemory,
    view: &View,
    vpls: &VplSet,
    request: DisplayRequest,
) -> Result<Option<(MethodOutput, Displayed, Timings)>, RenderError> {
    let View { camera, g, still } = *view;
    let mut t = Timings::default();
    // The method gets `memory` while the edges borrow its cache: the cache is taken out for
    // the frame and put back after it.
    let mut cache = std::mem::take(&mut memory.edge_resolve);
    let kept = still || cache.holds(g, [s.edge_samples, 0, 0, 0]);
    let edges = if s.edge_samples > 1 && kept {
        Some(t.time("edge_aa", || {
            find_edges(world, camera, g, s, None, &mut cache)
        })?)
    } else {
        None
    };
    let inputs = method_inputs(world, g, camera, vpls, s, progress);
    let all = s.component == Component::All;
    let show = ShowInputs {
        direct: all,
        emission: all,
        edges: match &edges {
            Some(r) => ShowEdges::Resolved(r.get()),
            None if s.edge_samples > 1 => ShowEdges::Find(s.edge_samples),
            None => ShowEdges::None,
        },
        request,
    };
    let shown = t.time("indirect", || {
        s.method.get().render_shown(&inputs, &show, memory)
    });
    drop(edges);
    memory.edge_resolve = cache;
    Ok(shown?.map(|(out, displayed)| (out, displayed, t)))
}

/// The frame shown by its method's backend: its images empty, of its size.
#[allow(clippy::too_many_arguments)]
fn shown_frame(
    s: &RenderSettings,
    start: Instant,
    mut t: Timings,
    gbuffer: GBuffer,
    vpls: VplSet,
    mut method: MethodOutput,
    shown: Displayed,
    camera: CameraFrame,
) -> Frame {
    let empty = || Image {
        width: s.width,
        height: s.height,
        pixels: Vec::new(),
    };
    t.0.extend(std::mem::take(&mut method.timings.0));
    t.0.push(("total".into(), start.elapsed().as_secs_f64() * 1e3));
    Frame {
        image: empty(),
        emission: empty(),
        direct: empty(),
        indirect: empty(),
        vpls,
        timings: t,
        method,
        gbuffer,
        camera,
        shown: Some(shown),
    }
}
