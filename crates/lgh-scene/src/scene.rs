//! The scene: everything a frame is rendered from.

use std::path::Path;

use glam::Vec3;

use crate::animation::Animation;
use crate::{Camera, Light, Material, Mesh, SceneError, Texture};

/// A scene in world space, ready to render.
#[derive(Clone, Debug)]
pub struct Scene {
    /// A short name (the file stem, or `cornell` for the built-in scene).
    pub name: String,
    /// All triangles.
    pub mesh: Mesh,
    /// Materials, indexed by [`Mesh::materials`].
    pub materials: Vec<Material>,
    /// Textures, indexed by [`Material::albedo_texture`].
    pub textures: Vec<Texture>,
    /// Point, spot and directional lights (emissive triangles are found from materials).
    pub lights: Vec<Light>,
    /// The camera; `None` until a file or [`Scene::finish`] provides one.
    pub camera: Option<Camera>,
    /// Exposure multiplier applied before tone mapping to PNG (1 = none).
    pub exposure: f32,
    /// What loading found and fixed, for the user.
    pub report: SceneReport,
    /// Motion over time (camera and light keyframes); empty for a still scene.
    pub animation: Animation,
}

/// Facts found while loading, worth telling the user.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SceneReport {
    /// Zero-area triangles removed.
    pub degenerate_triangles: usize,
    /// Non-fatal problems (missing textures, unsupported primitives), one line each.
    pub warnings: Vec<String>,
}

/// The largest coordinate a vertex may have, in scene units, at rest and when an animation
/// moves it: 1e12 keeps every product of ray tracing and shading (squared distances, areas
/// of the BVH's boxes) far inside `f32`'s range; a mesh beyond it is refused by name.
pub const MAX_COORDINATE: f32 = 1e12;

impl Scene {
    /// An empty scene named `name`.
    #[must_use]
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            mesh: Mesh::default(),
            materials: Vec::new(),
            textures: Vec::new(),
            lights: Vec::new(),
            camera: None,
            exposure: 1.0,
            report: SceneReport::default(),
            animation: Animation::default(),
        }
    }

    /// Validates and completes a loaded scene; `path` names the file in errors.
    ///
    /// Removes zero-area triangles (counted in [`Scene::report`]), and fails on a non-finite
    /// vertex, a triangle with a bad material index, no triangles, an invalid light or camera,
    /// or no light at all. Adds a camera that frames the whole mesh if there is none.
    ///
    /// # Errors
    /// A [`SceneError`] naming `path` and the problem.
    pub fn finish(&mut self, path: &Path) -> Result<(), SceneError> {
        self.finish_with(path, false)
    }

    /// [`Scene::finish`] for a mesh file loaded on its own: if it has no light, a point light
    /// is added at the camera (with a warning) instead of failing.
    ///
    /// # Errors
    /// As [`Scene::finish`], but for missing lights.
    pub fn finish_mesh_file(&mut self, path: &Path) -> Result<(), SceneError> {
        self.finish_with(path, true)
    }

    fn finish_with(&mut self, path: &Path, default_light: bool) -> Result<(), SceneError> {
        if let Some(i) = self.mesh.triangles.iter().flatten().find(|&&i| {
            self.mesh
                .positions
                .get(i as usize)
                .is_none_or(|p| !p.is_finite())
        }) {
            return Err(SceneError::new(
                path,
                format!("vertex {i} is missing or not finite (NaN or infinite coordinate)"),
            ));
        }
        if let Some((i, p)) = self
            .mesh
            .positions
            .iter()
            .enumerate()
            .find(|(_, p)| p.abs().max_element() > MAX_COORDINATE)
        {
            return Err(SceneError::new(
                path,
                format!(
                    "vertex {i} at ({}, {}, {}) lies beyond {MAX_COORDINATE:e} units from the origin (the most lgh takes; move the model or change its units)",
                    p.x, p.y, p.z
                ),
            ));
        }
        if let Some(m) = self.materials.iter().find(|m| !m.is_valid()) {
            return Err(SceneError::new(
                path,
                format!(
                    "material '{}': colour {} and emission {} must be finite and not negative",
                    m.name, m.albedo, m.emission
                ),
            ));
        }
        if let Some(&m) = self
            .mesh
            .materials
            .iter()
            .find(|&&m| m as usize >= self.materials.len())
        {
            return Err(SceneError::new(
                path,
                format!("triangle refers to material {m}, which does not exist"),
            ));
        }
        let before = self.mesh.len();
        let (lo, hi) = self.mesh.bounds();
        let scale = (hi - lo).max_element().max(f32::MIN_POSITIVE);
        let min_area2 = (scale * 1e-7).powi(4);
        self.mesh
            .retain_triangles(|m, t| m.face_cross(t).length_squared() > min_area2);
        self.report.degenerate_triangles += before - self.mesh.len();
        if self.mesh.is_empty() {
            return Err(SceneError::new(
                path,
                if before == 0 {
                    "the scene has no triangles".to_string()
                } else {
                    format!("all {before} triangles have zero area")
                },
            ));
        }
        // Framed once, here: the light added at the camera needs it too.
        if self.camera.is_none() {
            self.camera = Some(self.framing_camera());
        }
        if default_light {
            self.add_default_light();
        }
        if let Some(l) = self.lights.iter().find(|l| !l.is_valid()) {
            return Err(SceneError::new(
                path,
                format!("invalid light (non-finite or negative value, or zero direction): {l:?}"),
            ));
        }
        for (i, l) in self.lights.iter().enumerate() {
            if !l.emits() {
                self.report.warnings.push(format!(
                    "light {i} has zero power: it adds nothing to the image"
                ));
            }
        }
        let emitters = self.emissive_triangles().len();
        if emitters == 0 && !self.lights.is_empty() && !self.lights.iter().any(Light::emits) {
            self.report
                .warnings
                .push("no light emits anything: the image will be black".to_string());
        }
        if self.lights.is_empty() && emitters == 0 {
            return Err(SceneError::new(
                path,
                "the scene has no lights: add [[lights]] to a scene file, or give a material an emission",
            ));
        }
        if !self.exposure.is_finite() || self.exposure <= 0.0 {
            return Err(SceneError::new(path, "exposure must be a positive number"));
        }
        if self.camera.as_ref().is_some_and(|c| !c.is_valid()) {
            return Err(SceneError::new(
                path,
                "invalid camera: position equals look_at, up is parallel to the view, or fov is not in (0, 180)",
            ));
        }
        Ok(())
    }

    /// Adds a point light for a mesh file that brings none (most model files have no
    /// lights), with a warning: it sits at the camera, raised by a quarter of the scene's
    /// radius so that shadows show, with an intensity that gives an irradiance of 2 W/m^2 at
    /// the scene's centre. Does nothing if the scene has a light or an emissive material.
    fn add_default_light(&mut self) {
        if !self.lights.is_empty() || !self.emissive_triangles().is_empty() || self.mesh.is_empty()
        {
            return;
        }
        let camera = Some(self.camera())
            .filter(Camera::is_valid)
            .unwrap_or_else(|| self.framing_camera());
        let (centre, radius) = self.bounding_sphere();
        let up = camera.up.normalize_or_zero();
        let position = camera.position + 0.25 * radius * up;
        let d2 = position.distance_squared(centre).max(1e-12);
        self.lights.push(Light::Point {
            position,
            intensity: Vec3::splat(2.0 * d2),
        });
        self.report.warnings.push(
            "the scene has no lights: added a point light at the camera (a scene file sets lights with [[lights]])"
                .to_string(),
        );
    }

    /// A camera looking at the centre of the bounds from a three-quarter view, far enough
    /// back that the bounding sphere fits the default vertical field of view (45 degrees):
    /// from the front (+z, glTF's front) turned 30 degrees to the right (+x) and raised 20
    /// degrees (+y, up), unless one of the three other such views (from the left, or from
    /// behind) sees more than 1.5 times its projected area. Straight from +z, a mesh flat in
    /// x or y is seen edge on (a black image, and the light added at the camera makes no
    /// VPL); of the four views one sees any flat mesh at a cosine of at least 0.34.
    #[must_use]
    pub fn framing_camera(&self) -> Camera {
        let (c, r) = self.bounding_sphere();
        let fov = crate::camera::DEFAULT_FOV_DEGREES;
        let dist = r / (fov.to_radians() * 0.5).sin();
        let (turn, raise) = (30.0f32.to_radians(), 20.0f32.to_radians());
        let view = |right: f32, front: f32| {
            Vec3::new(
                right * turn.sin() * raise.cos(),
                raise.sin(),
                front * turn.cos() * raise.cos(),
            )
        };
        let views = [
            view(1.0, 1.0),
            view(-1.0, 1.0),
            view(1.0, -1.0),
            view(-1.0, -1.0),
        ];
        // Twice the projected area of the (two-sided) triangles seen along each view.
        let mut seen = [0.0f32; 4];
        for t in 0..self.mesh.len() {
            let cross = self.mesh.face_cross(t);
            for (s, v) in seen.iter_mut().zip(&views) {
                *s += cross.dot(*v).abs();
            }
        }
        let best = (1..4).fold(0, |b, i| if seen[i] > seen[b] { i } else { b });
        let towards = if seen[best] > 1.5 * seen[0] {
            views[best]
        } else {
            views[0]
        };
        Camera {
            position: c + dist * towards,
            look_at: c,
            up: Vec3::Y,
            fov_y_degrees: fov,
        }
    }

    /// Centre and radius of a sphere enclosing the mesh (the sphere around its bounding box).
    #[must_use]
    pub fn bounding_sphere(&self) -> (Vec3, f32) {
        let (lo, hi) = self.mesh.bounds();
        let c = 0.5 * (lo + hi);
        (c, (0.5 * (hi - lo).length()).max(1e-6))
    }

    /// Indices of the triangles whose material emits light (the area lights).
    #[must_use]
    pub fn emissive_triangles(&self) -> Vec<u32> {
        (0..self.mesh.len() as u32)
            .filter(|&t| {
                self.materials
                    .get(self.mesh.materials[t as usize] as usize)
                    .is_some_and(Material::is_emissive)
            })
            .collect()
    }

    /// The material of triangle `t`.
    #[inline]
    #[must_use]
    pub fn material_of(&self, t: usize) -> &Material {
        &self.materials[self.mesh.materials[t] as usize]
    }

    /// The camera (present after [`Scene::finish`]; a framing camera otherwise).
    #[must_use]
    pub fn camera(&self) -> Camera {
        self.camera.clone().unwrap_or_else(|| self.framing_camera())
    }
}
