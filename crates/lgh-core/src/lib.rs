//! # lgh-core: many-lights algorithms
//!
//! The scene-independent part of lgh: the data the many-lights methods work on and the
//! algorithms of the papers, with no file I/O, no ray tracing and no global state.
//!
//! | module | what it holds | paper |
//! | --- | --- | --- |
//! | [`rng`] | counter-based random numbers (deterministic whatever the thread count) | - |
//! | [`qmc`] | Owen-scrambled Sobol points for light paths, and the [`qmc::Sampler`] trait | Burley 2020 |
//! | [`sampling`] | warps (cosine hemisphere, triangle, raised cosine) and a discrete distribution | - |
//! | [`color`] | luminance and RGB helpers | - |
//! | [`vpl`] | virtual point lights, stored structure-of-arrays | Keller 1997; LGH 2019 section 3 |
//! | [`lighting_grid`] | the lighting grid hierarchy, built in parallel | LGH 2019 section 3.1 |
//! | [`blending`] | blending functions B_l(d), radii r_l = alpha h_l | LGH 2019 section 2.2, Fig. 2 |
//! | [`light_range`] | stochastic and clamped light ranges | SLC 2016 sections 3.1-3.2, Appendix A |
//! | [`sphere_tree`] | bounding sphere tree of light influence regions | SLC 2016 section 5.2 |
//! | [`reservoir`] | streaming weighted selection of shadow samples | LGH 2019 section 3.3, Appendix A |
//!
//! Everything here is plain data plus functions, so that other engines can use it with their
//! own ray tracer.
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod blending;
pub mod color;
pub mod light_range;
pub mod lighting_grid;
pub mod qmc;
pub mod reservoir;
pub mod rng;
pub mod sampling;
pub mod sphere_tree;
pub mod timing;
pub mod vpl;

pub use glam::{Vec2, Vec3, Vec3A};
