//! # lgh-render: the CPU renderer
//!
//! Ray tracing, the passes of a frame, the many-lights methods and image files.
//! [`frame`] is the recipe of a frame and the best place to start reading; [`methods`] holds
//! one folder per indirect-lighting method behind one contract.
//!
//! | module | what it does |
//! | --- | --- |
//! | [`frame`] | the recipe: the passes of a frame in order, with timings |
//! | [`settings`] | every setting of a frame (the command line derives its flags from them) |
//! | [`world`] | a scene prepared for rendering: BVH ([`world::accel`]), primary lights ([`world::lights`]), surface points, shadow-ray offsets |
//! | [`passes`] | the passes every frame runs: G-buffer, VPLs by light tracing |
//! | [`direct`] | direct light: punctual lights exactly, area lights analytic x filtered shadow ratio |
//! | [`methods`] | the indirect-lighting methods (`brute`, `lgh`, `slc`, `pt`) and their contract |
//! | [`shading`] | machinery the tiled methods share: tile binning, interleaved sampling, the ratio estimator |
//! | [`denoise`] | the edge-avoiding a-trous filter and the temporal filter |
//! | [`sequence`] | frame sequences with temporal filtering; flicker |
//! | [`accumulate`] | progressive rendering: the mean of N frames with independent VPL sets |
//! | [`memory`] | working memory frames reuse |
//! | [`budget`] | the memory a render needs, estimated before it allocates |
//! | [`image`] | EXR/PNG files, tone mapping, image metrics |
//! | [`output`] | output files written whole, never over a device or folder, cleaned up on Ctrl-C |
//! | [`region`] | one rectangle of a frame, equal to the whole frame's pixels (render farms) |
//! | [`progress`], [`raybench`] | progress reporting; ray throughput |
//!
//! Every pass is parallel (rayon) and deterministic: the same seed gives the same image
//! whatever the thread count.
//!
//! ```
//! use lgh_render::methods::lgh::{LGH, LghStats};
//! use lgh_render::{RenderSettings, Silent, World, render_frame};
//!
//! let mut scene = lgh_scene::cornell::cornell_box();
//! scene.finish(std::path::Path::new("<built-in>"))?;
//! let world = World::new(scene);
//! let settings = RenderSettings {
//!     width: 32,
//!     height: 18,
//!     vpls: 500,
//!     method: LGH,
//!     ..RenderSettings::default()
//! };
//! let frame = render_frame(&world, &settings, &Silent)?;
//! assert!(frame.indirect.pixels.iter().any(|p| p.x > 0.0));
//! assert!(frame.stats::<LghStats>().is_some_and(|s| s.grid_lights > 0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Feature flags
//! - `clap`: the settings structs are `clap::Args` and their enums `clap::ValueEnum`, so a
//!   command line can take them as flags (the `lgh` binary does).
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod accumulate;
pub mod budget;
pub mod denoise;
pub mod direct;
pub mod display;
pub mod frame;
pub mod image;
pub mod memory;
pub mod methods;
pub mod output;
pub mod passes;
pub mod progress;
pub mod raybench;
pub mod region;
pub mod sequence;
pub mod settings;
pub mod shading;
pub mod world;

pub use frame::{Frame, render_frame, render_frame_shown, render_frame_with};
pub use image::Image;
pub use memory::FrameMemory;
pub use methods::{METHODS, Method, MethodOutput};
pub use progress::{Progress, Silent};
pub use settings::{Component, RenderError, RenderSettings, SettingsError};
pub use world::World;
