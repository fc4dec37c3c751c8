//! Wavefront OBJ/MTL loading (with the `tobj` crate).
//!
//! Faces are triangulated; `Kd` is the albedo, `map_Kd` its texture (sRGB, relative to the
//! MTL file; its options `-clamp`, `-o` and `-s` are read: `mtl_map.rs`), `Ke` the
//! emitted radiance, times `map_Ke`'s mean over each triangle (`emissive_texture.rs`),
//! `map_d` (its alpha, else its grey level, times `d`) a cut-out at 0.5 ([`Cutout`]);
//! vertex colours (`v x y z r g b`, sRGB) multiply the albedo. A missing MTL file or texture is a warning, not an error: the geometry still renders with
//! default materials. What old exporters wrote and the parser does not read is mended, with
//! a warning: files in ISO-8859-1 or UTF-16 (decoded first), Windows path separators,
//! colours of one number, materials and `usemtl` without a name.

use std::cell::RefCell;
use std::collections::HashMap;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use glam::{Mat4, Vec2, Vec3};

use crate::emissive_texture::{EmissiveMap, Emitters};
use crate::error::contain_panics;
use crate::mesh::Primitive;
use crate::mtl_map;
use crate::text;
use crate::texture::{Wrap, srgb_to_linear};
use crate::texture_file::{TexelBudget, TextureError};
use crate::{Cutout, Material, Scene, SceneError, Texture};

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
    let warnings = RefCell::new(Vec::new());
    let parse = |mut reader: &mut dyn std::io::BufRead| {
        contain_panics(path, "OBJ/MTL", || {
            tobj::load_obj_buf(&mut reader, &opts, |name| {
                load_mtl(&beside(dir, name), &mtl_problem, &warnings)
            })
            .map_err(|e| SceneError::new(path, format!("cannot parse OBJ: {e}")))
        })
    };
    // UTF-8 streams through the parser; a file it cannot read is read again, mended where
    // it can be (decoded from another encoding, `usemtl` without a name), and parsed again.
    let parsed = match parse(&mut BufReader::new(file)) {
        Err(first) => match crate::obj_mend::mended(path)? {
            Some((text, notes)) => {
                // What the first pass found of its material libraries, found again.
                *mtl_problem.borrow_mut() = None;
                *warnings.borrow_mut() = notes;
                parse(&mut text.as_bytes())
            }
            None => Err(first),
        },
        parsed => parsed,
    };
    let (models, materials) = parsed?;
    let mut scene = Scene::new(file_stem(path));
    scene.report.warnings.append(&mut warnings.into_inner());
    let obj_materials = match (materials, mtl_problem.into_inner()) {
        (Ok(m), _) => m,
        (Err(_), Some(MtlProblem(why))) => return Err(SceneError::new(path, why)),
        (Err(tobj::LoadError::OpenFileFailed), None) => {
            scene
                .report
                .warnings
                .push("material library not found; using a grey default".to_string());
            Vec::new()
        }
        (Err(e), None) => {
            return Err(SceneError::new(
                path,
                format!("its material library does not parse: {e}"),
            ));
        }
    };
    let mut files = TextureFiles::default();
    // Per material, the options of its `map_Kd` that move the texture coordinates.
    let mut maps = Vec::with_capacity(obj_materials.len());
    // Per material, its emissive texture and the options of its `map_Ke`.
    let mut emissive_maps = Vec::with_capacity(obj_materials.len());
    let mut emitters = Emitters::default();
    // Transparent surfaces (`d` below 1 without `map_d`: glass) are opaque here: say so, once.
    let see_through: Vec<&str> = obj_materials
        .iter()
        .filter(|m| m.dissolve_texture.is_none() && m.dissolve.is_some_and(|d| d < 1.0))
        .map(|m| m.name.as_str())
        .collect();
    if let Some(first) = see_through.first() {
        scene.report.warnings.push(format!(
            "{} materials ('{first}'{}) are transparent (d < 1, glass); lgh renders them opaque",
            see_through.len(),
            if see_through.len() > 1 { ", ..." } else { "" }
        ));
    }
    for m in &obj_materials {
        if let Some(illum) = m.illumination_model.filter(|i| (3..=9).contains(i)) {
            let kd = m.diffuse.unwrap_or([0.8; 3]);
            scene.report.warnings.push(format!(
                "material '{}' is a mirror or glass (illum {illum}); lgh renders diffuse \
                 surfaces only, so it shows its Kd ({} {} {})",
                m.name, kd[0], kd[1], kd[2]
            ));
        }
        let map = m.diffuse_texture.as_deref().map(mtl_map::parse);
        let albedo_texture = match &map {
            Some(map) if !map.file.is_empty() => {
                files.colour(&mut scene, &beside(dir, map.file))?
            }
            _ => None,
        };
        let emission = m.emissive.map_or(Vec3::ZERO, Vec3::from_array);
        // `map_Ke` (an extension of the format that exporters write), where it emits.
        let emissive = match m.unknown_param.get("map_Ke").map(|s| mtl_map::parse(s)) {
            Some(map) if !map.file.is_empty() && emission.max_element() > 0.0 => {
                let path = beside(dir, map.file);
                files
                    .colour(&mut scene, &path)?
                    .map(|t| (EmissiveMap::new(t, map.wrap), map))
            }
            _ => None,
        };
        let cutout = match m.dissolve_texture.as_deref().map(mtl_map::parse) {
            Some(d) if !d.file.is_empty() => files
                .mask(&mut scene, &beside(dir, d.file))?
                .and_then(|t| map_d_cutout(t, &d, map.as_ref(), m.dissolve, &scene)),
            _ => None,
        };
        scene.materials.push(Material {
            name: m.name.clone(),
            albedo: m.diffuse.map_or(Vec3::splat(0.8), Vec3::from_array),
            albedo_texture,
            albedo_wrap: [map.as_ref().map_or(Wrap::Repeat, |m| m.wrap); 2],
            emission,
            cutout,
            normal_map: None,
        });
        maps.push(map.filter(|m| !m.keeps_coordinates()));
        emissive_maps.push(emissive);
    }
    // The default material for faces without one, before the emitters' materials that
    // the faces below may add.
    let default_material = scene.materials.len() as u32;
    let has_material = |id: Option<usize>| id.is_some_and(|id| id < obj_materials.len());
    if models
        .iter()
        .any(|model| !has_material(model.mesh.material_id))
    {
        scene.materials.push(Material::default());
    }
    for model in &models {
        let m = &model.mesh;
        let material = match m.material_id {
            Some(id) if has_material(Some(id)) => id as u32,
            _ => default_material,
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
            // `v x y z r g b`: sRGB-encoded, as Blender's and three.js's importers read it.
            colors: m
                .vertex_color
                .chunks_exact(3)
                .map(|c| Vec3::new(c[0], c[1], c[2]).map(|x| srgb_to_linear(x.clamp(0.0, 1.0))))
                .collect(),
            uvs: {
                let map = maps.get(material as usize).and_then(Option::as_ref);
                m.texcoords
                    .chunks_exact(2)
                    .map(|t| {
                        let uv = Vec2::new(t[0], t[1]);
                        map.map_or(uv, |map| map.apply(uv))
                    })
                    .collect()
            },
            indices: m
                .indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
            material,
        };
        match emissive_maps
            .get(material as usize)
            .and_then(Option::as_ref)
        {
            Some((e, map)) => {
                let uvs: Vec<Vec2> = m
                    .texcoords
                    .chunks_exact(2)
                    .map(|t| map.apply(Vec2::new(t[0], t[1])))
                    .collect();
                let of = emitters.materials(&mut scene, material, e, &uvs, &prim.indices);
                let material_of = |k: usize| of.get(k).copied().unwrap_or(material);
                scene
                    .mesh
                    .append_with(&prim, Mat4::IDENTITY, &model.name, material_of);
            }
            None => scene.mesh.append(&prim, Mat4::IDENTITY, &model.name),
        }
    }
    Ok(scene)
}

/// A material library that exists but cannot be used: an error, where a missing library is
/// a warning (its emitters, the scene's lights, would otherwise vanish behind "no lights").
struct MtlProblem(String);

/// Reads an MTL file for `tobj` (decoded from UTF-16 or ISO-8859-1 where it is not UTF-8,
/// with a warning into `warnings`), first mending what its parser does not read (a colour
/// of one number, the format's grey; a material without a name) and checking what it
/// would panic on (a colour of two numbers or none); the problem, named by file and line,
/// goes to `problem`.
fn load_mtl(
    path: &Path,
    problem: &RefCell<Option<MtlProblem>>,
    warnings: &RefCell<Vec<String>>,
) -> tobj::MTLLoadResult {
    if !path.exists() {
        return Err(tobj::LoadError::OpenFileFailed); // a warning: the geometry still renders
    }
    let text = crate::file_kind::read_capped(path, crate::file_kind::MAX_TEXT_BYTES, "MTL file")
        .and_then(|b| text::decode(b).map_err(|e| SceneError::new(path, e)));
    let text = match text {
        Ok((t, encoding)) => {
            let what = format!("material library {}", path.display());
            warnings.borrow_mut().extend(encoding.warning(&what));
            t
        }
        Err(e) => {
            *problem.borrow_mut() = Some(MtlProblem(e.to_string()));
            return Err(tobj::LoadError::OpenFileFailed);
        }
    };
    // A material without a name (Blender writes `newmtl` alone for a slot without one)
    // gets one that no `usemtl` names: its faces take the default material, as `usemtl`
    // alone gives them.
    let mut named = String::with_capacity(text.len());
    for (i, line) in text.lines().enumerate() {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            // A colour of one number is grey (the MTL format's rule), which the parser
            // does not know.
            [key @ ("Ka" | "Kd" | "Ks" | "Ke"), v] => {
                named.push_str(&format!("{key} {v} {v} {v}\n"));
                continue;
            }
            [key @ ("Ka" | "Kd" | "Ks" | "Ke")] | [key @ ("Ka" | "Kd" | "Ks" | "Ke"), _, _] => {
                *problem.borrow_mut() = Some(MtlProblem(format!(
                    "{} line {}: {key} needs one or three numbers",
                    path.display(),
                    i + 1
                )));
                return Err(tobj::LoadError::MaterialParseError);
            }
            ["newmtl"] => {
                warnings.borrow_mut().push(format!(
                    "material library {} line {}: a material without a name, which no face can use",
                    path.display(),
                    i + 1
                ));
                named.push_str(&format!("newmtl (no name, line {})\n", i + 1));
                continue;
            }
            _ => {}
        }
        named.push_str(line);
        named.push('\n');
    }
    tobj::load_mtl_buf(&mut named.as_bytes())
}

/// The file `name` that an OBJ or MTL file in `dir` refers to. Files written on Windows
/// separate folders with backslashes (`.\textures\wood.jpg`): where no file has the name
/// as written and the platform's separator is not a backslash, they are read as separators.
fn beside(dir: &Path, name: impl AsRef<Path>) -> PathBuf {
    let path = dir.join(&name);
    match name.as_ref().to_str() {
        Some(n) if std::path::MAIN_SEPARATOR != '\\' && n.contains('\\') && !path.exists() => {
            dir.join(n.replace('\\', "/"))
        }
        _ => path,
    }
}

/// The texture files an OBJ's materials read, each decoded once as a colour texture and
/// once as a cut-out's mask, within one budget.
#[derive(Debug, Default)]
struct TextureFiles {
    budget: TexelBudget,
    colour: HashMap<PathBuf, u32>,
    mask: HashMap<PathBuf, u32>,
}

impl TextureFiles {
    /// The colour texture at `path` (`map_Kd`, `map_Ke`), added to `scene`; `None` with a
    /// warning if it cannot be read; an error if it is over the budget.
    fn colour(&mut self, scene: &mut Scene, path: &Path) -> Result<Option<u32>, SceneError> {
        let decode = TexelBudget::decode_file;
        let without = "using the material colour";
        load_texture(
            scene,
            &mut self.budget,
            &mut self.colour,
            path,
            decode,
            without,
        )
    }

    /// The mask at `path` (`map_d`): the colour texture of that file where it has alpha,
    /// else the file read as a mask ([`TexelBudget::decode_mask_file`]).
    fn mask(&mut self, scene: &mut Scene, path: &Path) -> Result<Option<u32>, SceneError> {
        if let Some(&i) = self.colour.get(path)
            && scene
                .textures
                .get(i as usize)
                .is_some_and(Texture::has_alpha)
        {
            return Ok(Some(i));
        }
        let decode = TexelBudget::decode_mask_file;
        let without = "the surface has no cut-out";
        load_texture(
            scene,
            &mut self.budget,
            &mut self.mask,
            path,
            decode,
            without,
        )
    }
}

/// The texture at `path`, decoded by `decode` the first time (`loaded` remembers it) and
/// added to `scene`; if it cannot be read, a warning that says what happens `without` it.
fn load_texture(
    scene: &mut Scene,
    budget: &mut TexelBudget,
    loaded: &mut HashMap<PathBuf, u32>,
    path: &Path,
    decode: fn(&mut TexelBudget, &Path) -> Result<Texture, TextureError>,
    without: &str,
) -> Result<Option<u32>, SceneError> {
    if let Some(&i) = loaded.get(path) {
        return Ok(Some(i));
    }
    match decode(budget, path) {
        Ok(tex) => {
            scene.textures.push(tex);
            let i = scene.textures.len() as u32 - 1;
            loaded.insert(path.to_path_buf(), i);
            Ok(Some(i))
        }
        Err(TextureError::OverBudget(e)) => Err(SceneError::new(path, e)),
        Err(e) => {
            scene.report.warnings.push(format!(
                "texture {} not loaded ({e}); {without}",
                path.display()
            ));
            Ok(None)
        }
    }
}

/// The cut-out of a material whose `map_d` statement `d` loaded as `texture`: alpha = `d`
/// (the material's dissolve, default 1) x the mask, cut at 0.5, read at `map_d`'s own
/// coordinates, which the mesh holds as `map_Kd`'s (`kd`) maps them. `None` where it cuts
/// nothing; `map_Kd`'s mapping is undone only where its scale has no zero.
fn map_d_cutout(
    texture: u32,
    d: &mtl_map::TextureMap,
    kd: Option<&mtl_map::TextureMap>,
    dissolve: Option<f32>,
    scene: &Scene,
) -> Option<Cutout> {
    let factor = dissolve.filter(|d| d.is_finite()).unwrap_or(1.0);
    let mut cut = Cutout::new(Some(texture), [d.wrap; 2], factor, 0.5);
    // mesh uv = raw x s_k + o_k, so map_d's raw x s_d + o_d = uv x s + o.
    let (s_k, o_k) = kd.map_or((Vec2::ONE, Vec2::ZERO), |k| (k.scale, k.offset));
    if s_k.x != 0.0 && s_k.y != 0.0 {
        cut.scale = d.scale / s_k;
        cut.offset = d.offset - cut.scale * o_k;
    }
    cut.needed(&scene.textures)
}

/// The file name without extension, for scene names.
pub(crate) fn file_stem(path: &Path) -> String {
    path.file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("lgh-obj-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    const QUAD: &str = "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";

    /// Eight materials naming one texture decode it once (each decoded its own copy: 8 KB
    /// of PNG naming 6.5 GB).
    #[test]
    fn a_texture_named_by_many_materials_is_decoded_once() {
        let d = dir("shared-texture");
        image::RgbImage::new(4, 4).save(d.join("t.png")).unwrap();
        let mut mtl = String::new();
        let mut obj = format!("mtllib m.mtl\n{QUAD}");
        for i in 0..8 {
            mtl += &format!("newmtl m{i}\nKd 1 1 1\nmap_Kd t.png\n");
            obj += &format!("usemtl m{i}\nf 1/1 3/3 2/2\n");
        }
        std::fs::write(d.join("m.mtl"), mtl).unwrap();
        std::fs::write(d.join("s.obj"), obj).unwrap();
        let scene = load(&d.join("s.obj")).unwrap();
        assert_eq!(scene.textures.len(), 1);
        assert!(
            scene
                .materials
                .iter()
                .take(8)
                .all(|m| m.albedo_texture == Some(0))
        );
        let _ = std::fs::remove_dir_all(&d);
    }

    /// `map_Kd -clamp on -s 2 3 -o 0.5 0 t.png` loads t.png, clamped, and moves the
    /// coordinates of that material's faces (uv * s + o) and of no other's; its `map_d` of
    /// the same (black, opaque) file is a second texture, read as a grey mask at its own
    /// coordinates, which undo map_Kd's.
    #[test]
    fn texture_options_are_read_before_the_file_name() {
        let d = dir("map-options");
        image::RgbImage::new(4, 4).save(d.join("t.png")).unwrap();
        let mtl = "newmtl a\nmap_Kd -clamp on -s 2 3 -o 0.5 0 t.png\nmap_d t.png\n\
                   newmtl b\nmap_Kd t.png\n";
        std::fs::write(d.join("m.mtl"), mtl).unwrap();
        let obj = format!("mtllib m.mtl\n{QUAD}usemtl a\nf 1/1 3/3 2/2\nusemtl b\nf 1/1 4/4 3/3\n");
        std::fs::write(d.join("s.obj"), obj).unwrap();
        let scene = load(&d.join("s.obj")).unwrap();
        assert_eq!(scene.textures.len(), 2, "{:?}", scene.report.warnings);
        let [a, b] = [&scene.materials[0], &scene.materials[1]];
        let cut = a.cutout.expect("map_d cuts");
        assert_eq!(cut.texture, Some(1));
        assert_eq!((cut.factor, cut.cutoff), (1.0, 0.5));
        assert!((cut.scale - Vec2::new(0.5, 1.0 / 3.0)).abs().max_element() < 1e-6);
        assert!((cut.offset - Vec2::new(-0.25, 0.0)).abs().max_element() < 1e-6);
        assert_eq!(b.cutout, None);
        assert_eq!(
            (a.albedo_texture, a.albedo_wrap),
            (Some(0), [Wrap::Clamp; 2])
        );
        assert_eq!(
            (b.albedo_texture, b.albedo_wrap),
            (Some(0), [Wrap::Repeat; 2])
        );
        // Each triangle's coordinates: a's corner vt 3 = (1, 1) becomes (2.5, 3).
        let uvs_of = |material: u32| -> Vec<Vec2> {
            let mesh = &scene.mesh;
            (0..mesh.triangles.len())
                .filter(|&t| mesh.materials[t] == material)
                .flat_map(|t| mesh.triangles[t].map(|i| mesh.uvs[i as usize]))
                .collect()
        };
        assert!(uvs_of(0).contains(&Vec2::new(2.5, 3.0)), "{:?}", uvs_of(0));
        assert!(uvs_of(1).iter().all(|uv| uv.max_element() <= 1.0));
        let _ = std::fs::remove_dir_all(&d);
    }

    /// `map_Ke` (white on the left half, black on the right) makes the triangle over the
    /// left half an emitter of `Ke` and the one over the right half no light; a material
    /// with `map_Ke` and no `Ke` emits nothing; a face without a material keeps the default
    /// one, which is added before the emitters' copies.
    #[test]
    fn an_emissive_texture_lights_the_triangles_over_its_lit_texels() {
        let d = dir("map-ke");
        image::RgbImage::from_fn(8, 8, |x, _| image::Rgb([if x < 4 { 255 } else { 0 }; 3]))
            .save(d.join("e.png"))
            .unwrap();
        let mtl = "newmtl lamp\nKe 3 3 3\nmap_Ke e.png\nnewmtl dark\nmap_Ke e.png\n";
        std::fs::write(d.join("m.mtl"), mtl).unwrap();
        let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n\
                   vt 0.1 0\nvt 0.4 0\nvt 0.1 1\nvt 0.6 0\nvt 0.9 0\nvt 0.9 1\n\
                   f 1/1 2/2 3/3\n\
                   usemtl lamp\nf 1/1 2/2 3/3\nf 1/4 2/5 3/6\nusemtl dark\nf 1/1 2/2 3/3\n";
        std::fs::write(d.join("s.obj"), obj).unwrap();
        let scene = load(&d.join("s.obj")).unwrap();
        assert_eq!(scene.mesh.triangles.len(), 4);
        // Per material name, the emission of its triangles in order.
        let of = |name: &str| -> Vec<Vec3> {
            (0..4)
                .map(|t| scene.material_of(t))
                .filter(|m| m.name == name)
                .map(|m| m.emission)
                .collect()
        };
        let lamp = of("lamp");
        assert_eq!(lamp.len(), 2);
        assert!(
            (lamp[0] - Vec3::splat(3.0)).abs().max_element() < 1e-3,
            "{lamp:?}"
        );
        assert_eq!(lamp[1], Vec3::ZERO);
        assert_eq!(of("dark"), vec![Vec3::ZERO]);
        // The face before any `usemtl` keeps the default material, not an emitter's copy.
        assert_eq!(of("default"), vec![Vec3::ZERO]);
        let _ = std::fs::remove_dir_all(&d);
    }

    /// A texture and a material library named with Windows separators (`.\\t\\t.png`, as the
    /// assimp spider's MTL does) are found; a texture that is missing either way is a
    /// warning.
    #[test]
    fn windows_separators_in_mtl_paths_are_read() {
        let d = dir("backslash");
        std::fs::create_dir_all(d.join("t")).unwrap();
        image::RgbImage::new(4, 4)
            .save(d.join("t").join("t.png"))
            .unwrap();
        let mtl = "newmtl a\nKd 1 1 1\nmap_Kd .\\t\\t.png\nnewmtl b\nmap_Kd .\\t\\none.png\n";
        std::fs::write(d.join("t").join("m.mtl"), mtl).unwrap();
        let obj =
            format!("mtllib t\\m.mtl\n{QUAD}usemtl a\nf 1/1 3/3 2/2\nusemtl b\nf 1/1 4/4 3/3\n");
        std::fs::write(d.join("s.obj"), obj).unwrap();
        let scene = load(&d.join("s.obj")).unwrap();
        assert_eq!(scene.textures.len(), 1, "{:?}", scene.report.warnings);
        assert_eq!(scene.materials[0].albedo_texture, Some(0));
        assert_eq!(scene.materials[1].albedo_texture, None);
        assert!(
            scene.report.warnings.iter().any(|w| w.contains("none.png")),
            "{:?}",
            scene.report.warnings
        );
        let _ = std::fs::remove_dir_all(&d);
    }

    /// OBJ and MTL files in ISO-8859-1 and UTF-16 (as old exporters and some tools write
    /// them) load with a warning, their names decoded, so that `usemtl` finds its material;
    /// a material without a name is a warning and its faces take the default; a colour of
    /// one number (the format's grey) is read.
    #[test]
    fn latin1_utf16_and_unnamed_materials_load() {
        let d = dir("encodings");
        // "Terraindæk" in ISO-8859-1 in both files, as the assimp model regr01 has it.
        let mtl = b"newmtl Terraind\xe6k\nKd 0.1 0.2 0.3\nKs 0\nnewmtl\nKd 1 1 1\n".to_vec();
        std::fs::write(d.join("l.mtl"), mtl).unwrap();
        let obj = [
            b"mtllib l.mtl\n".as_slice(),
            QUAD.as_bytes(),
            b"usemtl\nf 1/1 4/4 3/3\nusemtl Terraind\xe6k\nf 1/1 3/3 2/2\n",
        ]
        .concat();
        std::fs::write(d.join("l.obj"), &obj).unwrap();
        let scene = load(&d.join("l.obj")).unwrap();
        let w = &scene.report.warnings;
        assert!(
            w.iter().any(|w| w.contains("OBJ file is not UTF-8")),
            "{w:?}"
        );
        assert!(
            w.iter().any(|w| w.contains("a material without a name")),
            "{w:?}"
        );
        assert!(
            w.iter().any(|w| w.contains("`usemtl` without a name")),
            "{w:?}"
        );
        let albedo = |t: usize| scene.materials[scene.mesh.materials[t] as usize].albedo;
        assert_eq!(albedo(0), Vec3::splat(0.8));
        assert_eq!(albedo(1), Vec3::new(0.1, 0.2, 0.3));
        // The same OBJ in UTF-16, big-endian, with its byte-order mark.
        let text: String = obj.iter().map(|&b| char::from(b)).collect();
        let utf16: Vec<u8> = [0xFE, 0xFF]
            .into_iter()
            .chain(text.encode_utf16().flat_map(u16::to_be_bytes))
            .collect();
        std::fs::write(d.join("u.obj"), utf16).unwrap();
        let scene = load(&d.join("u.obj")).unwrap();
        assert_eq!(scene.mesh.len(), 2);
        assert!(scene.report.warnings.iter().any(|w| w.contains("UTF-16")));
        let _ = std::fs::remove_dir_all(&d);
    }

    /// A vertex past `MAX_COORDINATE` is refused by name when the scene is finished.
    #[test]
    fn far_vertices_are_refused() {
        let d = dir("far");
        std::fs::write(d.join("f.obj"), "v 0 0 0\nv 1e13 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let mut scene = load(&d.join("f.obj")).unwrap();
        let e = scene.finish_mesh_file(&d.join("f.obj")).unwrap_err();
        assert!(
            e.message.contains("vertex 1") && e.message.contains("1e12"),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&d);
    }
}
