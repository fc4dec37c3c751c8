//! Ray tracing: a BVH over all triangles with closest-hit and any-hit queries, for single
//! rays and for batches, behind one of two backends chosen at run time ([`AccelKind`]).
//!
//! - **obvhs** (always built): obvhs's compressed 8-wide BVH (CWBVH, Ylitie et al. 2017),
//!   pure Rust (docs/design.md, "Ray tracing"). Two measures from that comparison are
//!   applied: each triangle's box is padded by 1e-4 of the scene size before the build (flat
//!   axis-aligned walls otherwise make traversal very slow), and triangles are stored in BVH
//!   leaf order so that the leaf test reads them sequentially.
//! - **Embree 3** (with the cargo feature `embree`, through the `lgh-embree` crate, the one
//!   crate with unsafe code): single rays through `rtcIntersect1`/`rtcOccluded1`, batches
//!   through the stream calls. A still scene is built at high quality (spatial splits), a
//!   mesh rebuilt every frame (moving objects) at low quality.
//!
//! Alpha cut-outs ([`Cutouts`]) are tested by both on every candidate hit, with the same
//! barycentrics: obvhs in its intersection closure, Embree in its filter functions.
//!
//! Nothing outside this module sees which BVH is used.

use std::time::Duration;

use glam::{Vec2, Vec3, Vec3A};
use obvhs::{BvhBuildParams, aabb::Aabb, cwbvh::CwBvh, ray::Ray, rt_triangle::RtTriangle};

use std::sync::Arc;

use lgh_scene::{Cutouts, Mesh};

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

/// A ray segment `origin + t dir`, t in (0, `t_max`), with a unit direction: one entry of a
/// batch ([`Accel::occluded_many`], [`Accel::intersect_many`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Segment {
    /// Origin.
    pub origin: Vec3,
    /// Unit direction.
    pub dir: Vec3,
    /// End of the segment.
    pub t_max: f32,
}

/// Which ray tracer builds and traverses the BVH.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum AccelKind {
    /// obvhs's compressed 8-wide BVH (pure Rust, always available).
    Obvhs,
    /// Embree 3 (only in builds with the `embree` feature).
    Embree,
}

impl AccelKind {
    /// Embree in builds with the `embree` feature, else obvhs.
    #[must_use]
    pub const fn default_kind() -> Self {
        if cfg!(feature = "embree") {
            Self::Embree
        } else {
            Self::Obvhs
        }
    }

    /// The kinds this build can use, the default first.
    #[must_use]
    pub fn available() -> Vec<Self> {
        if cfg!(feature = "embree") {
            vec![Self::Embree, Self::Obvhs]
        } else {
            vec![Self::Obvhs]
        }
    }

    /// The name on the command line and in statistics.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Self::Obvhs => "obvhs",
            Self::Embree => "embree",
        }
    }
}

/// The `--accel` flag of a command line: which ray tracer, if not the default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct AccelChoice {
    /// Ray tracer: obvhs (pure Rust, always built) or embree (Embree 3, in builds with the
    /// cargo feature `embree`). Default: embree when built in, else obvhs.
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    pub accel: Option<AccelKind>,
}

impl AccelChoice {
    /// The kind chosen, or the default.
    #[must_use]
    pub fn kind(&self) -> AccelKind {
        self.accel.unwrap_or(AccelKind::default_kind())
    }
}

impl std::fmt::Display for AccelKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Why a BVH could not be built with the backend asked for.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum AccelError {
    /// Embree was asked for in a build without the `embree` feature.
    #[error(
        "this build of lgh has no Embree: rebuild with `--features embree` (needs libembree-dev)"
    )]
    NotBuilt,
    /// Embree refused or failed.
    #[error("{0}")]
    Embree(String),
}

/// How much a build may spend on quality: a still scene is traced for long, a moving mesh is
/// rebuilt every frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuildUse {
    /// Built once, traced for long: the best traversal.
    Still,
    /// Rebuilt every frame: the fastest build.
    Rebuilt,
}

/// The obvhs backend's data.
struct Obvhs {
    bvh: CwBvh,
    tris: Vec<RtTriangle>,
    ids: Vec<u32>,
    cutouts: Option<Arc<Cutouts>>,
}

enum Backend {
    Obvhs(Obvhs),
    #[cfg(feature = "embree")]
    Embree(lgh_embree::Scene),
}

/// The acceleration structure of one scene.
pub struct Accel {
    backend: Backend,
    len: usize,
    /// Triangles with a cut-out, for statistics.
    cut: usize,
}

impl std::fmt::Debug for Accel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Accel")
            .field("kind", &self.kind())
            .field("triangles", &self.len)
            .field("cut_out", &self.cut)
            .finish()
    }
}

/// Every triangle's box, padded by 1e-4 to 2e-4 of the scene's size: the input of a BVH
/// build (obvhs here, the GPU backend's too). Flat axis-aligned walls otherwise give boxes of
/// zero thickness, which slow traversal by an order of magnitude (docs/design.md, "Ray
/// tracing"). Each side's pad differs, from a hash of the triangle and side: coincident
/// triangles (copies of one, or a scene whose units make its triangles equal in `f32`) would
/// otherwise give equal boxes, whose ties make obvhs's PLOC merge one pair per sweep, a
/// quadratic build (10^5 copies of a triangle: minutes; with the jitter, 0.1 s).
#[must_use]
pub fn padded_boxes(mesh: &Mesh) -> Vec<Aabb> {
    let (lo, hi) = mesh.bounds();
    let pad = 1e-4 * (hi - lo).max_element().max(1e-6);
    let jitter = |t: usize, side: u64| {
        let h = lgh_core::rng::hash(&[t as u64, side]);
        let [a, b, c] = [0, 21, 42].map(|s| ((h >> s) & 0x1f_ffff) as f32 / (1 << 21) as f32);
        Vec3A::new(a, b, c).mul_add(Vec3A::splat(pad), Vec3A::splat(pad))
    };
    (0..mesh.len())
        .map(|t| {
            let [a, b, c] = mesh.vertices(t).map(Vec3A::from);
            Aabb::new(
                a.min(b).min(c) - jitter(t, 0),
                a.max(b).max(c) + jitter(t, 1),
            )
        })
        .collect()
}

/// How far outside a triangle, in barycentric units, a hit still counts (see
/// [`closed_hit`]): a millionth of the triangle, far below a pixel.
const EDGE_SLACK: f32 = 1e-6;

/// The distance to `tri` along `ray` within [t_min, t_max], or infinity: obvhs's
/// Moller-Trumbore test (`RtTriangle::intersect`, the same arithmetic) with its edges
/// closed. obvhs rejects a barycentric of -0.0 (it tests sign bits), so a ray through the
/// edge two triangles share can miss both (390 of 486 rays through a quad's diagonal seen
/// from its back, the test below); and rounding can make both barycentrics slightly
/// negative (a glTF box seen head-on showed its far side at 2 pixels of 2,304). Hits up to
/// [`EDGE_SLACK`] outside a triangle count, which closes both kinds of crack.
#[inline]
fn closed_hit(tri: &RtTriangle, ray: &Ray) -> f32 {
    closed_hit_uv(tri, ray).0
}

/// [`closed_hit`] with the hit's barycentrics (b1, b2).
#[inline]
fn closed_hit_uv(tri: &RtTriangle, ray: &Ray) -> (f32, Vec2) {
    let c = tri.v0 - ray.origin;
    let r = ray.direction.cross(c);
    let inv_det = 1.0 / tri.ng.dot(ray.direction);
    let u = r.dot(tri.e2) * inv_det;
    let v = r.dot(tri.e1) * inv_det;
    let w = 1.0 - u - v;
    if inv_det != 0.0 && u >= -EDGE_SLACK && v >= -EDGE_SLACK && w >= -EDGE_SLACK {
        let t = tri.ng.dot(c) * inv_det;
        if t >= ray.tmin && t <= ray.tmax {
            return (t, Vec2::new(u, v));
        }
    }
    (f32::INFINITY, Vec2::ZERO)
}

/// `dir` with every -0.0 made +0.0 (adding +0.0 does it): obvhs's traversal missed the
/// hit of a ray along (-0, -0, -1) on a triangle that (+0, +0, -1) hits.
#[inline]
fn positive_zeros(dir: Vec3) -> Vec3 {
    dir + Vec3::ZERO
}

impl Obvhs {
    fn build(mesh: &Mesh, cutouts: Option<Arc<Cutouts>>) -> Self {
        let boxes = padded_boxes(mesh);
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
        Self {
            bvh,
            tris,
            ids,
            cutouts,
        }
    }

    /// The distance to leaf triangle `id` along `ray`, or infinity, with its cut-out tested.
    #[inline]
    fn masked_hit(&self, cutouts: &Cutouts, ray: &Ray, id: usize) -> f32 {
        let (t, b) = closed_hit_uv(&self.tris[id], ray);
        if t.is_finite() && !cutouts.covers(self.ids[id], b) {
            f32::INFINITY
        } else {
            t
        }
    }

    #[inline]
    fn intersect(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<Hit> {
        let ray = Ray::new(origin.into(), positive_zeros(dir).into(), 0.0, t_max);
        let mut hit = obvhs::ray::RayHit::none();
        let found = match &self.cutouts {
            None => self
                .bvh
                .ray_traverse(ray, &mut hit, |r, id| closed_hit(&self.tris[id], r)),
            Some(c) => self
                .bvh
                .ray_traverse(ray, &mut hit, |r, id| self.masked_hit(c, r, id)),
        };
        found.then(|| {
            let id = hit.primitive_id as usize;
            Hit {
                t: hit.t,
                triangle: self.ids[id],
                bary: self.tris[id].compute_barycentric(&ray),
            }
        })
    }

    #[inline]
    fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        let ray = Ray::new(origin.into(), positive_zeros(dir).into(), 0.0, t_max);
        !match &self.cutouts {
            None => self
                .bvh
                .ray_traverse_miss(ray, |r, id| closed_hit(&self.tris[id], r)),
            Some(c) => self
                .bvh
                .ray_traverse_miss(ray, |r, id| self.masked_hit(c, r, id)),
        }
    }
}

#[cfg(feature = "embree")]
fn embree_ray(s: &Segment) -> lgh_embree::Ray {
    lgh_embree::Ray {
        origin: s.origin.into(),
        dir: s.dir.into(),
        t_max: s.t_max,
    }
}

#[cfg(feature = "embree")]
fn from_embree(h: lgh_embree::Hit) -> Hit {
    Hit {
        t: h.t,
        triangle: h.triangle,
        bary: Vec2::from(h.uv),
    }
}

impl Accel {
    /// Builds the BVH over every triangle of `mesh` (in parallel) with the default backend
    /// ([`AccelKind::default_kind`]) for a still scene; if Embree cannot start (an old
    /// processor), with obvhs.
    #[must_use]
    pub fn build(mesh: &Mesh) -> Self {
        Self::build_with(mesh, AccelKind::default_kind(), BuildUse::Still)
            .unwrap_or_else(|_| Self::obvhs(mesh, None))
    }

    /// Builds the BVH over every triangle of `mesh` with the backend `kind`, at the quality
    /// that suits `usage`.
    ///
    /// # Errors
    /// Embree is not in this build, or refuses the mesh or fails.
    pub fn build_with(mesh: &Mesh, kind: AccelKind, usage: BuildUse) -> Result<Self, AccelError> {
        Self::build_cut(mesh, None, kind, usage)
    }

    /// [`Accel::build_with`] for a mesh whose triangles may have alpha cut-outs: every
    /// query passes through a triangle where [`Cutouts::covers`] is false (`cutouts` must
    /// be those of this mesh's triangles).
    ///
    /// # Errors
    /// As [`Accel::build_with`].
    pub fn build_cut(
        mesh: &Mesh,
        cutouts: Option<Arc<Cutouts>>,
        kind: AccelKind,
        usage: BuildUse,
    ) -> Result<Self, AccelError> {
        let cut = cutouts.as_ref().map_or(0, |c| c.len());
        let mut accel = match kind {
            AccelKind::Obvhs => Self::obvhs(mesh, cutouts),
            AccelKind::Embree => Self::embree(mesh, cutouts, usage)?,
        };
        accel.cut = cut;
        Ok(accel)
    }

    fn obvhs(mesh: &Mesh, cutouts: Option<Arc<Cutouts>>) -> Self {
        Self {
            backend: Backend::Obvhs(Obvhs::build(mesh, cutouts)),
            len: mesh.len(),
            cut: 0,
        }
    }

    #[cfg(feature = "embree")]
    fn embree(
        mesh: &Mesh,
        cutouts: Option<Arc<Cutouts>>,
        usage: BuildUse,
    ) -> Result<Self, AccelError> {
        let quality = match usage {
            BuildUse::Still => lgh_embree::BuildQuality::Medium,
            BuildUse::Rebuilt => lgh_embree::BuildQuality::Low,
        };
        let vertices: &[[f32; 3]] = bytemuck::cast_slice(&mesh.positions);
        let filter = cutouts.map(|c| -> lgh_embree::HitFilter {
            Arc::new(move |t, uv| c.covers(t, Vec2::from(uv)))
        });
        let scene = lgh_embree::Scene::with_filter(vertices, &mesh.triangles, quality, filter)
            .map_err(|e| AccelError::Embree(e.to_string()))?;
        Ok(Self {
            backend: Backend::Embree(scene),
            len: mesh.len(),
            cut: 0,
        })
    }

    #[cfg(not(feature = "embree"))]
    #[allow(clippy::unnecessary_wraps)]
    fn embree(_: &Mesh, _: Option<Arc<Cutouts>>, _: BuildUse) -> Result<Self, AccelError> {
        Err(AccelError::NotBuilt)
    }

    /// The backend in use.
    #[must_use]
    pub fn kind(&self) -> AccelKind {
        match self.backend {
            Backend::Obvhs(_) => AccelKind::Obvhs,
            #[cfg(feature = "embree")]
            Backend::Embree(_) => AccelKind::Embree,
        }
    }

    /// Number of triangles.
    #[must_use]
    pub fn len(&self) -> usize {
        self.len
    }

    /// True if there is no triangle.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Number of triangles with an alpha cut-out.
    #[must_use]
    pub fn cut_out(&self) -> usize {
        self.cut
    }

    /// The closest hit along `origin + t dir` for t in (0, `t_max`); `dir` must be unit length.
    #[inline]
    #[must_use]
    pub fn intersect(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<Hit> {
        match &self.backend {
            Backend::Obvhs(b) => b.intersect(origin, dir, t_max),
            #[cfg(feature = "embree")]
            Backend::Embree(s) => s
                .intersect(&embree_ray(&Segment { origin, dir, t_max }))
                .map(from_embree),
        }
    }

    /// True if anything lies on the segment `origin + t dir`, t in (0, `t_max`) (any-hit
    /// query: stops at the first hit found).
    #[inline]
    #[must_use]
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        match &self.backend {
            Backend::Obvhs(b) => b.occluded(origin, dir, t_max),
            #[cfg(feature = "embree")]
            Backend::Embree(s) => s.occluded(&embree_ray(&Segment { origin, dir, t_max })),
        }
    }

    /// Occlusion of a batch of segments: `out[i]` = [`Accel::occluded`] of `segments[i]`.
    /// Embree traces the batch as a stream (`rtcOccluded1M`) in its incoherent mode: the
    /// coherent mode, which regroups a stream into packets, made the brute force 1.55x
    /// slower even for one point's rays to many VPLs (docs/performance.md, "Embree").
    /// Answers are the same as one query at a time.
    ///
    /// # Panics
    /// If `out` is shorter than `segments`.
    pub fn occluded_many(&self, segments: &[Segment], out: &mut [bool]) {
        assert!(out.len() >= segments.len(), "one output per segment");
        match &self.backend {
            Backend::Obvhs(b) => {
                for (s, o) in segments.iter().zip(out) {
                    // An empty segment (the default) is traced by neither backend.
                    *o = s.t_max > 0.0 && b.occluded(s.origin, s.dir, s.t_max);
                }
            }
            #[cfg(feature = "embree")]
            Backend::Embree(scene) => {
                let mut rays = [lgh_embree::Ray::default(); 64];
                for (segs, out) in segments.chunks(64).zip(out.chunks_mut(64)) {
                    for (r, s) in rays.iter_mut().zip(segs) {
                        *r = embree_ray(s);
                    }
                    scene.occluded_many(&rays[..segs.len()], false, out);
                }
            }
        }
    }

    /// Closest hits of a batch of rays: `out[i]` = [`Accel::intersect`] of `rays[i]` (Embree:
    /// `rtcIntersect1M`, incoherent mode as in [`Accel::occluded_many`]).
    ///
    /// # Panics
    /// If `out` is shorter than `rays`.
    pub fn intersect_many(&self, rays: &[Segment], out: &mut [Option<Hit>]) {
        assert!(out.len() >= rays.len(), "one output per ray");
        match &self.backend {
            Backend::Obvhs(b) => {
                for (s, o) in rays.iter().zip(out) {
                    *o = b.intersect(s.origin, s.dir, s.t_max);
                }
            }
            #[cfg(feature = "embree")]
            Backend::Embree(scene) => {
                let mut er = [lgh_embree::Ray::default(); 64];
                let mut hits = [None; 64];
                for (segs, out) in rays.chunks(64).zip(out.chunks_mut(64)) {
                    for (r, s) in er.iter_mut().zip(segs) {
                        *r = embree_ray(s);
                    }
                    scene.intersect_many(&er[..segs.len()], false, &mut hits);
                    for (o, h) in out.iter_mut().zip(&hits) {
                        *o = h.map(from_embree);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rays through the edge two triangles share hit the surface: a quad split along its
    /// diagonal (both windings), seen from both sides by rays through points of the
    /// diagonal, straight, from an eye and obliquely. With obvhs's own test 390 of the 486
    /// rays fell through (all from the back side).
    #[test]
    fn rays_through_shared_edges_do_not_fall_through() {
        let mut mesh = Mesh {
            positions: vec![
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(-1.0, 1.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            ..Mesh::default()
        };
        mesh.normals = vec![Vec3::ZERO; 4];
        mesh.uvs = vec![Vec2::ZERO; 4];
        mesh.materials = vec![0; 2];
        mesh.objects = vec![0; 2];
        let mut missed = Vec::new();
        // Both windings, seen from both sides.
        for winding in [[[0, 1, 2], [0, 2, 3]], [[0, 2, 1], [0, 3, 2]]] {
            mesh.triangles = winding.to_vec();
            let accel = Accel::build_with(&mesh, AccelKind::Obvhs, BuildUse::Still).expect("bvh");
            for side in [1.0f32, -1.0] {
                for k in -40..=40 {
                    let s = k as f32 / 41.0;
                    for (o, d) in [
                        // Straight through the diagonal x = y.
                        (Vec3::new(s, s, 3.0 * side), Vec3::new(0.0, 0.0, -side)),
                        // From an eye on the axis, through points of the diagonal.
                        (
                            Vec3::new(0.0, 0.0, 3.0 * side),
                            Vec3::new(s, s, -3.0 * side).normalize(),
                        ),
                        // Obliquely, through the diagonal's points.
                        (
                            Vec3::new(s + 0.5, s - 0.25, 2.0 * side),
                            Vec3::new(-0.5, 0.25, -2.0 * side).normalize(),
                        ),
                    ] {
                        if accel.intersect(o, d, f32::INFINITY).is_none() {
                            missed.push((o, d));
                        }
                    }
                }
            }
        }
        assert!(
            missed.is_empty(),
            "{} rays fell through: {:?}",
            missed.len(),
            &missed[..missed.len().min(4)]
        );
    }
}
