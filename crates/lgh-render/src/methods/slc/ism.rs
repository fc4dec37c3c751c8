//! Imperfect shadow maps (Ritschel et al. 2008) with the range-based point-cloud culling of
//! Tokuyoshi & Harada 2016, section 4.3 and Program 1: the shadows of the `slc` methods as
//! the paper renders them.
//!
//! The scene is approximated by a point cloud sampled uniformly by area. Every VPL i gets a
//! tiny paraboloid depth map (`resolution`^2, 32 x 32 in the paper) around its normal, splatted
//! from its own random subset of the cloud (`points_per_map` consecutive points from a hashed
//! offset; the cloud is in random order, so a run is a random subset). Before splatting, a
//! point is kept only if (Program 1)
//!
//! - its normal faces away from the VPL (front-face culling: the receiver's own surface does
//!   not shadow it),
//! - it lies in the VPL's upper hemisphere, and
//! - it lies within the VPL's light range r_i (the stochastic range of Eq. 3).
//!
//! The last test is the paper's addition: ranges shrink as the VPL count grows at a fixed
//! error bound, so the number of splatted points per map falls and the splatting cost grows
//! sublinearly. A point stands for the area A / `points_per_map` (A the scene's area) and is
//! splatted as a square of about its projected size, so that the sparse cloud leaves few
//! holes (the original pull-push hole filling is not done). A shading point is lit by VPL i if
//! its distance is below the depth in its map texel, plus a bias of 3% of the distance.

use glam::{Vec2, Vec3};
use lgh_core::rng::{Rng, hash};
use lgh_core::sampling::{Distribution1D, orthonormal_basis, uniform_triangle};
use rayon::prelude::*;

use crate::world::World;

/// Settings of the imperfect shadow maps (command-line flags in brackets).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IsmSettings {
    /// Texels per side of each map (32 as in the paper).
    pub resolution: u32,
    /// Points splatted per map before culling (`--ism-points`; 8192 in the paper, 1024 by
    /// default here for the CPU).
    pub points_per_map: u32,
    /// Points in the scene's cloud, shared by all maps.
    pub cloud_points: u32,
}

impl Default for IsmSettings {
    fn default() -> Self {
        Self {
            resolution: 32,
            points_per_map: 1024,
            cloud_points: 1 << 16,
        }
    }
}

/// Points on the scene's surfaces, uniform by area, in random order.
#[derive(Clone, Debug, Default)]
pub struct PointCloud {
    /// Positions.
    pub position: Vec<Vec3>,
    /// Unit geometric normals.
    pub normal: Vec<Vec3>,
    /// Total surface area of the scene.
    pub area: f32,
}

impl PointCloud {
    /// Samples `count` points on the triangles of `world`, with probability proportional to
    /// area, from `seed`; points where an alpha cut-out removes the surface are dropped, and
    /// the area is the part that is there (estimated from the points kept).
    #[must_use]
    pub fn sample(world: &World, count: usize, seed: u64) -> Self {
        let mesh = &world.scene.mesh;
        let areas: Vec<f32> = (0..mesh.len()).map(|t| mesh.area(t)).collect();
        let Some(dist) = Distribution1D::new(&areas) else {
            return Self::default();
        };
        let (position, normal): (Vec<Vec3>, Vec<Vec3>) = (0..count)
            .into_par_iter()
            .filter_map(|k| {
                let mut rng = Rng::new(&[seed, k as u64, 0x15a]);
                let (t, _) = dist.sample(rng.next_f32());
                let [a, b, c] = mesh.vertices(t);
                let bary = uniform_triangle(rng.next_2d());
                let there = world
                    .cutouts
                    .as_ref()
                    .is_none_or(|c| c.covers(t as u32, bary));
                let p = a * (1.0 - bary.x - bary.y) + b * bary.x + c * bary.y;
                there.then(|| (p, world.face_normals[t]))
            })
            .unzip();
        let kept = position.len() as f64 / count.max(1) as f64;
        Self {
            position,
            normal,
            area: (dist.total() * kept) as f32,
        }
    }
}

/// Program 1 of the paper: true if the point at `p` with normal `n` can cast a shadow in the
/// map of the VPL at `q` with normal `m` and squared range `range2` (back-facing to the VPL,
/// in its upper hemisphere, within its range).
#[inline]
#[must_use]
pub fn keep_point(p: Vec3, n: Vec3, q: Vec3, m: Vec3, range2: f32) -> bool {
    let rel = p - q;
    rel.dot(n) > 0.0 && rel.dot(m) > 0.0 && rel.length_squared() < range2
}

/// The paraboloid map frame of one VPL: its position q, normal m and tangents (t, b), set
/// once per frame (shading looks the map up for every pixel and light).
#[derive(Clone, Copy, Debug, Default)]
struct MapFrame {
    q: Vec3,
    m: Vec3,
    t: Vec3,
    b: Vec3,
}

impl MapFrame {
    fn new(q: Vec3, m: Vec3) -> Self {
        let (t, b) = orthonormal_basis(m);
        Self { q, m, t, b }
    }

    /// The texel (x, y) of a `res`^2 map that the unit direction `w` falls in, by the
    /// paraboloid coordinates (w . t, w . b) / (1 + w . m) in [-1, 1]^2 (the upper
    /// hemisphere maps inside the unit disk); may lie outside the map.
    #[inline]
    fn texel(&self, w: Vec3, res: usize) -> (i32, i32) {
        let uv = Vec2::new(w.dot(self.t), w.dot(self.b)) / (1.0 + w.dot(self.m));
        let to = |c: f32| ((c * 0.5 + 0.5) * res as f32) as i32;
        (to(uv.x), to(uv.y))
    }
}

/// One depth map per VPL.
#[derive(Clone, Debug, Default)]
pub struct ShadowMaps {
    resolution: u32,
    depth: Vec<f32>,
    frames: Vec<MapFrame>,
    /// Points tested against Program 1 (all maps).
    pub points_tested: u64,
    /// Points that passed the culling and were splatted.
    pub points_splatted: u64,
}

impl ShadowMaps {
    /// Builds the maps of the VPLs (`positions`, unit `normals`, light ranges `range`) from
    /// `cloud`, in parallel over VPLs. The subsets are drawn from `seed`.
    #[must_use]
    pub fn build(
        cloud: &PointCloud,
        positions: &[Vec3],
        normals: &[Vec3],
        range: &[f32],
        settings: &IsmSettings,
        seed: u64,
    ) -> Self {
        let res = settings.resolution.max(1) as usize;
        let texels = res * res;
        let mut depth = Vec::new();
        depth.resize(positions.len() * texels, f32::INFINITY);
        let per_map = (settings.points_per_map as usize).min(cloud.position.len());
        // A point stands for the area A / per_map: a disk of that area's radius.
        let point_radius = if per_map > 0 {
            (cloud.area / (std::f32::consts::PI * per_map as f32)).sqrt()
        } else {
            0.0
        };
        let frames: Vec<MapFrame> = positions
            .par_iter()
            .zip(normals)
            .map(|(&q, &m)| MapFrame::new(q, m))
            .collect();
        let splatted: u64 = depth
            .par_chunks_mut(texels)
            .zip(&frames)
            .enumerate()
            .map(|(i, (map, frame))| {
                let (q, m) = (frame.q, frame.m);
                let range2 = range[i] * range[i];
                if per_map == 0 || range2 <= 0.0 || m == Vec3::ZERO {
                    return 0;
                }
                let start = (hash(&[seed, i as u64, 0x15b]) % cloud.position.len() as u64) as usize;
                let mut kept = 0u64;
                for k in 0..per_map {
                    let s = (start + k) % cloud.position.len();
                    let p = cloud.position[s];
                    if !keep_point(p, cloud.normal[s], q, m, range2) {
                        continue;
                    }
                    kept += 1;
                    let rel = p - q;
                    let dist = rel.length();
                    // Projected half-size in texels: the disk's angle over the paraboloid's
                    // about 4 / res radians per texel near the pole.
                    let half = ((point_radius / dist) * res as f32 * 0.25).min(3.0) as i32;
                    let (cx, cy) = frame.texel(rel / dist, res);
                    for y in (cy - half).max(0)..=(cy + half).min(res as i32 - 1) {
                        for x in (cx - half).max(0)..=(cx + half).min(res as i32 - 1) {
                            let d = &mut map[y as usize * res + x as usize];
                            *d = d.min(dist);
                        }
                    }
                }
                kept
            })
            .sum();
        Self {
            resolution: res as u32,
            depth,
            frames,
            points_tested: (positions.len() * per_map) as u64,
            points_splatted: splatted,
        }
    }

    /// True if the point `x` is lit by VPL `i` according to its map (points below the VPL's
    /// surface count as lit: their cosine is zero anyway).
    #[inline]
    #[must_use]
    pub fn visible(&self, i: usize, x: Vec3) -> bool {
        let frame = &self.frames[i];
        let rel = x - frame.q;
        let dist = rel.length();
        if dist <= 0.0 || rel.dot(frame.m) <= 0.0 {
            return true;
        }
        let res = self.resolution as usize;
        let (tx, ty) = frame.texel(rel / dist, res);
        let last = res as i32 - 1;
        let (tx, ty) = (tx.clamp(0, last) as usize, ty.clamp(0, last) as usize);
        dist <= self.depth[i * res * res + ty * res + tx] * 1.03
    }
}
