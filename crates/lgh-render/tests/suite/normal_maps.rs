//! Normal maps bend the normals the camera sees (the G-buffer, the edge resolve) and not
//! those of light paths (docs/design.md, "Normal maps").

use glam::{Vec2, Vec3};
use lgh_render::World;
use lgh_scene::normal_map::NormalMap;
use lgh_scene::texture::Wrap;
use lgh_scene::{Material, Texture};

use crate::common;

/// A floor whose normal map tilts every normal by `a` along its u direction (x): a camera
/// ray sees the tilt, a light path the floor's own normal.
#[test]
fn the_camera_sees_bent_normals_and_light_paths_do_not() {
    let a = 0.4f32;
    let code = |x: f32| (127.5 + 127.5 * x).round() as u8;
    let tex = Texture::from_linear8(1, 1, 3, &[code(a.sin()), 128, code(a.cos())]).unwrap();
    let mut scene = common::floor_scene(2.0, Vec3::splat(0.7));
    scene.textures.push(tex);
    scene.materials[0] = Material {
        albedo: Vec3::splat(0.7),
        normal_map: Some(NormalMap {
            texture: 0,
            wrap: [Wrap::Repeat; 2],
            scale: 1.0,
        }),
        ..Material::default()
    };
    // Texture coordinates along the floor: u = x, v = z.
    scene.mesh.uvs = scene
        .mesh
        .positions
        .iter()
        .map(|p| Vec2::new(p.x, p.z))
        .collect();
    scene.lights.push(lgh_scene::Light::Point {
        position: Vec3::new(0.0, 2.0, 0.0),
        intensity: Vec3::ONE,
    });
    scene
        .finish(std::path::Path::new("<normal-mapped floor>"))
        .expect("scene");
    let world = World::new(scene);
    let (o, d) = (Vec3::new(0.3, 2.0, 0.2), Vec3::NEG_Y);
    let seen = world.trace_camera(o, d).expect("the floor");
    let path = world.trace(o, d).expect("the floor");
    assert_eq!(path.normal, Vec3::Y);
    assert!((seen.normal.y - a.cos()).abs() < 0.01, "{}", seen.normal);
    assert!((seen.normal.length() - 1.0).abs() < 1e-5);
    // Tilted along the floor's u direction (x) and nowhere else.
    assert!(seen.normal.z.abs() < 0.01, "{}", seen.normal);
    assert!(
        (seen.normal.x.abs() - a.sin()).abs() < 0.01,
        "{}",
        seen.normal
    );
    // From below the floor the bent normal is on the side the ray came from.
    let under = world
        .trace_camera(Vec3::new(0.3, -2.0, 0.2), Vec3::Y)
        .expect("the floor");
    assert!(under.normal.dot(under.geo_normal) > 0.5, "{under:?}");
}
