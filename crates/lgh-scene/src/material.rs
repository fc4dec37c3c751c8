//! Diffuse materials with optional emission and alpha cut-outs.

use glam::{Vec2, Vec3};

pub use crate::normal_map::NormalMap;
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
    /// Where the surface is not there at all (leaves, fences), if anywhere.
    pub cutout: Option<Cutout>,
    /// A tangent-space normal map that bends the shading normal, if any.
    pub normal_map: Option<NormalMap>,
}

/// An alpha cut-out: the surface exists where alpha = `factor` x the texture's alpha (1
/// without a texture) is at least `cutoff`, and every ray passes through it elsewhere (glTF
/// `alphaMode` MASK with its `alphaCutoff`; BLEND and OBJ's `map_d` at 0.5;
/// docs/design.md, "Alpha cut-outs").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cutout {
    /// Index into [`crate::Scene::textures`] of the texture whose alpha is read
    /// ([`Texture::alpha_at`]), if any.
    pub texture: Option<u32>,
    /// How the texture reads beyond [0, 1].
    pub wrap: [Wrap; 2],
    /// The texture's coordinates from the mesh's (those of the albedo texture):
    /// uv x `scale` + `offset` (an OBJ `map_d` with other `-s`/`-o` than its `map_Kd`).
    pub scale: Vec2,
    /// See `scale`.
    pub offset: Vec2,
    /// The constant factor of alpha.
    pub factor: f32,
    /// The least alpha that is surface.
    pub cutoff: f32,
}

impl Cutout {
    /// A cut-out reading `texture` (if any) at the mesh's coordinates with `wrap`.
    #[must_use]
    pub fn new(texture: Option<u32>, wrap: [Wrap; 2], factor: f32, cutoff: f32) -> Self {
        Self {
            texture,
            wrap,
            scale: Vec2::ONE,
            offset: Vec2::ZERO,
            factor,
            cutoff,
        }
    }

    /// The alpha at the mesh's texture coordinate `uv`.
    #[must_use]
    pub fn alpha(&self, textures: &[Texture], uv: Vec2) -> f32 {
        let a = self
            .texture
            .and_then(|i| textures.get(i as usize))
            .map_or(1.0, |t| {
                t.alpha_at(uv * self.scale + self.offset, self.wrap)
            });
        self.factor * a
    }

    /// True if the surface is there at the mesh's texture coordinate `uv`.
    #[must_use]
    pub fn covers(&self, textures: &[Texture], uv: Vec2) -> bool {
        self.alpha(textures, uv) >= self.cutoff
    }

    /// The cut-out, or `None` where it never cuts: alpha is never below `cutoff` (no texture
    /// or one without alpha, and a factor at or above the cutoff).
    #[must_use]
    pub fn needed(self, textures: &[Texture]) -> Option<Self> {
        let masked = self
            .texture
            .and_then(|i| textures.get(i as usize))
            .is_some_and(Texture::has_alpha);
        (masked || self.factor < self.cutoff).then_some(self)
    }
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            albedo: Vec3::splat(0.8),
            albedo_texture: None,
            albedo_wrap: [Wrap::Repeat; 2],
            emission: Vec3::ZERO,
            cutout: None,
            normal_map: None,
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
