//! Emissive textures, read per triangle: glTF's `emissiveTexture` and OBJ's `map_Ke`.
//!
//! lgh's emitters are triangles of uniform radiance: the light sampling, the closed-form
//! irradiance of the direct light and the VPLs' emission all take one radiance a triangle.
//! A material's emission is its factor times its texture, so each of its triangles takes
//! the factor times the mean of the texture over the triangle's texture coordinates. A
//! triangle over black texels emits nothing and is no light at all; before this the whole
//! surface emitted the factor (often (1, 1, 1)), every unlit texel of a lamp or a screen a
//! light.
//!
//! Triangles with the same mean share a material, a copy of the file's with that emission
//! (means are cut to 15 bits of mantissa first, so that nearly equal ones meet).
//! What the camera sees of an emitter is that per-triangle mean too: the texture's detail
//! within a triangle is lost.

use std::collections::HashMap;

use glam::{Vec2, Vec3};

use crate::gltf_uv::{UvMap, wrap};
use crate::texture::{Texture, Wrap};
use crate::{Material, Scene};

/// Points per triangle at which the texture's mean is taken, at most and at least.
const MAX_POINTS: usize = 256;
const MIN_POINTS: usize = 64;
/// The bits of a mean kept before triangles share a material: 15 of the mantissa's 23
/// (a relative step of 3e-5, so that a dim mean of a strong factor keeps its light).
const MEAN_BITS: u32 = !0xff;

/// A material's emissive texture: the scene's texture, its coordinates and wrap.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EmissiveMap {
    texture: u32,
    /// The coordinate set and transform it reads.
    pub uv: UvMap,
    wrap: [Wrap; 2],
}

impl EmissiveMap {
    /// The scene's texture `texture` read at the primitive's first coordinate set as it is,
    /// with `wrap` in u and v (OBJ's `map_Ke`).
    pub fn new(texture: u32, wrap: Wrap) -> Self {
        Self {
            texture,
            uv: UvMap::IDENTITY,
            wrap: [wrap; 2],
        }
    }

    /// The emissive texture of `material`, where it has one that was decoded
    /// (`texture_of_image`: the scene's texture of each image) and the material emits.
    pub fn of(material: &gltf::Material<'_>, texture_of_image: &[Option<u32>]) -> Option<Self> {
        if material.emissive_factor().iter().all(|&c| c <= 0.0) {
            return None;
        }
        let info = material.emissive_texture()?;
        let texture = texture_of_image
            .get(info.texture().source().index())
            .copied()
            .flatten()?;
        let sampler = info.texture().sampler();
        Some(Self {
            texture,
            uv: UvMap::of(&info),
            wrap: [sampler.wrap_s(), sampler.wrap_t()].map(wrap),
        })
    }
}

/// The materials made for emissive textures: per file material and rounded mean, the
/// scene's material with that emission.
#[derive(Default)]
pub(crate) struct Emitters {
    made: HashMap<(u32, [u32; 3]), u32>,
}

impl Emitters {
    /// Per triangle of `indices` (over vertices with texture coordinates `uvs`, v up), the
    /// material of `material` with its emission times `map`'s texture's mean over the
    /// triangle. Without coordinates every triangle takes the mean of the whole texture.
    pub fn materials(
        &mut self,
        scene: &mut Scene,
        material: u32,
        map: &EmissiveMap,
        uvs: &[Vec2],
        indices: &[[u32; 3]],
    ) -> Vec<u32> {
        let Some(texture) = scene.textures.get(map.texture as usize) else {
            return vec![material; indices.len()];
        };
        let whole = || {
            mean(texture, map.wrap, [Vec2::ZERO, Vec2::X, Vec2::Y])
                .lerp(mean(texture, map.wrap, [Vec2::ONE, Vec2::Y, Vec2::X]), 0.5)
        };
        let means: Vec<Vec3> = if uvs.is_empty() {
            vec![whole(); indices.len()]
        } else {
            indices
                .iter()
                .map(|t| {
                    let corner = |i: u32| uvs.get(i as usize).copied().unwrap_or_default();
                    mean(texture, map.wrap, t.map(corner))
                })
                .collect()
        };
        means
            .into_iter()
            .map(|m| self.material_for(scene, material, m))
            .collect()
    }

    /// The material of `material` whose emission is its own times `mean` (rounded).
    fn material_for(&mut self, scene: &mut Scene, material: u32, mean: Vec3) -> u32 {
        let bits = mean
            .max(Vec3::ZERO)
            .to_array()
            .map(|c| c.to_bits() & MEAN_BITS);
        if let Some(&made) = self.made.get(&(material, bits)) {
            return made;
        }
        let Some(base) = scene.materials.get(material as usize) else {
            return material;
        };
        let made = Material {
            emission: base.emission * Vec3::from_array(bits.map(f32::from_bits)),
            ..base.clone()
        };
        scene.materials.push(made);
        let index = scene.materials.len() as u32 - 1;
        self.made.insert((material, bits), index);
        index
    }
}

/// The mean of `texture` over the triangle with texture coordinates `corners`: at the points
/// of a rank-1 lattice in the unit square folded onto the triangle (a point with s + t > 1
/// reflected to (1 - s, 1 - t)), as many as its texels, from [`MIN_POINTS`] to
/// [`MAX_POINTS`].
fn mean(texture: &Texture, wrap: [Wrap; 2], [a, b, c]: [Vec2; 3]) -> Vec3 {
    let texels =
        ((b - a).perp_dot(c - a) * 0.5).abs() * texture.width as f32 * texture.height as f32;
    let n = if texels.is_finite() {
        (texels.ceil() as usize).clamp(MIN_POINTS, MAX_POINTS)
    } else {
        MAX_POINTS
    };
    // The lattice's generator: the golden ratio's fraction.
    let g = 0.618_034_f32;
    let mut sum = Vec3::ZERO;
    for i in 0..n {
        let s = (i as f32 + 0.5) / n as f32;
        let t = (i as f32 * g + 0.5 / n as f32).fract();
        let (s, t) = if s + t > 1.0 {
            (1.0 - s, 1.0 - t)
        } else {
            (s, t)
        };
        sum += texture.sample_wrapped(a + (b - a) * s + (c - a) * t, wrap);
    }
    sum / n as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 x 2 texture, white on its left half and black on its right: a triangle over the
    /// left half emits the factor, one over the right half nothing, the lower left half of
    /// the square 0.729 of it (the integral of the bilinear ramp from u = 0.25 to 0.75
    /// against the density 2 (1 - u) of u); triangles with equal means share one material.
    #[test]
    fn each_triangle_emits_the_mean_of_its_texels() {
        let mut scene = Scene::new("t");
        let bytes = [255, 255, 255, 0, 0, 0, 255, 255, 255, 0, 0, 0];
        scene.textures = vec![Texture::from_srgb8(2, 2, 3, &bytes).unwrap()];
        scene.materials.push(Material {
            emission: Vec3::new(2.0, 4.0, 6.0),
            ..Material::default()
        });
        let map = EmissiveMap {
            texture: 0,
            uv: UvMap::IDENTITY,
            wrap: [Wrap::Clamp; 2],
        };
        // Texel centres at u = 0.25 (white) and 0.75 (black).
        let uvs = [
            Vec2::new(0.0, 0.0),
            Vec2::new(0.25, 0.0),
            Vec2::new(0.25, 1.0),
            Vec2::new(0.75, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ];
        let tris = [[0, 1, 2], [3, 4, 5], [0, 4, 6], [0, 1, 2]];
        let mut made = Emitters::default();
        let m = made.materials(&mut scene, 0, &map, &uvs, &tris);
        let emission = |k: usize| scene.materials[m[k] as usize].emission;
        assert!((emission(0) - Vec3::new(2.0, 4.0, 6.0)).abs().max_element() < 1e-3);
        assert_eq!(emission(1), Vec3::ZERO);
        let part = emission(2) / Vec3::new(2.0, 4.0, 6.0);
        assert!(
            (part - Vec3::splat(0.729)).abs().max_element() < 0.02,
            "{part}"
        );
        assert_eq!(m[0], m[3]);
        assert_eq!(scene.materials.len(), 4);
        // Without coordinates: the whole texture's mean, one half.
        let m = made.materials(&mut scene, 0, &map, &[], &tris[..1]);
        let whole = scene.materials[m[0] as usize].emission / Vec3::new(2.0, 4.0, 6.0);
        assert!(
            (whole - Vec3::splat(0.5)).abs().max_element() < 0.05,
            "{whole}"
        );
    }

    /// A glTF quad whose emissive texture is white on its left half and black on its
    /// right, with emissiveFactor (1, 1, 1): the left triangle emits, the right one is no
    /// light; the factor alone made both lights.
    #[test]
    fn a_gltf_file_emits_where_its_texture_is_lit() {
        use base64::Engine;
        let engine = base64::engine::general_purpose::STANDARD;
        let image =
            image::RgbImage::from_fn(8, 8, |x, _| image::Rgb([if x < 4 { 255 } else { 0 }; 3]));
        let mut png = Vec::new();
        image
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let f32s = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
        // Two triangles: u in [0.1, 0.4] (white) and u in [0.6, 0.9] (black), away from the
        // borders, where the repeat blends the two.
        let pos = f32s(&[
            0., 0., 0., 0.4, 0., 0., 0., 1., 0., 0.6, 0., 0., 1., 0., 0., 1., 1., 0.,
        ]);
        let uv = f32s(&[0.1, 1., 0.4, 1., 0.1, 0., 0.6, 1., 0.9, 1., 0.9, 0.]);
        let bin = [pos, uv].concat();
        let json = format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"material":0}}]}}],
"materials":[{{"emissiveFactor":[1,1,1],"emissiveTexture":{{"index":0}}}}],
"textures":[{{"source":0}}],"images":[{{"uri":"data:image/png;base64,{}"}}],
"buffers":[{{"uri":"data:application/octet-stream;base64,{}","byteLength":{}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":72}},{{"buffer":0,"byteOffset":72,"byteLength":48}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":6,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
  {{"bufferView":1,"componentType":5126,"count":6,"type":"VEC2"}}]}}"#,
            engine.encode(&png),
            engine.encode(&bin),
            bin.len()
        );
        let dir = std::env::temp_dir().join(format!("lgh-gltf-emission-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.gltf");
        std::fs::write(&path, json).unwrap();
        let scene = crate::gltf_file::load(&path).unwrap();
        let emission = |t: usize| scene.material_of(t).emission;
        assert_eq!(scene.mesh.triangles.len(), 2);
        assert!(
            (emission(0) - Vec3::ONE).abs().max_element() < 1e-3,
            "{}",
            emission(0)
        );
        assert_eq!(emission(1), Vec3::ZERO);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
