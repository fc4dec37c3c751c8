//! Wavefront OBJ/MTL loading (with the `tobj` crate).
//!
//! Faces are triangulated; `Kd` is the albedo, `map_Kd` its texture (sRGB, relative to the
//! MTL file), `Ke` the emitted radiance. A missing MTL file or texture is a warning, not an
//! error: the geometry still renders with default materials.

use std::cell::RefCell;
use std::io::BufReader;
use std::path::Path;

use glam::{Mat4, Vec2, Vec3};

use crate::error::contain_panics;
use crate::mesh::Primitive;
use crate::{Material, Scene, SceneError, Texture};

/// Loads an OBJ file (and the MTL files it names) into a scene without camera or punctual
/// lights. Call [`Scene::finish`] (or use [`crate::load`]) before rendering.
///
/// # Errors
/// The file cannot be read or does not parse as OBJ.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    crate::file_kind::regular_file(path)?;
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let dir = path.parent().unwrap_or(Path::new("."));
    let file = std::fs::File::open(path)
        .map_err(|e| SceneError::new(path, format!("cannot read OBJ: {e}")))?;
    let mtl_problem = RefCell::new(None);
    let (models, materials) = contain_panics(path, "OBJ/MTL", || {
        tobj::load_obj_buf(&mut BufReader::new(file), &opts, |name| {
            load_mtl(&dir.join(name), &mtl_problem)
        })
        .map_err(|e| SceneError::new(path, format!("cannot parse OBJ: {e}")))
    })?;
    let mut scene = Scene::new(file_stem(path));
    let obj_materials = match materials {
        Ok(m) => m,
        Err(e) => {
            let why = mtl_problem.into_inner().unwrap_or_else(|| e.to_string());
            scene.report.warnings.push(format!(
                "material library not loaded ({why}); using a grey default"
            ));
            Vec::new()
        }
    };
    for m in &obj_materials {
        if let Some(illum) = m.illumination_model.filter(|i| (3..=9).contains(i)) {
            let kd = m.diffuse.unwrap_or([0.8; 3]);
            scene.report.warnings.push(format!(
                "material '{}' is a mirror or glass (illum {illum}); lgh renders diffuse \
                 surfaces only, so it shows its Kd ({} {} {})",
                m.name, kd[0], kd[1], kd[2]
            ));
        }
        let albedo_texture = m
            .diffuse_texture
            .as_deref()
            .and_then(|name| load_texture(&mut scene, &dir.join(name)));
        scene.materials.push(Material {
            name: m.name.clone(),
            albedo: m.diffuse.map_or(Vec3::splat(0.8), Vec3::from_array),
            albedo_texture,
            emission: m.emissive.map_or(Vec3::ZERO, Vec3::from_array),
        });
    }
    let default_material = scene.materials.len() as u32;
    let mut uses_default = false;
    for model in &models {
        let m = &model.mesh;
        let material = match m.material_id {
            Some(id) if id < obj_materials.len() => id as u32,
            _ => {
                uses_default = true;
                default_material
            }
        };
        let prim = Primitive {
            positions: m
                .positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .collect(),
            normals: m
                .normals
                .chunks_exact(3)
                .map(|n| Vec3::new(n[0], n[1], n[2]))
                .collect(),
            uvs: m
                .texcoords
                .chunks_exact(2)
                .map(|t| Vec2::new(t[0], t[1]))
                .collect(),
            indices: m
                .indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
            material,
        };
        scene.mesh.append(&prim, Mat4::IDENTITY, &model.name);
    }
    if uses_default {
        scene.materials.push(Material::default());
    }
    Ok(scene)
}

/// Reads an MTL file for `tobj`, first checking what its parser would panic on (a colour
/// with fewer than three numbers); the problem, named by file and line, goes to `problem`.
fn load_mtl(path: &Path, problem: &RefCell<Option<String>>) -> tobj::MTLLoadResult {
    let Ok(text) = std::fs::read_to_string(path) else {
        *problem.borrow_mut() = Some(format!("{}: cannot read", path.display()));
        return Err(tobj::LoadError::OpenFileFailed);
    };
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if let Some(key @ ("Ka" | "Kd" | "Ks" | "Ke")) = words.next()
            && words.count() < 3
        {
            *problem.borrow_mut() = Some(format!(
                "{} line {}: {key} needs three numbers",
                path.display(),
                i + 1
            ));
            return Err(tobj::LoadError::MaterialParseError);
        }
    }
    tobj::load_mtl_buf(&mut text.as_bytes())
}

/// Loads an 8-bit image file as an sRGB texture; on failure records a warning and returns
/// `None`.
pub(crate) fn load_texture(scene: &mut Scene, path: &Path) -> Option<u32> {
    match image::open(path) {
        Ok(img) => {
            let rgb = img.to_rgb8();
            let tex = Texture::from_srgb8(rgb.width(), rgb.height(), 3, rgb.as_raw())?;
            scene.textures.push(tex);
            Some(scene.textures.len() as u32 - 1)
        }
        Err(e) => {
            scene.report.warnings.push(format!(
                "texture {} not loaded ({e}); using the material colour",
                path.display()
            ));
            None
        }
    }
}

/// The file name without extension, for scene names.
pub(crate) fn file_stem(path: &Path) -> String {
    path.file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned())
}
