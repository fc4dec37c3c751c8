//! # lgh-render: the CPU renderer
//!
//! Ray tracing, the passes of a frame and image files. [`frame`] is the recipe of a frame and
//! the best place to start reading.
//!
//! | module | what it does |
//! | --- | --- |
//! | [`accel`] | BVH over all triangles: closest-hit and any-hit rays |
//! | [`world`] | a scene prepared for rendering; surface points; shadow-ray offsets |
//! | [`lights`] | primary lights, sampled by power (light paths) or per area (direct light) |
//! | [`gbuffer`] | primary visibility: position, normal, albedo, depth, emission |
//! | [`direct`] | direct lighting with exact shadow rays |
//! | [`vpl_gen`] | VPLs by light tracing |
//! | [`brute`] | the brute-force many-lights reference |
//! | [`lgh`] | lighting grid hierarchy rendering: tiled lighting, shadow selection, ratio estimator |
//! | [`tiles`] | screen-tile binning of light volumes (shared by the tiled methods) |
//! | [`atrous`] | edge-avoiding a-trous filter |
//! | [`interleave`] | interleaved sampling: sub-image lattices, split/merge, discontinuity-aware blur |
//! | [`slc`] | stochastic light culling: stochastic and clamped tiled lighting |
//! | [`pt`] | progressive path tracing with many area lights: SLC light sampling and baselines |
//! | [`temporal`], [`sequence`] | temporal filtering of shadows; frame sequences and flicker |
//! | [`ratio`] | ray-traced shadows through the ratio estimator (shared by LGH and SLC) |
//! | [`frame`] | the passes in order, with timings |
//! | [`image`], [`tonemap`], [`metrics`] | EXR/PNG files, tone mapping, image differences |
//! | [`raybench`] | ray throughput measurement |
//!
//! Every pass is parallel (rayon) and deterministic: the same seed gives the same image
//! whatever the thread count.
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod accel;
pub mod atrous;
pub mod brute;
pub mod direct;
pub mod frame;
pub mod gbuffer;
pub mod image;
pub mod interleave;
pub mod ism;
pub mod lgh;
pub mod light_batch;
pub mod lights;
pub mod metrics;
pub mod passes;
pub mod progress;
pub mod pt;
pub mod ratio;
pub mod raybench;
pub mod sequence;
pub mod slc;
pub mod temporal;
pub mod tiles;
pub mod tonemap;
pub mod vpl_gen;
pub mod world;

pub use frame::{
    Component, Frame, FrameMemory, LghStats, Method, PtStats, RenderError, RenderSettings,
    SlcStats, render_frame, render_frame_with,
};
pub use image::Image;
pub use progress::{Progress, Silent};
pub use world::World;
