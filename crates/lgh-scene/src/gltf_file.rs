//! glTF 2.0 loading (with the `gltf` crate): `.gltf` with external or embedded buffers, and
//! `.glb`.
//!
//! Read: triangle primitives of every node of the default scene with their node transforms;
//! base colour factor x base colour texture x the vertex colours `COLOR_0`; emissive factor x
//! `KHR_materials_emissive_strength` x the emissive texture's mean over each triangle
//! (`emissive_texture.rs`); `alphaMode` MASK (and BLEND with a texture's alpha) as a
//! cut-out ([`Cutout`]); the first perspective camera; `KHR_lights_punctual` point, spot
//! and directional lights (colour x intensity taken as radiant intensity or irradiance). Not
//! read: metallic-roughness, skins, morph targets (the surfaces are diffuse). Normal maps
//! (`normalTexture` on the base colour's coordinates) bend the shading normal.

use std::path::Path;

use glam::{Mat4, Vec2, Vec3};

use crate::emissive_texture::{EmissiveMap, Emitters};
use crate::error::contain_panics;
use crate::gltf_uv::{UvMap, wrap};
use crate::mesh::Primitive;
use crate::normal_map::NormalMap;
use crate::obj::file_stem;
use crate::texture::Wrap;
use crate::{Camera, Cutout, Light, Material, Scene, SceneError};
use gltf::material::AlphaMode;

/// Loads a glTF or GLB file into a scene. Call [`Scene::finish`] (or use [`crate::load`])
/// before rendering.
///
/// # Errors
/// The file or one of its buffers or images cannot be read, or it is not valid glTF.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    crate::file_kind::regular_file(path)?;
    contain_panics(path, "glTF", || load_checked(path))
}

/// The cut-out of glTF material `m` (docs/design.md, "Alpha cut-outs"): MASK cuts at its
/// `alphaCutoff` where the base colour's alpha (factor `a` x texture) is below it; BLEND
/// with a texture of varying alpha is read as a cut-out at 0.5 (leaves drawn blended); a
/// blended surface of uniform alpha (glass) stays opaque. `None` where nothing is cut.
fn cutout_of(
    m: &gltf::Material,
    texture: Option<u32>,
    wrap: [Wrap; 2],
    a: f32,
    textures: &[crate::Texture],
) -> Option<Cutout> {
    let textured = texture
        .and_then(|t| textures.get(t as usize))
        .is_some_and(crate::Texture::has_alpha);
    let cutoff = match m.alpha_mode() {
        AlphaMode::Opaque => return None,
        AlphaMode::Mask => m.alpha_cutoff().unwrap_or(0.5),
        AlphaMode::Blend if textured => 0.5,
        AlphaMode::Blend => return None,
    };
    let cutoff = if cutoff.is_finite() { cutoff } else { 0.5 };
    Cutout::new(texture, wrap, a, cutoff).needed(textures)
}

/// The normal maps of a file's materials: each image read as data ([`Texture::linear`])
/// once, in place where no material reads it as colour, else as a copy.
struct NormalMaps {
    /// The scene texture of each image (as colour), from the import.
    texture_of_image: Vec<Option<u32>>,
    /// Images some material reads as colour (base colour, emission).
    colour: std::collections::HashSet<usize>,
    /// The data texture of each image made so far.
    linear: std::collections::HashMap<usize, u32>,
    /// Materials whose normal map reads other coordinates than their base colour.
    skipped: Vec<String>,
}

impl NormalMaps {
    fn new(doc: &gltf::Document, texture_of_image: &[Option<u32>]) -> Self {
        let colour = doc
            .materials()
            .flat_map(|m| {
                let base = m.pbr_metallic_roughness().base_color_texture();
                [base, m.emissive_texture()]
                    .into_iter()
                    .flatten()
                    .map(|i| i.texture().source().index())
            })
            .collect();
        Self {
            texture_of_image: texture_of_image.to_vec(),
            colour,
            linear: std::collections::HashMap::new(),
            skipped: Vec::new(),
        }
    }

    /// The normal map of material `m`, whose primitives' coordinates are those of `uv`
    /// (its base colour's): read only where its own set is that one (its transform, which
    /// the `gltf` crate does not give for normal textures, is taken to be the base
    /// colour's).
    fn of(&mut self, m: &gltf::Material, uv: UvMap, scene: &mut Scene) -> Option<NormalMap> {
        let nt = m.normal_texture()?;
        if nt.tex_coord() != uv.set {
            self.skipped.push(m.name().unwrap_or("unnamed").to_string());
            return None;
        }
        let image = nt.texture().source().index();
        let k = (*self.texture_of_image.get(image)?)?;
        let texture = match self.linear.get(&image) {
            Some(&t) => t,
            None => {
                let data = scene.textures.get(k as usize)?.as_linear();
                let t = if self.colour.contains(&image) {
                    scene.textures.push(data);
                    scene.textures.len() as u32 - 1
                } else {
                    *scene.textures.get_mut(k as usize)? = data;
                    k
                };
                self.linear.insert(image, t);
                t
            }
        };
        let sampler = nt.texture().sampler();
        let scale = nt.scale();
        Some(NormalMap {
            texture,
            wrap: [sampler.wrap_s(), sampler.wrap_t()].map(wrap),
            scale: if scale.is_finite() { scale } else { 1.0 },
        })
    }

    /// One warning naming the materials whose normal maps were not read.
    fn warning(&self) -> Option<String> {
        let first = self.skipped.first()?;
        Some(format!(
            "{} materials ('{first}'{}) have a normal map on another coordinate set than their base colour; it is not read",
            self.skipped.len(),
            if self.skipped.len() > 1 { ", ..." } else { "" }
        ))
    }
}

/// [`load`] of a file that exists.
fn load_checked(path: &Path) -> Result<Scene, SceneError> {
    let crate::gltf_import::Import {
        document: doc,
        buffers,
        textures,
        warnings,
    } = crate::gltf_import::import(path)?;
    let mut scene = Scene::new(file_stem(path));
    scene.report.warnings.extend(warnings);

    for ext in doc.extensions_used() {
        if ext == "KHR_materials_transmission" || ext == "KHR_materials_volume" {
            scene.report.warnings.push(format!(
                "the file uses {ext} (glass); lgh renders those surfaces opaque and diffuse"
            ));
        }
    }
    let mut texture_of_image = Vec::with_capacity(textures.len());
    for t in textures {
        texture_of_image.push(t.map(|t| {
            scene.textures.push(t);
            scene.textures.len() as u32 - 1
        }));
    }
    // Per material, the texture coordinates its base colour reads, and its emissive texture.
    let mut normal_maps = NormalMaps::new(&doc, &texture_of_image);
    let mut uv_maps = Vec::with_capacity(doc.materials().len());
    // Blended materials of uniform alpha (glass): opaque here, said once below.
    let mut blended = Vec::new();
    let mut emissive_maps = Vec::with_capacity(doc.materials().len());
    for m in doc.materials() {
        emissive_maps.push(EmissiveMap::of(&m, &texture_of_image));
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, a] = pbr.base_color_factor();
        uv_maps.push(
            pbr.base_color_texture()
                .map_or(UvMap::IDENTITY, |i| UvMap::of(&i)),
        );
        let albedo_texture = pbr
            .base_color_texture()
            .and_then(|info| {
                texture_of_image
                    .get(info.texture().source().index())
                    .copied()
            })
            .flatten();
        let albedo_wrap = pbr.base_color_texture().map_or([Wrap::Repeat; 2], |info| {
            let sampler = info.texture().sampler();
            [sampler.wrap_s(), sampler.wrap_t()].map(wrap)
        });
        let strength = m.emissive_strength().unwrap_or(1.0);
        let name = m.name().unwrap_or("unnamed");
        let cutout = cutout_of(&m, albedo_texture, albedo_wrap, a, &scene.textures);
        let uv_map = uv_maps.last().copied().unwrap_or(UvMap::IDENTITY);
        let normal_map = normal_maps.of(&m, uv_map, &mut scene);
        if m.alpha_mode() == AlphaMode::Blend && cutout.is_none() && a < 1.0 {
            blended.push(name);
        }
        scene.materials.push(Material {
            name: name.to_string(),
            albedo: Vec3::new(r, g, b),
            albedo_texture,
            albedo_wrap,
            emission: Vec3::from_array(m.emissive_factor()) * strength,
            cutout,
            normal_map,
        });
    }
    scene.report.warnings.extend(normal_maps.warning());
    if let Some(first) = blended.first() {
        scene.report.warnings.push(format!(
            "{} materials ('{first}'{}) are blended with a uniform alpha below 1 (glass); lgh \
             renders them opaque",
            blended.len(),
            if blended.len() > 1 { ", ..." } else { "" }
        ));
    }
    let default_material = scene.materials.len() as u32;
    scene.materials.push(Material::default());

    let gscene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| SceneError::new(path, "the glTF file has no scene"))?;
    let mut stack: Vec<(gltf::Node, Mat4)> = gscene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    let mut skipped_modes = 0usize;
    let mut emitters = Emitters::default();
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
                let Some(indices) = triangle_list(&p, &buffers).map_err(|e| {
                    SceneError::new(
                        path,
                        format!("mesh {} primitive {}: {e}", mesh.index(), p.index()),
                    )
                })?
                else {
                    skipped_modes += 1;
                    continue;
                };
                let reader = p.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                let positions: Vec<Vec3> = match reader.read_positions() {
                    Some(it) => it.map(Vec3::from_array).collect(),
                    None => continue,
                };
                let normals = reader
                    .read_normals()
                    .map(|it| it.map(Vec3::from_array).collect())
                    .unwrap_or_default();
                let material = p.material().index().map_or(default_material, |i| i as u32);
                let map = uv_maps.get(material as usize).unwrap_or(&UvMap::IDENTITY);
                let uvs = read_uvs(&reader, map);
                // COLOR_0 (linear, RGB or RGBA; its alpha is not read).
                let colors = reader
                    .read_colors(0)
                    .map(|it| it.into_rgb_f32().map(Vec3::from_array).collect())
                    .unwrap_or_default();
                let prim = Primitive {
                    positions,
                    normals,
                    uvs,
                    colors,
                    indices,
                    material,
                };
                match emissive_maps.get(material as usize).copied().flatten() {
                    Some(e) => {
                        let uvs = read_uvs(&reader, &e.uv);
                        let of = emitters.materials(&mut scene, material, &e, &uvs, &prim.indices);
                        let material_of = |k: usize| of.get(k).copied().unwrap_or(material);
                        scene.mesh.append_with(&prim, m, &object, material_of);
                    }
                    None => scene.mesh.append(&prim, m, &object),
                }
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

/// A primitive's texture coordinates of `map`'s set, transformed, with v up (lgh's
/// textures' convention); empty where it has none.
fn read_uvs<'a, 's, F>(reader: &gltf::mesh::Reader<'a, 's, F>, map: &UvMap) -> Vec<Vec2>
where
    F: Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
{
    reader
        .read_tex_coords(map.set)
        .map(|it| {
            it.into_f32()
                .map(|uv| {
                    let [u, v] = map.apply(uv);
                    Vec2::new(u, 1.0 - v)
                })
                .collect()
        })
        .unwrap_or_default()
}

/// The version of a glTF file older than 2.0 (`"1.0"`; the GLB header's version for `.glb`),
/// from its bytes, to explain why it does not load.
pub(crate) fn old_version(bytes: &[u8]) -> Option<String> {
    if let Some(header) = bytes.strip_prefix(b"glTF") {
        let v = u32::from_le_bytes(header.get(..4)?.try_into().ok()?);
        return (v < 2).then(|| format!("{v}.0"));
    }
    let json: gltf::json::Value = gltf::json::deserialize::from_slice(bytes).ok()?;
    let v = json.get("asset").and_then(|a| a.get("version"));
    let v = match v {
        Some(gltf::json::Value::String(s)) => s.clone(),
        // glTF 1.0 files often have no asset.version, and "version" where 2.0 has lists.
        None => "1.0".to_string(),
        Some(other) => other.to_string(),
    };
    (!v.starts_with('2')).then_some(v)
}

/// The triangles of primitive `p` as index triples, after checking every accessor it reads
/// against its buffer (the `gltf` crate's reader trusts counts and offsets, and would read out
/// of bounds or allocate for a count no buffer holds): `Ok(None)` for points and lines.
/// Triangle strips and fans are unrolled to lists.
fn triangle_list(
    p: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
) -> Result<Option<Vec<[u32; 3]>>, String> {
    use gltf::mesh::{Mode, Semantic};
    let mode = p.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        return Ok(None);
    }
    let Some(position) = p.get(&Semantic::Positions) else {
        return Err("no POSITION attribute".into());
    };
    check_accessor(&position, buffers)?;
    // Every attribute lgh may read: the normals, each coordinate set (a material may read
    // any of them, `gltf_uv`, `emissive_texture`) and the first colour set.
    let read = p.attributes().filter(|(s, _)| {
        matches!(
            s,
            Semantic::Normals | Semantic::TexCoords(_) | Semantic::Colors(0)
        )
    });
    for (semantic, a) in read {
        check_accessor(&a, buffers)?;
        if a.count() != position.count() {
            return Err(format!(
                "accessor {} ({semantic:?}) has {} elements for {} vertices",
                a.index(),
                a.count(),
                position.count()
            ));
        }
    }
    let vertices = position.count();
    let flat: Vec<u32> = match p.indices() {
        Some(a) => {
            check_accessor(&a, buffers)?;
            let reader = p.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let flat: Vec<u32> = reader
                .read_indices()
                .map(|it| it.into_u32().collect())
                .unwrap_or_default();
            if let Some(&i) = flat.iter().find(|&&i| i as usize >= vertices) {
                return Err(format!(
                    "accessor {}: index {i} out of range ({vertices} vertices)",
                    a.index()
                ));
            }
            flat
        }
        None => (0..u32::try_from(vertices).map_err(|_| "too many vertices")?).collect(),
    };
    let triangles = match mode {
        Mode::TriangleStrip => (2..flat.len())
            .map(|i| {
                // Every second triangle of a strip is flipped to keep the winding.
                if i % 2 == 0 {
                    [flat[i - 2], flat[i - 1], flat[i]]
                } else {
                    [flat[i - 1], flat[i - 2], flat[i]]
                }
            })
            .collect(),
        Mode::TriangleFan => (2..flat.len())
            .map(|i| [flat[0], flat[i - 1], flat[i]])
            .collect(),
        _ => flat.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
    };
    Ok(Some(triangles))
}

/// Checks that accessor `a` lies inside its buffer view and the view inside its buffer's
/// data, so that reading it stays in bounds and its count is backed by real bytes.
fn check_accessor(a: &gltf::Accessor, buffers: &[gltf::buffer::Data]) -> Result<(), String> {
    let name = format!("accessor {}", a.index());
    if a.sparse().is_some() {
        return Err(format!("{name} is sparse (not supported)"));
    }
    let Some(view) = a.view() else {
        return Err(format!("{name} has no buffer view"));
    };
    let data = buffers.get(view.buffer().index()).map_or(0, |d| d.0.len());
    let view_end = view.offset().checked_add(view.length());
    if view_end.is_none_or(|end| end > data) {
        return Err(format!(
            "buffer view {} (bytes {}..{}) does not fit its buffer of {data} bytes",
            view.index(),
            view.offset(),
            view.offset().saturating_add(view.length())
        ));
    }
    if a.count() == 0 {
        return Ok(());
    }
    let stride = view.stride().unwrap_or(a.size()).max(a.size());
    let needed = (a.count() - 1)
        .checked_mul(stride)
        .and_then(|n| n.checked_add(a.size()))
        .and_then(|n| n.checked_add(a.offset()));
    if needed.is_none_or(|n| n > view.length()) {
        return Err(format!(
            "{name} has {} elements of {} bytes, more than its buffer view {} holds ({} bytes)",
            a.count(),
            a.size(),
            view.index(),
            view.length()
        ));
    }
    Ok(())
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
