//! The seed inputs that mutation starts from: small valid files of every format lgh reads,
//! each using as many of its format's features as the loaders handle (indexed and strip
//! primitives, textures, alpha cut-outs, vertex colours, cameras, every light type,
//! animation keys), so that mutations reach
//! deep into the loaders instead of stopping at the first byte.

use base64::Engine;
use base64::engine::general_purpose::STANDARD;
use serde_json::{Value, json};

/// A 2x2 RGBA PNG texture whose alpha varies (cut-outs read it).
#[must_use]
pub fn png_texture() -> Vec<u8> {
    let pixels: [u8; 16] = [
        255, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 0, 200, 200, 200, 255,
    ];
    let mut out = std::io::Cursor::new(Vec::new());
    let img = image::RgbaImage::from_raw(2, 2, pixels.to_vec());
    if let Some(img) = img {
        let _ = img.write_to(&mut out, image::ImageFormat::Png);
    }
    out.into_inner()
}

/// The binary buffer of the glTF seed: a quad (4 positions, normals, uvs; 6 u16 indices), a
/// 5-vertex triangle strip (positions only) and the quad's vertex colours.
fn gltf_buffer() -> Vec<u8> {
    let mut b = Vec::new();
    let f = |b: &mut Vec<u8>, v: &[f32]| v.iter().for_each(|x| b.extend(x.to_le_bytes()));
    // 0: quad positions (48 bytes)
    f(
        &mut b,
        &[-1., 0., -1., 1., 0., -1., 1., 0., 1., -1., 0., 1.],
    );
    // 48: quad normals (48)
    f(&mut b, &[0., 1., 0., 0., 1., 0., 0., 1., 0., 0., 1., 0.]);
    // 96: quad uvs (32)
    f(&mut b, &[0., 0., 1., 0., 1., 1., 0., 1.]);
    // 128: quad indices (12)
    for i in [0u16, 2, 1, 0, 3, 2] {
        b.extend(i.to_le_bytes());
    }
    // 140: strip positions (60)
    f(
        &mut b,
        &[0., 0., 0., 0., 1., 0., 1., 0., 0., 1., 1., 0., 2., 0., 0.],
    );
    // 200: quad colours (48)
    f(
        &mut b,
        &[1., 0.5, 0.5, 0.5, 1., 0.5, 0.5, 0.5, 1., 1., 1., 1.],
    );
    b
}

/// The JSON of the glTF seed; `uri` is the buffer's URI (`None` for the GLB's binary chunk).
fn gltf_json(uri: Option<String>, byte_length: usize) -> Value {
    let mut buffer = json!({ "byteLength": byte_length });
    if let Some(uri) = uri {
        buffer["uri"] = Value::String(uri);
    }
    let image = format!("data:image/png;base64,{}", STANDARD.encode(png_texture()));
    json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{ "nodes": [0, 3, 4] }],
        "nodes": [
            { "mesh": 0, "children": [1, 2], "translation": [0.0, 0.0, 0.0] },
            { "mesh": 1, "rotation": [0.0, 0.383, 0.0, 0.924], "scale": [0.5, 0.5, 0.5] },
            { "extensions": { "KHR_lights_punctual": { "light": 1 } },
              "translation": [0.0, 2.0, 0.0], "rotation": [-0.707, 0.0, 0.0, 0.707] },
            { "camera": 0, "translation": [0.0, 1.0, 4.0] },
            { "extensions": { "KHR_lights_punctual": { "light": 0 } },
              "matrix": [1.0,0.0,0.0,0.0, 0.0,1.0,0.0,0.0, 0.0,0.0,1.0,0.0, 0.5,1.5,0.5,1.0] }
        ],
        "cameras": [{ "type": "perspective",
                      "perspective": { "yfov": 0.8, "znear": 0.01, "aspectRatio": 1.5 } }],
        "extensions": { "KHR_lights_punctual": { "lights": [
            { "type": "point", "color": [1.0, 0.9, 0.8], "intensity": 5.0 },
            { "type": "spot", "intensity": 20.0,
              "spot": { "innerConeAngle": 0.3, "outerConeAngle": 0.6 } }
        ] } },
        "materials": [
            { "name": "textured", "alphaMode": "MASK", "alphaCutoff": 0.4,
              "pbrMetallicRoughness": {
                "baseColorFactor": [0.8, 0.8, 0.8, 0.9], "metallicFactor": 0.0,
                "baseColorTexture": { "index": 0 } } },
            { "name": "glow", "emissiveFactor": [1.0, 0.5, 0.2],
              "pbrMetallicRoughness": { "metallicFactor": 0.0 },
              "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 2.0 } } }
        ],
        "textures": [{ "source": 0 }],
        "images": [{ "uri": image }],
        "meshes": [
            { "primitives": [{ "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2,
                                               "COLOR_0": 5 },
                               "indices": 3, "material": 0 }] },
            { "primitives": [{ "attributes": { "POSITION": 4 }, "mode": 5, "material": 1 }] }
        ],
        "buffers": [buffer],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 48 },
            { "buffer": 0, "byteOffset": 48, "byteLength": 48 },
            { "buffer": 0, "byteOffset": 96, "byteLength": 32 },
            { "buffer": 0, "byteOffset": 128, "byteLength": 12 },
            { "buffer": 0, "byteOffset": 140, "byteLength": 60 },
            { "buffer": 0, "byteOffset": 200, "byteLength": 48 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
              "min": [-1.0, 0.0, -1.0], "max": [1.0, 0.0, 1.0] },
            { "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3" },
            { "bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2" },
            { "bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR" },
            { "bufferView": 4, "componentType": 5126, "count": 5, "type": "VEC3",
              "min": [0.0, 0.0, 0.0], "max": [2.0, 1.0, 0.0] },
            { "bufferView": 5, "componentType": 5126, "count": 4, "type": "VEC3" }
        ]
    })
}

/// A `.gltf` file with its buffer and texture embedded as data URIs.
#[must_use]
pub fn gltf() -> Vec<u8> {
    let buffer = gltf_buffer();
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        STANDARD.encode(&buffer)
    );
    serde_json::to_vec_pretty(&gltf_json(Some(uri), buffer.len())).unwrap_or_default()
}

/// The same scene as a `.glb`: a 12-byte header, the JSON chunk and the binary chunk, each
/// padded to 4 bytes.
#[must_use]
pub fn glb() -> Vec<u8> {
    let mut bin = gltf_buffer();
    let mut json = serde_json::to_vec(&gltf_json(None, bin.len())).unwrap_or_default();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(&bin);
    out
}

/// An OBJ file: two objects, quads and triangles, positive and negative indices, texture
/// coordinates and normals, vertex colours, and two materials of `scene.mtl`.
pub const OBJ: &str = "\
# seed
mtllib scene.mtl
o floor
v -1 0 -1 1 0.5 0.5
v 1 0 -1 0.5 1 0.5
v 1 0 1 0.5 0.5 1
v -1 0 1 1 1 1
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 1 0
usemtl white
f 1/1/1 2/2/1 3/3/1 4/4/1
o lamp
v -0.2 1.9 -0.2 0.9 0.9 0.9
v 0.2 1.9 -0.2 0.9 0.9 0.9
v 0.2 1.9 0.2 0.9 0.9 0.9
v -0.2 1.9 0.2 0.9 0.9 0.9
usemtl light
f -3 -2 -1
f -4 -3 -1
g wall
v -1 0 -1 0.9 0.9 0.9
v -1 2 -1 0.9 0.9 0.9
v 1 2 -1 0.9 0.9 0.9
f 9 10 11
";

/// The MTL file of [`OBJ`]: a textured diffuse material with a cut-out and an emitter.
pub const MTL: &str = "\
newmtl white
Kd 0.8 0.8 0.8
map_Kd -s 2 2 -clamp on texture.png
map_d -s 4 4 texture.png
illum 2
newmtl light
Kd 0.5 0.5 0.5
Ke 10 10 10
";

/// A TOML scene file over [`OBJ`] (`scene.obj`) with a camera, every light type and
/// animation keys of the camera, a light and an object.
pub const TOML: &str = r#"
mesh = "scene.obj"
exposure = 1.5

[camera]
position = [0.0, 1.0, 3.0]
look_at = [0.0, 0.5, 0.0]
up = [0.0, 1.0, 0.0]
fov = 50.0

[[lights]]
type = "point"
position = [0.0, 1.5, 0.0]
intensity = [3.0, 3.0, 3.0]

[[lights]]
type = "spot"
position = [0.5, 1.8, 0.5]
direction = [0.0, -1.0, 0.0]
intensity = [8.0, 8.0, 8.0]
inner_angle = 20.0
outer_angle = 35.0

[[lights]]
type = "directional"
direction = [0.3, -1.0, 0.2]
irradiance = [1.0, 1.0, 1.0]

[[animation.camera]]
time = 0.0
position = [0.0, 1.0, 3.0]
look_at = [0.0, 0.5, 0.0]

[[animation.camera]]
time = 1.0
position = [1.0, 1.0, 3.0]
look_at = [0.0, 0.5, 0.0]

[[animation.lights]]
light = 0
time = 1.0
position = [0.5, 1.5, 0.0]

[[animation.objects]]
object = "lamp"
time = 1.0
translation = [0.0, -0.5, 0.0]
rotation = [0.0, 45.0, 0.0]
"#;

/// A 4x3 linear RGB image as EXR (for the image reader of `lgh diff`).
#[must_use]
pub fn exr_image() -> Vec<u8> {
    // A folder of its own per call: calls may run at once (tests in threads).
    static CALLS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("lgh-fuzz-seed-{}-{call}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join("seed.exr");
    let img = lgh_render::Image {
        width: 4,
        height: 3,
        pixels: (0..12)
            .map(|i| glam::Vec3::new(i as f32 * 0.1, 0.5, 1.0))
            .collect(),
    };
    let bytes = img
        .save(&path, 1.0)
        .ok()
        .and_then(|()| std::fs::read(&path).ok());
    let _ = std::fs::remove_dir_all(&dir);
    bytes.unwrap_or_default()
}
