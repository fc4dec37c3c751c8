//! The frame loop of the viewer: turns a [`ViewState`] into a shown frame. While the view is
//! still, frames with independent VPL sets (and, for lgh, random grid offsets) accumulate
//! into a running mean that converges (docs/design.md, "Accumulation"); any change restarts
//! it. While it moves, frames go through the temporal filter if it is on. Moving the light
//! regenerates the VPLs and rebuilds the hierarchy, as every frame does. With the heat map
//! on, the frame shown is the overdraw of the frame just rendered (lights per pixel).

use std::time::Instant;

use lgh_render::accumulate::frame_settings;
use lgh_render::display::{DisplayRequest, RunningMean, pack_pixel};
use lgh_render::image::heat::{HEAT_EXPOSURE, heat_map};
use lgh_render::methods::lgh::LghStats;
use lgh_render::sequence::Sequence;
use lgh_render::settings::MethodMap;
use lgh_render::world::accel::AccelKind;
use lgh_render::{
    FrameMemory, Image, RenderError, Silent, World, render_frame_shown, render_frame_with,
};
use lgh_scene::{Light, Scene};
use rayon::prelude::*;

use crate::state::ViewState;

/// A frame ready to show.
#[derive(Clone, Debug)]
pub struct ShownFrame {
    /// The linear image shown (the running mean while still); empty (its size kept) for a
    /// frame shown on the GPU without [`FrameLoop::with_linear`].
    pub image: Image,
    /// The image tone-mapped, one `0x00RRGGBB` per pixel (softbuffer's layout).
    pub pixels: Vec<u32>,
    /// The exposure `pixels` were tone-mapped with (the heat map has its own).
    pub exposure: f32,
    /// Per-pass times of this frame, ms (`total` is the whole render).
    pub timings: Vec<(String, f64)>,
    /// VPLs of this frame.
    pub vpls: usize,
    /// Grid lights of this frame's hierarchy (lgh).
    pub grid_lights: Option<usize>,
    /// The levels this frame's hierarchy shaded, lowest and l_max (lgh).
    pub levels: Option<(u32, u32)>,
    /// Frames in the running mean (1 while moving).
    pub accumulated: u32,
    /// With the heat map on and a method that counts them: the mean and the largest number
    /// of lights evaluated per pixel (the heat map's top).
    pub overdraw: Option<(f64, u32)>,
    /// Wall time of the frame, ms, including the view update.
    pub ms: f64,
    /// Where its indirect light was computed: "cpu" or "gpu".
    pub device: &'static str,
}

/// Where the running mean of a view's frames is kept.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum MeanAt {
    /// No running mean holds the last frame (the first frame, a heat map).
    Nowhere,
    /// The CPU's ([`RunningMean`]).
    Cpu,
    /// The GPU's: the frame was shown there ([`render_frame_shown`]).
    Gpu,
}

/// Renders the frames of a view.
pub struct FrameLoop {
    world: World,
    rest_lights: Vec<Light>,
    sequence: Sequence,
    memory: FrameMemory,
    mean: RunningMean,
    accumulated: u32,
    /// Where the running mean that holds the last frame is.
    mean_at: MeanAt,
    /// Shown frames bring back their linear image (an EXR screenshot needs it).
    linear: bool,
    shown_version: Option<u64>,
    frame: u64,
    exposure: f32,
    backend: Option<MethodMap>,
}

impl FrameLoop {
    /// The loop over `scene` (finished), shown with `exposure` (None: the scene's), traced
    /// with the ray tracer `accel`.
    ///
    /// # Errors
    /// The ray tracer is not in this build or cannot build the BVH.
    pub fn new(
        scene: Scene,
        exposure: Option<f32>,
        accel: AccelKind,
    ) -> Result<Self, lgh_render::world::accel::AccelError> {
        let exposure = exposure.unwrap_or(scene.exposure);
        let world = World::with_accel(scene, accel)?;
        let rest_lights = world.rest_view().1.to_vec();
        Ok(Self {
            world,
            rest_lights,
            sequence: Sequence::new(None),
            memory: FrameMemory::default(),
            mean: RunningMean::default(),
            accumulated: 0,
            mean_at: MeanAt::Nowhere,
            linear: false,
            shown_version: None,
            frame: 0,
            exposure,
            backend: None,
        })
    }

    /// The same loop computing the indirect light with `backend`'s method where it has one
    /// (the GPU's, `--device gpu`), and on the CPU where it has none.
    #[must_use]
    pub fn with_backend(self, backend: Option<MethodMap>) -> Self {
        Self { backend, ..self }
    }

    /// The same loop with frames shown on the GPU bringing back their linear image too
    /// (else only their packed pixels come back, and [`ShownFrame::image`] is empty): an
    /// EXR screenshot needs it.
    #[must_use]
    pub fn with_linear(self, linear: bool) -> Self {
        Self { linear, ..self }
    }

    /// The world rendered (its scene, radius and centre).
    #[must_use]
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The exposure of the shown frames.
    #[must_use]
    pub fn exposure(&self) -> f32 {
        self.exposure
    }

    /// Renders the next frame of `state`.
    ///
    /// # Errors
    /// The settings are invalid or the VPLs form no hierarchy.
    pub fn render(&mut self, state: &ViewState) -> Result<ShownFrame, RenderError> {
        let start = Instant::now();
        let still = self.shown_version == Some(state.version);
        if !still {
            let lights = state.lights(&self.rest_lights, self.world.centre);
            self.world.set_view(state.camera(), lights);
            self.accumulated = 0;
        }
        // Every frame its own seeds and, for lgh, its own grid offset.
        let mut settings = frame_settings(&state.settings, self.frame as u32, 2);
        // Still frames accumulate at their own sub-pixel positions (an anti-aliased image);
        // moving frames, and the first still one, sample pixel centres, so that nothing
        // shimmers, and resolve their edges from sub-pixel rays.
        settings.jitter = if still {
            lgh_render::accumulate::subpixel_jitter(self.accumulated)
        } else {
            glam::Vec2::ZERO
        };
        if settings.jitter == glam::Vec2::ZERO {
            settings.edge_samples = state.settings.edge_samples;
        }
        // The 1/d^2 clamp of all the VPLs shown so far (a still view converges to the fixed
        // clamp as frames accumulate).
        let shown = if still { self.accumulated + 1 } else { 1 };
        settings.vpl_clamp = state.settings.vpl_clamp / (shown as f32).sqrt();
        self.frame += 1;
        let mut device = "cpu";
        if let Some(m) = self.backend.and_then(|map| map(&settings)) {
            (settings.method, device) = (m, "gpu");
        }
        // A GPU frame is shown where it was made (only its packed pixels come back; moving
        // frames with the temporal filter run it there too), as long as the view shows the
        // frame itself (not the heat map); its running mean restarts where the last
        // frame's was on the CPU.
        let request = (device == "gpu" && !state.heatmap).then(|| DisplayRequest {
            exposure: self.exposure,
            restart: self.accumulated == 0 || self.mean_at != MeanAt::Gpu,
            linear: self.linear,
            taa: None,
        });
        let sequence = !still && state.taa;
        if sequence {
            self.sequence.taa = Some(Default::default());
        }
        let (world, memory) = (&self.world, &mut self.memory);
        let mut frame = match (request, sequence) {
            (Some(r), false) => render_frame_shown(world, &settings, &Silent, memory, r)?,
            (Some(r), true) => self.sequence.render_shown(world, &settings, &Silent, r)?,
            (None, false) => render_frame_with(world, &settings, &Silent, memory)?,
            (None, true) => self.sequence.render(world, &settings, &Silent)?,
        };
        self.shown_version = Some(state.version);
        let display_start = Instant::now();
        let mut exposure = self.exposure;
        let mut overdraw = None;
        let heat = state
            .heatmap
            .then_some(frame.method.lights_per_pixel.as_ref())
            .flatten();
        let (mean, packed) = if let Some(shown) = frame.shown.take() {
            self.accumulated = shown.frames;
            self.mean_at = MeanAt::Gpu;
            (shown.mean.unwrap_or_default(), shown.pixels)
        } else if let Some(counts) = heat {
            // The heat map stands for the frame (a running mean restarts after it).
            self.accumulated += 1;
            self.mean_at = MeanAt::Nowhere;
            let (colours, max) = heat_map(counts);
            overdraw = Some((frame.gbuffer.mean_over_hits(counts), max));
            exposure = HEAT_EXPOSURE;
            let packed = colours
                .par_iter()
                .map(|&c| pack_pixel(c, exposure))
                .collect();
            (colours, packed)
        } else {
            // The CPU's running mean (restarted where the last frame's was on the GPU).
            let request = DisplayRequest {
                exposure,
                restart: self.accumulated == 0 || self.mean_at != MeanAt::Cpu,
                linear: true,
                taa: None,
            };
            let shown = self
                .mean
                .show(std::mem::take(&mut frame.image.pixels), &request);
            self.accumulated = shown.frames;
            self.mean_at = MeanAt::Cpu;
            (shown.mean.unwrap_or_default(), shown.pixels)
        };
        let lgh_stats = frame.stats::<LghStats>();
        let mut timings = frame.timings.0.clone();
        timings.push((
            "display".into(),
            display_start.elapsed().as_secs_f64() * 1e3,
        ));
        let shown = ShownFrame {
            image: Image {
                width: frame.image.width,
                height: frame.image.height,
                pixels: mean,
            },
            pixels: packed,
            exposure,
            timings,
            vpls: frame.vpls.len(),
            grid_lights: lgh_stats.map(|s| s.grid_lights),
            levels: lgh_stats.map(|s| (state.settings.lgh.start_level.min(1), s.levels)),
            accumulated: self.accumulated,
            overdraw,
            ms: start.elapsed().as_secs_f64() * 1e3,
            device,
        };
        if !sequence {
            self.memory.recycle_gbuffer(frame.gbuffer);
        } else {
            self.sequence.recycle(frame);
        }
        Ok(shown)
    }
}
