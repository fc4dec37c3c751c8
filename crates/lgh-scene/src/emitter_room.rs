//! A built-in many-emitter scene for the area-light path tracer (Tokuyoshi & Harada 2016,
//! section 5): a closed room, 4 m x 2.5 m x 4 m (metres), whose ceiling carries a grid of
//! `n x n` small emissive tiles and whose side walls carry strips of smaller ones, with two
//! boxes on the floor as occluders. Tiles have eight power levels and tints chosen by a fixed
//! hash, so emitted power varies by about 40x between tiles. With the default `n = 32`:
//! 1024 ceiling tiles + 2 x 160 wall tiles = 1344 quads, 2688 emissive triangles.

use glam::{Mat4, Vec2, Vec3};

use crate::camera::Camera;
use crate::material::Material;
use crate::mesh::Primitive;
use crate::scene::Scene;

/// Room size (x, y, z) in metres.
const ROOM: Vec3 = Vec3::new(4.0, 2.5, 4.0);

/// Adds a quad with corners `v` (any winding) facing `towards` from its centre.
fn quad(scene: &mut Scene, mut v: [Vec3; 4], towards: Vec3, material: u32) {
    let centre = (v[0] + v[1] + v[2] + v[3]) * 0.25;
    if (v[1] - v[0]).cross(v[2] - v[0]).dot(towards - centre) < 0.0 {
        v.reverse();
    }
    let prim = Primitive {
        positions: v.to_vec(),
        normals: Vec::new(),
        uvs: vec![Vec2::ZERO; 4],
        colors: Vec::new(),
        indices: vec![[0, 1, 2], [0, 2, 3]],
        material,
    };
    scene.mesh.append(&prim, Mat4::IDENTITY, "room");
}

/// An axis-aligned box [lo, hi] with outward faces.
fn cuboid(scene: &mut Scene, lo: Vec3, hi: Vec3, material: u32) {
    let c = (lo + hi) * 0.5;
    let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let faces = [
        [
            p(lo.x, lo.y, lo.z),
            p(lo.x, hi.y, lo.z),
            p(lo.x, hi.y, hi.z),
            p(lo.x, lo.y, hi.z),
        ],
        [
            p(hi.x, lo.y, lo.z),
            p(hi.x, hi.y, lo.z),
            p(hi.x, hi.y, hi.z),
            p(hi.x, lo.y, hi.z),
        ],
        [
            p(lo.x, hi.y, lo.z),
            p(hi.x, hi.y, lo.z),
            p(hi.x, hi.y, hi.z),
            p(lo.x, hi.y, hi.z),
        ],
        [
            p(lo.x, lo.y, lo.z),
            p(hi.x, lo.y, lo.z),
            p(hi.x, lo.y, hi.z),
            p(lo.x, lo.y, hi.z),
        ],
        [
            p(lo.x, lo.y, lo.z),
            p(hi.x, lo.y, lo.z),
            p(hi.x, hi.y, lo.z),
            p(lo.x, hi.y, lo.z),
        ],
        [
            p(lo.x, lo.y, hi.z),
            p(hi.x, lo.y, hi.z),
            p(hi.x, hi.y, hi.z),
            p(lo.x, hi.y, hi.z),
        ],
    ];
    for f in faces {
        let centre = (f[0] + f[1] + f[2] + f[3]) * 0.25;
        quad(scene, f, 2.0 * centre - c, material);
    }
}

/// The scene with an `n x n` grid of ceiling tiles (n >= 1).
#[must_use]
pub fn emitter_room(n: u32) -> Scene {
    let n = n.max(1);
    let mut scene = Scene::new("emitter-room");
    scene.materials.push(Material {
        name: "wall".into(),
        albedo: Vec3::splat(0.7),
        ..Material::default()
    });
    scene.materials.push(Material {
        name: "floor".into(),
        albedo: Vec3::new(0.55, 0.5, 0.45),
        ..Material::default()
    });
    // Eight emitters: radiance 0.04 x 1.7^k (k = 0..7, 0.04 to 1.6), alternating warm and cool.
    for k in 0..8 {
        let power = 1.7f32.powi(k) * 0.04;
        let tint = if k % 2 == 0 {
            Vec3::new(1.0, 0.85, 0.7)
        } else {
            Vec3::new(0.75, 0.85, 1.0)
        };
        scene.materials.push(Material {
            name: format!("emitter{k}"),
            albedo: Vec3::splat(0.5),
            emission: tint * power,
            ..Material::default()
        });
    }
    let inside = ROOM * 0.5;
    let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let (w, h, d) = (ROOM.x, ROOM.y, ROOM.z);
    // Walls, floor, ceiling.
    quad(
        &mut scene,
        [p(0., 0., 0.), p(w, 0., 0.), p(w, 0., d), p(0., 0., d)],
        inside,
        1,
    );
    quad(
        &mut scene,
        [p(0., h, 0.), p(w, h, 0.), p(w, h, d), p(0., h, d)],
        inside,
        0,
    );
    quad(
        &mut scene,
        [p(0., 0., 0.), p(0., h, 0.), p(0., h, d), p(0., 0., d)],
        inside,
        0,
    );
    quad(
        &mut scene,
        [p(w, 0., 0.), p(w, h, 0.), p(w, h, d), p(w, 0., d)],
        inside,
        0,
    );
    quad(
        &mut scene,
        [p(0., 0., 0.), p(w, 0., 0.), p(w, h, 0.), p(0., h, 0.)],
        inside,
        0,
    );
    quad(
        &mut scene,
        [p(0., 0., d), p(w, 0., d), p(w, h, d), p(0., h, d)],
        inside,
        0,
    );
    // A fixed hash picks each tile's emitter.
    let pick = |a: u32, b: u32| {
        let x = a.wrapping_mul(0x9e37_79b9) ^ b.wrapping_mul(0x85eb_ca6b);
        2 + ((x ^ (x >> 15)).wrapping_mul(0x2c1b_3c6d) >> 29)
    };
    // Ceiling tiles, 1 mm below the ceiling, facing down.
    let cell = w / n as f32;
    let tile = cell * 0.45;
    let y = h - 1e-3;
    for i in 0..n {
        for j in 0..n {
            let c = p((i as f32 + 0.5) * cell, y, (j as f32 + 0.5) * d / n as f32);
            let e = Vec3::new(tile * 0.5, 0.0, tile * 0.5);
            let v = [
                c - e,
                c + Vec3::new(e.x, 0.0, -e.z),
                c + e,
                c + Vec3::new(-e.x, 0.0, e.z),
            ];
            quad(&mut scene, v, c - Vec3::Y, pick(i, j));
        }
    }
    // Strips on the two side walls (x = 0 and x = w), 1 mm off the wall: 4 rows x 40.
    let cols = 40;
    for (k, xw) in [(0u32, 1e-3f32), (1, w - 1e-3)] {
        for r in 0..4 {
            for c in 0..cols {
                let centre = p(
                    xw,
                    1.2 + r as f32 * 0.25,
                    (c as f32 + 0.5) * d / cols as f32,
                );
                let (ey, ez) = (0.04, 0.035);
                let v = [
                    centre + Vec3::new(0.0, -ey, -ez),
                    centre + Vec3::new(0.0, ey, -ez),
                    centre + Vec3::new(0.0, ey, ez),
                    centre + Vec3::new(0.0, -ey, ez),
                ];
                quad(&mut scene, v, inside, pick(100 + k * 7 + r, c));
            }
        }
    }
    cuboid(&mut scene, p(0.8, 0.0, 1.0), p(1.6, 1.2, 1.8), 0);
    cuboid(&mut scene, p(2.4, 0.0, 2.2), p(3.4, 0.6, 3.0), 0);
    scene.camera = Some(Camera {
        position: p(2.0, 1.3, 3.9),
        look_at: p(2.0, 0.9, 0.5),
        up: Vec3::Y,
        fov_y_degrees: 70.0,
    });
    scene
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_room_has_thousands_of_emitters_facing_inwards() {
        let mut s = emitter_room(32);
        s.finish(std::path::Path::new("<built-in>")).unwrap();
        let lights = s.emissive_triangles();
        assert_eq!(lights.len(), 2 * (32 * 32 + 2 * 4 * 40));
        let centre = ROOM * 0.5;
        for t in lights {
            let [a, b, c] = s.mesh.vertices(t as usize);
            let n = s.mesh.face_cross(t as usize);
            assert!(n.dot(centre - (a + b + c) / 3.0) > 0.0);
        }
    }
}
