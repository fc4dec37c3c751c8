//! Vertex colours multiply the albedo of every surface a ray finds: a floor whose vertices
//! are coloured c renders as the floor of albedo factor x c, and a gradient is
//! interpolated across a triangle.

use glam::{Mat4, Vec2, Vec3};
use lgh_render::image::metrics::diff;
use lgh_render::methods::brute::BRUTE;
use lgh_render::{RenderSettings, World};
use lgh_scene::mesh::Primitive;
use lgh_scene::{Camera, Light, Material, Scene};

use crate::common;

/// A floor of half-size 2 (albedo `albedo`, corner colours `colors`, none if empty), a
/// block on it and a point light.
fn scene(albedo: Vec3, colors: Vec<Vec3>) -> Scene {
    let mut scene = Scene::new("coloured floor");
    scene.materials.push(Material {
        albedo,
        ..Material::default()
    });
    let prim = Primitive {
        positions: common::floor_corners(2.0).to_vec(),
        uvs: vec![Vec2::ZERO; 4],
        colors,
        indices: vec![[0, 1, 2], [0, 2, 3]],
        material: 0,
        ..Default::default()
    };
    scene.mesh.append(&prim, Mat4::IDENTITY, "floor");
    scene.materials.push(Material::default());
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    // A wall standing on the floor, facing +x.
    common::quad(
        &mut scene,
        [
            c(0.0, 0.0, -1.0),
            c(0.0, 0.0, 1.0),
            c(0.0, 1.0, 1.0),
            c(0.0, 1.0, -1.0),
        ],
        1,
    );
    scene.lights.push(Light::Point {
        position: c(0.8, 1.5, 0.3),
        intensity: Vec3::splat(6.0),
    });
    scene.camera = Some(Camera {
        position: c(2.5, 2.5, 2.5),
        look_at: c(0.0, 0.2, 0.0),
        up: Vec3::Y,
        fov_y_degrees: 50.0,
    });
    scene
        .finish(std::path::Path::new("<coloured floor>"))
        .expect("scene");
    scene
}

/// Colour c at every floor vertex renders as the albedo 0.8 c (direct and indirect light:
/// the VPLs' flux too): rel_rmse below 1e-4 (interpolating equal colours rounds); white
/// vertices differ from it by far more.
#[test]
fn a_uniform_vertex_colour_is_an_albedo_factor() {
    let c = Vec3::new(0.5, 0.25, 1.0);
    let settings = RenderSettings {
        method: BRUTE,
        width: 48,
        height: 32,
        vpls: 1500,
        ..RenderSettings::default()
    };
    let render = |s: Scene| common::render(&World::new(s), &settings).image;
    let coloured = render(scene(Vec3::splat(0.8), vec![c; 4]));
    let factor = render(scene(0.8 * c, Vec::new()));
    let white = render(scene(Vec3::splat(0.8), vec![Vec3::ONE; 4]));
    let same = diff(&coloured, &factor).expect("same size");
    let other = diff(&white, &factor).expect("same size");
    assert!(same.rel_rmse < 1e-4, "{same:?}");
    assert!(other.rel_rmse > 0.2, "{other:?}");
}

/// A ray onto the floor sees the colours interpolated at its hit (a gradient from black at
/// x = -2 to white at x = 2, times the albedo).
#[test]
fn the_surface_albedo_interpolates_the_corners() {
    let [a, b, _, d] = common::floor_corners(2.0);
    let grey = |p: Vec3| Vec3::splat((p.x + 2.0) / 4.0);
    let corners = common::floor_corners(2.0).map(grey).to_vec();
    let world = World::new(scene(Vec3::splat(0.8), corners));
    assert_eq!((a.x, b.x, d.x), (-2.0, -2.0, 2.0));
    for x in [-1.5f32, -0.5, 0.7, 1.6] {
        let hit = world
            .trace(Vec3::new(x, 3.0, 1.5), Vec3::NEG_Y)
            .expect("the floor");
        let want = 0.8 * (x + 2.0) / 4.0;
        assert!(
            (hit.albedo - Vec3::splat(want)).abs().max_element() < 1e-5,
            "{x}: {hit:?}"
        );
    }
}
