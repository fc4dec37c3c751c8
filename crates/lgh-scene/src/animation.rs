//! Motion over time: camera keyframes and moving or turning primary lights, interpolated
//! linearly between keyframes (constant before the first and after the last).
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
//! ```
//!
//! Rigidly moving objects are not supported yet (the mesh is flattened on load).

use glam::Vec3;

use crate::{Camera, Light};

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

/// The motion of a scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Animation {
    /// Camera keyframes, sorted by time.
    pub camera: Vec<CameraKey>,
    /// Light keyframes, sorted by time within each light.
    pub lights: Vec<LightKey>,
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
        self.camera.is_empty() && self.lights.is_empty()
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
}
