//! A scene prepared for rendering: the scene, its BVH and the per-triangle data the passes
//! read in their inner loops.

use std::sync::Arc;

use glam::{Vec2, Vec3};
use lgh_scene::{Camera, Cutouts, Light, Scene};

pub mod accel;
pub mod lights;

use accel::{Accel, AccelError, AccelKind, BuildUse, Segment};
use lights::LightSet;

/// Everything a frame needs that does not depend on the camera or the settings.
#[derive(Debug)]
pub struct World {
    /// The scene.
    pub scene: Scene,
    /// The BVH over the scene's triangles.
    pub accel: Accel,
    /// The alpha cut-outs of the scene's triangles, which every ray tests (`None`: every
    /// triangle is opaque).
    pub cutouts: Option<Arc<Cutouts>>,
    /// Unit face normal of every triangle (counter-clockwise front).
    pub face_normals: Vec<Vec3>,
    /// All primary lights, with their sampling distributions.
    pub lights: LightSet,
    /// Centre of the scene's bounding sphere.
    pub centre: Vec3,
    /// Radius of the scene's bounding sphere.
    pub radius: f32,
    /// Offset of ray origins from surfaces, along the geometric normal (1e-4 x radius).
    pub ray_epsilon: f32,
    /// The scene's camera and lights as loaded, which the animation moves.
    rest: (Option<lgh_scene::Camera>, Vec<lgh_scene::Light>),
    /// The mesh as loaded, kept only if the animation moves objects.
    rest_mesh: Option<lgh_scene::Mesh>,
    /// Names the geometry: drawn afresh from a process-wide counter by every world and every
    /// change of its mesh, so that two equal ids mean the same triangles.
    geometry_id: u64,
}

/// The next [`World::geometry_id`].
fn next_geometry_id() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

/// The obvhs BVH of `mesh`, which cannot fail: where Embree cannot start.
fn obvhs(mesh: &lgh_scene::Mesh, cutouts: &Option<Arc<Cutouts>>, usage: BuildUse) -> Accel {
    Accel::build_cut(mesh, cutouts.clone(), AccelKind::Obvhs, usage)
        .unwrap_or_else(|_| Accel::build(mesh))
}

/// The unit face normal of every triangle of `mesh`.
fn face_normals(mesh: &lgh_scene::Mesh) -> Vec<Vec3> {
    (0..mesh.len())
        .map(|t| mesh.face_cross(t).normalize_or_zero())
        .collect()
}

/// The surface seen along a ray, with everything shading needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// World position.
    pub position: Vec3,
    /// Unit geometric normal, on the side the ray came from.
    pub geo_normal: Vec3,
    /// Unit shading normal (interpolated vertex normals; seen from the camera, bent by the
    /// material's normal map), in the same hemisphere as `geo_normal`.
    pub normal: Vec3,
    /// Diffuse albedo (factor x texture x vertex colour).
    pub albedo: Vec3,
    /// Emitted radiance towards the ray's origin (zero when the back of an emitter is seen).
    pub emission: Vec3,
    /// The triangle hit.
    pub triangle: u32,
}

impl World {
    /// Prepares `scene` (which must have passed [`Scene::finish`]): builds the BVH and the light
    /// tables.
    #[must_use]
    pub fn new(scene: Scene) -> Self {
        let cutouts = Cutouts::of(&scene).map(Arc::new);
        let accel = Accel::build_cut(
            &scene.mesh,
            cutouts.clone(),
            AccelKind::default_kind(),
            BuildUse::Still,
        )
        .unwrap_or_else(|_| obvhs(&scene.mesh, &cutouts, BuildUse::Still));
        Self::with(scene, accel, cutouts)
    }

    /// Prepares `scene` as [`World::new`] does, with the ray tracer `kind`.
    ///
    /// # Errors
    /// The backend is not in this build or cannot build the BVH.
    pub fn with_accel(scene: Scene, kind: AccelKind) -> Result<Self, AccelError> {
        let cutouts = Cutouts::of(&scene).map(Arc::new);
        let accel = Accel::build_cut(&scene.mesh, cutouts.clone(), kind, BuildUse::Still)?;
        Ok(Self::with(scene, accel, cutouts))
    }

    fn with(scene: Scene, accel: Accel, cutouts: Option<Arc<Cutouts>>) -> Self {
        let face_normals = face_normals(&scene.mesh);
        let rest_mesh = (!scene.animation.objects.is_empty()).then(|| scene.mesh.clone());
        let (centre, radius) = scene.bounding_sphere();
        let lights = LightSet::new(&scene, radius);
        let rest = (scene.camera.clone(), scene.lights.clone());
        Self {
            rest,
            rest_mesh,
            scene,
            accel,
            cutouts,
            face_normals,
            lights,
            centre,
            radius,
            ray_epsilon: 1e-4 * radius,
            geometry_id: next_geometry_id(),
        }
    }

    /// The id of the current geometry: equal ids (of any worlds of this process) mean the
    /// same triangles, so that what a camera sees of them can be reused.
    #[must_use]
    pub fn geometry_id(&self) -> u64 {
        self.geometry_id
    }

    /// Moves the camera, the lights and the animated objects to time `t` (seconds) of the
    /// scene's animation and rebuilds the light tables. If objects move, the BVH is rebuilt
    /// (in parallel; a full rebuild keeps its quality, where a refit would degrade as objects
    /// travel). The bounding sphere and the ray offset stay those of the loaded scene.
    ///
    /// # Errors
    /// The animation makes the scene unrenderable at `t` (see [`World::check_time`]; the
    /// world is then unchanged), or moves geometry out of range (the mesh is then posed but
    /// its BVH is not rebuilt: do not render the world before a successful `set_time`).
    pub fn set_time(&mut self, t: f32) -> Result<(), crate::RenderError> {
        if self.scene.animation.is_empty() {
            return Ok(());
        }
        self.check_time(t)?;
        let anim = &self.scene.animation;
        self.scene.camera = self.rest.0.as_ref().map(|c| anim.camera_at(c, t));
        self.scene.lights = anim.lights_at(&self.rest.1, t);
        if let Some(rest) = &self.rest_mesh
            && anim.pose_mesh(rest, t, &mut self.scene.mesh)
        {
            // Keyframes within lgh_scene::MAX_COORDINATE keep the posed mesh within a few
            // times it; this bounds what the BVH builder sees whatever the keyframes say.
            let limit = 8.0 * lgh_scene::MAX_COORDINATE;
            if let Some(p) = self
                .scene
                .mesh
                .positions
                .iter()
                .find(|p| !p.is_finite() || p.abs().max_element() > limit)
            {
                return Err(crate::RenderError::Animation {
                    time: t,
                    message: format!("the animation moves a vertex to {p}, out of range"),
                });
            }
            // A moving mesh is rebuilt every frame: the fastest build of the same backend.
            let (mesh, cutouts) = (&self.scene.mesh, &self.cutouts);
            self.accel =
                Accel::build_cut(mesh, cutouts.clone(), self.accel.kind(), BuildUse::Rebuilt)
                    .unwrap_or_else(|_| obvhs(mesh, cutouts, BuildUse::Rebuilt));
            self.face_normals = face_normals(&self.scene.mesh);
            self.geometry_id = next_geometry_id();
        }
        self.lights = LightSet::new(&self.scene, self.radius);
        Ok(())
    }

    /// Checks, without moving anything, that the animation's camera at time `t` is usable
    /// (interpolated keyframes can pass through their look-at point): a sequence checks all
    /// its frames before rendering the first.
    ///
    /// # Errors
    /// [`crate::RenderError::Animation`] naming the time.
    pub fn check_time(&self, t: f32) -> Result<(), crate::RenderError> {
        if let Some(c) = &self.rest.0
            && !self.scene.animation.camera.is_empty()
            && !self.scene.animation.camera_at(c, t).is_valid()
        {
            return Err(crate::RenderError::Animation {
                time: t,
                message:
                    "the interpolated camera looks at its own position, or along its up vector"
                        .into(),
            });
        }
        Ok(())
    }

    /// Places the camera and the punctual lights (an interactive viewer moving them) and
    /// rebuilds the light tables; the mesh and its BVH stay.
    pub fn set_view(&mut self, camera: Camera, lights: Vec<Light>) {
        self.scene.camera = Some(camera);
        self.scene.lights = lights;
        self.lights = LightSet::new(&self.scene, self.radius);
    }

    /// The camera and punctual lights as loaded (before any animation or [`World::set_view`]).
    #[must_use]
    pub fn rest_view(&self) -> (Option<Camera>, &[Light]) {
        (self.rest.0.clone(), &self.rest.1)
    }

    /// The surface at `hit` seen along the unit direction `dir` by a light path: its shading
    /// normal is the interpolated one, without the material's normal map
    /// ([`World::camera_surface`]).
    #[must_use]
    pub fn surface(&self, hit: &crate::world::accel::Hit, origin: Vec3, dir: Vec3) -> SurfacePoint {
        self.surface_with(hit, origin, dir, false)
    }

    /// The surface at `hit` seen along the unit direction `dir` from the camera: its shading
    /// normal bent by the material's normal map, if any. Normal maps shade what the camera
    /// sees; light paths keep the interpolated normals: a bent normal at a VPL would make it
    /// light its own plane (a VPL on a normal-mapped floor emitting along the floor), whose
    /// visibility is a ray grazing that plane (docs/design.md, "Normal maps").
    #[must_use]
    pub fn camera_surface(
        &self,
        hit: &crate::world::accel::Hit,
        origin: Vec3,
        dir: Vec3,
    ) -> SurfacePoint {
        self.surface_with(hit, origin, dir, true)
    }

    fn surface_with(
        &self,
        hit: &crate::world::accel::Hit,
        origin: Vec3,
        dir: Vec3,
        bend: bool,
    ) -> SurfacePoint {
        let t = hit.triangle as usize;
        let mesh = &self.scene.mesh;
        let [i0, i1, i2] = mesh.triangles[t].map(|i| i as usize);
        let (b1, b2) = (hit.bary.x, hit.bary.y);
        let b0 = 1.0 - b1 - b2;
        let face = self.face_normals[t];
        let front = face.dot(dir) < 0.0;
        let geo_normal = if front { face } else { -face };
        let (n0, n1, n2) = (mesh.normals[i0], mesh.normals[i1], mesh.normals[i2]);
        let mut normal = if n0 != Vec3::ZERO && n1 != Vec3::ZERO && n2 != Vec3::ZERO {
            (n0 * b0 + n1 * b1 + n2 * b2).normalize_or_zero()
        } else {
            Vec3::ZERO
        };
        if normal == Vec3::ZERO {
            normal = geo_normal;
        } else if normal.dot(geo_normal) < 0.0 {
            normal = -normal;
        }
        let uv: Vec2 = mesh.uvs[i0] * b0 + mesh.uvs[i1] * b1 + mesh.uvs[i2] * b2;
        let material = self.scene.material_of(t);
        if bend && let Some(map) = &material.normal_map {
            let corners = [i0, i1, i2].map(|i| mesh.positions[i]);
            let uvs = [i0, i1, i2].map(|i| mesh.uvs[i]);
            normal = map.bend(&self.scene.textures, uv, normal, geo_normal, corners, uvs);
        }
        SurfacePoint {
            position: origin + dir * hit.t,
            geo_normal,
            normal,
            albedo: material.albedo_at(&self.scene.textures, uv) * mesh.color_at(t, hit.bary),
            emission: if front { material.emission } else { Vec3::ZERO },
            triangle: hit.triangle,
        }
    }

    /// Traces a ray from `origin` and returns the surface it sees.
    #[must_use]
    pub fn trace(&self, origin: Vec3, dir: Vec3) -> Option<SurfacePoint> {
        self.accel
            .intersect(origin, dir, f32::INFINITY)
            .map(|h| self.surface(&h, origin, dir))
    }

    /// Traces a camera ray from `origin` and returns the surface it sees, its normal bent by
    /// the material's normal map ([`World::camera_surface`]).
    #[must_use]
    pub fn trace_camera(&self, origin: Vec3, dir: Vec3) -> Option<SurfacePoint> {
        self.accel
            .intersect(origin, dir, f32::INFINITY)
            .map(|h| self.camera_surface(&h, origin, dir))
    }

    /// A ray origin just off the surface at `p` (geometric normal `n_geo`), on the side that
    /// `towards` points to.
    #[inline]
    #[must_use]
    pub fn offset(&self, p: Vec3, n_geo: Vec3, towards: Vec3) -> Vec3 {
        let s = if n_geo.dot(towards) >= 0.0 { 1.0 } else { -1.0 };
        p + n_geo * (s * self.ray_epsilon)
    }

    /// True if something blocks the segment between surface points `a` (geometric normal
    /// `na`) and `b` (geometric normal `nb`). Both ends are moved off their surfaces first, so
    /// that neither surface shadows itself.
    #[inline]
    #[must_use]
    pub fn occluded_between(&self, a: Vec3, na: Vec3, b: Vec3, nb: Vec3) -> bool {
        self.shadow_segment(a, na, b, nb)
            .is_some_and(|s| self.accel.occluded(s.origin, s.dir, s.t_max))
    }

    /// The shadow ray of [`World::occluded_between`], for batches ([`Accel::occluded_many`]);
    /// `None` when the two points are too close for anything to lie between them.
    #[inline]
    #[must_use]
    pub fn shadow_segment(&self, a: Vec3, na: Vec3, b: Vec3, nb: Vec3) -> Option<Segment> {
        let o = self.offset(a, na, b - a);
        let e = self.offset(b, nb, a - b);
        let d = e - o;
        let len = d.length();
        (len > self.ray_epsilon).then(|| Segment {
            origin: o,
            dir: d / len,
            t_max: len * (1.0 - 1e-4),
        })
    }
}
