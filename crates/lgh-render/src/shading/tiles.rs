//! Screen-tile binning of light volumes: the CPU counterpart of rasterising light spheres
//! over the G-buffer (LGH 2019 section 3.2; Tokuyoshi & Harada 2016 Algorithm 1).
//!
//! The image is cut into square tiles; each tile knows the depth range of the surfaces it
//! sees, and the bounding boxes of its surface points in [`DEPTH_SLICES`] slices of that
//! range. A light whose influence is a sphere (centre, radius) is listed in every tile that
//! its projected bounding rectangle covers, whose depth range meets the sphere's, and one of
//! whose boxes the sphere meets; a light with infinite radius is listed everywhere. (The
//! boxes are an extension: a GPU rasterising light volumes gets a similar cut from its depth
//! test.) Lists keep the lights' order, so shading that walks them is deterministic. One
//! binning module serves every tiled method.

use glam::Vec3;
use lgh_scene::camera::CameraFrame;
use rayon::prelude::*;

use crate::passes::gbuffer::GBuffer;
use crate::shading::interleave::Lattice;
pub use crate::shading::tile_bounds::{AllBounds, DEPTH_SLICES, GROUP};
use crate::shading::tile_bounds::{TileBounds, quadrant};

/// Lights binned into screen tiles, as a compressed sparse row table.
#[derive(Clone, Debug, Default)]
pub struct TileBins {
    /// Tile edge in pixels.
    pub tile: u32,
    /// Tiles per row.
    pub tiles_x: u32,
    /// Tiles per column.
    pub tiles_y: u32,
    /// Tile t's lights are `lights[offsets[t]..offsets[t + 1]]`, in ascending light order.
    pub offsets: Vec<u32>,
    /// Light indices.
    pub lights: Vec<u32>,
}

impl TileBins {
    /// The lights listed in the tile that holds pixel (x, y).
    #[inline]
    #[must_use]
    pub fn lights_at(&self, x: u32, y: u32) -> &[u32] {
        let t = self.tile_index(x, y);
        &self.lights[self.offsets[t] as usize..self.offsets[t + 1] as usize]
    }

    /// Index of the tile that holds pixel (x, y).
    #[inline]
    #[must_use]
    pub fn tile_index(&self, x: u32, y: u32) -> usize {
        (y / self.tile * self.tiles_x + x / self.tile) as usize
    }

    /// Bins spheres (`centres[i]`, `radii[i]`; infinite radius = everywhere, a negative or
    /// NaN one nowhere) into tiles of `tile` pixels over the G-buffer `g` seen through `frame`.
    #[must_use]
    pub fn build(
        g: &GBuffer,
        frame: &CameraFrame,
        tile: u32,
        centres: &[Vec3],
        radii: &[f32],
    ) -> Self {
        Self::build_lattice(g, frame, tile, Lattice::FULL, centres, radii)
    }

    /// [`TileBins::build`] for one sub-image of interleaved sampling: tiles of `tile`
    /// sub-image pixels, that is `tile * n` full-resolution pixels, whose depth ranges only
    /// count the sub-image's pixels. [`TileBins::lights_at`] takes full-resolution pixels.
    /// (It finds the tile bounds of every sub-image; [`InterleavedBins::build`] finds them
    /// once for all.)
    #[must_use]
    pub fn build_lattice(
        g: &GBuffer,
        frame: &CameraFrame,
        tile: u32,
        lattice: Lattice,
        centres: &[Vec3],
        radii: &[f32],
    ) -> Self {
        let n = lattice.n.max(1);
        let bounds = AllBounds::new(g, n, tile.max(1) * n);
        Self::from_bounds(
            g,
            frame,
            &bounds,
            (lattice.sy * n + lattice.sx) as usize,
            BinLights::spheres(centres, radii),
        )
    }

    /// The bins of sub-image `s` from the tile bounds of every sub-image, of `lights`.
    fn from_bounds(
        g: &GBuffer,
        frame: &CameraFrame,
        all: &AllBounds,
        s: usize,
        lights: BinLights<'_>,
    ) -> Self {
        let BinLights {
            centres,
            radii,
            facing,
            holes,
        } = lights;
        let (tile, tiles_x, tiles_y) = (all.tile, all.tiles_x, all.tiles_y);
        let n_tiles = (tiles_x * tiles_y) as usize;
        let depth = |i: usize| {
            let z = (centres[i] - frame.origin).dot(frame.forward);
            (z - radii[i], z + radii[i])
        };
        // The (tile, light) pairs, chunk by chunk of lights in parallel, in light order.
        let pairs: Vec<Vec<(u32, u32)>> = (0..centres.len())
            .into_par_iter()
            .step_by(BIN_CHUNK)
            .map(|start| {
                let mut pairs = Vec::new();
                for i in start..(start + BIN_CHUNK).min(centres.len()) {
                    if radii[i].is_nan() || radii[i] < 0.0 {
                        continue;
                    }
                    let Some([x0, y0, x1, y1]) =
                        screen_rect(frame, g.width, g.height, centres[i], radii[i])
                    else {
                        continue;
                    };
                    let (lo, hi) = depth(i);
                    let m = facing.get(i).copied().unwrap_or(Vec3::ZERO);
                    let hole = holes.get(i).copied().unwrap_or(0.0);
                    let (tx0, tx1, ty0, ty1) = (x0 / tile, x1 / tile, y0 / tile, y1 / tile);
                    let lanes =
                        |b: &TileBounds| b.reach_lanes(lo, hi, centres[i], radii[i], m, hole);
                    // Group by group, each tested first where it holds more than one of
                    // the rectangle's tiles (a group that rejects the light rejects them all;
                    // a quadrant of it whose lane rejects the light, its tiles).
                    for gy in ty0 / GROUP..=ty1 / GROUP {
                        let rows = ty0.max(gy * GROUP)..=ty1.min(gy * GROUP + GROUP - 1);
                        for gx in tx0 / GROUP..=tx1 / GROUP {
                            let cols = tx0.max(gx * GROUP)..=tx1.min(gx * GROUP + GROUP - 1);
                            let several = rows.start() != rows.end() || cols.start() != cols.end();
                            let quadrants = if several {
                                lanes(all.group(s, gx, gy))
                            } else {
                                0b1111
                            };
                            if quadrants == 0 {
                                continue;
                            }
                            for ty in rows.clone() {
                                for tx in cols.clone() {
                                    let q = quadrant(tx, ty);
                                    if quadrants & (1 << q) != 0 && lanes(all.get(s, tx, ty)) != 0 {
                                        pairs.push((ty * tiles_x + tx, i as u32));
                                    }
                                }
                            }
                        }
                    }
                }
                pairs
            })
            .collect();
        // Stable counting sort by tile: each tile's lights stay in light order.
        let mut counts = vec![0u32; n_tiles + 1];
        for &(t, _) in pairs.iter().flatten() {
            counts[t as usize + 1] += 1;
        }
        for t in 0..n_tiles {
            counts[t + 1] += counts[t];
        }
        let mut next = counts.clone();
        let mut lights = vec![0u32; counts[n_tiles] as usize];
        for &(t, i) in pairs.iter().flatten() {
            lights[next[t as usize] as usize] = i;
            next[t as usize] += 1;
        }
        Self {
            tile,
            tiles_x,
            tiles_y,
            offsets: counts,
            lights,
        }
    }
}

/// Lights per task of the binning.
const BIN_CHUNK: usize = 4096;

/// The lights a binning lists: spheres of influence, and where else each gives nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct BinLights<'a> {
    /// Centres.
    pub centres: &'a [Vec3],
    /// Radii of the spheres (infinite: everywhere; negative or NaN: nowhere).
    pub radii: &'a [f32],
    /// Per light a normal m, where the light gives nothing at the points x behind the plane
    /// through its centre, m . (x - c) <= 0; zero where it lights both sides
    /// ([`emission_facing`]). Empty: zero for every light.
    pub facing: &'a [Vec3],
    /// Per light the distance from its centre within which it gives nothing (lgh's grid
    /// lights whose blending weight rises from r_l / 2, [`lgh_core::blending::LevelRole::hole`]);
    /// empty: none.
    pub holes: &'a [f32],
}

impl<'a> BinLights<'a> {
    /// Spheres alone.
    #[must_use]
    pub fn spheres(centres: &'a [Vec3], radii: &'a [f32]) -> Self {
        Self {
            centres,
            radii,
            ..Self::default()
        }
    }
}

/// What the binning culls a light by on its own side ([`BinLights::facing`]): its
/// emission normal `m` where it emits nothing behind its plane (the
/// emission cosine max(0, m . w) + `iso` with `iso` zero: a VPL, a grid light whose VPLs'
/// normals agree), else zero (no such cull).
#[inline]
#[must_use]
pub fn emission_facing(m: Vec3, iso: f32) -> Vec3 {
    if iso == 0.0 { m } else { Vec3::ZERO }
}

/// The pixel rectangle [x0, y0, x1, y1] (inclusive) covered by the sphere (c, r), or `None`
/// if it is off screen or wholly behind the eye. Conservative and tight: the exact bounds of
/// the ball's projection ([`CameraFrame::sphere_bounds`]); a sphere reaching the plane of
/// the eye, or of infinite radius, covers the whole image.
#[must_use]
pub fn screen_rect(
    frame: &CameraFrame,
    width: u32,
    height: u32,
    c: Vec3,
    r: f32,
) -> Option<[u32; 4]> {
    if width == 0 || height == 0 {
        return None;
    }
    // Wholly behind the plane of the eye: no pixel sees a point of it (the G-buffer's
    // depths are positive).
    if (c - frame.origin).dot(frame.forward) + r < 0.0 {
        return None;
    }
    let full = Some([0, 0, width - 1, height - 1]);
    let Some([lo_x, lo_y, hi_x, hi_y]) = frame.sphere_bounds(c, r) else {
        return full;
    };
    if hi_x < 0.0 || hi_y < 0.0 || lo_x >= width as f32 || lo_y >= height as f32 {
        return None;
    }
    let clamp_x = |v: f32| (v.max(0.0) as u32).min(width - 1);
    let clamp_y = |v: f32| (v.max(0.0) as u32).min(height - 1);
    Some([clamp_x(lo_x), clamp_y(lo_y), clamp_x(hi_x), clamp_y(hi_y)])
}

/// Tile bins for n x n interleaved sampling: light i belongs to sub-image `sub[i]`, and each
/// sub-image bins only its own lights ([`TileBins::build_lattice`]). With n = 1 it is one
/// [`TileBins`] over all lights.
#[derive(Clone, Debug, Default)]
pub struct InterleavedBins {
    n: u32,
    /// Per sub-image, the global indices of its lights (ascending).
    members: Vec<Vec<u32>>,
    bins: Vec<TileBins>,
}

impl InterleavedBins {
    /// Bins `lights` (light i of sub-image `sub[i]` < n^2) into the tiles of their
    /// sub-image, in parallel over sub-images.
    #[must_use]
    pub fn build(
        g: &GBuffer,
        frame: &CameraFrame,
        tile: u32,
        n: u32,
        lights: BinLights<'_>,
        sub: &[u16],
    ) -> Self {
        let n = n.max(1);
        let all = AllBounds::new(g, n, tile.max(1) * n);
        Self::from_bounds(g, frame, &all, lights, sub)
    }

    /// [`InterleavedBins::build`] with the tile bounds `all` of `g` already found (their
    /// interleaving and tile size).
    #[must_use]
    pub fn from_bounds(
        g: &GBuffer,
        frame: &CameraFrame,
        all: &AllBounds,
        lights: BinLights<'_>,
        sub: &[u16],
    ) -> Self {
        let n = all.n;
        let mut members = vec![Vec::new(); (n * n) as usize];
        for (i, &s) in sub.iter().enumerate() {
            members[usize::from(s)].push(i as u32);
        }
        let bins = members
            .par_iter()
            .enumerate()
            .map(|(s, m)| {
                // This sub-image's lights' values of `of` (none where `of` is empty).
                fn pick<T: Copy>(of: &[T], m: &[u32]) -> Vec<T> {
                    if of.is_empty() {
                        return Vec::new();
                    }
                    m.iter().map(|&i| of[i as usize]).collect()
                }
                let (c, r) = (pick(lights.centres, m), pick(lights.radii, m));
                let (f, h) = (pick(lights.facing, m), pick(lights.holes, m));
                let mine = BinLights {
                    centres: &c,
                    radii: &r,
                    facing: &f,
                    holes: &h,
                };
                TileBins::from_bounds(g, frame, all, s, mine)
            })
            .collect();
        Self { n, members, bins }
    }

    /// (sub-image, tile) of full-resolution pixel (x, y): two pixels have the same light list
    /// if their keys are equal.
    #[inline]
    #[must_use]
    pub fn tile_key(&self, x: u32, y: u32) -> (usize, usize) {
        let s = crate::shading::interleave::sub_image_of(x, y, self.n);
        (s, self.bins[s].tile_index(x, y))
    }

    /// The tile edge in full-resolution pixels (n times the sub-image tile).
    #[must_use]
    pub fn tile_pixels(&self) -> u32 {
        self.bins.first().map_or(1, |b| b.tile.max(1))
    }

    /// The global indices of the lights listed for full-resolution pixel (x, y) in its
    /// sub-image's tile.
    #[inline]
    pub fn lights_at(&self, x: u32, y: u32) -> impl Iterator<Item = usize> + '_ {
        let s = crate::shading::interleave::sub_image_of(x, y, self.n);
        let m = &self.members[s];
        self.bins[s]
            .lights_at(x, y)
            .iter()
            .map(move |&local| m[local as usize] as usize)
    }
}

/// Interleaved tile bins as one light list per (sub-image, tile), for a backend that reads
/// them elsewhere (the GPU): pixel p shades `lights[offsets[list[p]]..offsets[list[p] + 1]]`,
/// global light indices in ascending order.
#[derive(Clone, Debug, Default)]
pub struct FlatBins {
    /// The list of each pixel (row by row).
    pub list: Vec<u32>,
    /// `lists + 1` starts into `lights`.
    pub offsets: Vec<u32>,
    /// Global light indices.
    pub lights: Vec<u32>,
}

impl InterleavedBins {
    /// The bins as [`FlatBins`] for the pixels of a `width` x `height` image.
    #[must_use]
    pub fn flatten(&self, width: u32, height: u32) -> FlatBins {
        let mut base = Vec::with_capacity(self.bins.len());
        let mut offsets = vec![0u32];
        let mut lights = Vec::new();
        for (bins, members) in self.bins.iter().zip(&self.members) {
            base.push(offsets.len() as u32 - 1);
            for t in bins.offsets.windows(2) {
                let local = &bins.lights[t[0] as usize..t[1] as usize];
                lights.extend(local.iter().map(|&l| members[l as usize]));
                offsets.push(lights.len() as u32);
            }
        }
        let list = (0..width * height)
            .into_par_iter()
            .map(|p| {
                let (s, t) = self.tile_key(p % width, p / width);
                base[s] + t as u32
            })
            .collect();
        FlatBins {
            list,
            offsets,
            lights,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lgh_scene::camera::{Camera, CameraFrame};

    /// A `w` x `h` G-buffer that sees a plane at depth 1 everywhere, and a camera on the z
    /// axis looking at the origin.
    fn flat_view(w: u32, h: u32) -> (GBuffer, CameraFrame) {
        let n_px = (w * h) as usize;
        let g = GBuffer {
            width: w,
            height: h,
            position: vec![Vec3::ZERO; n_px],
            normal: vec![Vec3::Z; n_px],
            geo_normal: vec![Vec3::Z; n_px],
            albedo: vec![Vec3::ONE; n_px],
            depth: vec![1.0; n_px],
            emission: vec![Vec3::ZERO; n_px],
            view: None,
            deferred: Default::default(),
        };
        let camera = Camera {
            position: Vec3::new(0.0, 0.0, 5.0),
            look_at: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_degrees: 40.0,
        };
        (g, camera.frame(w, h))
    }

    /// Every light belongs to exactly one sub-image: over the n^2 pixels of one interleaving
    /// block, lights of infinite radius (listed everywhere) are each seen exactly once.
    #[test]
    fn interleaved_bins_list_every_light_in_exactly_one_sub_image() {
        let (w, h) = (16u32, 8u32);
        let (g, frame) = flat_view(w, h);
        let count = 37;
        // In front of the plane the pixels see (a light on it lights none of them).
        let centres: Vec<Vec3> = (0..count)
            .map(|i| Vec3::splat((i + 1) as f32 * 0.01))
            .collect();
        let radii = vec![f32::INFINITY; count];
        for n in [1u32, 2, 4] {
            let sub: Vec<u16> = (0..count).map(|i| (i % (n * n) as usize) as u16).collect();
            let bins = InterleavedBins::build(
                &g,
                &frame,
                4,
                n,
                BinLights::spheres(&centres, &radii),
                &sub,
            );
            let mut seen = vec![0u32; count];
            for y in 0..n {
                for x in 0..n {
                    for j in bins.lights_at(x + n, y) {
                        seen[j] += 1;
                    }
                }
            }
            assert!(seen.iter().all(|&c| c == 1), "n = {n}: {seen:?}");
        }
    }

    /// A sphere wholly behind the eye is off screen, one that reaches past the plane of the
    /// eye covers the image, and one in front covers the pixel of its centre.
    #[test]
    fn screen_rects_behind_across_and_in_front_of_the_eye() {
        let (w, h) = (32u32, 16u32);
        let (_, frame) = flat_view(w, h);
        // The camera at z = 5 looks down -z.
        assert_eq!(
            screen_rect(&frame, w, h, Vec3::new(0.0, 0.0, 7.0), 1.0),
            None
        );
        assert_eq!(
            screen_rect(&frame, w, h, Vec3::new(0.0, 0.0, 5.5), 1.0),
            Some([0, 0, w - 1, h - 1])
        );
        let c = Vec3::new(0.3, -0.2, 0.0);
        let Some([x0, y0, x1, y1]) = screen_rect(&frame, w, h, c, 0.2) else {
            panic!("a sphere in front is on screen");
        };
        let (p, _) = frame.project(c).unwrap();
        assert!((x0..=x1).contains(&(p.x as u32)) && (y0..=y1).contains(&(p.y as u32)));
        assert!(x1 - x0 < w / 2, "{x0}..{x1}: not tight");
    }
}
