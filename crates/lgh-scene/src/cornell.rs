//! The built-in default scene: the Cornell box as measured at Cornell.
//!
//! Geometry from the Cornell Program of Computer Graphics' published data
//! ("Cornell Box Data", graphics.cornell.edu/online/box/data.html), converted from millimetres
//! to metres. Reflectances are the usual RGB reductions of the measured spectra (white 0.725,
//! 0.71, 0.68; red 0.63, 0.065, 0.05; green 0.14, 0.45, 0.091), the ones the public-domain OBJ
//! version in `shared/scenes/cornell-box` also uses. The light is the published 130 x 105 mm
//! opening in the ceiling, as an emissive quad 0.1 mm below it; its radiance (17, 12, 4) is
//! the warm colour of the same OBJ version. The camera is the published one: at
//! (278, 273, -800) mm looking along +z, 35 mm focal length on a 25 mm film (39.3 degrees).

use glam::{Mat4, Vec2, Vec3};

use crate::animation::{Animation, LightKey, ObjectKey};
use crate::mesh::Primitive;
use crate::{Camera, Light, Material, Scene};

const WHITE: Vec3 = Vec3::new(0.725, 0.71, 0.68);
const RED: Vec3 = Vec3::new(0.63, 0.065, 0.05);
const GREEN: Vec3 = Vec3::new(0.14, 0.45, 0.091);
/// Emitted radiance of the ceiling light.
pub const LIGHT_RADIANCE: Vec3 = Vec3::new(17.0, 12.0, 4.0);

/// Quads in millimetres, each with its material index; the winding is fixed up below so that
/// every face's front points into the box (towards its centre).
const QUADS: &[([[f32; 3]; 4], u32)] = &[
    // floor, ceiling, back wall (white)
    (
        [
            [552.8, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 559.2],
            [549.6, 0.0, 559.2],
        ],
        0,
    ),
    (
        [
            [556.0, 548.8, 0.0],
            [556.0, 548.8, 559.2],
            [0.0, 548.8, 559.2],
            [0.0, 548.8, 0.0],
        ],
        0,
    ),
    (
        [
            [549.6, 0.0, 559.2],
            [0.0, 0.0, 559.2],
            [0.0, 548.8, 559.2],
            [556.0, 548.8, 559.2],
        ],
        0,
    ),
    // right wall (green, x = 0) and left wall (red, x ~ 556)
    (
        [
            [0.0, 0.0, 559.2],
            [0.0, 0.0, 0.0],
            [0.0, 548.8, 0.0],
            [0.0, 548.8, 559.2],
        ],
        2,
    ),
    (
        [
            [552.8, 0.0, 0.0],
            [549.6, 0.0, 559.2],
            [556.0, 548.8, 559.2],
            [556.0, 548.8, 0.0],
        ],
        1,
    ),
    // light
    (
        [
            [343.0, 548.7, 227.0],
            [343.0, 548.7, 332.0],
            [213.0, 548.7, 332.0],
            [213.0, 548.7, 227.0],
        ],
        3,
    ),
    // short block
    (
        [
            [130.0, 165.0, 65.0],
            [82.0, 165.0, 225.0],
            [240.0, 165.0, 272.0],
            [290.0, 165.0, 114.0],
        ],
        0,
    ),
    (
        [
            [290.0, 0.0, 114.0],
            [290.0, 165.0, 114.0],
            [240.0, 165.0, 272.0],
            [240.0, 0.0, 272.0],
        ],
        0,
    ),
    (
        [
            [130.0, 0.0, 65.0],
            [130.0, 165.0, 65.0],
            [290.0, 165.0, 114.0],
            [290.0, 0.0, 114.0],
        ],
        0,
    ),
    (
        [
            [82.0, 0.0, 225.0],
            [82.0, 165.0, 225.0],
            [130.0, 165.0, 65.0],
            [130.0, 0.0, 65.0],
        ],
        0,
    ),
    (
        [
            [240.0, 0.0, 272.0],
            [240.0, 165.0, 272.0],
            [82.0, 165.0, 225.0],
            [82.0, 0.0, 225.0],
        ],
        0,
    ),
    // tall block
    (
        [
            [423.0, 330.0, 247.0],
            [265.0, 330.0, 296.0],
            [314.0, 330.0, 456.0],
            [472.0, 330.0, 406.0],
        ],
        0,
    ),
    (
        [
            [423.0, 0.0, 247.0],
            [423.0, 330.0, 247.0],
            [472.0, 330.0, 406.0],
            [472.0, 0.0, 406.0],
        ],
        0,
    ),
    (
        [
            [472.0, 0.0, 406.0],
            [472.0, 330.0, 406.0],
            [314.0, 330.0, 456.0],
            [314.0, 0.0, 456.0],
        ],
        0,
    ),
    (
        [
            [314.0, 0.0, 456.0],
            [314.0, 330.0, 456.0],
            [265.0, 330.0, 296.0],
            [265.0, 0.0, 296.0],
        ],
        0,
    ),
    (
        [
            [265.0, 0.0, 296.0],
            [265.0, 330.0, 296.0],
            [423.0, 330.0, 247.0],
            [423.0, 0.0, 247.0],
        ],
        0,
    ),
];

/// Index of the block quads in [`QUADS`]: blocks face outwards, walls face inwards.
const FIRST_BLOCK_QUAD: usize = 6;

/// Builds the Cornell box scene (metres, +y up).
#[must_use]
pub fn cornell_box() -> Scene {
    let mut scene = Scene::new("cornell");
    scene.materials = vec![
        Material {
            name: "white".into(),
            albedo: WHITE,
            ..Material::default()
        },
        Material {
            name: "red".into(),
            albedo: RED,
            ..Material::default()
        },
        Material {
            name: "green".into(),
            albedo: GREEN,
            ..Material::default()
        },
        Material {
            name: "light".into(),
            albedo: Vec3::splat(0.78),
            emission: LIGHT_RADIANCE,
            ..Material::default()
        },
    ];
    let room_centre = Vec3::new(278.0, 274.4, 279.6) * 1e-3;
    let block_centres = [
        Vec3::new(186.0, 82.5, 169.0) * 1e-3,
        Vec3::new(368.5, 165.0, 351.5) * 1e-3,
    ];
    for (qi, (q, material)) in QUADS.iter().enumerate() {
        let mut v: Vec<Vec3> = q.iter().map(|p| Vec3::from_array(*p) * 1e-3).collect();
        let centre = v.iter().copied().sum::<Vec3>() / 4.0;
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        let (inside, object) = if qi < FIRST_BLOCK_QUAD {
            (room_centre, "room")
        } else {
            // the block this quad belongs to is the nearer block centre
            let [a, b] = block_centres;
            let (own, object) = if centre.distance(a) < centre.distance(b) {
                (a, "short_block")
            } else {
                (b, "tall_block")
            };
            (2.0 * centre - own, object) // a point outside the block, in front of the face
        };
        if n.dot(inside - centre) < 0.0 {
            v.reverse();
        }
        let prim = Primitive {
            positions: v,
            normals: Vec::new(),
            uvs: vec![Vec2::ZERO; 4],
            colors: Vec::new(),
            indices: vec![[0, 1, 2], [0, 2, 3]],
            material: *material,
        };
        scene.mesh.append(&prim, Mat4::IDENTITY, object);
    }
    scene.camera = Some(Camera {
        position: Vec3::new(0.278, 0.273, -0.8),
        look_at: Vec3::new(0.278, 0.273, 0.0),
        up: Vec3::Y,
        fov_y_degrees: 2.0 * (12.5f32 / 35.0).atan().to_degrees(),
    });
    scene
}

/// The Cornell box lit by a point light that crosses the room under the ceiling from left
/// to right in 2 seconds (the ceiling quad is dark): the animated default scene. The point
/// light emits the quad's power (pi L A = 4 pi I).
#[must_use]
pub fn cornell_moving_light() -> Scene {
    let mut scene = cornell_box();
    scene.name = "cornell-moving-light".into();
    for m in &mut scene.materials {
        m.emission = Vec3::ZERO;
    }
    let area = 0.130 * 0.105;
    scene.lights.push(Light::Point {
        position: Vec3::new(0.08, 0.45, 0.28),
        intensity: LIGHT_RADIANCE * (area / 4.0),
    });
    scene.animation = Animation {
        camera: Vec::new(),
        lights: vec![
            LightKey {
                light: 0,
                time: 0.0,
                position: Some(Vec3::new(0.08, 0.45, 0.28)),
                direction: None,
            },
            LightKey {
                light: 0,
                time: 2.0,
                position: Some(Vec3::new(0.48, 0.45, 0.28)),
                direction: None,
            },
        ],
        objects: Vec::new(),
    };
    scene
}

/// The Cornell box, lit by its ceiling light, with the tall block turning by 90 degrees about
/// the vertical and sliding 10 cm towards the red wall in 2 seconds: the default scene with a
/// rigidly moving object.
#[must_use]
pub fn cornell_moving_block() -> Scene {
    let mut scene = cornell_box();
    scene.name = "cornell-moving-block".into();
    let object = scene.mesh.object_id("tall_block");
    let key = |time, x, degrees| ObjectKey {
        object,
        time,
        translation: Vec3::new(x, 0.0, 0.0),
        rotation_degrees: Vec3::new(0.0, degrees, 0.0),
    };
    scene.animation = Animation {
        objects: vec![key(0.0, 0.0, 0.0), key(2.0, 0.1, 90.0)],
        ..Animation::default()
    };
    scene
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_scene_is_valid_and_the_light_faces_down() {
        let mut s = cornell_box();
        s.finish(std::path::Path::new("<built-in>")).unwrap();
        assert_eq!(s.mesh.len(), 32);
        let lights = s.emissive_triangles();
        assert_eq!(lights.len(), 2);
        for t in lights {
            assert!(s.mesh.face_cross(t as usize).normalize().y < -0.99);
        }
        // The floor faces up, the back wall towards the camera.
        assert!(s.mesh.face_cross(0).normalize().y > 0.99);
        assert!(s.mesh.face_cross(4).normalize().z < -0.99);
    }
}
