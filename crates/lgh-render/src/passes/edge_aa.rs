//! Anti-aliased edges of a single frame at the cost of a few primary rays: a geometry-aware
//! resolve of sub-pixel samples onto the shading of neighbouring pixels (docs/design.md,
//! "Anti-aliasing").
//!
//! Every pass shades one point per pixel, where its primary ray through the pixel centre
//! lands. A pixel on a silhouette or crease covers more than one surface, and one sample per
//! pixel draws such edges as stair-steps. Shading more points per pixel multiplies the cost
//! of every pass; instead, as MSAA does for rasterisers, the pixels whose 3 x 3 neighbourhood
//! shows more than one surface ("edge pixels", a few percent of a frame) trace
//! [`RenderSettings::edge_samples`] primary rays at stratified sub-pixel points (Roberts' R2
//! points, the first at the centre). Each sample takes the radiance of the pixel among the
//! 3 x 3 whose shaded point lies on the sample's surface (the pixel itself if it does,
//! else the nearest such neighbour, else the pixel itself), and the pixel becomes the mean
//! of its samples: the box filter of the pixel, with each surface shaded where a
//! neighbouring pixel shaded it.
//!
//! The resolve is a fixed linear map of the radiance images, the same for every component,
//! so the frame's parts still sum to its image. It depends only on the G-buffer and the
//! camera (no random numbers), so it is deterministic whatever the thread count.
//!
//! [`RenderSettings::edge_samples`]: crate::settings::RenderSettings::edge_samples

use glam::{Vec2, Vec3};
use lgh_scene::camera::CameraFrame;
use rayon::prelude::*;

use crate::accumulate::subpixel_jitter;
use crate::passes::gbuffer::GBuffer;
use crate::region::Region;
use crate::world::World;

/// Default sub-pixel samples of an edge pixel (`--edge-samples`): 8 gives 9 levels of
/// coverage along an edge.
pub const DEFAULT_EDGE_SAMPLES: u32 = 8;

/// Most sub-pixel samples of an edge pixel (the counts of a resolve are bytes).
pub const MAX_EDGE_SAMPLES: u32 = 64;

/// Least cosine between the geometric normals of one surface (about 18 degrees): points
/// across a crease sharper than this are different surfaces.
const SAME_SURFACE_COS: f32 = 0.95;

/// Largest distance of a point from another point's tangent plane, relative to that
/// point's depth, for the two to lie on one surface.
const SAME_SURFACE_PLANE: f32 = 2e-3;

/// What a primary ray saw, as far as the resolve cares.
#[derive(Clone, Copy)]
struct Seen {
    /// None for a ray that left the scene.
    hit: Option<(Vec3, Vec3)>,
    /// True if the surface emits towards the camera (a light's face, drawn by the emission
    /// image, is a surface of its own).
    emits: bool,
}

impl Seen {
    fn pixel(g: &GBuffer, i: usize) -> Self {
        Self {
            hit: g.is_hit(i).then(|| (g.position[i], g.geo_normal[i])),
            emits: g.emission[i] != Vec3::ZERO,
        }
    }

    /// True if `self` lies on the surface of `other` (a pixel's shaded point), within a
    /// distance from its tangent plane relative to `depth`, the depth of that pixel.
    fn on(&self, other: &Seen, depth: f32) -> bool {
        if self.emits != other.emits {
            return false;
        }
        match (self.hit, other.hit) {
            (None, None) => true,
            (Some((p, n)), Some((q, m))) => {
                n.dot(m) >= SAME_SURFACE_COS
                    && m.dot(p - q).abs() <= SAME_SURFACE_PLANE * depth.max(1e-6)
            }
            _ => false,
        }
    }
}

/// The resolve of one frame: for each edge pixel, how many of its samples take the radiance
/// of each pixel of its 3 x 3 neighbourhood.
#[derive(Clone, Debug, Default)]
pub struct EdgeResolve {
    width: u32,
    height: u32,
    samples: u32,
    /// (pixel, sample counts of its 3 x 3 neighbours, row by row, the pixel at 4).
    edges: Vec<(u32, [u8; 9])>,
}

/// The depth of pixel `i`, the scale of [`Seen::on`]'s plane test (1 where it sees nothing).
fn depth(g: &GBuffer, i: usize) -> f32 {
    if g.is_hit(i) { g.depth[i] } else { 1.0 }
}

/// The 3 x 3 neighbour `k` (0..9, row by row) of pixel (x, y), if inside the image.
fn neighbour(x: u32, y: u32, k: usize, w: u32, h: u32) -> Option<usize> {
    let nx = x as i64 + (k % 3) as i64 - 1;
    let ny = y as i64 + (k / 3) as i64 - 1;
    ((0..i64::from(w)).contains(&nx) && (0..i64::from(h)).contains(&ny))
        .then(|| ny as usize * w as usize + nx as usize)
}

impl EdgeResolve {
    /// Finds the edge pixels of `g` (seen through `camera`) within `keep` (all of them if
    /// `None`: a piece of a frame resolves only its own pixels and guard band) and resolves
    /// `samples` sub-pixel samples of each (1 = nothing to do).
    #[must_use]
    pub fn new(
        world: &World,
        camera: &CameraFrame,
        g: &GBuffer,
        samples: u32,
        keep: Option<&Region>,
    ) -> Self {
        let (w, h) = (g.width, g.height);
        let samples = samples.clamp(1, MAX_EDGE_SAMPLES);
        let mut out = Self {
            width: w,
            height: h,
            samples,
            edges: Vec::new(),
        };
        if samples == 1 || g.is_empty() {
            return out;
        }
        let offsets: Vec<Vec2> = (0..samples).map(subpixel_jitter).collect();
        out.edges = (0..h)
            .into_par_iter()
            .flat_map_iter(|y| {
                let offsets = &offsets;
                (0..w).filter_map(move |x| {
                    if keep.is_some_and(|r| !r.contains(x, y)) {
                        return None;
                    }
                    let i = y as usize * w as usize + x as usize;
                    let here = Seen::pixel(g, i);
                    let near: [Option<usize>; 9] =
                        std::array::from_fn(|k| neighbour(x, y, k, w, h));
                    let edge = near
                        .iter()
                        .flatten()
                        .any(|&j| !Seen::pixel(g, j).on(&here, depth(g, i)));
                    if !edge {
                        return None;
                    }
                    let mut counts = [0u8; 9];
                    counts[4] = 1; // the centre sample is the pixel's own shaded point
                    for &o in &offsets[1..] {
                        let s = world.trace_camera(
                            camera.origin,
                            camera.direction(camera.sample_point(x, y) + o),
                        );
                        let seen = Seen {
                            hit: s.as_ref().map(|s| (s.position, s.geo_normal)),
                            emits: s.is_some_and(|s| s.emission != Vec3::ZERO),
                        };
                        counts[best_match(g, &seen, &near)] += 1;
                    }
                    Some((i as u32, counts))
                })
            })
            .collect();
        out
    }

    /// The resolve of a `width` x `height` frame with `samples` sub-pixel samples per edge
    /// pixel from its edge pixels' counts (pixel, counts of its 3 x 3 neighbours row by
    /// row), in any order: what [`EdgeResolve::new`] finds, found by another backend
    /// (lgh-gpu traces the samples on the GPU).
    #[must_use]
    pub fn from_edges(
        width: u32,
        height: u32,
        samples: u32,
        mut edges: Vec<(u32, [u8; 9])>,
    ) -> Self {
        edges.sort_unstable_by_key(|e| e.0);
        Self {
            width,
            height,
            samples: samples.clamp(1, MAX_EDGE_SAMPLES),
            edges,
        }
    }

    /// The edge pixels and their counts, in pixel order.
    #[must_use]
    pub fn edges(&self) -> &[(u32, [u8; 9])] {
        &self.edges
    }

    /// Number of edge pixels.
    #[must_use]
    pub fn edge_pixels(&self) -> usize {
        self.edges.len()
    }

    /// The image's width and height.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Sub-pixel samples per edge pixel.
    #[must_use]
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Applies the resolve to a radiance image of the frame's size (`pixels`, row-major).
    pub fn apply(&self, pixels: &mut [Vec3]) {
        if self.edges.is_empty() || pixels.len() != self.width as usize * self.height as usize {
            return;
        }
        let inv = 1.0 / self.samples as f32;
        let (w, h) = (self.width, self.height);
        let resolved: Vec<Vec3> = self
            .edges
            .par_iter()
            .map(|&(i, counts)| {
                let (x, y) = (i % w, i / w);
                (0..9)
                    .filter(|&k| counts[k] > 0)
                    .filter_map(|k| neighbour(x, y, k, w, h).map(|j| (k, j)))
                    .map(|(k, j)| pixels[j] * f32::from(counts[k]))
                    .sum::<Vec3>()
                    * inv
            })
            .collect();
        for (&(i, _), v) in self.edges.iter().zip(resolved) {
            pixels[i as usize] = v;
        }
    }
}

/// The neighbour (0..9) whose shaded point lies on the surface `seen`: the pixel itself (4)
/// if its does, else the nearest that does, else the pixel itself.
fn best_match(g: &GBuffer, seen: &Seen, near: &[Option<usize>; 9]) -> usize {
    let on = |j: usize| seen.on(&Seen::pixel(g, j), depth(g, j));
    if near[4].is_some_and(on) {
        return 4;
    }
    let distance = |j: usize| match seen.hit {
        Some((p, _)) => p.distance_squared(g.position[j]),
        None => 0.0,
    };
    (0..9)
        .filter_map(|k| near[k].filter(|&j| on(j)).map(|j| (k, distance(j))))
        .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
        .map_or(4, |(k, _)| k)
}
