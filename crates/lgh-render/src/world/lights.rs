//! The primary lights of a scene and how they are sampled: by power to start light paths
//! (VPL generation), by emitted power per area for direct lighting from area lights.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};
use lgh_core::color::luminance;
use lgh_core::qmc::Sampler;
use lgh_core::sampling::{
    Distribution1D, concentric_disk, cosine_hemisphere, orthonormal_basis, uniform_cone,
    uniform_sphere, uniform_triangle,
};
use lgh_scene::{Light, Scene};

/// An emissive triangle (area light), one-sided along its counter-clockwise normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emitter {
    /// Triangle index in the mesh.
    pub triangle: u32,
    /// First vertex.
    pub v0: Vec3,
    /// Edge v1 - v0.
    pub e1: Vec3,
    /// Edge v2 - v0.
    pub e2: Vec3,
    /// Unit front normal.
    pub normal: Vec3,
    /// Area.
    pub area: f32,
    /// Emitted radiance (RGB).
    pub radiance: Vec3,
}

impl Emitter {
    /// The three vertices, counter-clockwise from the front.
    #[must_use]
    pub fn vertices(&self) -> [Vec3; 3] {
        [self.v0, self.v0 + self.e1, self.v0 + self.e2]
    }
}

/// A point sampled on an area light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterSample {
    /// The point.
    pub position: Vec3,
    /// The emitter's unit front normal.
    pub normal: Vec3,
    /// Emitted radiance.
    pub radiance: Vec3,
    /// Probability density of the point, per unit area (over all emitters).
    pub pdf_area: f32,
}

/// A ray leaving a light, for light tracing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmittedRay {
    /// Start of the ray.
    pub origin: Vec3,
    /// Unit direction.
    pub dir: Vec3,
    /// Flux the ray carries (RGB, W): emitted radiance or intensity divided by the densities of
    /// the choices made (light, point, direction).
    pub flux: Vec3,
}

/// All primary lights of a scene with their sampling tables.
#[derive(Clone, Debug)]
pub struct LightSet {
    /// Point, spot and directional lights.
    pub punctual: Vec<Light>,
    /// Emissive triangles.
    pub emitters: Vec<Emitter>,
    by_radiant_area: Option<Distribution1D>,
    by_power: Option<Distribution1D>,
    /// The punctual lights alone by power: the direct pass samples them where there are
    /// more than [`crate::direct::EXACT_PUNCTUAL`].
    pub punctual_by_power: Option<Distribution1D>,
    centre: Vec3,
    radius: f32,
}

impl LightSet {
    /// Collects the lights of `scene`; `radius` is the scene's bounding-sphere radius (the
    /// disk that directional lights shine through).
    #[must_use]
    pub fn new(scene: &Scene, radius: f32) -> Self {
        let (centre, _) = scene.bounding_sphere();
        let emitters: Vec<Emitter> = scene
            .emissive_triangles()
            .into_iter()
            .map(|t| {
                let [a, b, c] = scene.mesh.vertices(t as usize);
                let cross = (b - a).cross(c - a);
                Emitter {
                    triangle: t,
                    v0: a,
                    e1: b - a,
                    e2: c - a,
                    normal: cross.normalize_or_zero(),
                    area: 0.5 * cross.length(),
                    radiance: scene.material_of(t as usize).emission,
                }
            })
            .collect();
        let radiant_area: Vec<f32> = emitters
            .iter()
            .map(|e| e.area * luminance(e.radiance))
            .collect();
        let mut set = Self {
            punctual: scene.lights.clone(),
            emitters,
            by_radiant_area: Distribution1D::new(&radiant_area),
            by_power: None,
            punctual_by_power: None,
            centre,
            radius,
        };
        let powers: Vec<f32> = (0..set.len()).map(|i| luminance(set.power(i))).collect();
        set.by_power = Distribution1D::new(&powers);
        set.punctual_by_power = Distribution1D::new(&powers[..set.punctual.len()]);
        set
    }

    /// Number of lights: punctual lights first, then emitters.
    #[must_use]
    pub fn len(&self) -> usize {
        self.punctual.len() + self.emitters.len()
    }

    /// True if there is no light.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// True if no light emits anything (every power is zero), so no light path can start.
    #[must_use]
    pub fn emits_nothing(&self) -> bool {
        self.by_power.is_none()
    }

    /// Emitted power (RGB, W) of light `i` (directional lights: through the scene's disk).
    #[must_use]
    pub fn power(&self, i: usize) -> Vec3 {
        match self.punctual.get(i) {
            Some(Light::Point { intensity, .. }) => *intensity * (4.0 * PI),
            Some(Light::Spot {
                intensity,
                cos_inner,
                cos_outer,
                ..
            }) => *intensity * (2.0 * PI * (1.0 - 0.5 * (cos_inner + cos_outer))),
            Some(Light::Directional { irradiance, .. }) => {
                *irradiance * (PI * self.radius * self.radius)
            }
            None => {
                let e = &self.emitters[i - self.punctual.len()];
                e.radiance * (PI * e.area)
            }
        }
    }

    /// The lights' distribution by power ([`LightSet::sample_emission`]'s choice, over
    /// the punctual lights then the emitters), `None` if nothing emits; for backends that
    /// start light paths elsewhere.
    #[must_use]
    pub fn power_distribution(&self) -> Option<&Distribution1D> {
        self.by_power.as_ref()
    }

    /// The emitters' distribution by radiance x area ([`LightSet::sample_emitter`]'s
    /// first choice), `None` without emitters; for backends that sample them elsewhere.
    #[must_use]
    pub fn emitter_distribution(&self) -> Option<&Distribution1D> {
        self.by_radiant_area.as_ref()
    }

    /// Total emitted power of all lights.
    #[must_use]
    pub fn total_power(&self) -> Vec3 {
        (0..self.len()).map(|i| self.power(i)).sum()
    }

    /// A point on an area light: an emitter in proportion to radiance x area, then a point
    /// uniformly on it, for numbers `u` (a 2D point of a low-discrepancy set, or two random
    /// numbers). The emitter is picked with `u.x`, whose remainder inside the
    /// picked emitter's interval is the first coordinate of the point on it, so that the
    /// strata of `u` are kept on the emitters. Also returns the emitter's index.
    #[must_use]
    pub fn sample_emitter(&self, u: Vec2) -> Option<(usize, EmitterSample)> {
        let dist = self.by_radiant_area.as_ref()?;
        let (i, p, u_x) = dist.sample_remapped(u.x);
        let e = &self.emitters[i];
        let b = uniform_triangle(Vec2::new(u_x, u.y));
        Some((
            i,
            EmitterSample {
                position: e.v0 + e.e1 * b.x + e.e2 * b.y,
                normal: e.normal,
                radiance: e.radiance,
                pdf_area: p / e.area,
            },
        ))
    }

    /// Starts a light path: picks a light in proportion to its power, then a point and a
    /// direction on it. `None` if the scene emits nothing.
    ///
    /// The numbers are drawn in a fixed order, so that with a [`lgh_core::qmc::PathSampler`]
    /// the two 2D choices that place a path (the point on an area light or a punctual light's
    /// direction, then an area light's direction) fill one stratified 4D group; the light is
    /// picked with the first number, whose remainder inside the picked light's interval then
    /// serves as the first coordinate of the point, so the choice does not break the strata.
    #[must_use]
    pub fn sample_emission(&self, rng: &mut impl Sampler) -> Option<EmittedRay> {
        let dist = self.by_power.as_ref()?;
        let u = rng.next_2d();
        let u_dir = rng.next_2d();
        let (i, p_light, u_x) = dist.sample_remapped(u.x);
        let u = Vec2::new(u_x, u.y);
        let ray = match self.punctual.get(i) {
            Some(Light::Point {
                position,
                intensity,
            }) => EmittedRay {
                origin: *position,
                dir: uniform_sphere(u),
                flux: *intensity * (4.0 * PI),
            },
            Some(
                l @ Light::Spot {
                    position,
                    direction,
                    intensity,
                    cos_outer,
                    ..
                },
            ) => {
                let dir = uniform_cone(*direction, *cos_outer, u);
                EmittedRay {
                    origin: *position,
                    dir,
                    flux: *intensity * (l.falloff(dir) * 2.0 * PI * (1.0 - cos_outer)),
                }
            }
            Some(Light::Directional {
                direction,
                irradiance,
            }) => {
                let (t, b) = orthonormal_basis(*direction);
                let d = concentric_disk(u) * self.radius;
                EmittedRay {
                    origin: self.centre - *direction * (2.0 * self.radius) + t * d.x + b * d.y,
                    dir: *direction,
                    flux: *irradiance * (PI * self.radius * self.radius),
                }
            }
            None => {
                let e = &self.emitters[i - self.punctual.len()];
                let b = uniform_triangle(u);
                let p = e.v0 + e.e1 * b.x + e.e2 * b.y;
                EmittedRay {
                    origin: p + e.normal * (1e-4 * self.radius),
                    dir: cosine_hemisphere(e.normal, u_dir),
                    flux: e.radiance * (PI * e.area),
                }
            }
        };
        Some(EmittedRay {
            flux: ray.flux / p_light,
            ..ray
        })
    }
}
