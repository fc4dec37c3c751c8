//! What each screen tile sees, for the binning of light volumes ([`crate::shading::tiles`]):
//! the depth range of its surface points, their boxes and normal cones per depth slice, and
//! the same merged over groups of tiles, which reject a light for a whole group at once.

use glam::{BVec4A, Vec3, Vec4};
use rayon::prelude::*;

use crate::passes::gbuffer::GBuffer;

/// Tiles per side of a group: [`AllBounds`] also keeps the bounds of each group of
/// `GROUP` x `GROUP` tiles of a sub-image, which the binning tests a light against before the
/// group's tiles.
pub const GROUP: u32 = 4;

/// What every tile of every sub-image of n x n interleaving (n = 1: the image) sees: its
/// depth range and, per depth slice, the box and normal cone of its surface points. Found
/// in one pass over the G-buffer, in parallel over rows of tiles; it depends on the
/// G-buffer alone, so a caller may keep it while the view stands still
/// ([`crate::memory::ViewCache`]).
///
/// Beside the tiles it keeps their groups of [`GROUP`] x [`GROUP`] (`AllBounds::group`):
/// per group the depth range of its tiles and, in the four lanes, the box of each quadrant's
/// tiles (2 x 2 tiles), without normal cones. A light that may reach a point of a tile may
/// reach the tile's group by the same test (each of its bounds is at least as wide, and the
/// float operations are monotone in them), so the binning skips a group's tiles when the
/// group rejects the light, and its lists stay exactly those of testing every tile.
#[derive(Debug)]
pub struct AllBounds {
    /// Tile edge in full-resolution pixels.
    pub(super) tile: u32,
    pub(super) tiles_x: u32,
    pub(super) tiles_y: u32,
    pub(super) n: u32,
    n2: usize,
    /// Tile (tx, ty) of sub-image s is entry (ty n^2 + s) tiles_x + tx.
    bounds: Vec<TileBounds>,
    /// Groups per row.
    groups_x: u32,
    /// Group (gx, gy) of sub-image s is entry (gy n^2 + s) groups_x + gx.
    groups: Vec<TileBounds>,
}

impl AllBounds {
    /// The bounds of G-buffer `g` under n x n interleaving, with tiles of `tile`
    /// full-resolution pixels.
    #[must_use]
    pub fn new(g: &GBuffer, n: u32, tile: u32) -> Self {
        Self::with_guests(g, n, tile, None)
    }

    /// [`AllBounds::new`] where pixels also count in the tiles of the sub-images of their
    /// bits in `guests` (one mask per pixel, bit s = sub-image s;
    /// [`crate::shading::interleave::missed_sub_images`]), which shade them as guests: the
    /// tile of a sub-image then lists the lights that reach its guests too.
    #[must_use]
    pub fn with_guests(g: &GBuffer, n: u32, tile: u32, guests: Option<&[u64]>) -> Self {
        let tiles_x = g.width.div_ceil(tile);
        let tiles_y = g.height.div_ceil(tile);
        let n2 = (n * n) as usize;
        let mut bounds = vec![TileBounds::EMPTY; tiles_y as usize * n2 * tiles_x as usize];
        bounds
            .par_chunks_mut(n2 * tiles_x as usize)
            .enumerate()
            .for_each(|(ty, row)| {
                let ys = ty as u32 * tile..((ty as u32 + 1) * tile).min(g.height);
                // Pixel (x, y) of the row of tiles is in entry k of `row` (sub-image s, tile
                // tx), counted along x instead of divided.
                let visit = |f: &mut dyn FnMut(usize, usize)| {
                    for y in ys.clone() {
                        let start = (y * g.width) as usize;
                        for (i, (_, s, tx)) in (start..).zip(row_phases(y, g.width, n, tile)) {
                            if !g.is_hit(i) {
                                continue;
                            }
                            f(s * tiles_x as usize + tx, i);
                            let mut guest = guests.map_or(0, |m| m[i] & !(1 << s));
                            while guest != 0 {
                                let other = guest.trailing_zeros() as usize;
                                guest &= guest - 1;
                                f(other * tiles_x as usize + tx, i);
                            }
                        }
                    }
                };
                visit(&mut |k, i| {
                    row[k].zmin = row[k].zmin.min(g.depth[i]);
                    row[k].zmax = row[k].zmax.max(g.depth[i]);
                });
                visit(&mut |k, i| row[k].add(g.depth[i], g.position[i], g.normal[i]));
            });
        let groups_x = tiles_x.div_ceil(GROUP);
        let groups_y = tiles_y.div_ceil(GROUP);
        let mut all = Self {
            tile,
            tiles_x,
            tiles_y,
            n,
            n2,
            bounds,
            groups_x,
            groups: Vec::new(),
        };
        let mut groups = vec![TileBounds::GROUP_EMPTY; groups_y as usize * n2 * groups_x as usize];
        groups
            .par_chunks_mut(n2 * groups_x as usize)
            .enumerate()
            .for_each(|(gy, row)| {
                let gy = gy as u32;
                for (k, group) in row.iter_mut().enumerate() {
                    let (s, gx) = (k / groups_x as usize, k as u32 % groups_x);
                    for ty in gy * GROUP..((gy + 1) * GROUP).min(tiles_y) {
                        for tx in gx * GROUP..((gx + 1) * GROUP).min(tiles_x) {
                            let quadrant = quadrant(tx, ty);
                            group.merge(quadrant, all.get(s, tx, ty));
                        }
                    }
                }
            });
        all.groups = groups;
        all
    }

    /// Tile (`tx`, `ty`) of sub-image `s`.
    #[inline]
    pub(super) fn get(&self, s: usize, tx: u32, ty: u32) -> &TileBounds {
        &self.bounds[(ty as usize * self.n2 + s) * self.tiles_x as usize + tx as usize]
    }

    /// The group of tiles (`gx`, `gy`) of sub-image `s`: tiles `gx GROUP..(gx + 1) GROUP` by
    /// `gy GROUP..(gy + 1) GROUP` (those that exist).
    #[inline]
    pub(super) fn group(&self, s: usize, gx: u32, gy: u32) -> &TileBounds {
        &self.groups[(gy as usize * self.n2 + s) * self.groups_x as usize + gx as usize]
    }
}

/// The quadrant of its group that tile (`tx`, `ty`) lies in: the lane of the group's bounds
/// that holds its boxes (0 and 1 the upper two, left then right; 2 and 3 the lower two).
#[inline]
pub(super) fn quadrant(tx: u32, ty: u32) -> usize {
    usize::from(ty % GROUP >= GROUP / 2) * 2 + usize::from(tx % GROUP >= GROUP / 2)
}

/// Depth slices of a tile's range that get their own bounding box of surface points (the
/// lanes of a `Vec4`): a tile that sees a column in front of a far wall then does not list
/// the lights in between. A sphere's screen rectangle and depth range bound its box, about
/// twice its volume, so without the boxes about half the listed lights never reach a pixel;
/// four slices list about 1.6 lights per reaching light, eight gain no more (docs/design.md,
/// "Tile binning").
pub const DEPTH_SLICES: usize = 4;

/// Relative rounding allowance of the tangent-plane test: n . c - n . x and n . (c - x)
/// differ by a few float epsilons of |c| + |x|.
const ROUNDING: f32 = 1e-5;

/// What a tile sees: the depth range of its surface points and, per slice of that range, the
/// bounding box of the points in it, stored axis by axis with the slices in SIMD lanes (an
/// empty box has lo = +inf and hi = -inf, so that nothing is near it); and per slice a cone
/// of the points' shading normals n_x (the first point's normal n_s and the largest
/// |n_x - n_s|) with the lowest n_s . x of its points, which tells the lights that every
/// point of the slice sees behind its tangent plane.
#[derive(Clone, Copy, Debug)]
pub(super) struct TileBounds {
    zmin: f32,
    zmax: f32,
    lo: [[f32; DEPTH_SLICES]; 3],
    hi: [[f32; DEPTH_SLICES]; 3],
    /// n_s per axis (zero for an empty slice).
    normal: [[f32; DEPTH_SLICES]; 3],
    /// The largest |n_x - n_s|.
    spread: [f32; DEPTH_SLICES],
    /// The lowest n_s . x.
    plane: [f32; DEPTH_SLICES],
}

impl TileBounds {
    const EMPTY: Self = Self {
        zmin: f32::INFINITY,
        zmax: f32::NEG_INFINITY,
        lo: [[f32::INFINITY; DEPTH_SLICES]; 3],
        hi: [[f32::NEG_INFINITY; DEPTH_SLICES]; 3],
        normal: [[0.0; DEPTH_SLICES]; 3],
        spread: [0.0; DEPTH_SLICES],
        plane: [f32::INFINITY; DEPTH_SLICES],
    };

    /// An empty group: no points, and no normal cones (n_s stays 0 and the lowest n_s . x is
    /// -inf, so that no light is behind a group's points).
    const GROUP_EMPTY: Self = Self {
        plane: [f32::NEG_INFINITY; DEPTH_SLICES],
        ..Self::EMPTY
    };

    /// Widens lane `lane` of a group (made from [`TileBounds::GROUP_EMPTY`]) to hold every
    /// box of tile `t`, and the group's depth range to hold `t`'s.
    fn merge(&mut self, lane: usize, t: &TileBounds) {
        self.zmin = self.zmin.min(t.zmin);
        self.zmax = self.zmax.max(t.zmax);
        for a in 0..3 {
            for k in 0..DEPTH_SLICES {
                self.lo[a][lane] = self.lo[a][lane].min(t.lo[a][k]);
                self.hi[a][lane] = self.hi[a][lane].max(t.hi[a][k]);
            }
        }
    }

    /// Adds a surface point at depth `z` (within the depth range, set before) with shading
    /// normal `n` to its slice.
    fn add(&mut self, z: f32, p: Vec3, n: Vec3) {
        let span = self.zmax - self.zmin;
        let k = if span > 0.0 {
            (((z - self.zmin) / span * DEPTH_SLICES as f32) as usize).min(DEPTH_SLICES - 1)
        } else {
            0
        };
        if self.lo[0][k] > self.hi[0][k] {
            // The slice's first point sets its normal.
            for a in 0..3 {
                self.normal[a][k] = n[a];
            }
        }
        for (a, v) in p.to_array().into_iter().enumerate() {
            self.lo[a][k] = self.lo[a][k].min(v);
            self.hi[a][k] = self.hi[a][k].max(v);
        }
        let ns = Vec3::new(self.normal[0][k], self.normal[1][k], self.normal[2][k]);
        self.spread[k] = self.spread[k].max((n - ns).length());
        self.plane[k] = self.plane[k].min(ns.dot(p));
    }

    /// Whether any lane of [`TileBounds::reach_lanes`] may hold a point the light reaches.
    #[cfg(test)]
    fn may_reach(&self, lo: f32, hi: f32, c: Vec3, r: f32, m: Vec3, hole: f32) -> bool {
        self.reach_lanes(lo, hi, c, r, m, hole) != 0
    }

    /// Per lane (a tile's depth slice k, a group's quadrant k), bit k clear only if no
    /// surface point of the lane can lie in the sphere (`c`, `r`) of depth range [`lo`,
    /// `hi`] in front of its tangent plane: the depth ranges do not meet (every bit clear),
    /// or the sphere misses the lane's box, or `c` lies behind every point's tangent plane
    /// (n_x . (c - x) <= 0 for every point x of the lane, whose light is then zero: bounded
    /// by n_s . c - min n_s . x + max |n_x - n_s| |c - x|), or, for a light with emission
    /// normal `m` not zero, every point lies behind the light's plane (m . (x - c) <= 0), or
    /// every point lies within `hole` of `c` ([`BinLights::holes`]).
    ///
    /// A tile of a group's quadrant k that the light reaches has bit k of the group set (its
    /// boxes lie in the quadrant's box, its depth range in the group's, and the bounds are
    /// monotone in them), so the binning skips the tiles of the quadrants whose bit is
    /// clear, and its lists stay those of testing every tile.
    #[inline]
    pub(super) fn reach_lanes(&self, lo: f32, hi: f32, c: Vec3, r: f32, m: Vec3, hole: f32) -> u32 {
        if self.zmin > hi || self.zmax < lo {
            return 0;
        }
        // Squared distances from c to each box, nearest and farthest, and n_s . c, four
        // boxes at once.
        let (mut d2, mut far2, mut nc) = (Vec4::ZERO, Vec4::ZERO, Vec4::ZERO);
        // The greatest m . (x - c) over each box.
        let mut front = Vec4::ZERO;
        for (a, ca) in c.to_array().into_iter().enumerate() {
            let ca = Vec4::splat(ca);
            let (lo, hi) = (Vec4::from_array(self.lo[a]), Vec4::from_array(self.hi[a]));
            let d = (lo - ca).max(ca - hi).max(Vec4::ZERO);
            d2 += d * d;
            let f = (ca - lo).abs().max((hi - ca).abs());
            far2 += f * f;
            nc += Vec4::from_array(self.normal[a]) * ca;
            let ma = Vec4::splat(m[a]);
            front += ((lo - ca) * ma).max((hi - ca) * ma);
        }
        // The bound less a rounding allowance, so that a light the shading would give a
        // grazing, non-zero cosine is kept whatever the tile size.
        let far = far2.sqrt();
        let allowance = (Vec4::splat(c.length()) + far) * ROUNDING;
        let behind =
            (nc - Vec4::from_array(self.plane) + Vec4::from_array(self.spread) * far + allowance)
                .cmple(Vec4::ZERO);
        // Behind the light's own plane (m . (x - c) <= 0 over the whole box), where a light
        // that emits only in front of it gives nothing.
        let unlit = (front + allowance).cmple(Vec4::ZERO) & BVec4A::splat(m != Vec3::ZERO);
        // Within the hole, where the light gives nothing.
        let inside = (far + allowance).cmplt(Vec4::splat(hole));
        // An empty slice holds no point (its infinite distance would pass a light of
        // infinite reach).
        let points = Vec4::from_array(self.lo[0]).cmple(Vec4::from_array(self.hi[0]));
        (d2.cmple(Vec4::splat(r * r)) & points & !behind & !unlit & !inside).bitmask()
    }
}

/// For pixels (0, y), (1, y), ... (`width` of them) under n x n interleaving with tiles of
/// `tile` full-resolution pixels: the column phase x mod n, the sub-image and the tile
/// column x / tile, found by counting instead of dividing.
pub(super) fn row_phases(
    y: u32,
    width: u32,
    n: u32,
    tile: u32,
) -> impl Iterator<Item = (usize, usize, usize)> {
    let s0 = ((y % n) * n) as usize;
    // (x mod n, x mod tile, x / tile)
    (0..width).scan((0u32, 0u32, 0usize), move |(phase, in_tile, tx), _| {
        let out = (*phase as usize, s0 + *phase as usize, *tx);
        *phase += 1;
        if *phase == n {
            *phase = 0;
        }
        *in_tile += 1;
        if *in_tile == tile {
            *in_tile = 0;
            *tx += 1;
        }
        Some(out)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use lgh_core::rng::Rng;

    /// A `w` x `h` G-buffer of scattered points: positions drifting across the image with
    /// noise, random normals and depths, and one pixel in nine seeing nothing.
    fn scattered(w: u32, h: u32, rng: &mut Rng) -> GBuffer {
        let n_px = (w * h) as usize;
        let mut g = GBuffer {
            width: w,
            height: h,
            position: Vec::with_capacity(n_px),
            normal: Vec::with_capacity(n_px),
            geo_normal: Vec::with_capacity(n_px),
            albedo: vec![Vec3::ONE; n_px],
            depth: Vec::with_capacity(n_px),
            emission: vec![Vec3::ZERO; n_px],
            view: None,
            deferred: Default::default(),
        };
        let mut r = |s: f32| (rng.next_f32() - 0.5) * s;
        for i in 0..n_px {
            let (x, y) = (
                (i as u32 % w) as f32 / w as f32,
                (i as u32 / w) as f32 / h as f32,
            );
            let p = Vec3::new(4.0 * x - 2.0 + r(0.5), 2.0 * y - 1.0 + r(0.5), r(3.0));
            let n = Vec3::new(r(2.0), r(2.0), r(2.0)).normalize_or(Vec3::Z);
            g.position.push(p);
            g.normal.push(n);
            g.geo_normal.push(n);
            let z = 2.0 + p.z + r(0.2);
            g.depth.push(if i % 9 == 4 { f32::INFINITY } else { z });
        }
        g
    }

    /// A group's quadrant (its lane of [`TileBounds::reach_lanes`]) may reach every light
    /// that one of the quadrant's tiles may reach, so that skipping the tiles of a group or
    /// quadrant that rejects a light lists exactly what testing every tile lists; and the
    /// quadrants do reject lights that their tiles would have tested.
    #[test]
    fn a_group_reaches_every_light_its_tiles_reach() {
        let mut rng = Rng::new(&[77]);
        let (mut tile_hits, mut group_misses) = (0usize, 0usize);
        for (n, tile) in [(1u32, 4u32), (2, 8), (3, 6)] {
            let g = scattered(61, 43, &mut rng);
            let all = AllBounds::new(&g, n, tile);
            for light in 0..300 {
                let c = Vec3::new(
                    6.0 * rng.next_f32() - 3.0,
                    4.0 * rng.next_f32() - 2.0,
                    4.0 * rng.next_f32() - 2.0,
                );
                let r = if light % 25 == 0 {
                    f32::INFINITY
                } else {
                    0.05 + 1.5 * rng.next_f32().powi(2)
                };
                let m = if light % 2 == 0 {
                    Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5
                } else {
                    Vec3::ZERO
                };
                let hole = if light % 3 == 0 {
                    r.min(4.0) * rng.next_f32()
                } else {
                    0.0
                };
                let z = 2.0 + c.z;
                let (lo, hi) = if r.is_finite() {
                    (z - r, z + r)
                } else {
                    (f32::NEG_INFINITY, f32::INFINITY)
                };
                for s in 0..(n * n) as usize {
                    for ty in 0..all.tiles_y {
                        for tx in 0..all.tiles_x {
                            let group = all.group(s, tx / GROUP, ty / GROUP);
                            let quadrant = quadrant(tx, ty);
                            let lanes = group.reach_lanes(lo, hi, c, r, m, hole);
                            let in_group = lanes & (1 << quadrant) != 0;
                            if all.get(s, tx, ty).may_reach(lo, hi, c, r, m, hole) {
                                tile_hits += 1;
                                assert!(
                                    in_group,
                                    "n {n}, light {light} at {c} (r {r}, m {m}, hole {hole}): \
                                     tile ({tx}, {ty}) of sub-image {s} reached, its \
                                     quadrant of the group not"
                                );
                            } else if !in_group {
                                group_misses += 1;
                            }
                        }
                    }
                }
            }
        }
        assert!(
            tile_hits > 1000 && group_misses > 1000,
            "{tile_hits} {group_misses}"
        );
    }

    /// An empty tile or slice keeps no light, not even one of infinite reach.
    #[test]
    fn nothing_reaches_an_empty_tile() {
        let far = f32::INFINITY;
        let c = Vec3::ZERO;
        assert!(!TileBounds::EMPTY.may_reach(-far, far, c, far, Vec3::ZERO, 0.0));
        assert!(!TileBounds::GROUP_EMPTY.may_reach(-far, far, c, far, Vec3::ZERO, 0.0));
        // A tile with one point, within the hole of a light of infinite reach: its three
        // empty slices do not keep the light.
        let mut t = TileBounds::EMPTY;
        (t.zmin, t.zmax) = (1.0, 1.0);
        t.add(1.0, Vec3::X, Vec3::Y);
        assert!(t.may_reach(-far, far, c, far, Vec3::ZERO, 0.0));
        assert!(!t.may_reach(-far, far, c, far, Vec3::ZERO, 2.0));
    }
}

#[cfg(test)]
mod guest_tests {
    use super::*;
    use lgh_core::rng::Rng;

    /// A pixel that shades other sub-images as their guest counts in their tiles' depth
    /// ranges (and nowhere else): with every pixel at depth 2-3 but one at depth 0.5, that
    /// pixel's guest sub-images' tiles reach down to 0.5, the others' do not.
    #[test]
    fn guests_count_in_the_tiles_of_the_sub_images_they_shade() {
        let (w, h, n, tile) = (32u32, 16u32, 4u32, 16u32);
        let mut rng = Rng::new(&[5]);
        let mut g = facing_points(w, h, &mut rng);
        let guest = (5 * w + 21) as usize; // tile (1, 0), sub-image (1, 1) = 5
        g.depth[guest] = 0.5;
        let mut masks = vec![0u64; (w * h) as usize];
        masks[guest] = (1 << 0) | (1 << 14);
        let plain = AllBounds::new(&g, n, tile);
        let with = AllBounds::with_guests(&g, n, tile, Some(&masks));
        for s in 0..16 {
            for tx in 0..2 {
                let near = with.get(s, tx, 0).zmin;
                let want = if tx == 1 && matches!(s, 0 | 5 | 14) {
                    0.5
                } else {
                    plain.get(s, tx, 0).zmin
                };
                assert_eq!(near, want, "sub-image {s}, tile {tx}");
                assert!(s == 5 && tx == 1 || plain.get(s, tx, 0).zmin >= 2.0);
            }
        }
    }

    /// `w` x `h` pixels facing the camera at depths 2-3.
    fn facing_points(w: u32, h: u32, rng: &mut Rng) -> GBuffer {
        let n_px = (w * h) as usize;
        let depth: Vec<f32> = (0..n_px).map(|_| 2.0 + rng.next_f32()).collect();
        let position = (0..n_px)
            .map(|i| Vec3::new((i as u32 % w) as f32, (i as u32 / w) as f32, -depth[i]))
            .collect();
        GBuffer::from_planes((w, h), position, vec![Vec3::Z; n_px], depth)
    }
}
