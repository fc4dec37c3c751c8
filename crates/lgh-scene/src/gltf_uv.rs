//! The texture coordinates a glTF material's base colour reads: its `texCoord` set and its
//! `KHR_texture_transform` (offset, rotation, scale: uv' = T R S uv, the extension's
//! matrices), applied to the primitive's coordinates when it is loaded, since a
//! primitive has one material; and the wrap modes of the texture's sampler, which apply
//! where the texture is read.

use crate::texture::Wrap;

/// glTF's sampler wrap mode as lgh's [`Wrap`].
pub(crate) fn wrap(mode: gltf::texture::WrappingMode) -> Wrap {
    match mode {
        gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
        gltf::texture::WrappingMode::ClampToEdge => Wrap::Clamp,
        gltf::texture::WrappingMode::MirroredRepeat => Wrap::Mirror,
    }
}

/// The coordinate set and transform of a base-colour texture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct UvMap {
    /// `TEXCOORD_n` read.
    pub set: u32,
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
}

impl UvMap {
    /// Set 0, unchanged.
    pub const IDENTITY: Self = Self {
        set: 0,
        offset: [0.0; 2],
        rotation: 0.0,
        scale: [1.0; 2],
    };

    /// The map of a material's base-colour texture: its set (the transform's own, where
    /// it names one) and transform.
    pub fn of(info: &gltf::texture::Info<'_>) -> Self {
        match info.texture_transform() {
            Some(t) => Self {
                set: t.tex_coord().unwrap_or(info.tex_coord()),
                offset: t.offset(),
                rotation: t.rotation(),
                scale: t.scale(),
            },
            None => Self {
                set: info.tex_coord(),
                ..Self::IDENTITY
            },
        }
    }

    /// `uv` (glTF's, v down) transformed.
    pub fn apply(&self, [u, v]: [f32; 2]) -> [f32; 2] {
        if *self == Self::IDENTITY {
            return [u, v];
        }
        let (s, c) = self.rotation.sin_cos();
        let (su, sv) = (self.scale[0] * u, self.scale[1] * v);
        [
            c * su + s * sv + self.offset[0],
            -s * su + c * sv + self.offset[1],
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The extension's example: offset (0, 1), rotation pi / 2, scale (0.5, 0.5) maps
    /// (0, 0) to (0, 1), (1, 0) to (0, 0.5) and (0, 1) to (0.5, 1).
    #[test]
    fn the_transform_is_the_extensions_matrix() {
        let m = UvMap {
            set: 0,
            offset: [0.0, 1.0],
            rotation: std::f32::consts::FRAC_PI_2,
            scale: [0.5, 0.5],
        };
        for (uv, want) in [
            ([0.0, 0.0], [0.0, 1.0]),
            ([1.0, 0.0], [0.0, 0.5]),
            ([0.0, 1.0], [0.5, 1.0]),
        ] {
            let got = m.apply(uv);
            assert!(
                (got[0] - want[0]).abs() < 1e-6 && (got[1] - want[1]).abs() < 1e-6,
                "{uv:?}: {got:?} against {want:?}"
            );
        }
    }

    /// A file whose base colour reads TEXCOORD_1 through a transform (scale 2, offset 0.25
    /// in u) loads with the transformed second set (v flipped as lgh's textures read it),
    /// and with its sampler's wrap modes; its alpha mask cuts nothing, since its texture is
    /// missing and its factor's alpha is 1.
    #[test]
    fn a_file_loads_with_its_materials_set_and_transform() {
        let scene = load(&transformed_file(3)).unwrap();
        let uvs: Vec<[f32; 2]> = scene.mesh.uvs.iter().map(|t| [t.x, t.y]).collect();
        // (u, v) -> (2u + 0.25, 2v), then v -> 1 - v.
        assert_eq!(uvs, vec![[0.25, 1.0], [1.25, 1.0], [0.25, 0.0]]);
        // The sampler's CLAMP_TO_EDGE in u and MIRRORED_REPEAT in v.
        assert_eq!(scene.materials[0].albedo_wrap, [Wrap::Clamp, Wrap::Mirror]);
        assert_eq!(scene.materials[0].cutout, None);
    }

    /// The second coordinate set shorter than the positions is refused with one line
    /// naming it (only the first set was checked, and a material may read any).
    #[test]
    fn a_short_second_coordinate_set_is_refused() {
        let e = load(&transformed_file(2)).unwrap_err().to_string();
        assert!(
            e.contains("TexCoords(1)") && e.contains("2 elements"),
            "{e}"
        );
    }

    /// The gltf_file loader's result for `json`, written to a file of its own.
    fn load(json: &str) -> Result<crate::Scene, crate::SceneError> {
        use std::sync::atomic::{AtomicU32, Ordering};
        static N: AtomicU32 = AtomicU32::new(0);
        let k = N.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("lgh-gltf-uv-{}-{k}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.gltf");
        std::fs::write(&path, json).unwrap();
        let scene = crate::gltf_file::load(&path);
        let _ = std::fs::remove_dir_all(&dir);
        scene
    }

    /// A triangle whose base colour reads TEXCOORD_1 (`count1` elements) through a
    /// transform, with a sampler and an alpha mask.
    fn transformed_file(count1: usize) -> String {
        let f32s = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
        let pos = f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        let uv0 = f32s(&[0.0; 6]);
        let uv1 = f32s(&[0.0, 0.0, 0.5, 0.0, 0.0, 0.5]);
        let bin = [pos, uv0, uv1].concat();
        use base64::Engine;
        let data = base64::engine::general_purpose::STANDARD.encode(&bin);
        format!(
            r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_texture_transform"],
"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1,"TEXCOORD_1":2}},"material":0}}]}}],
"materials":[{{"alphaMode":"MASK","pbrMetallicRoughness":{{"baseColorTexture":{{"index":0,"texCoord":1,
  "extensions":{{"KHR_texture_transform":{{"offset":[0.25,0],"scale":[2,2]}}}}}}}}}}],
"textures":[{{"source":0,"sampler":0}}],"images":[{{"uri":"missing.png"}}],
"samplers":[{{"wrapS":33071,"wrapT":33648}}],
"buffers":[{{"uri":"data:application/octet-stream;base64,{data}","byteLength":{}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}},
  {{"buffer":0,"byteOffset":60,"byteLength":24}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
  {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}},
  {{"bufferView":2,"componentType":5126,"count":{count1},"type":"VEC2"}}]}}"#,
            bin.len()
        )
    }
}
