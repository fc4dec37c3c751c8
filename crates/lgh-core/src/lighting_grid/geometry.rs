//! Grid geometry of the hierarchy (LGH 2019 section 3.1; docs/design.md, "Hierarchy").

use glam::{UVec3, Vec3};

/// The nested grids of a hierarchy with levels 1..=`l_max`.
///
/// The top level is one cubic cell of size h_top = 1.1 x the longest edge of the lights'
/// bounding box, centred on the box; every finer level halves the spacing:
/// h_l = h_top / 2^(l_max - l), so level l has 2^(l_max - l) cells and 2^(l_max - l) + 1
/// vertices per axis, all levels share the origin (the min corner), and every vertex of level
/// l + 1 is also a vertex of level l. Level 0 (the input lights) uses h_0 = h_1 / 2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridGeometry {
    /// The common min corner of every level's grid.
    pub origin: Vec3,
    /// Cell size of the top level.
    pub h_top: f32,
    /// The top level (at least 1).
    pub l_max: u32,
}

/// The factor between the longest edge of the bounds and the top cell (LGH demo code).
pub const TOP_CELL_SCALE: f32 = 1.1;

/// The least top cell, for a zero-size box at the origin (one light there, or all).
const MIN_CELL: f32 = 1e-10;

/// The finest allowed hierarchy: level 1 has at most 2^(MAX_LEVELS - 1) = 512 cells per axis.
pub const MAX_LEVELS: u32 = 10;

impl GridGeometry {
    /// The geometry for lights with bounds `lo..hi` and `l_max` levels (clamped to
    /// 1..=[`MAX_LEVELS`]). A zero-size box (one light, or all at one point) gets a small
    /// positive cell so that every formula stays finite.
    #[must_use]
    pub fn new(lo: Vec3, hi: Vec3, l_max: u32) -> Self {
        let centre = 0.5 * (lo + hi);
        let edge = (hi - lo).max_element();
        // Relative to the box's distance from the origin (cells far finer than that lose
        // their coordinates to rounding), not to the scene's units: a box a tenth of a
        // millimetre wide in metres keeps its fine cells.
        let floor = (1e-3 * centre.abs().max_element()).max(MIN_CELL);
        let h_top = (TOP_CELL_SCALE * edge).max(floor);
        Self {
            origin: centre - Vec3::splat(0.5 * h_top),
            h_top,
            l_max: l_max.clamp(1, MAX_LEVELS),
        }
    }

    /// h_l: the cell size of level `l` (h_0 = h_1 / 2).
    #[inline]
    #[must_use]
    pub fn cell_size(&self, l: u32) -> f32 {
        if l == 0 {
            0.5 * self.cell_size(1)
        } else {
            self.h_top / (1u32 << (self.l_max - l.min(self.l_max))) as f32
        }
    }

    /// r_l = alpha h_l, the radius of the blending function of level `l`.
    #[inline]
    #[must_use]
    pub fn radius(&self, l: u32, alpha: f32) -> f32 {
        alpha * self.cell_size(l)
    }

    /// Number of cells per axis of level `l` >= 1.
    #[inline]
    #[must_use]
    pub fn cells_per_axis(&self, l: u32) -> u32 {
        1 << (self.l_max - l.clamp(1, self.l_max))
    }

    /// World position of vertex `v` of level `l`.
    #[inline]
    #[must_use]
    pub fn vertex_position(&self, l: u32, v: UVec3) -> Vec3 {
        self.origin + v.as_vec3() * self.cell_size(l)
    }
}
