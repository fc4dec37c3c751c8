//! # lgh-scene: what is rendered
//!
//! The scene description of lgh and the only crate that knows file formats:
//!
//! | module | what it holds |
//! | --- | --- |
//! | [`scene`] | [`Scene`]: one world-space triangle mesh, materials, textures, lights, camera |
//! | [`mesh`] | [`Mesh`]: triangles, structure-of-arrays |
//! | [`material`], [`texture`] | diffuse albedo (factor x texture), emitted radiance, alpha cut-outs |
//! | [`normal_map`] | tangent-space normal maps: the shading normal bent per hit |
//! | [`cutouts`] | [`Cutouts`]: the alpha test of every ray, per triangle, for the tracers |
//! | [`light`] | point, spot and directional lights (emissive triangles come from materials) |
//! | [`camera`] | a pinhole camera and its primary rays |
//! | [`obj`], [`gltf_file`], [`scene_file`] | loaders: Wavefront OBJ/MTL, glTF 2.0, the TOML scene file |
//! | [`cornell`] | the built-in default scene (the Cornell box as measured at Cornell) |
//!
//! [`load`] opens any supported file by its extension. Every loader returns a
//! [`SceneError`] naming the file and the problem; none panics on bad input.
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod animation;
pub mod camera;
pub mod cornell;
pub mod cutouts;
mod emissive_texture;
pub mod emitter_room;
pub mod error;
pub mod file_kind;
pub mod gltf_file;
pub mod gltf_import;
mod gltf_uv;
pub mod light;
pub mod material;
pub mod mesh;
mod mtl_map;
pub mod normal_map;
pub mod obj;
mod obj_mend;
pub mod scene;
pub mod scene_file;
#[cfg(test)]
mod test_files;
mod text;
pub mod texture;
pub mod texture_file;

pub use camera::Camera;
pub use cutouts::Cutouts;
pub use error::SceneError;
pub use light::Light;
pub use material::{Cutout, Material};
pub use mesh::Mesh;
pub use scene::MAX_COORDINATE;
pub use scene::{Scene, SceneReport};
pub use texture::Texture;

use std::path::Path;

/// Loads a scene from a file, chosen by extension: `.toml` (scene file), `.gltf`/`.glb`, `.obj`.
///
/// A mesh file loaded directly gets its own lights (emissive materials, glTF punctual lights)
/// and camera, or a default camera that frames the whole mesh and, if it has no light, a
/// point light at the camera ([`Scene::finish_mesh_file`], with a warning).
///
/// # Errors
/// A [`SceneError`] naming the file and the problem: unreadable file, parse error, unknown
/// extension, non-finite vertices, no triangles, no lights (scene files).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    file_kind::regular_file(path)?;
    if has_extension(path, &["toml"]) {
        return scene_file::load(path);
    }
    let mut scene = load_mesh_file(path)?;
    scene.finish_mesh_file(path)?;
    Ok(scene)
}

/// Loads a mesh file (`.obj`, `.gltf`, `.glb`) without finishing it (see [`Scene::finish`]),
/// so that a scene file can add lights and a camera first.
///
/// # Errors
/// The file cannot be read or parsed, or its extension is not a mesh format.
pub fn load_mesh_file(path: &Path) -> Result<Scene, SceneError> {
    if has_extension(path, &["gltf", "glb"]) {
        gltf_file::load(path)
    } else if has_extension(path, &["obj"]) {
        obj::load(path)
    } else {
        Err(SceneError::new(
            path,
            "unknown scene format (expected .toml, .gltf, .glb or .obj)",
        ))
    }
}

fn has_extension(path: &Path, exts: &[&str]) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| exts.iter().any(|x| e.eq_ignore_ascii_case(x)))
}
