//! The trilinear splat of one level (LGH 2019 section 3.1), parallel and deterministic.
//!
//! Each source light adds its trilinear weights w to the 8 vertices of its cell: weight W,
//! position, squared position, intensity and normal sums (docs/design.md, "Hierarchy"). On a GPU this is a
//! scatter with atomics; here it is organised so that no two tasks ever write the same memory,
//! without atomics or locks:
//!
//! 1. every source gets its cell and in-cell fraction f, and is packed with its attributes
//!    into 40 bytes (plus 28 for the mass, variance and mean of a source that stands for
//!    several lights); the packed sources are sorted by cell row (z, then y) with a stable
//!    two-pass counting sort (input order is kept within a row). The sort is bound by memory
//!    bandwidth, so each pass buckets into a per-thread buffer that stays in the L2 cache
//!    and then copies it out in one stream (a restriction needs no sort at all; see
//!    `Workspace::gather_rows`);
//! 2. vertex row (v_y, v_z) receives from the sources of the four cell rows
//!    (v_y - 1 or v_y, v_z - 1 or v_z). Each vertex layer is cut into bands of consecutive
//!    vertex rows holding about [`BAND_SOURCES`] sources; a band task reads its cell rows in
//!    order and sums their contributions in a rolling pair of dense vertex rows (kept in the
//!    L2 cache), emitting each vertex row in x order once it is complete;
//! 3. bands are concatenated in (z, y) order, in parallel, so the level comes out in vertex
//!    order.
//!
//! A vertex's contributions arrive in an order fixed by the data (cell row y - 1 before y,
//! layer z - 1 before z, input order within a row), and the bands are cut by the data, not by
//! the thread pool, so the result does not depend on the number of threads. Each source's
//! moments are computed once per layer and shifted exactly to each corner. Positions are
//! accumulated relative to the receiving
//! vertex, in cell units and in double precision, which keeps the variance Q/W - (P/W)^2
//! free of cancellation far from the origin and the sums of coarse levels exact to ~1e-12.
//!
//! | file | concept |
//! | --- | --- |
//! | `mod.rs` | the sources and levels, locating a source, the splat's entry points |
//! | `accum.rs` | the double-precision sums of one vertex |
//! | `sort.rs` | packing the sources and the parallel counting sort by cell row (step 1) |
//! | `sweep.rs` | the band sweep that sums the contributions row by row (step 2) |
//! | `count.rs` | counting a level's vertices without building it (the level rule) |

use glam::{DVec3, UVec3, Vec3};
use rayon::prelude::*;

use super::geometry::GridGeometry;

mod accum;
mod count;
mod sort;
mod sweep;

pub(crate) use accum::Accum;
pub use count::{count_vertices, count_vertices_and_finer};
pub use sort::Workspace;
use sort::split_lengths;
pub use sweep::BAND_SOURCES;
use sweep::{sweep_band, with_rows};

/// The lights a level is built from: the input lights (S_0), or the grid lights of S_1 for
/// the gather construction. Optional arrays default to: no normal (zero), unit mass, zero
/// variance.
#[derive(Clone, Copy, Debug)]
pub struct Sources<'a> {
    /// Positions.
    pub positions: &'a [Vec3],
    /// RGB intensities.
    pub intensity: &'a [Vec3],
    /// Normals (oriented lights such as VPLs).
    pub normals: Option<&'a [Vec3]>,
    /// Mass of each source (the W of a grid light standing for several inputs).
    pub mass: Option<&'a [f32]>,
    /// Per-axis positional variance of each source (the spread of the inputs it stands for).
    pub variance: Option<&'a [Vec3]>,
    /// For the restriction from the next finer level: the sources' integer vertex
    /// coordinates there. The trilinear weights then come from the vertex (fractions 0, 1/2
    /// or 1, exactly), while the moments use the source's position; see
    /// [`Level::as_restriction_sources`].
    pub finer_vertices: Option<&'a [UVec3]>,
}

/// The grid lights of one level in vertex order (z, then y, then x), before compaction.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Level {
    /// Integer vertex coordinates.
    pub vertex: Vec<UVec3>,
    /// Weighted mean position P/W.
    pub position: Vec<Vec3>,
    /// Weighted intensity sum (not divided by W: every level keeps the total).
    pub intensity: Vec<Vec3>,
    /// Per-axis positional variance Q/W - (P/W)^2.
    pub variance: Vec<Vec3>,
    /// Weighted mean normal M/W (not renormalised).
    pub normal: Vec<Vec3>,
    /// Total weight W (mass) of the vertex.
    pub mass: Vec<f32>,
}

impl Level {
    /// Number of grid lights.
    #[must_use]
    pub fn len(&self) -> usize {
        self.vertex.len()
    }

    /// True if there is none.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.vertex.is_empty()
    }

    /// Appends the grid light of vertex `v` with sums `a` at a level of cell size `h` of a
    /// grid with origin `origin`.
    #[inline]
    pub(super) fn push(&mut self, v: UVec3, a: &Accum, origin: DVec3, h: f64) {
        let inv_w = 1.0 / a.w();
        let mean = a.p() * inv_w;
        self.vertex.push(v);
        self.position
            .push((origin + (v.as_dvec3() + mean) * h).as_vec3());
        self.intensity.push(a.i().as_vec3());
        self.variance
            .push(((a.q() * inv_w - mean * mean).max(DVec3::ZERO) * (h * h)).as_vec3());
        self.normal.push((a.n() * inv_w).as_vec3());
        self.mass.push(a.w() as f32);
    }

    /// This level's grid lights as sources for a coarser level (the gather from S_1): each
    /// counts with its mass and its variance. `normals` says
    /// whether the input lights had normals.
    #[must_use]
    pub fn as_sources(&self, normals: bool) -> Sources<'_> {
        Sources {
            positions: &self.position,
            intensity: &self.intensity,
            normals: normals.then_some(&self.normal[..]),
            mass: Some(&self.mass),
            variance: Some(&self.variance),
            finer_vertices: None,
        }
    }

    /// This level's grid lights as the sources of the next coarser level by exact
    /// restriction. A hat function of spacing 2h is a sum of hats of spacing h with weights
    /// (1/2, 1, 1/2) at the fine vertices, so a coarse vertex's sums (W, P, Q, intensity,
    /// normal) are the fine vertices' sums weighted by the trilinear weights *of the fine
    /// vertices* (the 3x3x3 stencil (1/2, 1, 1/2)^3). The result equals splatting the input
    /// lights at the coarse level (the all-scatter hierarchy) up to rounding, at the cost of
    /// splatting |S_(l-1)| sources instead of |S_0|. Must be taken before compaction: a
    /// zero-intensity vertex still carries mass.
    #[must_use]
    pub fn as_restriction_sources(&self, normals: bool) -> Sources<'_> {
        Sources {
            finer_vertices: Some(&self.vertex),
            ..self.as_sources(normals)
        }
    }

    pub(crate) fn truncate(&mut self, n: usize) {
        self.vertex.truncate(n);
        self.position.truncate(n);
        self.intensity.truncate(n);
        self.variance.truncate(n);
        self.normal.truncate(n);
        self.mass.truncate(n);
    }

    pub(super) fn clear(&mut self) {
        self.vertex.clear();
        self.position.clear();
        self.intensity.clear();
        self.variance.clear();
        self.normal.clear();
        self.mass.clear();
    }
}

/// Cell and in-cell fraction of a point at level spacing `h` with `r` cells per axis.
#[inline]
pub(crate) fn locate(p: Vec3, origin: Vec3, h: f32, r: u32) -> (UVec3, Vec3) {
    cell_of((p - origin) / h, r)
}

/// Cell and in-cell fraction (each in [0, 1]) of the point at grid coordinates `u` (its
/// offset from the origin in cells) in a grid of `r` cells per axis.
#[inline]
pub(crate) fn cell_of(u: Vec3, r: u32) -> (UVec3, Vec3) {
    // Truncation after the clamp is the floor (the clamped value is not negative), without
    // the libm call that `floor` costs on baseline x86-64.
    let c = u.clamp(Vec3::ZERO, Vec3::splat((r - 1) as f32)).as_uvec3();
    (c, (u - c.as_vec3()).clamp(Vec3::ZERO, Vec3::ONE))
}

/// Cell and in-cell fraction (0, 1/2 or 1 per axis, exactly) of vertex `v` of the next finer
/// grid (2r cells per axis) in a grid of `r` cells per axis.
#[inline]
pub(crate) fn locate_finer_vertex(v: UVec3, r: u32) -> (UVec3, Vec3) {
    let c = (v / 2).min(UVec3::splat(r - 1));
    (c, (v - 2 * c).as_vec3() * 0.5)
}

/// The 8 trilinear weights: for corner (dx, dy, dz), w = prod over axes of (d ? f : 1 - f).
#[inline]
pub(crate) fn corner_weight(f: Vec3, d: UVec3) -> f32 {
    let pick = |fa: f32, da: u32| if da == 1 { fa } else { 1.0 - fa };
    pick(f.x, d.x) * pick(f.y, d.y) * pick(f.z, d.z)
}
/// Sources per task, at least, of the passes that go layer by layer: below this, a task
/// costs rayon more than it saves.
pub(super) const LAYER_TASK_SOURCES: usize = 1 << 13;

/// Layers per task of a pass over `layers` layers of `n` sources in all (see
/// [`LAYER_TASK_SOURCES`]).
pub(super) fn layers_per_task(n: usize, layers: usize) -> usize {
    (LAYER_TASK_SOURCES * layers / n.max(1)).max(1)
}

/// Builds the grid lights of `level` from `src` into `out` (see the module docs), using
/// (and growing) the working memory `ws`.
pub fn splat_into(
    ws: &mut Workspace,
    src: &Sources,
    geom: &GridGeometry,
    level: u32,
    out: &mut Level,
) {
    ws.sort_by_row(src, geom, level);
    sweep_into(ws, geom, level, out);
}

/// [`splat_into`] right after [`count_vertices`] of the same `src` at the same `level` of the
/// same `geom`: the count's sort (which packed the sources) is reused. (The number of levels
/// is chosen by counting; the level kept is then built without sorting again.)
pub(crate) fn splat_counted_into(
    ws: &mut Workspace,
    src: &Sources,
    geom: &GridGeometry,
    level: u32,
    out: &mut Level,
) {
    if ws.sorted != Some((*geom, level, src.positions.len())) {
        ws.sort_by_row(src, geom, level);
    }
    sweep_into(ws, geom, level, out);
}

/// Sweeps the bands of a prepared workspace into `out`.
/// Each band writes its own part (kept in `ws` between builds), and the parts are then
/// copied to their places in `out` in parallel.
fn sweep_into(ws: &mut Workspace, geom: &GridGeometry, level: u32, out: &mut Level) {
    let mut parts = std::mem::take(&mut ws.parts);
    parts.resize_with(ws.bands.len(), Level::default);
    let w = &*ws;
    parts
        .par_iter_mut()
        .zip(w.bands.par_iter())
        .for_each(|(part, &b)| {
            part.clear();
            with_rows(|rows| sweep_band(w, b, rows, geom, level, part));
        });
    let used = &parts[..ws.bands.len()];
    let n = used.iter().map(Level::len).sum();
    concat_into(used, n, &mut out.vertex, |p| &p.vertex);
    concat_into(used, n, &mut out.position, |p| &p.position);
    concat_into(used, n, &mut out.intensity, |p| &p.intensity);
    concat_into(used, n, &mut out.variance, |p| &p.variance);
    concat_into(used, n, &mut out.normal, |p| &p.normal);
    concat_into(used, n, &mut out.mass, |p| &p.mass);
    ws.parts = parts;
}

/// Writes field `get` of the `parts` (`n` elements in all) one after the other into `out`,
/// in parallel.
fn concat_into<T: Copy + Default + Send + Sync>(
    parts: &[Level],
    n: usize,
    out: &mut Vec<T>,
    get: impl Fn(&Level) -> &[T] + Sync,
) {
    out.resize(n, T::default());
    let places = split_lengths(out, parts.iter().map(|p| get(p).len()));
    let copy = |(dst, p): (&mut [T], &Level)| dst.copy_from_slice(get(p));
    // Below this, a parallel loop costs more than it saves.
    if n < 1 << 15 {
        places.into_iter().zip(parts).for_each(copy);
    } else {
        places.into_par_iter().zip(parts).for_each(copy);
    }
}

/// Builds the grid lights of `level` from `src` with fresh working memory.
#[must_use]
pub fn splat(src: &Sources, geom: &GridGeometry, level: u32) -> Level {
    let mut out = Level::default();
    splat_into(&mut Workspace::default(), src, geom, level, &mut out);
    out
}

/// Finishes accumulated sums into a level (shared with the reference builder).
pub(crate) fn level_from_sums(
    sums: impl IntoIterator<Item = (UVec3, Accum)>,
    geom: &GridGeometry,
    level: u32,
) -> Level {
    let mut out = Level::default();
    let (origin, h) = (geom.origin.as_dvec3(), f64::from(geom.cell_size(level)));
    for (v, a) in sums {
        out.push(v, &a, origin, h);
    }
    out
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Unit-mass point sources without normals.
    pub(crate) fn point_sources<'a>(positions: &'a [Vec3], intensity: &'a [Vec3]) -> Sources<'a> {
        Sources {
            positions,
            intensity,
            normals: None,
            mass: None,
            variance: None,
            finer_vertices: None,
        }
    }
}
