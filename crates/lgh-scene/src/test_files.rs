//! Small files the unit tests load.

/// A glTF triangle (corners (0,0,0), (1,0,0), (0,1,0), texture coordinates equal to
/// x and y) whose material has `material` (JSON) and an embedded 2 x 1 RGBA texture of
/// alpha 0 then 200.
pub(crate) fn gltf(material: &str) -> crate::Scene {
    use base64::Engine;
    let enc = base64::engine::general_purpose::STANDARD;
    let mut png = Vec::new();
    image::RgbaImage::from_raw(2, 1, vec![255, 255, 255, 0, 255, 255, 255, 200])
        .unwrap()
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let f32s = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let pos = f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    // glTF's v points down the image; the loader flips it to lgh's v up.
    let uv = f32s(&[0.0, 1.0, 1.0, 1.0, 0.0, 0.0]);
    let bin = [pos, uv].concat();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"material":0}}]}}],
"materials":[{material}],
"textures":[{{"source":0,"sampler":0}}],"samplers":[{{"wrapS":33071,"wrapT":33071}}],
"images":[{{"uri":"data:image/png;base64,{}"}}],
"buffers":[{{"uri":"data:application/octet-stream;base64,{}","byteLength":{}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
  {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}}]}}"#,
        enc.encode(&png),
        enc.encode(&bin),
        bin.len()
    );
    let dir =
        std::env::temp_dir().join(format!("lgh-cutouts-{}-{}", std::process::id(), json.len()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("t.gltf");
    std::fs::write(&path, json).unwrap();
    let scene = crate::gltf_file::load(&path).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    scene
}
