//! Primary light sources other than emissive triangles.

use glam::Vec3;

/// A punctual or distant light. Emissive triangles (area lights) are not listed here: they
/// come from materials with a non-zero emission (see [`crate::Scene::emissive_triangles`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Isotropic point light with radiant intensity `intensity` (RGB, W/sr).
    Point {
        /// Position.
        position: Vec3,
        /// Radiant intensity (RGB, W/sr).
        intensity: Vec3,
    },
    /// Spot light: a point light whose intensity falls off from `intensity` inside the inner
    /// cone to zero at the outer cone (smoothstep in cos theta).
    Spot {
        /// Position.
        position: Vec3,
        /// Unit axis of the cone.
        direction: Vec3,
        /// Radiant intensity on the axis (RGB, W/sr).
        intensity: Vec3,
        /// Cosine of the inner cone half-angle (full intensity inside).
        cos_inner: f32,
        /// Cosine of the outer cone half-angle (zero outside).
        cos_outer: f32,
    },
    /// Distant light (a sun) travelling along `direction`, with irradiance `irradiance` (RGB,
    /// W/m^2) on a surface facing it.
    Directional {
        /// Unit direction the light travels in (from the light towards the scene).
        direction: Vec3,
        /// Irradiance on a surface perpendicular to the light (RGB, W/m^2).
        irradiance: Vec3,
    },
}

impl Light {
    /// Spot-light fall-off factor for a unit direction `w` leaving the light: 1 inside the inner
    /// cone, 0 outside the outer cone, smoothstep in between. Point and directional lights
    /// return 1.
    #[must_use]
    pub fn falloff(&self, w: Vec3) -> f32 {
        match *self {
            Light::Spot {
                direction,
                cos_inner,
                cos_outer,
                ..
            } => {
                let c = direction.dot(w);
                if c <= cos_outer {
                    0.0
                } else if c >= cos_inner {
                    1.0
                } else {
                    let t = (c - cos_outer) / (cos_inner - cos_outer).max(1e-6);
                    t * t * (3.0 - 2.0 * t)
                }
            }
            _ => 1.0,
        }
    }

    /// True if the light emits something (a light of zero power adds nothing to the image).
    #[must_use]
    pub fn emits(&self) -> bool {
        match *self {
            Light::Point { intensity, .. } | Light::Spot { intensity, .. } => {
                intensity.max_element() > 0.0
            }
            Light::Directional { irradiance, .. } => irradiance.max_element() > 0.0,
        }
    }

    /// True if every number of the light is finite and its direction (if any) has length.
    #[must_use]
    pub fn is_valid(&self) -> bool {
        match *self {
            Light::Point {
                position,
                intensity,
            } => position.is_finite() && intensity.is_finite() && intensity.min_element() >= 0.0,
            Light::Spot {
                position,
                direction,
                intensity,
                cos_inner,
                cos_outer,
            } => {
                position.is_finite()
                    && direction.is_finite()
                    && direction.length() > 0.5
                    && intensity.is_finite()
                    && intensity.min_element() >= 0.0
                    && cos_inner.is_finite()
                    && cos_outer.is_finite()
            }
            Light::Directional {
                direction,
                irradiance,
            } => {
                direction.is_finite()
                    && direction.length() > 0.5
                    && irradiance.is_finite()
                    && irradiance.min_element() >= 0.0
            }
        }
    }
}
