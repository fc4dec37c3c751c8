//! The same small scene written as glTF and as OBJ/MTL renders the same image.

use lgh_render::methods::brute::BRUTE;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use lgh_render::image::metrics::diff;
use lgh_render::{RenderSettings, Silent, World, render_frame};

struct Quad {
    corners: [Vec3; 4],
    uvs: [Vec2; 4],
}

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

/// Material 0: textured floor; 1: red box faces; 2: emissive ceiling panel (facing down).
fn scene_quads() -> Vec<(u32, Quad)> {
    let uv = [
        Vec2::new(0.0, 0.0),
        Vec2::new(0.0, 2.0),
        Vec2::new(2.0, 2.0),
        Vec2::new(2.0, 0.0),
    ];
    let mut q = vec![(
        0,
        Quad {
            corners: [
                v(-2., 0., -2.),
                v(-2., 0., 2.),
                v(2., 0., 2.),
                v(2., 0., -2.),
            ],
            uvs: uv,
        },
    )];
    // A box from (-0.5, 0, -0.5) to (0.5, 1, 0.5): top and four sides, facing out.
    let faces = [
        [
            v(-0.5, 1., -0.5),
            v(-0.5, 1., 0.5),
            v(0.5, 1., 0.5),
            v(0.5, 1., -0.5),
        ],
        [
            v(-0.5, 0., 0.5),
            v(0.5, 0., 0.5),
            v(0.5, 1., 0.5),
            v(-0.5, 1., 0.5),
        ],
        [
            v(0.5, 0., -0.5),
            v(-0.5, 0., -0.5),
            v(-0.5, 1., -0.5),
            v(0.5, 1., -0.5),
        ],
        [
            v(0.5, 0., 0.5),
            v(0.5, 0., -0.5),
            v(0.5, 1., -0.5),
            v(0.5, 1., 0.5),
        ],
        [
            v(-0.5, 0., -0.5),
            v(-0.5, 0., 0.5),
            v(-0.5, 1., 0.5),
            v(-0.5, 1., -0.5),
        ],
    ];
    for corners in faces {
        q.push((1, Quad { corners, uvs: uv }));
    }
    q.push((
        2,
        Quad {
            corners: [
                v(-1., 3., -1.),
                v(1., 3., -1.),
                v(1., 3., 1.),
                v(-1., 3., 1.),
            ],
            uvs: uv,
        },
    ));
    q
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lgh-test-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write_texture(dir: &Path) {
    let px: [u8; 12] = [230, 230, 230, 40, 40, 200, 40, 40, 200, 230, 230, 230];
    image::save_buffer(
        dir.join("checker.png"),
        &px,
        2,
        2,
        image::ExtendedColorType::Rgb8,
    )
    .unwrap();
}

fn write_obj(dir: &Path, quads: &[(u32, Quad)]) -> PathBuf {
    let mut obj = String::from("mtllib scene.mtl\n");
    let names = ["floor", "box", "lamp"];
    for (i, (m, q)) in quads.iter().enumerate() {
        for c in q.corners {
            writeln!(obj, "v {} {} {}", c.x, c.y, c.z).unwrap();
        }
        for t in q.uvs {
            writeln!(obj, "vt {} {}", t.x, t.y).unwrap();
        }
        let b = 4 * i + 1;
        writeln!(obj, "usemtl {}", names[*m as usize]).unwrap();
        writeln!(
            obj,
            "f {b}/{b} {}/{} {}/{} {}/{}",
            b + 1,
            b + 1,
            b + 2,
            b + 2,
            b + 3,
            b + 3
        )
        .unwrap();
    }
    let mtl = "newmtl floor\nKd 1 1 1\nmap_Kd checker.png\n\n\
               newmtl box\nKd 0.7 0.1 0.1\n\n\
               newmtl lamp\nKd 0.5 0.5 0.5\nKe 10 9 8\n";
    std::fs::write(dir.join("scene.obj"), obj).unwrap();
    std::fs::write(dir.join("scene.mtl"), mtl).unwrap();
    dir.join("scene.obj")
}

fn write_gltf(dir: &Path, quads: &[(u32, Quad)]) -> PathBuf {
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut prims = Vec::new();
    for m in 0..3u32 {
        let qs: Vec<&Quad> = quads
            .iter()
            .filter(|(mm, _)| *mm == m)
            .map(|(_, q)| q)
            .collect();
        let (mut pos, mut uv, mut idx) = (Vec::new(), Vec::new(), Vec::new());
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for (k, q) in qs.iter().enumerate() {
            for (c, t) in q.corners.iter().zip(q.uvs) {
                pos.extend_from_slice(&[c.x, c.y, c.z]);
                uv.extend_from_slice(&[t.x, 1.0 - t.y]);
                lo = lo.min(*c);
                hi = hi.max(*c);
            }
            let b = 4 * k as u32;
            idx.extend_from_slice(&[b, b + 1, b + 2, b, b + 2, b + 3]);
        }
        let mut add = |bytes: Vec<u8>, count: usize, comp: u32, ty: &str, extra: String| {
            let offset = bin.len();
            bin.extend_from_slice(&bytes);
            views.push(format!(
                r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{}}}"#,
                bytes.len()
            ));
            accessors.push(format!(
                r#"{{"bufferView":{},"componentType":{comp},"count":{count},"type":"{ty}"{extra}}}"#,
                views.len() - 1
            ));
            accessors.len() - 1
        };
        let f32s = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
        let n = pos.len() / 3;
        let pa = add(
            f32s(&pos),
            n,
            5126,
            "VEC3",
            format!(
                r#","min":[{},{},{}],"max":[{},{},{}]"#,
                lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
            ),
        );
        let ta = add(f32s(&uv), n, 5126, "VEC2", String::new());
        let ia = add(
            idx.iter().flat_map(|x| x.to_le_bytes()).collect(),
            idx.len(),
            5125,
            "SCALAR",
            String::new(),
        );
        prims.push(format!(
            r#"{{"attributes":{{"POSITION":{pa},"TEXCOORD_0":{ta}}},"indices":{ia},"material":{m}}}"#
        ));
    }
    std::fs::write(dir.join("scene.bin"), &bin).unwrap();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_materials_emissive_strength"],
"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{}]}}],
"materials":[
 {{"name":"floor","pbrMetallicRoughness":{{"baseColorFactor":[1,1,1,1],"baseColorTexture":{{"index":0}}}}}},
 {{"name":"box","pbrMetallicRoughness":{{"baseColorFactor":[0.7,0.1,0.1,1]}}}},
 {{"name":"lamp","pbrMetallicRoughness":{{"baseColorFactor":[0.5,0.5,0.5,1]}},"emissiveFactor":[1,0.9,0.8],
   "extensions":{{"KHR_materials_emissive_strength":{{"emissiveStrength":10}}}}}}],
"textures":[{{"source":0}}],"images":[{{"uri":"checker.png"}}],
"buffers":[{{"uri":"scene.bin","byteLength":{}}}],
"bufferViews":[{}],"accessors":[{}]}}"#,
        prims.join(","),
        bin.len(),
        views.join(","),
        accessors.join(",")
    );
    std::fs::write(dir.join("scene.gltf"), json).unwrap();
    dir.join("scene.gltf")
}

#[test]
fn gltf_and_obj_versions_render_the_same_image() {
    let dir = temp_dir("formats");
    write_texture(&dir);
    let quads = scene_quads();
    let obj = lgh_scene::load(&write_obj(&dir, &quads)).unwrap();
    let gltf = lgh_scene::load(&write_gltf(&dir, &quads)).unwrap();
    assert!(obj.report.warnings.is_empty(), "{:?}", obj.report.warnings);
    assert!(
        gltf.report.warnings.is_empty(),
        "{:?}",
        gltf.report.warnings
    );
    assert_eq!(obj.mesh.len(), 14);
    assert_eq!(gltf.mesh.len(), 14);
    assert_eq!(obj.textures.len(), 1);
    assert_eq!(gltf.textures.len(), 1);
    let settings = RenderSettings {
        width: 64,
        height: 48,
        vpls: 2000,
        area_samples: 4,
        method: BRUTE,
        ..RenderSettings::default()
    };
    let a = render_frame(&World::new(obj), &settings, &Silent)
        .unwrap()
        .image;
    let b = render_frame(&World::new(gltf), &settings, &Silent)
        .unwrap()
        .image;
    let m = diff(&a, &b).unwrap();
    assert!(m.rel_rmse < 1e-4, "{m:?}");
    // The checker texture shows: the floor has blue and white pixels.
    assert!(b.pixels.iter().any(|p| p.z > 2.0 * p.x && p.z > 0.01));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A glTF camera node and `KHR_lights_punctual` lights are used, placed by their node
/// transforms (cameras and lights look along their local -z).
#[test]
fn gltf_camera_and_punctual_lights_are_loaded() {
    let dir = temp_dir("gltf-camera");
    write_texture(&dir);
    let path = write_gltf(&dir, &scene_quads());
    let text = std::fs::read_to_string(&path).unwrap();
    // Node 1: a camera at (0, 2, 6) (translation only: looks along -z); node 2: a point light;
    // node 3: a spot light rotated to look down (-90 degrees about x).
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let text = text
        .replace(
            r#""nodes":[{"mesh":0}]"#,
            &format!(
                r#""nodes":[{{"mesh":0}},{{"camera":0,"translation":[0,2,6]}},{{"translation":[1,2.5,0],"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}},{{"translation":[0,2.8,0],"rotation":[{},0,0,{}],"extensions":{{"KHR_lights_punctual":{{"light":1}}}}}}]"#,
                -s, s
            ),
        )
        .replace(r#""scenes":[{"nodes":[0]}]"#, r#""scenes":[{"nodes":[0,1,2,3]}]"#)
        .replace(
            r#""extensionsUsed":["KHR_materials_emissive_strength"]"#,
            r#""extensionsUsed":["KHR_materials_emissive_strength","KHR_lights_punctual"],
"cameras":[{"type":"perspective","perspective":{"yfov":0.8,"znear":0.1}}],
"extensions":{"KHR_lights_punctual":{"lights":[{"type":"point","color":[1,0.5,0.25],"intensity":4},{"type":"spot","intensity":10,"spot":{"innerConeAngle":0.2,"outerConeAngle":0.5}}]}}"#,
        );
    std::fs::write(&path, text).unwrap();
    let scene = lgh_scene::load(&path).unwrap();
    let cam = scene.camera.clone().unwrap();
    assert!((cam.position - Vec3::new(0.0, 2.0, 6.0)).length() < 1e-5);
    assert!(((cam.look_at - cam.position).normalize() - Vec3::NEG_Z).length() < 1e-5);
    assert!((cam.fov_y_degrees - 0.8f32.to_degrees()).abs() < 1e-3);
    assert_eq!(scene.lights.len(), 2);
    let mut saw_point = false;
    let mut saw_spot = false;
    for l in &scene.lights {
        match *l {
            lgh_scene::Light::Point {
                position,
                intensity,
            } => {
                assert!((position - Vec3::new(1.0, 2.5, 0.0)).length() < 1e-5);
                assert!((intensity - Vec3::new(4.0, 2.0, 1.0)).length() < 1e-5);
                saw_point = true;
            }
            lgh_scene::Light::Spot {
                direction,
                cos_inner,
                cos_outer,
                ..
            } => {
                assert!((direction - Vec3::NEG_Y).length() < 1e-4, "{direction}");
                assert!((cos_inner - 0.2f32.cos()).abs() < 1e-6);
                assert!((cos_outer - 0.5f32.cos()).abs() < 1e-6);
                saw_spot = true;
            }
            _ => {}
        }
    }
    assert!(saw_point && saw_spot);
    let _ = std::fs::remove_dir_all(&dir);
}
