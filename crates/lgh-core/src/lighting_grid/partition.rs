//! How the hierarchy shares one input light among its grid lights at a shading point, and the
//! normaliser that makes the shares sum to one: the basis of the unbiased shadow estimate of
//! `lgh` (an extension of Lin & Yuksel 2019 sections 2.2 and 3.3; docs/design.md, "Unbiased
//! estimate").
//!
//! A grid light g of level l stands for w_g(p_i) of every input light i (the trilinear
//! weight of its vertex at spacing h_l; the hierarchy must be the all-scatter one, which the
//! restriction builds exactly), and is shaded at x with the blending weight B_l(|x - p_g|),
//! the distance taken to its centroid p_g. Input light i is thus counted at x with the total
//! weight
//!
//! Lambda_i(x) = sum over levels l, sum over the 8 vertices g of p_i's cell of level l,
//! of w_g(p_i) B_l(|x - p_g|),
//!
//! which is near 1 (the B_l sum to one at any one distance, and the w_g to one at any level)
//! but not equal to it: the centroids are not where input light i is. The shares
//! pi_ig(x) = w_g(p_i) B_l(|x - p_g|) / Lambda_i(x) sum to exactly one over the grid lights
//! of all levels, so the sum over g of the sum over i of pi_ig f_i is the sum of the f_i,
//! whatever the hierarchy's approximation. Blending by the distance to the vertex instead
//! would need no lookup of centroids, but at alpha = 1 it counts a light near x up to three
//! times (the vertices of coarse levels are far from x even when all their light is near).

use glam::{UVec3, Vec3};

use rayon::prelude::*;

use super::splat::cell_of;
use super::{GridGeometry, LightingGrid};
use crate::blending::{LevelRole, blend};

/// The levels a hierarchy shades and their blending radii: levels `lowest..=l_max`
/// (`lowest` 0 adds the input lights themselves as S_0), with r_l = alpha h_l.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadedLevels {
    /// The lowest level shaded (0 or 1).
    pub lowest: u32,
    /// alpha of r_l = alpha h_l.
    pub alpha: f32,
}

/// How far a grid light's centroid can lie from its vertex, in cells: the diagonal of a cell
/// (a centroid lies within one cell of its vertex along every axis).
const VERTEX_REACH: f32 = 1.732_051;

/// How far it can lie from the centre of a cell whose corner is its vertex: half a diagonal
/// more.
const CELL_REACH: f32 = 0.866_026 + VERTEX_REACH;

/// B_l if it is the same at every distance in `near..=far` (radius `r`), else `None`.
fn constant_blend(role: LevelRole, near: f32, far: f32, r: f32) -> Option<f32> {
    let (ones_from, ones_to) = match role {
        LevelRole::Only => return Some(1.0),
        LevelRole::Lowest => (f32::NEG_INFINITY, r),
        LevelRole::Middle => (r, r),
        LevelRole::Top => (r, f32::INFINITY),
    };
    let (zero_below, zero_above) = match role {
        LevelRole::Only => (f32::NEG_INFINITY, f32::INFINITY),
        LevelRole::Lowest => (f32::NEG_INFINITY, 2.0 * r),
        LevelRole::Middle => (0.5 * r, 2.0 * r),
        LevelRole::Top => (0.5 * r, f32::INFINITY),
    };
    if far <= zero_below || near >= zero_above {
        Some(0.0)
    } else if near >= ones_from && far <= ones_to && ones_from < ones_to {
        Some(1.0)
    } else {
        None
    }
}

/// The largest level, in vertices, whose centroids [`Partition`] keeps in a dense table
/// (24 MB).
const MAX_DENSE: usize = 1 << 21;

/// Lambda_i(x) for one hierarchy: its geometry, levels, and the centroid of every vertex's
/// light, in a dense table per level where the level is small enough (x fastest; NaN where
/// no light), so that the 8 lights around a point are read from 4 places in memory without a
/// search, and as sorted rows for the larger levels.
#[derive(Clone, Debug)]
pub struct Partition {
    /// The shaded levels and their radii.
    pub levels: ShadedLevels,
    geometry: GridGeometry,
    /// Per level l >= 1 (index l - 1).
    centroids: Vec<Centroids>,
    /// Per shaded level, `lowest..=l_max`: its constants, computed once instead of per call
    /// of [`Partition::blend_total`] (which runs once per visible shadow sample).
    shaded: Vec<LevelConstants>,
}

/// One shaded level's constants for [`Partition::blend_total`].
#[derive(Clone, Copy, Debug)]
struct LevelConstants {
    l: u32,
    role: LevelRole,
    /// h_l and 1 / h_l.
    h: f32,
    inv_h: f32,
    /// r_l = alpha h_l and 1 / r_l.
    r: f32,
    inv_r: f32,
    /// Cells per axis.
    cells: u32,
}

/// The centroids of one level's lights by vertex.
#[derive(Clone, Debug)]
enum Centroids {
    /// Every vertex (x fastest), NaN where there is no light.
    Dense(Vec<Vec3>),
    /// The lights in vertex order: where each row (y, z) starts, each light's x and centroid.
    Rows {
        start: Vec<u32>,
        x: Vec<u32>,
        position: Vec<Vec3>,
    },
}

impl Partition {
    /// The partition of `grid` shaded at `levels`.
    #[must_use]
    pub fn new(grid: &LightingGrid, levels: ShadedLevels) -> Self {
        Self::with_dense_limit(grid, levels, MAX_DENSE)
    }

    /// [`Partition::new`] with dense tables for levels of at most `max_dense` vertices.
    fn with_dense_limit(grid: &LightingGrid, levels: ShadedLevels, max_dense: usize) -> Self {
        let geometry = grid.geometry;
        let centroids = (1..=geometry.l_max)
            .into_par_iter()
            .map(|l| {
                let side = geometry.cells_per_axis(l) as usize + 1;
                let range = grid.level_range(l);
                let (vertex, position) = (&grid.vertex[range.clone()], &grid.position[range]);
                if side * side * side <= max_dense {
                    let mut table = vec![Vec3::NAN; side * side * side];
                    for (v, &p) in vertex.iter().zip(position) {
                        table[(v.z as usize * side + v.y as usize) * side + v.x as usize] = p;
                    }
                    return Centroids::Dense(table);
                }
                let mut start = vec![0u32; side * side + 1];
                for v in vertex {
                    start[v.z as usize * side + v.y as usize + 1] += 1;
                }
                for k in 1..start.len() {
                    start[k] += start[k - 1];
                }
                Centroids::Rows {
                    start,
                    x: vertex.iter().map(|v| v.x).collect(),
                    position: position.to_vec(),
                }
            })
            .collect();
        let shaded = (levels.lowest..=geometry.l_max)
            .map(|l| {
                let (h, r) = (geometry.cell_size(l), geometry.radius(l, levels.alpha));
                LevelConstants {
                    l,
                    role: LevelRole::of(l, levels.lowest, geometry.l_max),
                    h,
                    inv_h: 1.0 / h,
                    r,
                    inv_r: 1.0 / r,
                    cells: geometry.cells_per_axis(l),
                }
            })
            .collect();
        Self {
            levels,
            geometry,
            centroids,
            shaded,
        }
    }

    /// The centroid of the light at vertex `v` of level `l`, if it has one.
    #[inline]
    fn centroid(&self, l: u32, v: UVec3) -> Option<Vec3> {
        let side = self.geometry.cells_per_axis(l) as usize + 1;
        if v.x as usize >= side || v.y as usize >= side {
            return None;
        }
        match self.centroids.get(l as usize - 1)? {
            Centroids::Dense(table) => table
                .get((v.z as usize * side + v.y as usize) * side + v.x as usize)
                .copied()
                .filter(|q| !q.x.is_nan()),
            Centroids::Rows { start, x, position } => {
                let row = v.z as usize * side + v.y as usize;
                let (a, b) = (*start.get(row)? as usize, *start.get(row + 1)? as usize);
                let k = x[a..b].binary_search(&v.x).ok()?;
                Some(position[a + k])
            }
        }
    }

    /// Lambda_i(x) of the module docs for the input light at `p` and the shading point `x`.
    #[must_use]
    pub fn blend_total(&self, x: Vec3, p: Vec3) -> f32 {
        let origin = self.geometry.origin;
        let mut total = 0.0;
        for &LevelConstants {
            l,
            role,
            h,
            inv_h,
            r,
            inv_r,
            cells,
        } in &self.shaded
        {
            if l == 0 {
                total += blend(role, (x - p).length(), r);
                continue;
            }
            // `locate`, multiplying by 1 / h_l.
            let (c, f) = cell_of((p - origin) * inv_h, cells);
            let centre = origin + (c.as_vec3() + Vec3::splat(0.5)) * h;
            // Where B_l is the same at every distance the level's centroids can have, the
            // level adds that value times the weights, which sum to one (every vertex around
            // a light of non-zero intensity has a light).
            let dc = (x - centre).length();
            if let Some(b) = constant_blend(role, dc - CELL_REACH * h, dc + CELL_REACH * h, r) {
                total += b;
                continue;
            }
            // The 8 corners' centroids and weights (no light: weight 0, centroid x), kept as
            // whole points: scattering them into per-axis lane arrays stored scalars that
            // the vector loads after them waited on (store forwarding failed), the largest
            // cost of this function in a profile of the shadow pass.
            let mut q = [x; 8];
            let mut w = [0.0f32; 8];
            let (wx, wy, wz) = ([1.0 - f.x, f.x], [1.0 - f.y, f.y], [1.0 - f.z, f.z]);
            let mut put = |corner: usize, found: Option<Vec3>| {
                if let Some(p) = found {
                    q[corner] = p;
                    w[corner] = wx[corner & 1] * wy[(corner >> 1) & 1] * wz[corner >> 2];
                }
            };
            match self.centroids.get(l as usize - 1) {
                Some(Centroids::Dense(table)) => {
                    // The cell's corners are 8 fixed offsets from its first (c + 1 <= r,
                    // inside the table).
                    let side = cells as usize + 1;
                    let base = (c.z as usize * side + c.y as usize) * side + c.x as usize;
                    let plane = side * side;
                    let offsets = [
                        0,
                        1,
                        side,
                        side + 1,
                        plane,
                        plane + 1,
                        plane + side,
                        plane + side + 1,
                    ];
                    for (corner, &o) in offsets.iter().enumerate() {
                        put(
                            corner,
                            table.get(base + o).copied().filter(|q| !q.x.is_nan()),
                        );
                    }
                }
                _ => {
                    for corner in 0..8usize {
                        let d = UVec3::new(
                            corner as u32 & 1,
                            (corner as u32 >> 1) & 1,
                            corner as u32 >> 2,
                        );
                        put(corner, self.centroid(l, c + d));
                    }
                }
            }
            let (rise_off, fall_off) = role.floors();
            let mut b = [0.0f32; 8];
            for k in 0..8 {
                let (dx, dy, dz) = (q[k].x - x.x, q[k].y - x.y, q[k].z - x.z);
                let t = (dx * dx + dy * dy + dz * dz).sqrt() * inv_r;
                let rising = (2.0 * t - 1.0).clamp(0.0, 1.0).max(rise_off);
                let falling = (2.0 - t).clamp(0.0, 1.0).max(fall_off);
                b[k] = w[k] * rising.min(falling);
            }
            // Pairwise, in the order of the lanes above.
            total += ((b[0] + b[1]) + (b[2] + b[3])) + ((b[4] + b[5]) + (b[6] + b[7]));
        }
        total
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lighting_grid::{Construction, InputLights, LevelCount, LightingGrid};
    use crate::rng::Rng;

    /// The shares w_g(p_i) B_l(|x - p_g|) / Lambda_i of every input light, summed over all
    /// grid lights of all levels, are one, for random lights and shading points, with and
    /// without S_0 and at several alpha; and Lambda stays within a plausible range.
    #[test]
    fn shares_sum_to_one() {
        let mut rng = Rng::new(&[41]);
        let mut v = || {
            Vec3::new(
                4.0 * rng.next_f32(),
                2.0 * rng.next_f32(),
                3.0 * rng.next_f32(),
            )
        };
        let p: Vec<Vec3> = (0..400).map(|_| v()).collect();
        let i = vec![Vec3::ONE; p.len()];
        let input = InputLights {
            positions: &p,
            intensity: &i,
            normals: None,
        };
        for construction in [Construction::Restrict, Construction::ScatterAll] {
            let (grid, _) =
                LightingGrid::build(&input, LevelCount::Fixed(5), construction).unwrap();
            let geom = grid.geometry;
            for (lowest, alpha) in [(1, 1.0), (0, 1.0), (1, 2.0)] {
                let shaded = ShadedLevels { lowest, alpha };
                let dense = Partition::new(&grid, shaded);
                let rows = Partition::with_dense_limit(&grid, shaded, 0);
                for _ in 0..20 {
                    let x = v();
                    for &pi in p.iter().take(50) {
                        let lambda = dense.blend_total(x, pi);
                        assert_eq!(lambda, rows.blend_total(x, pi));
                        assert!(lambda > 0.2 && lambda < 3.0, "{lambda}");
                        // The shares of every grid light that holds pi, by brute force.
                        let mut sum = 0.0;
                        for l in lowest..=geom.l_max {
                            let role = LevelRole::of(l, lowest, geom.l_max);
                            let r = geom.radius(l, alpha);
                            if l == 0 {
                                sum += blend(role, (x - pi).length(), r);
                                continue;
                            }
                            for g in grid.level_range(l) {
                                let d = (pi - geom.vertex_position(l, grid.vertex[g]))
                                    / geom.cell_size(l);
                                let t = (Vec3::ONE - d.abs()).max(Vec3::ZERO);
                                let w = t.x * t.y * t.z;
                                sum += w * blend(role, (x - grid.position[g]).length(), r);
                            }
                        }
                        assert!((sum / lambda - 1.0).abs() < 1e-4, "{sum} vs {lambda}");
                    }
                }
            }
        }
    }
}
