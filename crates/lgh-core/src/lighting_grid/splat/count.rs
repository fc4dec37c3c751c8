//! Counting the vertices a level would have without building it: the automatic level rule
//! (|S_1| < N/2) counts |S_1| at several level counts from one sort.

use glam::{UVec3, Vec3, Vec4};
use rayon::prelude::*;

use super::super::geometry::GridGeometry;
use super::sort::Workspace;
use super::{Sources, layers_per_task};

/// Number of vertices of `level` that receive a non-zero weight from `src` (the length of
/// [`super::splat`]'s result, before compaction), without computing their grid lights: after the
/// same sort, one task per vertex layer marks the vertices it touches in a bit set of the
/// layer (33 KB at 512 cells per axis: it stays in the L1 cache), with the same weight
/// products as the splat, so the same weights are zero. Used to choose the number of levels.
/// The sort stays in `ws`, so that building the level next does not sort again.
pub fn count_vertices(ws: &mut Workspace, src: &Sources, geom: &GridGeometry, level: u32) -> usize {
    ws.sort_by_row(src, geom, level);
    count_sorted::<false>(ws).0
}

/// [`count_vertices`], and the same count at the same `level` of the next finer geometry
/// (l_max + 1: twice the cells per axis) from the same sort and in the same pass over the
/// sources (`None` for a restriction's sources, whose fine vertices have no finer cell).
///
/// A source in cell c with fraction f lies in the finer cell 2c + b with fraction 2f - b, b =
/// [2f >= 1], per axis. Both are exact in floating point and equal to locating it on the
/// finer grid directly (whose spacing is exactly half), so the same weights are zero.
pub fn count_vertices_and_finer(
    ws: &mut Workspace,
    src: &Sources,
    geom: &GridGeometry,
    level: u32,
) -> (usize, Option<usize>) {
    ws.sort_by_row(src, geom, level);
    if src.finer_vertices.is_some() {
        return (count_sorted::<false>(ws).0, None);
    }
    let (n, finer) = count_sorted::<true>(ws);
    (n, Some(finer))
}

/// The vertex counts of the sort in `ws` (and, if `FINER`, of the grid twice as fine). One
/// task per layer m counts vertex layer m from the sources of cell layers m - 1 and m, and
/// the finer vertex layers 2m (from the same sources) and 2m + 1 (from layer m): each source
/// is read twice.
///
/// A source strictly inside its cell (see [`interior`]) gives all 8 corners a non-zero
/// weight, so it only marks its cell; the layer's marked cells are then dilated to their
/// corners row by row ([`LayerBits::count_with_corners`]). Only the other sources (on a
/// cell face) mark their corners one by one, with the sweep's weight products.
fn count_sorted<const FINER: bool>(ws: &Workspace) -> (usize, usize) {
    let r = ws.r as usize;
    let fine_side = if FINER { 2 * r + 1 } else { 0 };
    // Finer cell and fraction of x and y: t = 2f, b = [t >= 1], cell 2c + b, fraction t - b,
    // in SSE lanes (a scalar comparison becomes a branch, mispredicted half the time).
    let finer_xy = |c: UVec3, f: Vec3| {
        let t = Vec4::new(f.x, f.y, 0.0, 0.0) * 2.0;
        let upper = t.cmpge(Vec4::ONE);
        let b = upper.bitmask();
        let fine = t - Vec4::select(upper, Vec4::ONE, Vec4::ZERO);
        (
            UVec3::new(2 * c.x + (b & 1), 2 * c.y + ((b >> 1) & 1), 0),
            Vec3::new(fine.x, fine.y, 0.0),
        )
    };
    (0..ws.r + 1)
        .into_par_iter()
        .with_min_len(layers_per_task(ws.src.len(), r))
        .map(|m| {
            let sides = [r + 1, r + 1, fine_side, fine_side, fine_side, fine_side];
            count_layers(
                sides,
                |[
                    mut cells,
                    mut corners,
                    mut even_cells,
                    mut even,
                    mut odd_cells,
                    mut odd,
                ]| {
                    // With t = 2 f_z, a source of cell layer m lies in the finer cell layer 2m
                    // (t < 1, fraction t) or 2m + 1 (t >= 1, fraction t - 1), and its z weights
                    // follow without asking which: max(0, t - 1) in finer vertex layer 2m + 2,
                    // min(t, 2 - t) in 2m + 1, max(0, 1 - t) in 2m (the same values as
                    // 1 - fraction and fraction, exactly).
                    if m > 0 {
                        for ps in ws.layer(m - 1) {
                            let c = ps.cell_xy();
                            if interior(ps.f) {
                                cells.set(c, true);
                            } else {
                                corners.mark(c, ps.f, ps.f.z);
                            }
                            if FINER {
                                let (c, fxy) = finer_xy(c, ps.f);
                                let t = 2.0 * ps.f.z;
                                let upper = t >= 1.0;
                                if interior(fxy.with_z(t - f32::from(upper))) {
                                    even_cells.set(c, upper);
                                } else {
                                    even.mark(c, fxy, (t - 1.0).max(0.0));
                                }
                            }
                        }
                    }
                    if m < ws.r {
                        for ps in ws.layer(m) {
                            let c = ps.cell_xy();
                            if interior(ps.f) {
                                cells.set(c, true);
                            } else {
                                corners.mark(c, ps.f, 1.0 - ps.f.z);
                            }
                            if FINER {
                                let (c, fxy) = finer_xy(c, ps.f);
                                let t = 2.0 * ps.f.z;
                                let upper = t >= 1.0;
                                if interior(fxy.with_z(t - f32::from(upper))) {
                                    even_cells.set(c, !upper);
                                    odd_cells.set(c, true);
                                } else {
                                    even.mark(c, fxy, (1.0 - t).max(0.0));
                                    odd.mark(c, fxy, t.min(2.0 - t));
                                }
                            }
                        }
                    }
                    let n = corners.count_with_corners(&cells);
                    let n_finer = if FINER {
                        even.count_with_corners(&even_cells) + odd.count_with_corners(&odd_cells)
                    } else {
                        0
                    };
                    (n, n_finer)
                },
            )
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// True if every trilinear weight of a source with in-cell fraction `f` is non-zero: each
/// factor f or 1 - f is at least 2^-40 (1 - f is at least 2^-24 once f < 1 in f32), so a
/// product of three is at least 2^-120, above the smallest normal f32 (2^-126).
#[inline]
fn interior(f: Vec3) -> bool {
    const MIN: f32 = 1.0 / (1u64 << 40) as f32;
    f.min_element() >= MIN && f.max_element() < 1.0
}

/// `N` bit sets of `sides[k]` rows of `sides[k]` bits (see [`LayerBits`]), cleared, handed
/// to `visit`.
fn count_layers<const N: usize, T>(
    sides: [usize; N],
    visit: impl FnOnce([LayerBits; N]) -> T,
) -> T {
    with_bits(|bits| {
        let row_words = sides.map(|side| side.div_ceil(64));
        let words: [usize; N] = std::array::from_fn(|k| sides[k] * row_words[k]);
        bits.clear();
        bits.resize(words.iter().sum(), 0);
        let mut rest: &mut [u64] = bits;
        let mut k = 0;
        let layers: [LayerBits; N] = std::array::from_fn(|_| {
            let (layer, tail) = std::mem::take(&mut rest).split_at_mut(words[k]);
            rest = tail;
            k += 1;
            LayerBits {
                bits: layer,
                row_words: row_words[k - 1],
            }
        });
        visit(layers)
    })
}

/// The vertices (or cells) of one layer marked so far, one bit each, row by row: bit x of
/// row y is bit x % 64 of word y * row_words + x / 64.
struct LayerBits<'a> {
    bits: &'a mut [u64],
    row_words: usize,
}

impl LayerBits<'_> {
    /// Sets the bit of (`c.x`, `c.y`) if `on`, without a branch.
    #[inline]
    fn set(&mut self, c: UVec3, on: bool) {
        let (x, y) = (c.x as usize, c.y as usize);
        self.bits[y * self.row_words + x / 64] |= u64::from(on) << (x % 64);
    }

    /// Marks the layer's vertices of cell `c` (x, y) that a source with fraction `f` (x, y)
    /// and z weight `wz` gives a non-zero weight: the same products as the sweep's, so that
    /// the same weights are zero. Without branches: every corner's word is written.
    #[inline]
    fn mark(&mut self, c: UVec3, f: Vec3, wz: f32) {
        for (dy, wy) in [1.0 - f.y, f.y].into_iter().enumerate() {
            let wyz = wz * wy;
            for (dx, wx) in [1.0 - f.x, f.x].into_iter().enumerate() {
                let hit = (wyz > 0.0) & (wx * wyz > 0.0);
                self.set(c + UVec3::new(dx as u32, dy as u32, 0), hit);
            }
        }
    }

    /// Number of vertices marked here or a corner of a cell marked in `cells`: vertex
    /// (x, y) is a corner of cells x - 1 and x of rows y - 1 and y.
    fn count_with_corners(&self, cells: &LayerBits) -> usize {
        let w = self.row_words;
        let rows = self.bits.len() / w.max(1);
        let cell_row = |y: usize| &cells.bits[y * w..(y + 1) * w];
        let mut n = 0;
        for y in 0..rows {
            let mut carry = 0;
            for k in 0..w {
                let c = if y > 0 { cell_row(y - 1)[k] } else { 0 } | cell_row(y)[k];
                let corners = c | c << 1 | carry;
                carry = c >> 63;
                n += (corners | self.bits[y * w + k]).count_ones() as usize;
            }
        }
        n
    }
}

thread_local! {
    static BITS: std::cell::RefCell<Vec<u64>> = const { std::cell::RefCell::new(Vec::new()) };
}

fn with_bits<T>(f: impl FnOnce(&mut Vec<u64>) -> T) -> T {
    BITS.with(|s| f(&mut s.borrow_mut()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lighting_grid::geometry::MAX_LEVELS;
    use crate::lighting_grid::splat::splat;
    use crate::lighting_grid::splat::tests::point_sources;
    use crate::rng::Rng;

    /// The vertex count agrees with the splat, for positions and for the vertices of a
    /// finer grid (restriction), whose fractions are exactly 0, 1/2 or 1: the zero weights
    /// must not count.
    #[test]
    fn count_vertices_matches_the_splat() {
        let mut rng = Rng::new(&[7, 11]);
        let (lo, hi) = (Vec3::ZERO, Vec3::splat(4.0));
        let mut ws = Workspace::default();
        let positions: Vec<Vec3> = (0..3000)
            .map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0)
            .collect();
        let intensity = vec![Vec3::ONE; positions.len()];
        for l_max in 1..=6 {
            let geom = GridGeometry::new(lo, hi, l_max);
            let fine = 2 * geom.cells_per_axis(1);
            let vertices: Vec<UVec3> = (0..positions.len())
                .map(|_| {
                    UVec3::new(
                        rng.next_u32() % (fine + 1),
                        rng.next_u32() % (fine + 1),
                        rng.next_u32() % 3,
                    )
                })
                .collect();
            let src = point_sources(&positions, &intensity);
            let restriction = Sources {
                finer_vertices: Some(&vertices),
                ..src
            };
            for s in [src, restriction] {
                let n = count_vertices(&mut ws, &s, &geom, 1);
                assert_eq!(n, splat(&s, &geom, 1).len(), "l_max {l_max}");
                let (both, finer) = count_vertices_and_finer(&mut ws, &s, &geom, 1);
                assert_eq!(both, n, "l_max {l_max}");
                assert_eq!(finer.is_none(), s.finer_vertices.is_some());
            }
            // The count at l_max + 1 from this sort, against a sort at l_max + 1. Some
            // positions on the cell boundaries of the finer grid (fractions 0 and 1/2).
            if l_max < MAX_LEVELS {
                let mut on_edges = positions.clone();
                for (i, p) in on_edges.iter_mut().enumerate().take(500) {
                    let h = geom.cell_size(1) / 2.0;
                    let snapped = ((*p - geom.origin) / h).floor() * h + geom.origin;
                    *p = if i % 2 == 0 {
                        snapped
                    } else {
                        Vec3::new(snapped.x, p.y, snapped.z)
                    };
                }
                let s = Sources {
                    positions: &on_edges,
                    ..src
                };
                let finer = GridGeometry {
                    l_max: l_max + 1,
                    ..geom
                };
                let expected = splat(&s, &finer, 1).len();
                let (n, n_finer) = count_vertices_and_finer(&mut ws, &s, &geom, 1);
                assert_eq!(n, splat(&s, &geom, 1).len(), "l_max {l_max}");
                assert_eq!(n_finer, Some(expected), "l_max {l_max}");
            }
        }
    }
}
