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
//! weights (compressed rows), each light's list built by its own task in a fixed order, so
//! the result does not depend on the thread count.

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
        let counts: Vec<u32> = (0..grid.len())
            .into_par_iter()
            .map(|j| {
                let mut n = 0;
                if j >= first_parent {
                    for_each_child(lookup, j, |_, _| n += 1);
                }
                n
            })
            .collect();
        let mut start = Vec::with_capacity(grid.len() + 1);
        let mut at = 0u32;
        start.push(0);
        for n in &counts {
            at += n;
            start.push(at);
        }
        let mut child = vec![(0u32, 0.0f32); at as usize];
        // Each light fills its own slice of `child`, in parallel.
        let mut slices = Vec::with_capacity(grid.len());
        let mut rest = child.as_mut_slice();
        for n in &counts {
            let (head, tail) = rest.split_at_mut(*n as usize);
            slices.push(head);
            rest = tail;
        }
        slices.into_par_iter().enumerate().for_each(|(j, out)| {
            if out.is_empty() {
                return;
            }
            let mut k = 0;
            let mut sum = 0.0;
            for_each_child(lookup, j, |c, w| {
                sum += w;
                out[k] = (c, sum);
                k += 1;
            });
        });
        Self { start, child }
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
