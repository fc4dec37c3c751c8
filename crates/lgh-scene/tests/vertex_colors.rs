//! Vertex colours multiply the albedo: glTF's `COLOR_0` (linear) and OBJ's `v x y z r g b`
//! (sRGB) are read per vertex, white where a primitive has none, and interpolated by
//! `Mesh::color_at`.

use glam::{Vec2, Vec3};

fn temp_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("lgh-vc-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Two glTF triangles: the first with `COLOR_0` red, green, blue at its corners (as
/// `colors`, a JSON accessor type and component type), the second without colours.
fn gltf(color_type: &str, count: usize) -> Result<lgh_scene::Scene, lgh_scene::SceneError> {
    use base64::Engine;
    let f32s = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let pos = f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let col = f32s(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
    let bin = [pos, col].concat();
    let data = base64::engine::general_purpose::STANDARD.encode(&bin);
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
"nodes":[{{"mesh":0}},{{"mesh":1,"translation":[0,0,1]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"COLOR_0":1}}}}]}},
  {{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"buffers":[{{"uri":"data:application/octet-stream;base64,{data}","byteLength":{}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":36}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
  {{"bufferView":1,"componentType":5126,"count":{count},"type":"{color_type}"}}]}}"#,
        bin.len()
    );
    let d = temp_dir(&format!("gltf-{count}"));
    let path = d.join("t.gltf");
    std::fs::write(&path, json).unwrap();
    let scene = lgh_scene::gltf_file::load(&path);
    let _ = std::fs::remove_dir_all(&d);
    scene
}

#[test]
fn gltf_color_0_is_read_and_interpolated() {
    let scene = gltf("VEC3", 3).unwrap();
    let mesh = &scene.mesh;
    assert_eq!(mesh.len(), 2);
    assert_eq!(mesh.colors.len(), mesh.positions.len());
    // The order of the nodes' triangles is the loader's: find the coloured one.
    let coloured = (0..2)
        .find(|&t| mesh.color_at(t, Vec2::ZERO) != Vec3::ONE)
        .expect("a coloured triangle");
    let c = |b1: f32, b2: f32| mesh.color_at(coloured, Vec2::new(b1, b2));
    assert_eq!(c(0.0, 0.0), Vec3::X);
    assert_eq!(c(1.0, 0.0), Vec3::Y);
    assert_eq!(c(0.0, 1.0), Vec3::Z);
    assert!((c(1.0 / 3.0, 1.0 / 3.0) - Vec3::splat(1.0 / 3.0)).length() < 1e-6);
    // The other triangle has none: white.
    assert_eq!(mesh.color_at(1 - coloured, Vec2::new(0.2, 0.3)), Vec3::ONE);
}

#[test]
fn a_short_color_accessor_is_refused() {
    let e = gltf("VEC3", 2).unwrap_err().to_string();
    assert!(e.contains("Colors(0)") && e.contains("2 elements"), "{e}");
}

/// OBJ colours after the position are sRGB: 0.5 reads as 0.214; a value over 1 is clamped;
/// a file without colours has none.
#[test]
fn obj_vertex_colours_are_decoded_from_srgb() {
    let d = temp_dir("obj");
    std::fs::write(
        d.join("c.obj"),
        "v 0 0 0 0.5 0 1\nv 1 0 0 1 1 1\nv 0 1 0 2 0.5 0\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(d.join("p.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let scene = lgh_scene::obj::load(&d.join("c.obj")).unwrap();
    let c = scene.mesh.color_at(0, Vec2::ZERO);
    assert!((c - Vec3::new(0.214_041, 0.0, 1.0)).length() < 1e-5, "{c}");
    let c = scene.mesh.color_at(0, Vec2::new(0.0, 1.0));
    assert!((c - Vec3::new(1.0, 0.214_041, 0.0)).length() < 1e-5, "{c}");
    let plain = lgh_scene::obj::load(&d.join("p.obj")).unwrap();
    assert!(plain.mesh.colors.is_empty());
    assert_eq!(plain.mesh.color_at(0, Vec2::new(0.3, 0.3)), Vec3::ONE);
    let _ = std::fs::remove_dir_all(&d);
}
