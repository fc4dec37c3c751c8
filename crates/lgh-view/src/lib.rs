//! # lgh-view: the interactive viewer
//!
//! `lgh view` flies through a scene while the many-lights renderer draws it: the lighting
//! grid hierarchy is an interactive method (LGH paper, section 5), and here every frame
//! regenerates the VPLs and rebuilds the hierarchy, so moving the light is as cheap as moving
//! the camera.
//!
//! | module | what it holds |
//! | --- | --- |
//! | [`state`] | the view (settings, camera, light) and the actions that change it; key map and help |
//! | [`engine`] | the frame loop: one frame of a view, accumulation while still, temporal filtering while moving |
//! | [`headless`] | the same loop without a window, driven by a key script: tests, CI, benchmarks |
//! | [`window`] | the window (winit + softbuffer): input on the event loop, rendering on a worker thread |
//! | [`overlay`] | the window's on-screen text: the readout and the help (the `font8x8` bitmap font) |
//!
//! The renderer knows nothing of windows: this crate drives `lgh-render` through its public
//! API only.
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod engine;
pub mod headless;
pub mod overlay;
pub mod state;
pub mod window;

use std::path::PathBuf;

use clap::Args;
use lgh_render::RenderSettings;
use lgh_render::methods::lgh;
use lgh_render::settings::{Device, MethodMap, parse_size};

/// Arguments of `lgh view`.
#[derive(Debug, Args)]
pub struct ViewArgs {
    /// Scene file: .toml, .gltf, .glb or .obj, or builtin:NAME (see `lgh render --help`).
    /// Default: the Cornell box with a point light (builtin:cornell-moving-light, still),
    /// whose light can be moved.
    pub scene: Option<PathBuf>,
    /// Size of the rendered frame, WIDTHxHEIGHT (the window shows it scaled).
    #[arg(long, default_value = "640x360", value_parser = parse_size)]
    pub size: (u32, u32),
    /// The starting rendering settings (keys change them; see the controls in `lgh view --help`).
    #[command(flatten)]
    pub settings: RenderSettings,
    /// The ray tracer.
    #[command(flatten)]
    pub accel: lgh_render::world::accel::AccelChoice,
    /// Start with temporal filtering of the shadows (T toggles it).
    #[arg(long)]
    pub taa: bool,
    /// Quit after N frames (1 to a million).
    #[arg(long)]
    pub frames: Option<u64>,
    /// Write the last frame shown to this PNG at exit.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Write statistics as JSON at exit: `fps` (frames over wall time), the median of each
    /// pass in ms, and the settings.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Run the same loop without a window (for tests, CI and benchmarks); needs --frames.
    #[arg(long)]
    pub headless: bool,
    /// Turn the light by this many degrees every frame, in [-360, 360] (a moving light: VPLs
    /// and hierarchy are rebuilt each frame, and nothing accumulates).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub light_speed: f32,
    /// Keys pressed one per frame from the first frame on, as a script (e.g. "w,w,a,m,l"):
    /// the same actions as the keyboard, in either case. H and O, which only toggle what the
    /// window draws over the frame, change nothing in a script.
    #[arg(long, value_delimiter = ',')]
    pub keys: Vec<String>,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Refuse views estimated to need more memory than this (e.g. 8G, 512MB, 2GiB).
    /// Default: the memory the system has available.
    #[arg(long, value_parser = lgh_render::budget::parse_bytes)]
    pub max_memory: Option<u64>,
    /// Where the indirect light is computed: cpu, or gpu (the passes `lgh render --device
    /// gpu` runs there; a method not ported yet, cycled to with M, runs on the CPU and the
    /// readout says so).
    #[arg(long, value_enum, default_value_t = Device::Cpu)]
    pub device: Device,
    /// With `--device gpu`: the GPU method standing for each method (set by the program that
    /// links the GPU backend, e.g. `lgh_gpu::gpu_method`; not a flag).
    #[arg(skip)]
    pub backend: Option<MethodMap>,
}

/// The most frames `--frames` takes (a million: over four hours at 60 fps).
pub const MAX_FRAMES: u64 = 1_000_000;

/// The viewer's alpha when `--alpha` is not given: 1.5, for interactive rates (the render
/// defaults' 3 measured 3.1 fps where the paper's 1 gave 6.0). Against the paper's 1 it
/// costs 4% of the frame and lowers FLIP by a quarter; at 1 the image is up to 12% too dark
/// (Sponza, k = 1; docs/performance.md, "The viewer frame (2026-12-03, fifth session)").
pub const INTERACTIVE_ALPHA: f32 = 1.5;

/// The viewer's a-trous passes when `--filter-passes` is not given: one fewer than the
/// render default, 3.4 ms less a frame at 640x360. With the temporal filter on, FLIP of a
/// 12-frame sequence at the viewer's settings rose by 0.2-0.9% on five scenes, where 3
/// passes cost 1-3% (docs/performance.md, "The viewer frame (2026-12-03, fifth session)").
pub const INTERACTIVE_FILTER_PASSES: u32 = 4;

/// Shadow samples per pixel the viewer starts lgh with (K cycles 0, 1, 4): the render
/// default (5) gave 4.4 fps at 640x360, not an interactive start.
pub const INTERACTIVE_SHADOW_SAMPLES: u32 = 1;

impl ViewArgs {
    /// Starts at interactive settings where the command line leaves them (`given(id)` tells
    /// whether the flag of clap id `id` was given): alpha [`INTERACTIVE_ALPHA`] and S_1 the
    /// lowest level shaded, one hierarchy (no normal bins), [`INTERACTIVE_FILTER_PASSES`]
    /// a-trous passes, and for lgh 4 x 4 interleaving ([`lgh::INTERACTIVE_INTERLEAVE`]) and
    /// [`INTERACTIVE_SHADOW_SAMPLES`] shadow sample,
    /// instead of the render defaults, which favour accuracy.
    pub fn use_interactive_defaults(&mut self, given: impl Fn(&str) -> bool) {
        let lgh_method = [lgh::LGH, lgh::LGH_UNSHADOWED].contains(&self.settings.method);
        if !given("interleave") && lgh_method {
            self.settings.tiling.interleave = Some(lgh::INTERACTIVE_INTERLEAVE);
        }
        if !given("alpha") {
            self.settings.lgh.alpha = INTERACTIVE_ALPHA;
        }
        if !given("start_level") {
            self.settings.lgh.start_level = 1;
        }
        if !given("normal_bins") {
            self.settings.lgh.normal_bins = false;
        }
        if !given("filter_passes") {
            self.settings.shadows.filter_passes = INTERACTIVE_FILTER_PASSES;
        }
        if !given("samples") && lgh_method {
            self.settings.shadows.samples = Some(INTERACTIVE_SHADOW_SAMPLES);
        }
    }

    /// Checks the flags that the settings' validation does not see, before any work: the
    /// frame count, the light's speed, the key script, and the output paths (they exist,
    /// take a file, and are not one file).
    ///
    /// # Errors
    /// The first bad flag, named.
    pub fn check(&self) -> anyhow::Result<()> {
        if let Some(n) = self.frames
            && !(1..=MAX_FRAMES).contains(&n)
        {
            anyhow::bail!("--frames {n}: expected 1 to {MAX_FRAMES}");
        }
        if !self.light_speed.is_finite() || self.light_speed.abs() > 360.0 {
            anyhow::bail!(
                "--light-speed {}: must be a number of degrees per frame in [-360, 360]",
                self.light_speed
            );
        }
        headless::check_keys(&self.keys)?;
        let mut outputs = Vec::new();
        if let Some(p) = &self.screenshot {
            lgh_render::image::check_output_path(p)?;
            outputs.push(("--screenshot", p.as_path()));
        }
        if let Some(p) = &self.stats {
            outputs.push(("--stats", p.as_path()));
        }
        lgh_render::output::check_outputs(&outputs)?;
        Ok(())
    }

    /// The starting settings with the frame size of `--size`.
    #[must_use]
    pub fn render_settings(&self) -> RenderSettings {
        RenderSettings {
            width: self.size.0,
            height: self.size.1,
            ..self.settings.clone()
        }
    }
}
