//! What the GPU needs to turn a ray's hit into a surface (`shaders/surface.wgsl`, the
//! mirror of lgh-render's `World::surface`): each triangle's face normal, corner normals,
//! texture coordinates and material in the BVH's leaf order, the materials, and the
//! textures as 8-bit sRGB texels decoded through the CPU's own table, so that a texel reads
//! the same on both.

use glam::{Vec3, Vec4};
use lgh_scene::texture::{Texture, code_table, nearest_code};
use rayon::prelude::*;

use crate::context::{GpuContext, GpuError};

/// `TriShade` in `shaders/surface.wgsl` (80 bytes): face normal (w: the material's index,
/// as bits), corner normals with the texture coordinates in their w and in `uv` (w: the
/// word of its corners' vertex colours in the texel buffer as bits, 0 for white).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TriShade {
    face: Vec4,
    n0: Vec4,
    n1: Vec4,
    n2: Vec4,
    uv: Vec4,
}

/// `Material` in `shaders/surface.wgsl`: albedo factor (w: the texture's index as bits,
/// [`NO_TEXTURE`] for none), emission (w: the texture's wrap in u | in v << 2, as bits) and
/// the normal map (its texture's index as bits or [`NO_TEXTURE`], its scale, its wrap as
/// bits, 0).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuMaterial {
    albedo: Vec4,
    emission: Vec4,
    normal: Vec4,
}

/// A material without a texture (`NO_TEXTURE` in the WGSL).
pub const NO_TEXTURE: u32 = u32::MAX;
/// Words before the texture headers in the texel buffer: the sRGB decoding table.
const TABLE: usize = 256;

/// The surfaces of a scene on the GPU.
#[derive(Debug)]
pub struct GpuSurfaces {
    /// [`TriShade`] per triangle, in the BVH's leaf order.
    pub shade: wgpu::Buffer,
    /// [`GpuMaterial`] per material.
    pub materials: wgpu::Buffer,
    /// The sRGB table, the texture headers and the texels ([`texel_words`]).
    pub texels: wgpu::Buffer,
}

impl GpuSurfaces {
    /// Uploads the surfaces of `world`'s triangles, `order` being the mesh's index of each
    /// triangle in leaf order.
    ///
    /// # Errors
    /// A buffer exceeds the adapter's largest storage buffer.
    pub fn new(
        ctx: &GpuContext,
        world: &lgh_render::World,
        order: &[u32],
    ) -> Result<Self, GpuError> {
        let scene = &world.scene;
        let mut texels = texel_words(&scene.textures);
        let colors = append_colors(&mut texels, &scene.mesh, order);
        Ok(Self {
            shade: ctx.storage("triangle shading", &shade_records(world, order, &colors))?,
            materials: ctx.storage("materials", &materials(scene))?,
            texels: ctx.storage("texels", &texels)?,
        })
    }
}

impl GpuSurfaces {
    /// The first six bindings of a kernel that traces rays to surfaces (primary rays, light
    /// paths, the edge resolve): its uniform `params`, the BVH nodes, the triangles, the
    /// triangles' shading data, the materials and the texels; the kernel's own buffers
    /// follow.
    #[must_use]
    pub fn bindings<'a>(
        &'a self,
        params: wgpu::BindingResource<'a>,
        scene: &'a crate::GpuScene,
    ) -> Vec<wgpu::BindingResource<'a>> {
        vec![
            params,
            scene.nodes.as_entire_binding(),
            scene.tris.as_entire_binding(),
            self.shade.as_entire_binding(),
            self.materials.as_entire_binding(),
            self.texels.as_entire_binding(),
        ]
    }
}

/// Appends the vertex colours of each triangle in `order` to the texel words (its three
/// corners' linear RGB as float bits, 9 words) and returns each one's first word; none
/// where the mesh has no colours (`TriShade.uv.w` 0: white).
fn append_colors(words: &mut Vec<u32>, mesh: &lgh_scene::Mesh, order: &[u32]) -> Vec<u32> {
    if mesh.colors.is_empty() {
        return Vec::new();
    }
    let mut first = Vec::with_capacity(order.len());
    for &t in order {
        first.push(words.len() as u32);
        for i in mesh.triangles[t as usize] {
            let c = mesh.colors.get(i as usize).copied().unwrap_or(Vec3::ONE);
            words.extend(c.to_array().map(f32::to_bits));
        }
    }
    first
}

/// Each triangle's [`TriShade`], in `order`, with the first word of its colours
/// (`colors`, by leaf; empty: none).
fn shade_records(world: &lgh_render::World, order: &[u32], colors: &[u32]) -> Vec<TriShade> {
    let mesh = &world.scene.mesh;
    order
        .par_iter()
        .enumerate()
        .map(|(leaf, &t)| {
            let t = t as usize;
            let [i0, i1, i2] = mesh.triangles[t].map(|i| i as usize);
            let [u0, u1, u2] = [i0, i1, i2].map(|i| mesh.uvs.get(i).copied().unwrap_or_default());
            let normal = |i: usize| mesh.normals.get(i).copied().unwrap_or(Vec3::ZERO);
            let material = f32::from_bits(mesh.materials.get(t).copied().unwrap_or(0));
            TriShade {
                face: world.face_normals[t].extend(material),
                n0: normal(i0).extend(u0.x),
                n1: normal(i1).extend(u0.y),
                n2: normal(i2).extend(u1.x),
                uv: Vec4::new(
                    u1.y,
                    u2.x,
                    u2.y,
                    f32::from_bits(colors.get(leaf).copied().unwrap_or(0)),
                ),
            }
        })
        .collect()
}

/// The scene's materials as the GPU reads them; a texture index with no texture behind it
/// reads as none (as `Material::albedo_at` does).
fn materials(scene: &lgh_scene::Scene) -> Vec<GpuMaterial> {
    scene
        .materials
        .iter()
        .map(|m| {
            let k = m
                .albedo_texture
                .filter(|&k| (k as usize) < scene.textures.len())
                .unwrap_or(NO_TEXTURE);
            let wrap = lgh_scene::texture::Wrap::pair_code;
            let normal = m
                .normal_map
                .filter(|n| (n.texture as usize) < scene.textures.len())
                .map_or(Vec4::new(f32::from_bits(NO_TEXTURE), 1.0, 0.0, 0.0), |n| {
                    Vec4::new(
                        f32::from_bits(n.texture),
                        n.scale,
                        f32::from_bits(wrap(n.wrap)),
                        0.0,
                    )
                });
            GpuMaterial {
                albedo: m.albedo.extend(f32::from_bits(k)),
                emission: m.emission.extend(f32::from_bits(wrap(m.albedo_wrap))),
                normal,
            }
        })
        .collect()
}

/// The texel buffer: the sRGB table (256 words, float bits), a header per texture (first
/// texel, width, height, 1 if its texels are data (`Texture::linear`: code / 255) else 0),
/// then each texture's texels as 8-bit codes, r | g << 8 | b << 16.
#[must_use]
pub fn texel_words(textures: &[Texture]) -> Vec<u32> {
    let srgb = code_table(false);
    let mut words: Vec<u32> = srgb.iter().map(|x| x.to_bits()).collect();
    let mut first = TABLE + 4 * textures.len();
    for t in textures {
        words.extend([first as u32, t.width, t.height, u32::from(t.linear)]);
        first += t.texels.len();
    }
    for t in textures {
        let table = code_table(t.linear);
        let at = words.len();
        words.resize(at + t.texels.len(), 0);
        words[at..]
            .par_iter_mut()
            .zip(&t.texels)
            .for_each(|(w, c)| {
                let [r, g, b] = c.to_array().map(|x| u32::from(nearest_code(&table, x)));
                *w = r | g << 8 | b << 16;
            });
    }
    words
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_code_round_trips_and_other_values_take_the_nearest() {
        for linear in [false, true] {
            let table = code_table(linear);
            for (i, &x) in table.iter().enumerate() {
                assert_eq!(usize::from(nearest_code(&table, x)), i);
            }
            assert_eq!(nearest_code(&table, -1.0), 0);
            assert_eq!(nearest_code(&table, 2.0), 255);
            let between = 0.5 * (table[100] + table[101]) - 1e-6;
            assert_eq!(nearest_code(&table, between), 100);
        }
    }

    #[test]
    fn the_texel_words_hold_each_texture_after_its_header() {
        let a = Texture::from_srgb8(2, 1, 3, &[0, 10, 20, 255, 128, 1]).expect("texture");
        let b = Texture::from_srgb8(1, 1, 4, &[7, 8, 9, 0]).expect("texture");
        let w = texel_words(&[a, b]);
        assert_eq!(&w[TABLE..TABLE + 8], &[264, 2, 1, 0, 266, 1, 1, 0]);
        assert_eq!(w[264], 10 << 8 | 20 << 16);
        assert_eq!(w[265], 255 | 128 << 8 | 1 << 16);
        assert_eq!(w[266], 7 | 8 << 8 | 9 << 16);
    }
}
