//! Motion over time: camera keyframes, moving or turning primary lights and rigidly moving
//! objects, interpolated linearly between keyframes (constant before the first and after the
//! last).
//!
//! In a scene file:
//!
//! ```toml
//! [[animation.camera]]          # keyframes of the camera
//! time = 0.0                    # seconds
//! position = [0.0, 1.0, 3.9]
//! look_at = [0.0, 1.0, 0.0]
//!
//! [[animation.lights]]          # keyframes of light number `light` of the file's [[lights]]
//! light = 0
//! time = 0.0
//! position = [-0.5, 1.5, 0.0]   # point and spot lights
//! direction = [0.0, -1.0, 0.0]  # spot and directional lights (optional)
//!
//! [[animation.objects]]         # keyframes of a named object of the mesh
//! object = "tall_block"         # an OBJ `o`/`g` name, a glTF node name (`nodeN` if unnamed)
//! time = 0.0
//! translation = [0.1, 0.0, 0.0] # offset from where the file puts it (default 0)
//! rotation = [0.0, 45.0, 0.0]   # degrees about x, y, z, applied in that order about the
//!                               # object's bounding-box centre at rest (default 0)
//! ```
//!
//! Rotation angles are interpolated as angles (so 0 to 360 degrees is one full turn), then
//! turned into a rotation.

use glam::{EulerRot, Mat4, Quat, Vec3};

use crate::{Camera, Light, Mesh};

/// One camera keyframe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraKey {
    /// Time in seconds.
    pub time: f32,
    /// Eye position.
    pub position: Vec3,
    /// Point looked at.
    pub look_at: Vec3,
}

/// One keyframe of a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightKey {
    /// Index into [`crate::Scene::lights`].
    pub light: usize,
    /// Time in seconds.
    pub time: f32,
    /// New position (point and spot lights).
    pub position: Option<Vec3>,
    /// New direction (spot and directional lights), normalised.
    pub direction: Option<Vec3>,
}

/// One keyframe of a rigidly moving object: its pose relative to the rest pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObjectKey {
    /// Index into [`Mesh::object_names`].
    pub object: u32,
    /// Time in seconds.
    pub time: f32,
    /// Offset from the rest position.
    pub translation: Vec3,
    /// Rotation about x, y and z in degrees (applied in that order), about the object's
    /// bounding-box centre at rest.
    pub rotation_degrees: Vec3,
}

/// The motion of a scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Animation {
    /// Camera keyframes, sorted by time.
    pub camera: Vec<CameraKey>,
    /// Light keyframes, sorted by time within each light.
    pub lights: Vec<LightKey>,
    /// Object keyframes, sorted by time within each object.
    pub objects: Vec<ObjectKey>,
}

/// Linear interpolation of keyed values at time `t`: (value before, value after, weight).
fn interpolate<T: Copy>(keys: &[(f32, T)], t: f32, lerp: impl Fn(T, T, f32) -> T) -> Option<T> {
    let first = keys.first()?;
    if t <= first.0 {
        return Some(first.1);
    }
    for w in keys.windows(2) {
        let ((t0, a), (t1, b)) = (w[0], w[1]);
        if t <= t1 {
            let s = if t1 > t0 { (t - t0) / (t1 - t0) } else { 1.0 };
            return Some(lerp(a, b, s));
        }
    }
    keys.last().map(|k| k.1)
}

impl Animation {
    /// True if nothing moves.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.camera.is_empty() && self.lights.is_empty() && self.objects.is_empty()
    }

    /// The rigid transform of `object` at time `t` about the rest-pose centre `pivot`
    /// (`None` if the object has no keyframe).
    #[must_use]
    pub fn object_transform(&self, object: u32, pivot: Vec3, t: f32) -> Option<Mat4> {
        let keys: Vec<(f32, (Vec3, Vec3))> = self
            .objects
            .iter()
            .filter(|k| k.object == object)
            .map(|k| (k.time, (k.translation, k.rotation_degrees)))
            .collect();
        let (translation, degrees) =
            interpolate(&keys, t, |a, b, s| (a.0.lerp(b.0, s), a.1.lerp(b.1, s)))?;
        let r = degrees * (std::f32::consts::PI / 180.0);
        let rotation = Quat::from_euler(EulerRot::XYZ, r.x, r.y, r.z);
        Some(
            Mat4::from_translation(pivot + translation)
                * Mat4::from_quat(rotation)
                * Mat4::from_translation(-pivot),
        )
    }

    /// Moves the animated objects of `rest` to their pose at time `t`, writing the vertex
    /// positions and normals of `posed` (a copy of `rest` with the same topology). Vertices of
    /// objects without keyframes keep their rest values. Returns true if anything moved.
    pub fn pose_mesh(&self, rest: &Mesh, t: f32, posed: &mut Mesh) -> bool {
        if self.objects.is_empty() {
            return false;
        }
        let count = rest.object_names.len();
        let mut lo = vec![Vec3::splat(f32::INFINITY); count];
        let mut hi = vec![Vec3::splat(f32::NEG_INFINITY); count];
        let mut vertex_object = vec![u32::MAX; rest.positions.len()];
        for (tri, &o) in rest.triangles.iter().zip(&rest.objects) {
            if o as usize >= count {
                continue; // an object without a name cannot be animated
            }
            for &v in tri {
                let Some(&p) = rest.positions.get(v as usize) else {
                    continue;
                };
                lo[o as usize] = lo[o as usize].min(p);
                hi[o as usize] = hi[o as usize].max(p);
                vertex_object[v as usize] = o;
            }
        }
        let transforms: Vec<Option<Mat4>> = (0..count)
            .map(|o| self.object_transform(o as u32, (lo[o] + hi[o]) * 0.5, t))
            .collect();
        let vertices = posed
            .positions
            .iter_mut()
            .zip(&mut posed.normals)
            .zip(rest.positions.iter().zip(&rest.normals))
            .zip(&vertex_object);
        for (((p, n), (&rp, &rn)), &o) in vertices {
            let m = transforms.get(o as usize).copied().flatten();
            *p = m.map_or(rp, |m| m.transform_point3(rp));
            *n = m.map_or(rn, |m| m.transform_vector3(rn));
        }
        true
    }

    /// The camera at time `t` (its up vector and field of view from `base`).
    #[must_use]
    pub fn camera_at(&self, base: &Camera, t: f32) -> Camera {
        let keys: Vec<(f32, (Vec3, Vec3))> = self
            .camera
            .iter()
            .map(|k| (k.time, (k.position, k.look_at)))
            .collect();
        match interpolate(&keys, t, |a, b, s| (a.0.lerp(b.0, s), a.1.lerp(b.1, s))) {
            Some((position, look_at)) => Camera {
                position,
                look_at,
                ..base.clone()
            },
            None => base.clone(),
        }
    }

    /// The lights at time `t`, from the scene's lights `base`.
    #[must_use]
    pub fn lights_at(&self, base: &[Light], t: f32) -> Vec<Light> {
        let mut out = base.to_vec();
        for (i, light) in out.iter_mut().enumerate() {
            let keys: Vec<&LightKey> = self.lights.iter().filter(|k| k.light == i).collect();
            let pos: Vec<(f32, Vec3)> = keys
                .iter()
                .filter_map(|k| k.position.map(|p| (k.time, p)))
                .collect();
            let dir: Vec<(f32, Vec3)> = keys
                .iter()
                .filter_map(|k| k.direction.map(|d| (k.time, d)))
                .collect();
            let p = interpolate(&pos, t, |a, b, s| a.lerp(b, s));
            let d = interpolate(&dir, t, |a, b, s| a.lerp(b, s).normalize_or_zero());
            match light {
                Light::Point { position, .. } => {
                    if let Some(p) = p {
                        *position = p;
                    }
                }
                Light::Spot {
                    position,
                    direction,
                    ..
                } => {
                    if let Some(p) = p {
                        *position = p;
                    }
                    if let Some(d) = d.filter(|d| *d != Vec3::ZERO) {
                        *direction = d;
                    }
                }
                Light::Directional { direction, .. } => {
                    if let Some(d) = d.filter(|d| *d != Vec3::ZERO) {
                        *direction = d;
                    }
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keyframes_interpolate_linearly_and_hold_at_the_ends() {
        let anim = Animation {
            camera: vec![
                CameraKey {
                    time: 0.0,
                    position: Vec3::ZERO,
                    look_at: Vec3::Z,
                },
                CameraKey {
                    time: 2.0,
                    position: Vec3::X * 2.0,
                    look_at: Vec3::Z,
                },
            ],
            lights: vec![
                LightKey {
                    light: 0,
                    time: 1.0,
                    position: Some(Vec3::Y),
                    direction: None,
                },
                LightKey {
                    light: 0,
                    time: 3.0,
                    position: Some(Vec3::Y * 3.0),
                    direction: None,
                },
            ],
            objects: Vec::new(),
        };
        let base = Camera {
            position: Vec3::ONE,
            look_at: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_degrees: 40.0,
        };
        assert_eq!(anim.camera_at(&base, 1.0).position, Vec3::X);
        assert_eq!(anim.camera_at(&base, -1.0).position, Vec3::ZERO);
        assert_eq!(anim.camera_at(&base, 5.0).position, Vec3::X * 2.0);
        let lights = vec![Light::Point {
            position: Vec3::ZERO,
            intensity: Vec3::ONE,
        }];
        let at = |t| match anim.lights_at(&lights, t)[0] {
            Light::Point { position, .. } => position,
            _ => unreachable!(),
        };
        assert_eq!(at(0.0), Vec3::Y);
        assert_eq!(at(2.0), Vec3::Y * 2.0);
        assert_eq!(at(9.0), Vec3::Y * 3.0);
    }

    /// Two unit squares as two objects; the second one spins and slides.
    fn two_squares() -> Mesh {
        let mut mesh = Mesh::default();
        for (i, name) in ["still", "moving"].iter().enumerate() {
            let x = i as f32 * 2.0;
            let prim = crate::mesh::Primitive {
                positions: vec![
                    Vec3::new(x, 0.0, 0.0),
                    Vec3::new(x + 1.0, 0.0, 0.0),
                    Vec3::new(x + 1.0, 0.0, 1.0),
                    Vec3::new(x, 0.0, 1.0),
                ],
                normals: vec![Vec3::Y; 4],
                uvs: Vec::new(),
                colors: Vec::new(),
                indices: vec![[0, 2, 1], [0, 3, 2]],
                material: 0,
            };
            mesh.append(&prim, Mat4::IDENTITY, name);
        }
        mesh
    }

    #[test]
    fn objects_move_rigidly_about_their_rest_centre() {
        let rest = two_squares();
        let moving = 1;
        let anim = Animation {
            objects: vec![
                ObjectKey {
                    object: moving,
                    time: 0.0,
                    translation: Vec3::ZERO,
                    rotation_degrees: Vec3::ZERO,
                },
                ObjectKey {
                    object: moving,
                    time: 2.0,
                    translation: Vec3::new(0.0, 2.0, 0.0),
                    rotation_degrees: Vec3::new(180.0, 0.0, 0.0),
                },
            ],
            ..Animation::default()
        };
        let mut posed = rest.clone();
        assert!(anim.pose_mesh(&rest, 1.0, &mut posed));
        // the still square is untouched
        assert_eq!(posed.positions[..4], rest.positions[..4]);
        // half way: up by 1, turned by 90 degrees about x through the centre (2.5, 0, 0.5)
        let centre = Vec3::new(2.5, 1.0, 0.5);
        for v in 4..8 {
            let p = posed.positions[v];
            let r = rest.positions[v];
            assert!((p.x - r.x).abs() < 1e-5, "x kept: {p} vs {r}");
            assert!((p.z - centre.z).abs() < 1e-5, "turned into the y axis: {p}");
            assert!(
                ((p.y - centre.y).abs() - 0.5).abs() < 1e-5,
                "half an edge from the centre: {p}"
            );
            assert!(
                posed.normals[v].abs_diff_eq(Vec3::Z, 1e-5),
                "{}",
                posed.normals[v]
            );
        }
        // distances between vertices are kept (rigid)
        let d = |m: &Mesh, a: usize, b: usize| m.positions[a].distance(m.positions[b]);
        for (a, b) in [(4, 5), (4, 6), (5, 7)] {
            assert!((d(&posed, a, b) - d(&rest, a, b)).abs() < 1e-5);
        }
        // no keyframe for the still object, and nothing to do without object keys
        assert!(anim.object_transform(0, Vec3::ZERO, 1.0).is_none());
        assert!(!Animation::default().pose_mesh(&rest, 1.0, &mut posed));
    }
}
