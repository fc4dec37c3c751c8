//! Hand-made hostile inputs, by class, beside the mutations: what a mutation of bytes never
//! produces (issue 38's probe found each of these classes):
//!
//! - **special files** named where a file is read: the scene itself, an MTL library, a
//!   texture, a scene file's mesh, a glTF buffer and image; as /dev/zero (never ends), a FIFO
//!   (blocks forever), a folder, and a link to /dev/zero under a plain name;
//! - **bombs**: small files that promise huge images or buffers (a PNG header of 30000 x
//!   30000 as a texture, an embedded glTF image and a `diff` input; a glTF buffer whose
//!   `byteLength` exceeds its file);
//! - **instancing**: one mesh placed by many glTF nodes, and a deep chain of nodes.
//!
//! Each case runs on a thread of its own: a case that panics, takes longer than
//! [`crate::SLOW_CASE_MS`] or never returns (a blocked read) is a finding.

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use crate::seeds;

/// The class of a hostile case.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Class {
    /// A FIFO, device, folder or link to a device where a file is read.
    SpecialFile,
    /// A small file that promises a huge image or buffer.
    Bomb,
    /// Many instances of one mesh, or a deep node tree.
    Instancing,
}

/// One hostile case: its name, its class, and how it ended.
#[derive(Clone, Debug)]
pub struct HostileOutcome {
    /// What the case is.
    pub name: String,
    /// Its class.
    pub class: Class,
    /// `Ok(message)`: refused with that error, or loaded ("loaded"); `Err(finding)`: a
    /// panic, a slow case or a hang.
    pub result: Result<String, String>,
    /// How long it took, in ms.
    pub ms: f64,
}

/// What a case loads: a scene, or an image as `lgh diff` reads it.
enum Load {
    Scene(PathBuf),
    Image(PathBuf),
}

/// A PNG whose header says `w` x `h` 8-bit RGB pixels, with one row of data: a few dozen
/// bytes.
fn png_header(w: u32, h: u32) -> Vec<u8> {
    let mut bytes = seeds::png_texture();
    bytes[16..20].copy_from_slice(&w.to_be_bytes());
    bytes[20..24].copy_from_slice(&h.to_be_bytes());
    let crc = crc32(&bytes[12..29]);
    bytes[29..33].copy_from_slice(&crc.to_be_bytes());
    bytes
}

/// The CRC-32 of PNG chunks.
fn crc32(data: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in data {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 == 1 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// Makes the special file `kind` at `path` (a FIFO through `mkfifo`); false where it cannot.
fn special(kind: &str, path: &Path) -> bool {
    let _ = std::fs::remove_file(path);
    match kind {
        "zero" => std::os::unix::fs::symlink("/dev/zero", path).is_ok(),
        "folder" => std::fs::create_dir_all(path).is_ok(),
        "fifo" => std::process::Command::new("mkfifo")
            .arg(path)
            .status()
            .is_ok_and(|s| s.success()),
        _ => false,
    }
}

/// A glTF document naming `buffer_uri` (of `len` bytes) and `image_uri`, with one triangle
/// mesh of `count` vertices placed by `nodes` nodes (each the child of the one before if
/// `chain`).
fn gltf(
    buffer_uri: &str,
    len: usize,
    image_uri: Option<&str>,
    count: u64,
    nodes: usize,
    chain: bool,
) -> String {
    let node_list: Vec<String> = (0..nodes)
        .map(|i| {
            if chain && i + 1 < nodes {
                format!(r#"{{"mesh":0,"children":[{}]}}"#, i + 1)
            } else {
                r#"{"mesh":0}"#.to_string()
            }
        })
        .collect();
    let roots: Vec<String> = if chain {
        vec!["0".into()]
    } else {
        (0..nodes).map(|i| i.to_string()).collect()
    };
    let images = image_uri.map_or(String::new(), |u| {
        format!(
            r#","images":[{{"uri":"{u}"}}],"textures":[{{"source":0}}],"materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}]"#
        )
    });
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[{}]}}],"nodes":[{}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
        "buffers":[{{"uri":"{buffer_uri}","byteLength":{len}}}],
        "bufferViews":[{{"buffer":0,"byteLength":{len}}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":{count},"type":"VEC3","min":[0,0,0],"max":[1,1,1]}}]{images}}}"#,
        roots.join(","),
        node_list.join(",")
    )
}

/// Writes the files of case `name` into `dir` and says what to load; `None` where the case
/// cannot be made here (no `mkfifo`).
fn setup(name: &str, dir: &Path) -> Option<Load> {
    let write = |file: &str, bytes: &[u8]| {
        let p = dir.join(file);
        let _ = std::fs::write(&p, bytes);
        p
    };
    let obj_with = |mtl: &str, png: &[u8]| {
        write("scene.mtl", mtl.as_bytes());
        write("texture.png", png);
        write("scene.obj", seeds::OBJ.as_bytes())
    };
    let tri = {
        let mut b = Vec::new();
        for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
            b.extend(v.to_le_bytes());
        }
        b
    };
    let (class_part, kind) = name.split_once(':').unwrap_or((name, ""));
    Some(match class_part {
        "scene" => {
            let p = dir.join("special.obj");
            special(kind, &p).then_some(Load::Scene(p))?
        }
        "mtllib" => {
            obj_with(seeds::MTL, &seeds::png_texture());
            special(kind, &dir.join("scene.mtl")).then_some(())?;
            Load::Scene(dir.join("scene.obj"))
        }
        "texture" => {
            obj_with(seeds::MTL, &seeds::png_texture());
            special(kind, &dir.join("texture.png")).then_some(())?;
            Load::Scene(dir.join("scene.obj"))
        }
        "mesh" => {
            write("scene.toml", seeds::TOML.as_bytes());
            special(kind, &dir.join("scene.obj")).then_some(())?;
            Load::Scene(dir.join("scene.toml"))
        }
        "buffer" => {
            special(kind, &dir.join("b.bin")).then_some(())?;
            Load::Scene(write(
                "s.gltf",
                gltf("b.bin", 36, None, 3, 1, false).as_bytes(),
            ))
        }
        "image" => {
            write("b.bin", &tri);
            special(kind, &dir.join("i.png")).then_some(())?;
            Load::Scene(write(
                "s.gltf",
                gltf("b.bin", 36, Some("i.png"), 3, 1, false).as_bytes(),
            ))
        }
        "bomb-texture" => Load::Scene(obj_with(seeds::MTL, &png_header(30_000, 30_000))),
        "bomb-diff" => Load::Image(write("image.png", &png_header(30_000, 30_000))),
        "bomb-gltf-image" => {
            use base64::Engine;
            write("b.bin", &tri);
            let uri = format!(
                "data:image/png;base64,{}",
                base64::engine::general_purpose::STANDARD.encode(png_header(30_000, 30_000))
            );
            Load::Scene(write(
                "s.gltf",
                gltf("b.bin", 36, Some(&uri), 3, 1, false).as_bytes(),
            ))
        }
        "bomb-buffer" => {
            write("b.bin", &tri);
            Load::Scene(write(
                "s.gltf",
                gltf("b.bin", 1 << 30, None, 3, 1, false).as_bytes(),
            ))
        }
        "instances" => {
            write("b.bin", &tri);
            Load::Scene(write(
                "s.gltf",
                gltf("b.bin", 36, None, 3_000_000, 10_000, false).as_bytes(),
            ))
        }
        "chain" => {
            write("b.bin", &tri);
            Load::Scene(write(
                "s.gltf",
                gltf("b.bin", 36, None, 3, 20_000, true).as_bytes(),
            ))
        }
        _ => return None,
    })
}

/// Every hostile case by name (`slot:kind` for special files) with its class.
#[must_use]
pub fn cases() -> Vec<(String, Class)> {
    let mut out = Vec::new();
    for slot in ["scene", "mtllib", "texture", "mesh", "buffer", "image"] {
        for kind in ["zero", "fifo", "folder"] {
            out.push((format!("{slot}:{kind}"), Class::SpecialFile));
        }
    }
    for name in [
        "bomb-texture",
        "bomb-diff",
        "bomb-gltf-image",
        "bomb-buffer",
    ] {
        out.push((name.to_string(), Class::Bomb));
    }
    for name in ["instances", "chain"] {
        out.push((name.to_string(), Class::Instancing));
    }
    out
}

/// Runs every hostile case in a folder of its own under `work_dir`.
#[must_use]
pub fn run(work_dir: &Path) -> Vec<HostileOutcome> {
    cases()
        .into_iter()
        .map(|(name, class)| {
            let dir = work_dir.join(name.replace(':', "-"));
            let _ = std::fs::remove_dir_all(&dir);
            let _ = std::fs::create_dir_all(&dir);
            let start = Instant::now();
            let result = match setup(&name, &dir) {
                None => Ok("not made here".to_string()),
                Some(load) => run_one(load),
            };
            let ms = start.elapsed().as_secs_f64() * 1e3;
            let result = match result {
                Ok(_) if ms > crate::SLOW_CASE_MS => Err(format!("slow: {ms:.0} ms")),
                r => r,
            };
            // A FIFO some thread still waits on is left in place; the rest is removed.
            if result.is_ok() {
                let _ = std::fs::remove_dir_all(&dir);
            }
            HostileOutcome {
                name,
                class,
                result,
                ms,
            }
        })
        .collect()
}

/// Loads on a thread of its own, waiting at most five times [`crate::SLOW_CASE_MS`].
fn run_one(load: Load) -> Result<String, String> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let outcome = std::panic::catch_unwind(|| match &load {
            Load::Scene(p) => lgh_scene::load(p).map(|_| ()).map_err(|e| e.to_string()),
            Load::Image(p) => lgh_render::Image::load(p)
                .map(|_| ())
                .map_err(|e| e.to_string()),
        });
        let _ = tx.send(outcome);
    });
    match rx.recv_timeout(Duration::from_millis(5 * crate::SLOW_CASE_MS as u64)) {
        Ok(Ok(Ok(()))) => Ok("loaded".into()),
        Ok(Ok(Err(message))) => Ok(message),
        Ok(Err(payload)) => Err(format!("panic: {}", crate::panic_text(payload.as_ref()))),
        Err(_) => Err("hangs".into()),
    }
}
