//! Reading a glTF file's buffers and images within budgets, where `gltf::import` would read
//! whatever its URIs name to the end (/dev/zero never ends, a FIFO blocks) and decode every
//! image at whatever size its header promises:
//!
//! - the `.gltf`/`.glb` file and every buffer and image file must be regular files; a buffer
//!   file is read up to its `byteLength` and no further;
//! - images are decoded within the texel budget ([`crate::texture_file`]);
//! - the triangles that the node tree instances are counted, from the accessors' counts,
//!   before any is flattened ([`instanced_triangles`], at most [`MAX_TRIANGLES`]).

use std::path::{Path, PathBuf};

use base64::Engine;
use gltf::Document;
use gltf::buffer::Data;

use crate::file_kind::{read_capped, read_exactly};
use crate::texture_file::{TexelBudget, TextureError};
use crate::{SceneError, Texture};

/// The most triangles a scene may have after instancing: 16M, a few GB with the BVH.
pub const MAX_TRIANGLES: u64 = 1 << 24;

/// The largest `.gltf` or `.glb` file read: 2 GiB.
const MAX_GLTF_BYTES: u64 = 2 << 30;

/// A glTF document with its buffers, and its images as textures (`None`: not readable, with a
/// warning in `warnings`).
pub(crate) struct Import {
    pub document: Document,
    pub buffers: Vec<Data>,
    pub textures: Vec<Option<Texture>>,
    pub warnings: Vec<String>,
}

/// Validation problems named at most in a loading error (a Draco-compressed file lists
/// one per accessor: a hundred).
const MAX_PROBLEMS: usize = 3;

/// `e` in one short line: of a validation's problems, the unsupported extensions first (they
/// say why), then the first others, at most [`MAX_PROBLEMS`], and how many more there are.
fn describe(e: &gltf::Error) -> String {
    use gltf::json::validation::Error as Problem;
    let gltf::Error::Validation(problems) = e else {
        return e.to_string();
    };
    let mut sorted: Vec<_> = problems.iter().collect();
    sorted.sort_by_key(|(_, p)| !matches!(p, Problem::Unsupported));
    let mut line: Vec<String> = sorted
        .iter()
        .take(MAX_PROBLEMS)
        .map(|(path, problem)| format!("{path}: {problem}"))
        .collect();
    if problems.len() > MAX_PROBLEMS {
        line.push(format!("and {} more", problems.len() - MAX_PROBLEMS));
    }
    format!("invalid glTF: {}", line.join("; "))
}

/// Parses and validates a glTF file as `gltf::Gltf::from_slice` does, except that POSITION
/// accessors without their `min` and `max` are read, with a warning (the second value),
/// instead of refused: glTF 2.0 requires them, some exporters leave them out, and lgh
/// computes its own bounds.
fn parse(bytes: &[u8]) -> Result<(gltf::Gltf, Option<String>), gltf::Error> {
    use gltf::json::validation::{Error as Problem, Validate};
    let gltf = gltf::Gltf::from_slice_without_validation(bytes)?;
    let root = gltf.document.as_json();
    let dangling = panicking_problems(root);
    if !dangling.is_empty() {
        return Err(gltf::Error::Validation(dangling));
    }
    let mut problems = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, problem| {
        problems.push((path(), problem));
    });
    let bound = |path: &gltf::json::Path| {
        let p = path.as_str();
        p.ends_with(r#""POSITION"].min"#) || p.ends_with(r#""POSITION"].max"#)
    };
    let (bounds, others): (Vec<_>, Vec<_>) = problems
        .into_iter()
        .partition(|(path, problem)| matches!(problem, Problem::Missing) && bound(path));
    if !others.is_empty() {
        return Err(gltf::Error::Validation(others));
    }
    let warning = (!bounds.is_empty()).then(|| {
        format!(
            "{} POSITION attributes lack the min and max that glTF 2.0 requires; read anyway",
            bounds.len().div_ceil(2)
        )
    });
    Ok((gltf, warning))
}

/// The problems on which the `gltf` crate panics instead of reporting them (found by
/// lgh-fuzz): a POSITION attribute whose accessor does not exist (its validation reads the
/// accessor's bounds), an image with neither a `uri` nor a `bufferView`, and one in a
/// `bufferView` without its `mimeType` (its `source` unwraps them). The loader contains such
/// panics, but with a vaguer line.
fn panicking_problems(
    root: &gltf::json::Root,
) -> Vec<(gltf::json::Path, gltf::json::validation::Error)> {
    use gltf::json::validation::{Checked, Error as Problem};
    use gltf::json::{Path, mesh::Semantic};
    let mut problems = Vec::new();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive
                .attributes
                .get(&Checked::Valid(Semantic::Positions));
            if position.is_some_and(|a| a.value() >= root.accessors.len()) {
                let path = Path::new()
                    .field("meshes")
                    .index(m)
                    .field("primitives")
                    .index(p);
                let path = path.field("attributes").key("POSITION");
                problems.push((path, Problem::IndexOutOfBounds));
            }
        }
    }
    for (i, image) in root.images.iter().enumerate() {
        let path = Path::new().field("images").index(i);
        if image.buffer_view.is_some() && image.mime_type.is_none() {
            problems.push((path.field("mimeType"), Problem::Missing));
        } else if image.buffer_view.is_none() && image.uri.is_none() {
            problems.push((path.field("uri"), Problem::Missing));
        }
    }
    problems
}

/// Reads `path` as described in the module documentation.
pub(crate) fn import(path: &Path) -> Result<Import, SceneError> {
    let bytes = read_capped(path, MAX_GLTF_BYTES, "glTF file")?;
    let (gltf::Gltf { document, mut blob }, bounds_warning) = parse(&bytes).map_err(|e| {
        let message = match crate::gltf_file::old_version(&bytes) {
            Some(v) => format!("glTF {v} is not supported (lgh reads glTF 2.0)"),
            None => format!("cannot load glTF: {}", describe(&e)),
        };
        SceneError::new(path, message)
    })?;
    drop(bytes);
    let triangles = instanced_triangles(&document);
    if triangles > MAX_TRIANGLES {
        return Err(SceneError::new(
            path,
            format!(
                "its node tree places {triangles} triangles, more than the {MAX_TRIANGLES} lgh takes"
            ),
        ));
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut buffers = Vec::new();
    for b in document.buffers() {
        let len = b.length() as u64;
        let at = |m: String| SceneError::new(path, format!("buffer {}: {m}", b.index()));
        let mut data = match b.source() {
            gltf::buffer::Source::Bin => blob
                .take()
                .ok_or_else(|| at("the GLB file has no binary chunk".into()))?,
            gltf::buffer::Source::Uri(uri) => match data_uri(uri) {
                Some(encoded) => decode_base64(encoded).map_err(at)?,
                None => read_exactly(&file_uri(dir, uri).map_err(at)?, len)?,
            },
        };
        if (data.len() as u64) < len {
            return Err(at(format!(
                "holds {} bytes where its byteLength says {len}",
                data.len()
            )));
        }
        data.truncate(len as usize);
        while data.len() % 4 != 0 {
            data.push(0);
        }
        buffers.push(Data(data));
    }
    let mut budget = TexelBudget::default();
    let mut textures = Vec::new();
    let mut warnings: Vec<String> = bounds_warning.into_iter().collect();
    for img in document.images() {
        let decoded = match img.source() {
            gltf::image::Source::View { view, .. } => {
                let start = view.offset();
                let bytes = buffers
                    .get(view.buffer().index())
                    .and_then(|b| b.0.get(start..start.checked_add(view.length())?));
                match bytes {
                    Some(bytes) => budget.decode_bytes(bytes),
                    None => Err(TextureError::Unreadable(
                        "its buffer view lies outside its buffer".into(),
                    )),
                }
            }
            gltf::image::Source::Uri { uri, .. } => match data_uri(uri) {
                Some(encoded) => decode_base64(encoded)
                    .map_err(TextureError::Unreadable)
                    .and_then(|b| budget.decode_bytes(&b)),
                None => file_uri(dir, uri)
                    .map_err(TextureError::Unreadable)
                    .and_then(|p| budget.decode_file(&p)),
            },
        };
        textures.push(match decoded {
            Ok(t) => Some(t),
            Err(TextureError::OverBudget(m)) => {
                return Err(SceneError::new(path, format!("image {}: {m}", img.index())));
            }
            Err(TextureError::Unreadable(m)) => {
                warnings.push(format!(
                    "image {} not loaded ({m}); using the material colour",
                    img.index()
                ));
                None
            }
        });
    }
    Ok(Import {
        document,
        buffers,
        textures,
        warnings,
    })
}

/// The base64 text of a `data:` URI.
fn data_uri(uri: &str) -> Option<&str> {
    let rest = uri.strip_prefix("data:")?;
    Some(rest.split_once(";base64,").map_or(rest, |(_, b)| b))
}

fn decode_base64(text: &str) -> Result<Vec<u8>, String> {
    base64::engine::general_purpose::STANDARD
        .decode(text)
        .map_err(|e| format!("bad base64 data: {e}"))
}

/// The file a non-`data:` URI names: `file:` URIs as they are, relative ones (percent-decoded)
/// against the glTF file's folder; other schemes are not read.
fn file_uri(dir: &Path, uri: &str) -> Result<PathBuf, String> {
    if let Some(rest) = uri
        .strip_prefix("file://")
        .or_else(|| uri.strip_prefix("file:"))
    {
        return Ok(PathBuf::from(rest));
    }
    if uri.contains(':') {
        return Err(format!("the URI scheme of \"{uri}\" is not supported"));
    }
    let name = urlencoding::decode(uri).map_err(|_| format!("\"{uri}\" is not valid UTF-8"))?;
    Ok(dir.join(&*name))
}

/// The triangles of the default scene's node tree, each mesh counted once per node that
/// places it: from the accessors' counts, before any index is read. Node trees that are not
/// trees (a node with two parents, a cycle) are counted up to a repeat; the loader refuses
/// them afterwards.
#[must_use]
pub fn instanced_triangles(doc: &Document) -> u64 {
    use gltf::mesh::Mode;
    let per_mesh: Vec<u64> = doc
        .meshes()
        .map(|m| {
            m.primitives()
                .map(|p| {
                    let n = p.indices().map_or_else(
                        || p.get(&gltf::Semantic::Positions).map_or(0, |a| a.count()),
                        |a| a.count(),
                    ) as u64;
                    match p.mode() {
                        Mode::Triangles => n / 3,
                        Mode::TriangleStrip | Mode::TriangleFan => n.saturating_sub(2),
                        _ => 0,
                    }
                })
                .sum()
        })
        .collect();
    let Some(scene) = doc.default_scene().or_else(|| doc.scenes().next()) else {
        return 0;
    };
    let mut seen = vec![false; doc.nodes().len()];
    let mut stack: Vec<gltf::Node> = scene.nodes().collect();
    let mut total = 0u64;
    while let Some(node) = stack.pop() {
        match seen.get_mut(node.index()) {
            Some(s) if !*s => *s = true,
            _ => continue,
        }
        if let Some(m) = node.mesh() {
            total = total.saturating_add(per_mesh.get(m.index()).copied().unwrap_or(0));
        }
        stack.extend(node.children());
    }
    total
}

#[cfg(test)]
mod describe_tests {
    use super::*;

    /// A file with a required extension lgh does not read and an accessor problem for each
    /// of its many accessors is refused in one short line that names the extension.
    #[test]
    fn many_problems_make_one_short_line_naming_the_extension() {
        let accessors: Vec<String> = (0..40)
            .map(|_| {
                r#"{"bufferView": 7, "componentType": 5126, "count": 3, "type": "VEC3"}"#.into()
            })
            .collect();
        let json = format!(
            r#"{{"asset": {{"version": "2.0"}}, "extensionsUsed": ["KHR_draco_mesh_compression"],
            "extensionsRequired": ["KHR_draco_mesh_compression"], "accessors": [{}]}}"#,
            accessors.join(",")
        );
        let Err(e) = gltf::Gltf::from_slice(json.as_bytes()) else {
            panic!("loaded");
        };
        let line = describe(&e);
        assert!(line.contains("KHR_draco_mesh_compression"), "{line}");
        assert!(line.contains("more") && line.len() < 300, "{line}");
        assert!(!line.contains('\n'));
    }
}

#[cfg(test)]
mod bounds_tests {
    use super::*;

    /// A one-triangle glTF whose POSITION accessor has `bounds` (JSON members, maybe none)
    /// and whose index accessor reads buffer view `index_view` (1 exists, others do not).
    fn triangle(bounds: &str, index_view: u32) -> String {
        let f32s = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let mut bin: Vec<u8> = f32s.iter().flat_map(|x| x.to_le_bytes()).collect();
        bin.extend([0u16, 1, 2, 0].iter().flat_map(|i| i.to_le_bytes()));
        let data = base64::engine::general_purpose::STANDARD.encode(&bin);
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"buffers":[{{"uri":"data:application/octet-stream;base64,{data}","byteLength":{}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":8}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"{bounds}}},
  {{"bufferView":{index_view},"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#,
            bin.len()
        )
    }

    /// POSITION without min and max (which some exporters leave out) is read with one
    /// warning; with them there is none; any other problem is still refused, and named.
    #[test]
    fn positions_without_bounds_are_read_with_a_warning() {
        let with = triangle(r#","min":[0,0,0],"max":[1,1,0]"#, 1);
        let (_, warning) = parse(with.as_bytes()).unwrap();
        assert_eq!(warning, None);
        let (gltf, warning) = parse(triangle("", 1).as_bytes()).unwrap();
        let warning = warning.expect("a warning");
        assert!(
            warning.starts_with("1 POSITION attributes lack"),
            "{warning}"
        );
        assert_eq!(gltf.document.meshes().count(), 1);
        // A second problem (the index accessor's buffer view does not exist) is refused.
        let Err(e) = parse(triangle("", 9).as_bytes()) else {
            panic!("loaded");
        };
        let line = describe(&e);
        assert!(
            line.contains("bufferView") && !line.contains("POSITION"),
            "{line}"
        );
    }

    /// The problems on which the `gltf` crate panics are refused in one line that names
    /// them: a POSITION accessor that does not exist, an image without a source or, in a
    /// buffer view, without its MIME type.
    #[test]
    fn what_the_gltf_crate_panics_on_is_named() {
        let cases = [
            (
                triangle("", 1).replace(r#""POSITION":0"#, r#""POSITION":7"#),
                "POSITION",
            ),
            (
                triangle("", 1).replace(r#""asset""#, r#""images":[{"name":"x"}],"asset""#),
                "images[0].uri",
            ),
            (
                triangle("", 1).replace(r#""asset""#, r#""images":[{"bufferView":0}],"asset""#),
                "images[0].mimeType",
            ),
        ];
        for (json, named) in cases {
            assert_ne!(json, triangle("", 1), "the case changed nothing");
            let Err(e) = parse(json.as_bytes()) else {
                panic!("loaded: {named}");
            };
            let line = describe(&e);
            assert!(line.contains(named), "{named}: {line}");
        }
    }

    /// Through the loader: the triangle is there and the warning is the scene's.
    #[test]
    fn the_loader_reports_the_warning() {
        let dir = std::env::temp_dir().join(format!("lgh-bounds-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.gltf");
        std::fs::write(&path, triangle("", 1)).unwrap();
        let scene = crate::gltf_file::load(&path);
        let _ = std::fs::remove_dir_all(&dir);
        let scene = scene.unwrap();
        assert_eq!(scene.mesh.len(), 1);
        assert!(
            scene
                .report
                .warnings
                .iter()
                .any(|w| w.contains("lack the min and max")),
            "{:?}",
            scene.report.warnings
        );
    }
}
