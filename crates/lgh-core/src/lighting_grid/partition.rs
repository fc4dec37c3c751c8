//! How the hierarchy shares one input light among its grid lights at a shading point, and the
//! normaliser that makes the shares sum to one: the basis of the unbiased shadow estimate of
//! `lgh` (an extension of Lin & Yuksel 2019 sections 2.2 and 3.3; docs/design.md, "Unbiased
//! estimate").
//!
//! A grid light g of level l stands for w_g(p_i) of every input light i (the trilinear
//! weight of its vertex at spacing h_l; the hierarchy must be the all-scatter one, which the
//! restriction builds exactly), and is shaded at x with the blending weight B_l(|x - p_g|),
//! the distance taken to its centroid p_g, times its geometry term G_g(x) = cos_x cos_v /
//! (|x - p_g|^2 + eps^2) (its normal m_g and isotropic share as the lighting loop shades
//! it, stored to 8 bits: [`quantized_emission`]). Input light i is counted at x with the
//! total weight
//!
//! Lambda_i(x) = sum over the admitted levels l, sum over the 8 vertices g of p_i's cell of
//! level l, of w_g(p_i) B_l(|x - p_g|) G_g(x)
//!
//! (level 0, the input lights themselves as S_0, adds B_0(|x - p_i|) G_i(x)). A level is
//! admitted where its blending weight at the light's own distance is not zero,
//! B_l(|x - p_i|) > 0: two levels at any distance, since the B_l of neighbouring levels
//! overlap pairwise (Eq. 3). The shares pi_ig(x) = w_g(p_i) B_l(|x - p_g|) G_g(x) /
//! Lambda_i(x) of the admitted levels' grid lights (zero for the others) sum to exactly one,
//! so the sum over g of the sum over i of pi_ig f_i is the sum of the f_i, whatever the
//! hierarchy's approximation.
//!
//! Any shares that sum to one keep the estimate unbiased. These are (up to the walk's and
//! the representatives' draws) proportional to the probability that the lighting loop's
//! selection, which draws g in proportion to B_l(|x - p_g|) I_g G_g(x), reaches light i
//! through g: the balance heuristic of multiple importance sampling (Veach 1997) over the
//! grid lights. A sample's weight then no longer depends on which of light i's grid lights
//! drew it. Shares without G_g (w_g B_l alone, the first version) gave a VPL's light to a
//! grid light whose centroid lies at a grazing angle or behind the receiver: one rarely
//! drawn, whose samples then weighed hundreds of times the pixel's mean (discs of twice the
//! brightness after the filters), or never drawn (light lost). Blending by the distance to
//! the vertex instead would need no lookup of centroids, but at alpha = 1 it counts a light
//! near x up to three times (the vertices of coarse levels are far from x even when all
//! their light is near).
//!
//! The admission only restricts which grid lights share light i (a sample drawn through a
//! level that is not admitted weighs zero), so the estimate stays unbiased wherever an
//! admitted grid light of i can be drawn at x. It halves the cost of Lambda_i: without it
//! every level whose centroids could lie within reach of B_l was evaluated, about four a
//! call, and at nearly two thirds of those the weight was zero at all 8 corners. The
//! admitted levels hold nearly all of a light's share anyway: images within rel_rmse 0.003
//! of those of the full sum, and the same error against the brute force within seed noise
//! (docs/performance.md, thirty-sixth session).

use glam::{UVec3, Vec3};

use rayon::prelude::*;

use super::splat::cell_of;
use super::{GridGeometry, LightingGrid};
use crate::blending::{LevelRole, blend};
use crate::vpl::light_geometry;

/// The levels a hierarchy shades and their blending radii: levels `lowest..=l_max`
/// (`lowest` 0 adds the input lights themselves as S_0), with r_l = alpha h_l.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadedLevels {
    /// The lowest level shaded (0 or 1).
    pub lowest: u32,
    /// alpha of r_l = alpha h_l.
    pub alpha: f32,
}

/// Whether level `c` is admitted to Lambda_i(x) for an input light at distance `dist`
/// from x: B_l(dist) > 0 (module docs).
#[inline(always)]
fn admitted(c: &LevelConstants, dist: f32) -> bool {
    blend(c.role, dist, c.r) > 0.0
}

/// The largest level, in vertices, whose lights [`Partition`] keeps in a dense table
/// (32 MB).
const MAX_DENSE: usize = 1 << 21;

/// What [`Partition::share_total`] reads of a grid light: its centroid p_g and, in one
/// word, its emission normal m_g and isotropic share ([`quantized_emission`]): 16 bytes, so
/// that the table's reads cost little more than the centroids' alone (in full precision the
/// cache misses tripled the function's time; docs/performance.md, thirty-fifth session).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
struct VertexLight {
    position: Vec3,
    emission: u32,
}

impl VertexLight {
    /// A vertex without a light (NaN position).
    const NONE: Self = Self {
        position: Vec3::NAN,
        emission: 0,
    };

    fn new(position: Vec3, m: Vec3, iso: f32) -> Self {
        let snorm = |v: f32| ((v.clamp(-1.0, 1.0) * 127.0).round() as i8 as u8) as u32;
        let iso = ((iso * 4.0).clamp(0.0, 1.0) * 255.0).round() as u32;
        Self {
            position,
            emission: snorm(m.x) | (snorm(m.y) << 8) | (snorm(m.z) << 16) | (iso << 24),
        }
    }

    /// m_g and the isotropic share, as stored.
    #[inline(always)]
    fn emission(&self) -> (Vec3, f32) {
        let e = self.emission;
        let snorm = |shift: u32| f32::from((e >> shift) as u8 as i8) * (1.0 / 127.0);
        let iso = (e >> 24) as f32 * (0.25 / 255.0);
        (Vec3::new(snorm(0), snorm(8), snorm(16)), iso)
    }

    fn is_light(&self) -> bool {
        !self.position.x.is_nan()
    }
}

/// The emission normal `m` (|m| <= 1) and isotropic share `iso` (at most 1/4, as
/// [`crate::vpl::GridEmission::isotropic`] gives) as [`Partition`] weighs a grid light:
/// each component of m to 1/127, the share to 1/1020. The unbiased estimate weighs the
/// light it drew by its emission cosine with these over its exact one, so that the shares
/// stay exact.
#[must_use]
pub fn quantized_emission(m: Vec3, iso: f32) -> (Vec3, f32) {
    VertexLight::new(Vec3::ZERO, m, iso).emission()
}

/// Lambda_i(x) for one hierarchy: its geometry, levels, and the light of every vertex, in a
/// dense table per level where the level is small enough (x fastest; NaN where no light), so
/// that the 8 lights around a point are read from 4 places in memory without a search, and
/// as sorted rows for the larger levels.
#[derive(Clone, Debug)]
pub struct Partition {
    /// The shaded levels and their radii.
    pub levels: ShadedLevels,
    geometry: GridGeometry,
    /// Per level l >= 1 (index l - 1).
    lights: Vec<VertexLights>,
    /// Per shaded level, `lowest..=l_max`: its constants, computed once instead of per call
    /// of [`Partition::share_total`] (which runs once per visible shadow sample).
    shaded: Vec<LevelConstants>,
}

/// One shaded level's constants for [`Partition::share_total`].
#[derive(Clone, Copy, Debug)]
struct LevelConstants {
    l: u32,
    role: LevelRole,
    /// 1 / h_l.
    inv_h: f32,
    /// r_l = alpha h_l and 1 / r_l.
    r: f32,
    inv_r: f32,
    /// Cells per axis.
    cells: u32,
}

/// One level's lights by vertex.
#[derive(Clone, Debug)]
enum VertexLights {
    /// Every vertex (x fastest), [`VertexLight::NONE`] where there is no light.
    Dense(Vec<VertexLight>),
    /// The lights in vertex order: where each row (y, z) starts, each light's x and itself.
    Rows {
        start: Vec<u32>,
        x: Vec<u32>,
        light: Vec<VertexLight>,
    },
}

impl Partition {
    /// The partition of `grid` shaded at `levels`, with `iso[g]` the isotropic emission share
    /// of grid light g (in the grid's order; [`crate::vpl::GridEmission::isotropic`] of its
    /// normal).
    ///
    /// # Panics
    /// If `iso` does not hold one share per grid light.
    #[must_use]
    pub fn new(grid: &LightingGrid, levels: ShadedLevels, iso: &[f32]) -> Self {
        Self::with_dense_limit(grid, levels, iso, MAX_DENSE)
    }

    /// [`Partition::new`] with dense tables for levels of at most `max_dense` vertices.
    fn with_dense_limit(
        grid: &LightingGrid,
        levels: ShadedLevels,
        iso: &[f32],
        max_dense: usize,
    ) -> Self {
        assert_eq!(iso.len(), grid.position.len(), "one share per grid light");
        let geometry = grid.geometry;
        let lights = (1..=geometry.l_max)
            .into_par_iter()
            .map(|l| {
                let side = geometry.cells_per_axis(l) as usize + 1;
                let range = grid.level_range(l);
                let vertex = &grid.vertex[range.clone()];
                let light =
                    range.map(|g| VertexLight::new(grid.position[g], grid.normal[g], iso[g]));
                if side * side * side <= max_dense {
                    let mut table = vec![VertexLight::NONE; side * side * side];
                    for (v, vl) in vertex.iter().zip(light) {
                        table[(v.z as usize * side + v.y as usize) * side + v.x as usize] = vl;
                    }
                    return VertexLights::Dense(table);
                }
                let mut start = vec![0u32; side * side + 1];
                for v in vertex {
                    start[v.z as usize * side + v.y as usize + 1] += 1;
                }
                for k in 1..start.len() {
                    start[k] += start[k - 1];
                }
                VertexLights::Rows {
                    start,
                    x: vertex.iter().map(|v| v.x).collect(),
                    light: light.collect(),
                }
            })
            .collect();
        let shaded = (levels.lowest..=geometry.l_max)
            .map(|l| {
                let (h, r) = (geometry.cell_size(l), geometry.radius(l, levels.alpha));
                LevelConstants {
                    l,
                    role: LevelRole::of(l, levels.lowest, geometry.l_max),
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
            lights,
            shaded,
        }
    }

    /// The light at vertex `v` of level `l`, if it has one.
    #[inline]
    fn light(&self, l: u32, v: UVec3) -> Option<VertexLight> {
        let side = self.geometry.cells_per_axis(l) as usize + 1;
        if v.x as usize >= side || v.y as usize >= side {
            return None;
        }
        match self.lights.get(l as usize - 1)? {
            VertexLights::Dense(table) => table
                .get((v.z as usize * side + v.y as usize) * side + v.x as usize)
                .copied()
                .filter(VertexLight::is_light),
            VertexLights::Rows { start, x, light } => {
                let row = v.z as usize * side + v.y as usize;
                let (a, b) = (*start.get(row)? as usize, *start.get(row + 1)? as usize);
                let k = x[a..b].binary_search(&v.x).ok()?;
                Some(light[a + k])
            }
        }
    }

    /// Whether level `l` is admitted to Lambda_i(x) for the input light at `p` and the
    /// shading point `x`: its blending weight at the light's own distance, B_l(|x - p|), is
    /// not zero (module docs). A sample of light i drawn through a grid light of a level
    /// that is not admitted weighs zero.
    #[must_use]
    pub fn admits(&self, l: u32, x: Vec3, p: Vec3) -> bool {
        let k = l.wrapping_sub(self.levels.lowest) as usize;
        self.shaded
            .get(k)
            .is_some_and(|c| admitted(c, (x - p).length()))
    }

    /// Lambda_i(x) of the module docs for the input light at `p` with normal `n_p` and the
    /// shading point `x` with normal `n_x`, with the clamp `eps2` of the lighting loop.
    #[must_use]
    pub fn share_total(&self, x: Vec3, n_x: Vec3, p: Vec3, n_p: Vec3, eps2: f32) -> f32 {
        let origin = self.geometry.origin;
        let dist = (x - p).length();
        let mut total = 0.0;
        for level in &self.shaded {
            let LevelConstants {
                l,
                role,
                inv_h,
                r,
                inv_r,
                cells,
                ..
            } = *level;
            if l == 0 {
                let d = p - x;
                let d2 = d.length_squared();
                let inv_d = d2.sqrt().recip();
                let g = light_geometry(d, d2, inv_d, n_x, n_p, 0.0, eps2);
                if g > 0.0 {
                    total += blend(role, d2 * inv_d, r) * g;
                }
                continue;
            }
            if !admitted(level, dist) {
                continue;
            }
            // `locate`, multiplying by 1 / h_l.
            let (c, f) = cell_of((p - origin) * inv_h, cells);
            // The 8 corners' lights and weights (no light: weight 0, at x), kept as whole
            // records: scattering them into per-axis lane arrays stored scalars that the
            // vector loads after them waited on (store forwarding failed), the largest cost
            // of this function in a profile of the shadow pass.
            let mut q = [VertexLight {
                position: x,
                ..VertexLight::NONE
            }; 8];
            let mut w = [0.0f32; 8];
            let (wx, wy, wz) = ([1.0 - f.x, f.x], [1.0 - f.y, f.y], [1.0 - f.z, f.z]);
            let mut put = |corner: usize, found: Option<VertexLight>| {
                if let Some(vl) = found {
                    q[corner] = vl;
                    w[corner] = wx[corner & 1] * wy[(corner >> 1) & 1] * wz[corner >> 2];
                }
            };
            match self.lights.get(l as usize - 1) {
                Some(VertexLights::Dense(table)) => {
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
                            table.get(base + o).copied().filter(VertexLight::is_light),
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
                        put(corner, self.light(l, c + d));
                    }
                }
            }
            let (rise_off, fall_off) = role.floors();
            let mut b = [0.0f32; 8];
            for k in 0..8 {
                let (d, (m, iso)) = (q[k].position - x, q[k].emission());
                let d2 = d.length_squared();
                let inv_d = d2.sqrt().recip();
                let t = d2 * inv_d * inv_r;
                let rising = (2.0 * t - 1.0).clamp(0.0, 1.0).max(rise_off);
                let falling = (2.0 - t).clamp(0.0, 1.0).max(fall_off);
                let g = light_geometry(d, d2, inv_d, n_x, m, iso, eps2);
                b[k] = w[k] * rising.min(falling) * g;
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
    use crate::vpl::GridEmission;

    /// The shares w_g(p_i) B_l(|x - p_g|) G_g(x) / Lambda_i of every input light, summed over
    /// all grid lights of the admitted levels by brute force, are one, for random lights,
    /// normals and shading points, with and without S_0, at several alpha, with dense tables
    /// and rows.
    #[test]
    fn shares_sum_to_one() {
        let mut rng = Rng::new(&[41]);
        let mut u = || rng.next_f32();
        let v = |u: &mut dyn FnMut() -> f32| Vec3::new(4.0 * u(), 2.0 * u(), 3.0 * u());
        let p: Vec<Vec3> = (0..400).map(|_| v(&mut u)).collect();
        let dir = |u: &mut dyn FnMut() -> f32| {
            Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize_or(Vec3::Y)
        };
        let n: Vec<Vec3> = (0..p.len()).map(|_| dir(&mut u)).collect();
        let i = vec![Vec3::ONE; p.len()];
        let input = InputLights {
            positions: &p,
            intensity: &i,
            normals: Some(&n),
        };
        let eps2 = 1e-3;
        let mut counted = 0;
        for construction in [Construction::Restrict, Construction::ScatterAll] {
            let (grid, _) =
                LightingGrid::build(&input, LevelCount::Fixed(5), construction).unwrap();
            let iso: Vec<f32> = (grid.normal.iter())
                .map(|&m| GridEmission::EnergyConserving.isotropic(m))
                .collect();
            let geom = grid.geometry;
            for (lowest, alpha) in [(1, 1.0), (0, 1.0), (1, 2.0), (0, 3.0)] {
                let shaded = ShadedLevels { lowest, alpha };
                let dense = Partition::new(&grid, shaded, &iso);
                let rows = Partition::with_dense_limit(&grid, shaded, &iso, 0);
                for _ in 0..20 {
                    let (x, nx) = (v(&mut u), dir(&mut u));
                    for (&pi, &ni) in p.iter().zip(&n).take(50) {
                        let lambda = dense.share_total(x, nx, pi, ni, eps2);
                        assert_eq!(lambda, rows.share_total(x, nx, pi, ni, eps2));
                        // The shares of every grid light that holds pi, by brute force.
                        let mut sum = 0.0;
                        for l in lowest..=geom.l_max {
                            let role = LevelRole::of(l, lowest, geom.l_max);
                            let r = geom.radius(l, alpha);
                            let admitted = blend(role, (x - pi).length(), r) > 0.0;
                            assert_eq!(admitted, dense.admits(l, x, pi));
                            if !admitted {
                                continue;
                            }
                            let g = |q: Vec3, m: Vec3, iso: f32| {
                                let (d, d2) = (q - x, (q - x).length_squared());
                                light_geometry(d, d2, d2.sqrt().recip(), nx, m, iso, eps2)
                            };
                            if l == 0 {
                                sum += blend(role, (x - pi).length(), r) * g(pi, ni, 0.0);
                                continue;
                            }
                            for k in grid.level_range(l) {
                                let d = (pi - geom.vertex_position(l, grid.vertex[k]))
                                    / geom.cell_size(l);
                                let t = (Vec3::ONE - d.abs()).max(Vec3::ZERO);
                                let w = t.x * t.y * t.z;
                                let b = blend(role, (x - grid.position[k]).length(), r);
                                let (m, iso) = quantized_emission(grid.normal[k], iso[k]);
                                sum += w * b * g(grid.position[k], m, iso);
                            }
                        }
                        if sum == 0.0 {
                            assert_eq!(lambda, 0.0);
                            continue;
                        }
                        counted += 1;
                        // Relative, except where grazing cosines leave a sum near zero.
                        let tolerance = 1e-4 * lambda + 1e-6;
                        assert!((sum - lambda).abs() < tolerance, "{sum} vs {lambda}");
                    }
                }
            }
        }
        // Most lights are in front of most points.
        assert!(counted > 4000, "{counted}");
    }

    /// Two levels are admitted at any distance (the B_l of neighbouring levels overlap
    /// pairwise), one where a level's weight is one; none outside the shaded levels.
    #[test]
    fn two_levels_are_admitted() {
        let p: Vec<Vec3> = (0..64)
            .map(|k| Vec3::new((k % 4) as f32, ((k / 4) % 4) as f32, (k / 16) as f32))
            .collect();
        let input = InputLights {
            positions: &p,
            intensity: &vec![Vec3::ONE; p.len()],
            normals: None,
        };
        let (grid, _) =
            LightingGrid::build(&input, LevelCount::Fixed(5), Construction::Restrict).unwrap();
        let iso = vec![0.0; grid.position.len()];
        let mut rng = Rng::new(&[47]);
        for lowest in [0, 1] {
            let part = Partition::new(&grid, ShadedLevels { lowest, alpha: 2.0 }, &iso);
            for _ in 0..2000 {
                let x = Vec3::new(20.0 * rng.next_f32() - 8.0, 1.5, 1.5);
                let q = Vec3::splat(1.5);
                let admitted = (0..=6).filter(|&l| part.admits(l, x, q)).count();
                let d = (x - q).length();
                let one = (lowest..=5).any(|l| {
                    let role = LevelRole::of(l, lowest, 5);
                    blend(role, d, grid.geometry.radius(l, 2.0)) == 1.0
                });
                assert_eq!(admitted, if one { 1 } else { 2 }, "{d}");
            }
            assert!(!part.admits(6, Vec3::ZERO, Vec3::ONE));
            assert_eq!(part.admits(0, Vec3::ONE, Vec3::ONE), lowest == 0);
        }
    }

    /// The stored emission is within its steps of the given one.
    #[test]
    fn emission_is_stored_to_its_steps() {
        let mut rng = Rng::new(&[43]);
        for _ in 0..1000 {
            let mut c = || 2.0 * rng.next_f32() - 1.0;
            let m = Vec3::new(c(), c(), c()).clamp_length_max(1.0);
            let iso = 0.125 * (c() + 1.0);
            let (mq, iq) = quantized_emission(m, iso);
            assert!(
                (mq - m).abs().max_element() <= 0.5 / 127.0 + 1e-6,
                "{m} {mq}"
            );
            assert!((iq - iso).abs() <= 0.125 / 255.0 + 1e-6, "{iso} {iq}");
        }
        assert_eq!(quantized_emission(Vec3::NEG_Y, 0.0), (Vec3::NEG_Y, 0.0));
    }

    /// A light whose grid lights all face away from x, or lie behind its tangent plane,
    /// has no share there; one in front has its geometry term's weight: the total is
    /// G_i(x) where the hierarchy is the single light itself (every level's centroid is p).
    #[test]
    fn a_single_light_weighs_its_geometry_term() {
        let p = [Vec3::new(1.0, 1.0, 1.0)];
        let n = [Vec3::NEG_Y];
        let input = InputLights {
            positions: &p,
            intensity: &[Vec3::ONE],
            normals: Some(&n),
        };
        let (grid, _) =
            LightingGrid::build(&input, LevelCount::Fixed(3), Construction::Restrict).unwrap();
        let iso = vec![0.0; grid.position.len()];
        let part = Partition::new(
            &grid,
            ShadedLevels {
                lowest: 0,
                alpha: 1.0,
            },
            &iso,
        );
        let eps2 = 0.01;
        // Below the light, facing it: the B_l sum to one at one distance, so Lambda = G.
        let (x, nx) = (Vec3::new(1.0, 0.0, 1.0), Vec3::Y);
        let expected = 1.0 / (1.0 + eps2);
        let lambda = part.share_total(x, nx, p[0], n[0], eps2);
        assert!((lambda - expected).abs() < 1e-5 * expected, "{lambda}");
        // Facing away from it, or above it (behind its emission): nothing.
        assert_eq!(part.share_total(x, -nx, p[0], n[0], eps2), 0.0);
        let above = Vec3::new(1.0, 2.0, 1.0);
        assert_eq!(part.share_total(above, -nx, p[0], n[0], eps2), 0.0);
    }
}
