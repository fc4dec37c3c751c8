//! glTF 2.0 loading (with the `gltf` crate): `.gltf` with external or embedded buffers, and
//! `.glb`.
//!
//! Read: triangle primitives of every node of the default scene with their node transforms;
//! base colour factor x base colour texture; emissive factor x `KHR_materials_emissive_strength`;
//! the first perspective camera; `KHR_lights_punctual` point, spot and directional lights
//! (colour x intensity taken as radiant intensity or irradiance). Not read: metallic-roughness,
//! normal maps, skins, morph targets (the surfaces are diffuse).

use std::path::Path;

use glam::{Mat4, Vec2, Vec3};

use crate::mesh::Primitive;
use crate::obj::file_stem;
use crate::{Camera, Light, Material, Scene, SceneError, Texture};

/// Loads a glTF or GLB file into a scene. Call [`Scene::finish`] (or use [`crate::load`])
/// before rendering.
///
/// # Errors
/// The file or one of its buffers or images cannot be read, or it is not valid glTF.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    if !path.is_file() {
        return Err(SceneError::new(path, "file not found"));
    }
    contain_panics(path, || load_checked(path))
}

/// Runs `f`, turning a panic inside it (a bug of the glTF crate on a malformed file, which it
/// does not validate everywhere) into an error naming the file. The panic message is kept
/// off stderr while `f` runs, so that the user sees one line.
fn contain_panics(
    path: &Path,
    f: impl FnOnce() -> Result<Scene, SceneError>,
) -> Result<Scene, SceneError> {
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    std::panic::set_hook(hook);
    result.unwrap_or_else(|_| {
        Err(SceneError::new(
            path,
            "malformed glTF: the loader failed on it (an accessor, buffer or index out of range?)",
        ))
    })
}

/// [`load`] of a file that exists.
fn load_checked(path: &Path) -> Result<Scene, SceneError> {
    let (doc, buffers, images) =
        gltf::import(path).map_err(|e| SceneError::new(path, format!("cannot load glTF: {e}")))?;
    let mut scene = Scene::new(file_stem(path));

    let mut texture_of_image = vec![None; images.len()];
    for (i, img) in images.iter().enumerate() {
        texture_of_image[i] = convert_image(img).map(|t| {
            scene.textures.push(t);
            scene.textures.len() as u32 - 1
        });
        if texture_of_image[i].is_none() {
            scene.report.warnings.push(format!(
                "image {i} has an unsupported pixel format ({:?}); ignored",
                img.format
            ));
        }
    }
    for m in doc.materials() {
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, _] = pbr.base_color_factor();
        let albedo_texture = pbr
            .base_color_texture()
            .and_then(|info| {
                texture_of_image
                    .get(info.texture().source().index())
                    .copied()
            })
            .flatten();
        let strength = m.emissive_strength().unwrap_or(1.0);
        scene.materials.push(Material {
            name: m.name().unwrap_or("unnamed").to_string(),
            albedo: Vec3::new(r, g, b),
            albedo_texture,
            emission: Vec3::from_array(m.emissive_factor()) * strength,
        });
    }
    let default_material = scene.materials.len() as u32;
    scene.materials.push(Material::default());

    let gscene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| SceneError::new(path, "the glTF file has no scene"))?;
    let mut stack: Vec<(gltf::Node, Mat4)> = gscene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    let mut skipped_modes = 0usize;
    // glTF nodes form strict trees: a node met twice has two parents or is its own ancestor
    // (a cycle, which would never end).
    let mut seen = vec![false; doc.nodes().len()];
    while let Some((node, parent)) = stack.pop() {
        let Some(visited) = seen.get_mut(node.index()) else {
            return Err(SceneError::new(
                path,
                format!("node {} does not exist", node.index()),
            ));
        };
        if std::mem::replace(visited, true) {
            return Err(SceneError::new(
                path,
                format!(
                    "node {} has two parents or is its own ancestor (glTF nodes form trees)",
                    node.index()
                ),
            ));
        }
        let m = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            let object = node
                .name()
                .map_or_else(|| format!("node{}", node.index()), str::to_string);
            for p in mesh.primitives() {
                if p.mode() != gltf::mesh::Mode::Triangles {
                    skipped_modes += 1;
                    continue;
                }
                let reader = p.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                let positions: Vec<Vec3> = match reader.read_positions() {
                    Some(it) => it.map(Vec3::from_array).collect(),
                    None => continue,
                };
                let normals = reader
                    .read_normals()
                    .map(|it| it.map(Vec3::from_array).collect())
                    .unwrap_or_default();
                let uvs = reader
                    .read_tex_coords(0)
                    .map(|it| it.into_f32().map(|[u, v]| Vec2::new(u, 1.0 - v)).collect())
                    .unwrap_or_default();
                let flat: Vec<u32> = match reader.read_indices() {
                    Some(it) => it.into_u32().collect(),
                    None => (0..positions.len() as u32).collect(),
                };
                let material = p.material().index().map_or(default_material, |i| i as u32);
                let prim = Primitive {
                    positions,
                    normals,
                    uvs,
                    indices: flat.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
                    material,
                };
                scene.mesh.append(&prim, m, &object);
            }
        }
        if scene.camera.is_none()
            && let Some(cam) = node.camera()
            && let gltf::camera::Projection::Perspective(p) = cam.projection()
        {
            let position = m.transform_point3(Vec3::ZERO);
            let forward = m.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
            scene.camera = Some(Camera {
                position,
                look_at: position + forward,
                up: m.transform_vector3(Vec3::Y).normalize_or_zero(),
                fov_y_degrees: p.yfov().to_degrees(),
            });
        }
        if let Some(light) = node.light() {
            scene.lights.push(convert_light(&light, m));
        }
        stack.extend(node.children().map(|c| (c, m)));
    }
    if skipped_modes > 0 {
        scene.report.warnings.push(format!(
            "{skipped_modes} primitives are points or lines, not triangles; skipped"
        ));
    }
    Ok(scene)
}

/// A `KHR_lights_punctual` light placed by the node transform `m` (lights look along -z).
fn convert_light(light: &gltf::khr_lights_punctual::Light, m: Mat4) -> Light {
    use gltf::khr_lights_punctual::Kind;
    let value = Vec3::from_array(light.color()) * light.intensity();
    let position = m.transform_point3(Vec3::ZERO);
    let direction = m.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    match light.kind() {
        Kind::Point => Light::Point {
            position,
            intensity: value,
        },
        Kind::Directional => Light::Directional {
            direction,
            irradiance: value,
        },
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => Light::Spot {
            position,
            direction,
            intensity: value,
            cos_inner: inner_cone_angle.cos(),
            cos_outer: outer_cone_angle.cos(),
        },
    }
}

/// Converts a decoded glTF image (8-bit grey, RGB or RGBA, sRGB-encoded) to a linear texture.
fn convert_image(img: &gltf::image::Data) -> Option<Texture> {
    use gltf::image::Format;
    match img.format {
        Format::R8G8B8 => Texture::from_srgb8(img.width, img.height, 3, &img.pixels),
        Format::R8G8B8A8 => Texture::from_srgb8(img.width, img.height, 4, &img.pixels),
        Format::R8 => {
            let rgb: Vec<u8> = img.pixels.iter().flat_map(|&g| [g, g, g]).collect();
            Texture::from_srgb8(img.width, img.height, 3, &rgb)
        }
        Format::R8G8 => {
            let rgb: Vec<u8> = img
                .pixels
                .chunks_exact(2)
                .flat_map(|p| [p[0], p[0], p[0]])
                .collect();
            Texture::from_srgb8(img.width, img.height, 3, &rgb)
        }
        _ => None,
    }
}
