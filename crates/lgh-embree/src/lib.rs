//! A small safe wrapper of Embree 3 (Wald et al. 2014, "Embree: A Kernel Framework for
//! Efficient CPU Ray Tracing"), the second ray-tracing backend of lgh.
//!
//! This is the one crate of the workspace that holds unsafe code (the project's decision:
//! every other crate keeps `forbid(unsafe_code)`). It declares the dozen C functions it calls
//! in `sys.rs` by hand, so that each declaration can be read against the header, and
//! exposes a triangle [`Scene`] with closest-hit and occlusion queries for single rays and
//! for streams of rays. How it is kept sound:
//!
//! - every `unsafe` block carries a `// SAFETY:` comment naming the Embree guarantee that it
//!   relies on;
//! - a [`Scene`] is built and committed inside [`Scene::new`] and never modified afterwards;
//!   Embree's documentation guarantees that the query functions (`rtcIntersect1`,
//!   `rtcOccluded1` and their stream variants `rtcIntersect1M`, `rtcOccluded1M`) may be
//!   called from any number of threads at once on a committed scene, which is what makes the
//!   `Send` and `Sync` implementations sound;
//! - the struct layouts are those of Embree's default configuration, which the build script
//!   checks in the library's `rtcore_config.h` before linking, and compile-time size
//!   assertions check the declarations;
//! - a scene made with a [`HitFilter`] owns it, boxed at a fixed address that Embree holds
//!   as the geometry's user data, and Embree calls it only during queries on that scene;
//! - inputs Embree does not check (vertex indices, counts that must fit 32 bits, non-finite
//!   vertices) are checked here before any call.
//!
//! Without the library at build time the crate is a stub: [`Scene::new`] returns
//! [`Error::NotBuilt`] (the `required` feature turns that into a build error).

#![warn(missing_docs)]

use std::fmt;

#[cfg(embree)]
mod scene;
#[cfg(embree)]
#[allow(missing_docs, unsafe_code)]
mod sys;
#[cfg(embree)]
pub use scene::Scene;

#[cfg(not(embree))]
mod stub;
#[cfg(not(embree))]
pub use stub::Scene;

/// Which hits count, asked of every candidate hit on a scene made with
/// [`Scene::with_filter`]: the triangle's index and the hit's barycentrics (u, v) (the
/// weights of its second and third corners); false makes the ray go on as if the triangle
/// were not there (alpha cut-outs). It must not panic (it runs inside Embree's traversal).
pub type HitFilter = std::sync::Arc<dyn Fn(u32, [f32; 2]) -> bool + Send + Sync>;

/// True if this build links Embree (else every [`Scene::new`] fails with
/// [`Error::NotBuilt`]).
pub const AVAILABLE: bool = cfg!(embree);

/// A ray segment: `origin + t dir` for t in (0, `t_max`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Ray {
    /// Origin.
    pub origin: [f32; 3],
    /// Direction (any length; `t` is measured in its units).
    pub dir: [f32; 3],
    /// End of the segment.
    pub t_max: f32,
}

/// The closest hit along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray.
    pub t: f32,
    /// Index of the triangle in the slice given to [`Scene::new`].
    pub triangle: u32,
    /// Barycentric coordinates (u, v): the point is (1 - u - v) v0 + u v1 + v v2.
    pub uv: [f32; 2],
}

/// How much time the BVH build spends on quality.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BuildQuality {
    /// Fast build for geometry rebuilt every frame (Embree's `RTC_BUILD_QUALITY_LOW` with
    /// the dynamic scene flag): a moving object.
    Low,
    /// Embree's default (`RTC_BUILD_QUALITY_MEDIUM`).
    #[default]
    Medium,
    /// Spatial splits (`RTC_BUILD_QUALITY_HIGH`): the fastest traversal, for a scene built
    /// once and traced for long.
    High,
}

/// Why a scene could not be made.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Error {
    /// This build does not link Embree.
    NotBuilt,
    /// The device could not be created (e.g. the processor lacks SSE2), with Embree's error
    /// code.
    Device(i32),
    /// The mesh is not acceptable: an index out of range, a non-finite vertex, or more than
    /// 2^32 - 1 triangles or vertices.
    Mesh(String),
    /// Embree reported an error while building (e.g. out of memory), with its code.
    Build(i32),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NotBuilt => write!(
                f,
                "this build of lgh has no Embree (build with --features embree and libembree-dev installed)"
            ),
            Self::Device(c) => write!(f, "Embree device could not be created (error {c})"),
            Self::Mesh(why) => write!(f, "mesh not accepted by Embree: {why}"),
            Self::Build(c) => write!(f, "Embree failed to build the scene (error {c})"),
        }
    }
}

impl std::error::Error for Error {}

/// Checks what Embree itself does not: indices in range, finite vertices, counts that fit
/// its 32-bit ids.
fn check_mesh(vertices: &[[f32; 3]], triangles: &[[u32; 3]]) -> Result<(), Error> {
    if vertices.len() >= u32::MAX as usize || triangles.len() >= u32::MAX as usize {
        return Err(Error::Mesh(
            "more than 2^32 - 2 vertices or triangles".into(),
        ));
    }
    if let Some(i) = vertices
        .iter()
        .position(|v| !v.iter().all(|c| c.is_finite()))
    {
        return Err(Error::Mesh(format!("vertex {i} is not finite")));
    }
    let n = vertices.len() as u32;
    if let Some(t) = triangles.iter().position(|t| t.iter().any(|&i| i >= n)) {
        return Err(Error::Mesh(format!(
            "triangle {t} names a vertex out of range"
        )));
    }
    Ok(())
}
