//! Finding the grid light at a vertex of a level: a dense table of every vertex where it is
//! small enough, else a table of where each vertex row starts among the level's lights
//! (which are in vertex order) and a search within the row.

use glam::{UVec3, Vec3};
use rayon::prelude::*;

use super::LightingGrid;
use super::splat::locate;

/// A grid with, per level, where each vertex row (y, z) starts among the level's lights
/// (which are in (z, y, x) order): a vertex is found by one table read and a search within
/// its row (a few entries), instead of a binary search over the whole level, whose cache
/// misses dominated the draw.
#[derive(Clone, Copy, Debug)]
pub struct VertexLookup<'a> {
    /// The grid.
    pub grid: &'a LightingGrid,
    /// Its row tables.
    pub rows: &'a VertexRows,
}

/// The tables of [`VertexLookup`], owned (built for one grid; valid until it changes).
#[derive(Clone, Debug, Default)]
pub struct VertexRows {
    /// Per level l (index l - 1), one of the two tables.
    rows: Vec<LevelTable>,
}

/// How one level's vertices are found.
#[derive(Clone, Debug)]
enum LevelTable {
    /// The light index of every vertex (x fastest), [`NO_LIGHT`] where there is none.
    Dense(Vec<u32>),
    /// `(r + 1)^2 + 1` row starts, absolute light indices.
    Rows(Vec<u32>),
}

/// A vertex without a light in a dense table.
const NO_LIGHT: u32 = u32::MAX;

/// The largest level, in vertices, given a dense table (16 MB of indices).
const MAX_DENSE: usize = 1 << 22;

impl VertexRows {
    /// The row tables of `grid` (one pass over its vertices).
    #[must_use]
    pub fn new(grid: &LightingGrid) -> Self {
        let rows = (1..=grid.l_max())
            .into_par_iter()
            .map(|l| {
                let side = grid.geometry.cells_per_axis(l) as usize + 1;
                let range = grid.level_range(l);
                if side * side * side <= MAX_DENSE {
                    let mut table = vec![NO_LIGHT; side * side * side];
                    for (j, v) in grid.vertex[range.clone()].iter().enumerate() {
                        let at = (v.z as usize * side + v.y as usize) * side + v.x as usize;
                        table[at] = (range.start + j) as u32;
                    }
                    return LevelTable::Dense(table);
                }
                LevelTable::Rows(row_starts(grid, l))
            })
            .collect();
        Self { rows }
    }
}

/// Where each vertex row (y, z) of level `l` >= 1 of `grid` starts among the level's
/// lights, which are in (z, y, x) order: `(r + 1)^2 + 1` absolute light indices for r cells
/// per axis; row (y, z) holds the lights `starts[z (r + 1) + y]..starts[z (r + 1) + y + 1]`.
#[must_use]
pub fn row_starts(grid: &LightingGrid, l: u32) -> Vec<u32> {
    let side = grid.geometry.cells_per_axis(l) as usize + 1;
    let range = grid.level_range(l);
    let mut start = vec![0u32; side * side + 1];
    for v in &grid.vertex[range.clone()] {
        start[v.z as usize * side + v.y as usize + 1] += 1;
    }
    // Prefix sums: row k is then start[k]..start[k + 1].
    let mut at = range.start as u32;
    for s in &mut start {
        at += *s;
        *s = at;
    }
    start
}

impl<'a> VertexLookup<'a> {
    /// The lookup of `grid` with its row tables `rows` (from [`VertexRows::new`] of the same
    /// grid).
    #[must_use]
    pub fn new(grid: &'a LightingGrid, rows: &'a VertexRows) -> Self {
        Self { grid, rows }
    }

    /// Cell and in-cell fraction of point `p` at level `l`.
    #[must_use]
    pub fn locate(&self, l: u32, p: Vec3) -> (UVec3, Vec3) {
        let geom = self.grid.geometry;
        locate(p, geom.origin, geom.cell_size(l), geom.cells_per_axis(l))
    }

    /// Index of the light at vertex `v` of level `l`, if it has one.
    #[inline]
    #[must_use]
    pub fn find(&self, l: u32, v: UVec3) -> Option<usize> {
        let side = self.grid.geometry.cells_per_axis(l) as usize + 1;
        if v.x as usize >= side || v.y as usize >= side {
            return None;
        }
        match &self.rows.rows[l as usize - 1] {
            LevelTable::Dense(table) => {
                let at = (v.z as usize * side + v.y as usize) * side + v.x as usize;
                table
                    .get(at)
                    .copied()
                    .filter(|&j| j != NO_LIGHT)
                    .map(|j| j as usize)
            }
            LevelTable::Rows(rows) => {
                let row = v.z as usize * side + v.y as usize;
                let (&a, &b) = (rows.get(row)?, rows.get(row + 1)?);
                let (a, b) = (a as usize, b as usize);
                self.grid.vertex[a..b]
                    .binary_search_by_key(&v.x, |u| u.x)
                    .ok()
                    .map(|k| a + k)
            }
        }
    }
}
