//! Ray tracing: a BVH over all triangles with closest-hit and any-hit queries.
//!
//! The BVH is obvhs's compressed 8-wide BVH (CWBVH, Ylitie et al. 2017), the measured choice
//! (docs/design.md, "Ray tracing"); nothing outside this module sees which BVH is used.
//! Two measures from that comparison are applied: each triangle's box is padded by 1e-4 of the scene
//! size before the build (flat axis-aligned walls otherwise make traversal very slow), and
//! triangles are stored in BVH leaf order so that the leaf test reads them sequentially.

use std::time::Duration;

use glam::{Vec2, Vec3, Vec3A};
use obvhs::{BvhBuildParams, aabb::Aabb, cwbvh::CwBvh, ray::Ray, rt_triangle::RtTriangle};

use lgh_scene::Mesh;

/// A ray-triangle intersection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) ray direction.
    pub t: f32,
    /// Index of the triangle in the scene mesh.
    pub triangle: u32,
    /// Barycentric coordinates (b1, b2): the point is (1 - b1 - b2) v0 + b1 v1 + b2 v2.
    pub bary: Vec2,
}

/// The acceleration structure of one scene.
pub struct Accel {
    bvh: CwBvh,
    tris: Vec<RtTriangle>,
    ids: Vec<u32>,
}

impl std::fmt::Debug for Accel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Accel")
            .field("triangles", &self.tris.len())
            .finish()
    }
}

impl Accel {
    /// Builds the BVH over every triangle of `mesh` (in parallel).
    #[must_use]
    pub fn build(mesh: &Mesh) -> Self {
        let (lo, hi) = mesh.bounds();
        let pad = Vec3A::splat(1e-4 * (hi - lo).max_element().max(1e-6));
        let boxes: Vec<Aabb> = (0..mesh.len())
            .map(|t| {
                let [a, b, c] = mesh.vertices(t).map(Vec3A::from);
                Aabb::new(a.min(b).min(c) - pad, a.max(b).max(c) + pad)
            })
            .collect();
        let bvh = obvhs::cwbvh::builder::build_cwbvh(
            &boxes,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        let ids = bvh.primitive_indices.clone();
        let tris = ids
            .iter()
            .map(|&i| {
                let [a, b, c] = mesh.vertices(i as usize).map(Vec3A::from);
                RtTriangle::new(a, b, c)
            })
            .collect();
        Self { bvh, tris, ids }
    }

    /// Number of triangles.
    #[must_use]
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// True if there is no triangle.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// The closest hit along `origin + t dir` for t in (0, `t_max`); `dir` must be unit length.
    #[inline]
    #[must_use]
    pub fn intersect(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<Hit> {
        let ray = Ray::new(origin.into(), dir.into(), 0.0, t_max);
        let mut hit = obvhs::ray::RayHit::none();
        if self
            .bvh
            .ray_traverse(ray, &mut hit, |r, id| self.tris[id].intersect(r))
        {
            let id = hit.primitive_id as usize;
            let bary = self.tris[id].compute_barycentric(&ray);
            Some(Hit {
                t: hit.t,
                triangle: self.ids[id],
                bary,
            })
        } else {
            None
        }
    }

    /// True if anything lies on the segment `origin + t dir`, t in (0, `t_max`) (any-hit
    /// query: stops at the first hit found).
    #[inline]
    #[must_use]
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        let ray = Ray::new(origin.into(), dir.into(), 0.0, t_max);
        !self
            .bvh
            .ray_traverse_miss(ray, |r, id| self.tris[id].intersect(r))
    }
}
