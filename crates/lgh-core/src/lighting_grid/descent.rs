//! Drawing, for a grid light of level l >= 2, one of the S_1 lights it is made of, with
//! probability equal to its share of the light: a walk down the levels, one random child per
//! level (an extension of Lin & Yuksel 2019; docs/design.md, "Unbiased estimate").
//!
//! A grid light V of level l >= 2 of the restriction (and of the all-scatter hierarchy, which
//! it equals) is a weighted sum of the lights u of level l - 1 at the 27 vertices around 2V,
//! with the stencil weights w_l(v_u - V) in {1/2, 1}^3. Picking a child u with probability
//! w lum(I_u) / lum(I_V), level after level, reaches an S_1 light u with probability equal to
//! its share of V, and an input light drawn from u in proportion to its share of u then has
//! exactly its share of V (`representative` proves the same chain for the per-frame draw).
//! Every pixel draws afresh: the per-frame representatives of a coarse light are shared by
//! the whole image, so a few unlucky draws make the whole image too bright or too dark.
//!
//! The children of every light are kept as one list per light with running sums of the
//! weights (compressed rows), built in fixed chunks of lights, each by one task in light
//! order with one lookup of each child, and joined in chunk order, so the result does not
//! depend on the thread count.

use glam::IVec3;
use rayon::prelude::*;

use super::lookup::VertexLookup;
use crate::color::luminance;

/// The children of every grid light of level >= 2 (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct Descent {
    /// `start[j]..start[j + 1]` are the children of grid light j (empty for S_1).
    start: Vec<u32>,
    /// Each child's grid index and the running sum of w lum(I_u) within its light's list.
    child: Vec<(u32, f32)>,
}

impl Descent {
    /// The children of every light of `lookup`'s grid, which was built from its input
    /// lights by restriction or all-scatter (the gather of section 3.1 weighs other
    /// children; it is not supported).
    #[must_use]
    pub fn new(lookup: VertexLookup) -> Self {
        let grid = lookup.grid;
        let first_parent = grid.level_range(1).end.min(grid.len());
        // The lights of levels >= 2 in fixed chunks, each chunk's lists made by one task in
        // light order (one pass of lookups), then joined in chunk order.
        let parts: Vec<(Vec<u32>, Vec<Child>)> = (first_parent..grid.len())
            .into_par_iter()
            .step_by(DESCENT_CHUNK)
            .map(|start| {
                let end = (start + DESCENT_CHUNK).min(grid.len());
                let mut counts = Vec::with_capacity(end - start);
                let mut child = Vec::new();
                for j in start..end {
                    let before = child.len();
                    let mut sum = 0.0;
                    for_each_child(lookup, j, |c, w| {
                        sum += w;
                        child.push((c, sum));
                    });
                    counts.push((child.len() - before) as u32);
                }
                (counts, child)
            })
            .collect();
        let mut start = Vec::with_capacity(grid.len() + 1);
        start.resize(first_parent + 1, 0u32);
        let mut at = 0u32;
        for (counts, _) in &parts {
            for n in counts {
                at += n;
                start.push(at);
            }
        }
        let mut child = Vec::with_capacity(at as usize);
        for (_, c) in parts {
            child.extend(c);
        }
        Self { start, child }
    }

    /// The tables as they are stored, for a backend that walks them elsewhere (the GPU):
    /// light j's children are `children[starts[j]..starts[j + 1]]`, each (grid index,
    /// running sum of the weights).
    #[must_use]
    pub fn tables(&self) -> (&[u32], &[(u32, f32)]) {
        (&self.start, &self.child)
    }

    /// A child of light `j` drawn with probability proportional to its weight, by the
    /// uniform number `u` in [0, 1); `None` for a light without children (S_1).
    #[inline]
    #[must_use]
    pub fn child(&self, j: usize, u: f32) -> Option<usize> {
        let (a, b) = (self.start[j] as usize, self.start[j + 1] as usize);
        let list = &self.child[a..b];
        let total = list.last()?.1;
        let target = u * total;
        // Branch-free: the number of running sums at or below the target.
        let k = list.iter().filter(|&&(_, s)| s <= target).count();
        Some(list[k.min(list.len() - 1)].0 as usize)
    }

    /// The S_1 light reached from light `j` by drawing a child level after level with the
    /// uniform numbers of `next` (`j` itself if it is an S_1 light).
    #[inline]
    pub fn to_level_one(&self, mut j: usize, mut next: impl FnMut() -> f32) -> usize {
        while let Some(c) = self.child(j, next()) {
            j = c;
        }
        j
    }
}

/// A child's grid index and the running sum of the weights up to it.
type Child = (u32, f32);

/// Lights per task of [`Descent::new`].
const DESCENT_CHUNK: usize = 2048;

/// Visits the children of grid light `j` (level >= 2) with their weights w lum(I_u): the
/// lights of the level below at the 27 vertices around twice its vertex, with the stencil
/// weights (1/2, 1, 1/2) per axis, in a fixed order.
fn for_each_child(lookup: VertexLookup, j: usize, mut visit: impl FnMut(u32, f32)) {
    let grid = lookup.grid;
    let l = grid.level_start.partition_point(|&s| s as usize <= j) as u32;
    if l < 2 {
        return;
    }
    let v = grid.vertex[j].as_ivec3() * 2;
    let side = grid.geometry.cells_per_axis(l - 1) as i32 + 1;
    for dz in -1..=1 {
        for dy in -1..=1 {
            for dx in -1..=1 {
                let u = v + IVec3::new(dx, dy, dz);
                if u.min_element() < 0 || u.max_element() >= side {
                    continue;
                }
                let Some(c) = lookup.find(l - 1, u.as_uvec3()) else {
                    continue;
                };
                let stencil = [dx, dy, dz]
                    .iter()
                    .map(|&d| if d == 0 { 1.0 } else { 0.5 })
                    .product::<f32>();
                let w = stencil * luminance(grid.intensity[c]);
                if w > 0.0 {
                    visit(c as u32, w);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::lighting_grid::lookup::VertexRows;
    use crate::lighting_grid::{Construction, InputLights, LevelCount, LightingGrid};
    use crate::rng::Rng;

    /// The walk from a light V of level l reaches S_1 light u with probability
    /// w_l(x_u - V) lum(I_u) / lum(I_V), x_u the vertex of u (the hat of spacing h_l at u's
    /// vertex: the restriction's stencils compose to it), for the restriction and the
    /// all-scatter hierarchy. Chi-square over 20 000 walks from every light of levels 2..=4
    /// (p = 0.001; the bins with expected counts below 5 pooled).
    #[test]
    fn walks_reach_s1_lights_with_their_share() {
        let mut rng = Rng::new(&[5, 5]);
        let p: Vec<Vec3> = (0..300)
            .map(|_| Vec3::new(rng.next_f32(), 0.5 * rng.next_f32(), rng.next_f32()))
            .collect();
        let i: Vec<Vec3> = (0..300)
            .map(|k| Vec3::splat(0.5 + (k % 7) as f32))
            .collect();
        let input = InputLights {
            positions: &p,
            intensity: &i,
            normals: None,
        };
        for construction in [Construction::Restrict, Construction::ScatterAll] {
            let (grid, _) =
                LightingGrid::build(&input, LevelCount::Fixed(4), construction).unwrap();
            let rows = VertexRows::new(&grid);
            let descent = Descent::new(VertexLookup::new(&grid, &rows));
            let geom = grid.geometry;
            let s1 = grid.level_range(1);
            for l in 2..=4 {
                for j in grid.level_range(l) {
                    let v = geom.vertex_position(l, grid.vertex[j]);
                    let expected: Vec<f64> = s1
                        .clone()
                        .map(|u| {
                            let d =
                                (geom.vertex_position(1, grid.vertex[u]) - v) / geom.cell_size(l);
                            let t = (Vec3::ONE - d.abs()).max(Vec3::ZERO);
                            f64::from(t.x * t.y * t.z * luminance(grid.intensity[u]))
                        })
                        .collect();
                    let total: f64 = expected.iter().sum();
                    let n = 20_000;
                    let mut count = vec![0u32; s1.len()];
                    for _ in 0..n {
                        count[descent.to_level_one(j, || rng.next_f32())] += 1;
                    }
                    let (mut chi2, mut df, mut pool_e, mut pool_c) = (0.0, 0, 0.0, 0.0);
                    for (e, &c) in expected.iter().zip(&count) {
                        let e = e / total * f64::from(n);
                        if e == 0.0 {
                            assert_eq!(c, 0, "an S_1 light without a share was reached");
                        } else if e < 5.0 {
                            (pool_e, pool_c) = (pool_e + e, pool_c + f64::from(c));
                        } else {
                            chi2 += (f64::from(c) - e).powi(2) / e;
                            df += 1;
                        }
                    }
                    if pool_e > 0.0 {
                        chi2 += (pool_c - pool_e).powi(2) / pool_e;
                        df += 1;
                    }
                    // Wilson-Hilferty: the 0.999 quantile of chi-square with df - 1 degrees.
                    let k = f64::from(df.max(2) - 1);
                    let limit =
                        k * (1.0 - 2.0 / (9.0 * k) + 3.09 * (2.0 / (9.0 * k)).sqrt()).powi(3);
                    assert!(
                        chi2 <= limit.max(10.83),
                        "{construction:?} light {j} (level {l}): chi2 {chi2}, df {k}"
                    );
                }
            }
        }
    }
}
