//! Diffuse materials with optional emission.

use glam::{Vec2, Vec3};

use crate::texture::{Texture, Wrap};

/// A Lambertian material: albedo = `albedo` x texture (if any); emitted radiance `emission`
/// (one-sided, on the front face: counter-clockwise winding, as in glTF and OBJ).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name from the file, for messages.
    pub name: String,
    /// Diffuse reflectance factor (linear RGB, each channel in [0, 1]).
    pub albedo: Vec3,
    /// Index into [`crate::Scene::textures`] of a colour texture multiplied with `albedo`.
    pub albedo_texture: Option<u32>,
    /// How `albedo_texture` reads beyond [0, 1] in u and in v (glTF's sampler of the
    /// reference, MTL's `-clamp`).
    pub albedo_wrap: [Wrap; 2],
    /// Emitted radiance (linear RGB, W / (sr m^2)); zero for non-emitters.
    pub emission: Vec3,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            albedo: Vec3::splat(0.8),
            albedo_texture: None,
            albedo_wrap: [Wrap::Repeat; 2],
            emission: Vec3::ZERO,
        }
    }
}

impl Material {
    /// True if its colour and emission are finite and not negative (a colour above one is
    /// clamped where it is used, see [`Material::albedo_at`]).
    #[must_use]
    pub fn is_valid(&self) -> bool {
        self.albedo.is_finite()
            && self.emission.is_finite()
            && self.albedo.min_element() >= 0.0
            && self.emission.min_element() >= 0.0
    }

    /// The albedo at texture coordinate `uv`, clamped to [0, 1] so that no surface creates
    /// energy.
    #[must_use]
    pub fn albedo_at(&self, textures: &[Texture], uv: Vec2) -> Vec3 {
        let t = self
            .albedo_texture
            .and_then(|i| textures.get(i as usize))
            .map_or(Vec3::ONE, |t| t.sample_wrapped(uv, self.albedo_wrap));
        (self.albedo * t).clamp(Vec3::ZERO, Vec3::ONE)
    }

    /// True if the material emits light.
    #[must_use]
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}
