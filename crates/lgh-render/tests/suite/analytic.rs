//! Known-answer tests of direct lighting.

use crate::common;
use lgh_render::methods::brute::BRUTE_UNSHADOWED;

use std::f64::consts::PI;
use std::path::Path;

use glam::Vec3;
use lgh_render::direct::direct_irradiance;
use lgh_render::passes::gbuffer::GBuffer;
use lgh_render::{Component, RenderSettings, Silent, World, render_frame};
use lgh_scene::{Light, Material};

/// A diffuse plane under a point light at height h: E(x) = I h / d^3 and L = albedo / pi E,
/// at every pixel, to float precision (no sampling is involved).
#[test]
fn plane_under_point_light_matches_analytic_irradiance() {
    let albedo = Vec3::new(0.8, 0.5, 0.2);
    let intensity = Vec3::new(10.0, 20.0, 5.0);
    let h = 1.5f32;
    let mut scene = common::floor_scene(2.0, albedo);
    scene.lights.push(Light::Point {
        position: Vec3::new(0.3, h, -0.2),
        intensity,
    });
    scene.finish(Path::new("<test>")).unwrap();
    let world = World::new(scene);
    let settings = RenderSettings {
        width: 48,
        height: 32,
        vpls: 0,
        component: Component::Direct,
        method: BRUTE_UNSHADOWED,
        // Each pixel's shaded point, not the mean over its area (edge anti-aliasing).
        edge_samples: 1,
        ..RenderSettings::default()
    };
    let frame = render_frame(&world, &settings, &Silent).unwrap();
    let g = GBuffer::render(&world, &world.scene.camera().frame(48, 32), 48, 32);
    let mut checked = 0;
    for i in 0..g.len() {
        if !g.is_hit(i) {
            continue;
        }
        let d = Vec3::new(0.3, h, -0.2) - g.position[i];
        let expected = albedo * intensity * (h / d.length().powi(3)) / std::f32::consts::PI;
        let got = frame.image.pixels[i];
        assert!(
            ((got - expected).abs() / expected).max_element() < 1e-4,
            "pixel {i}: {got} vs {expected}"
        );
        checked += 1;
    }
    assert!(checked > 800, "{checked} pixels");
}

/// Irradiance under the centre of an a x b emissive rectangle at height h (the classic
/// rectangle-to-point form factor, four corner pieces):
/// E = Le * 2 * sum over the 4 quarter rectangles of [X/sqrt(1+X^2) atan(Y/sqrt(1+X^2)) +
/// Y/sqrt(1+Y^2) atan(X/sqrt(1+Y^2))] / 2, with X = a/(2h), Y = b/(2h).
/// The area-light estimator is unbiased: 400k samples give a relative standard error of about
/// 0.1%; the tolerance is 0.6%.
#[test]
fn area_light_estimate_matches_form_factor() {
    let (a, b, h) = (0.6f32, 0.4f32, 1.0f32);
    let le = Vec3::splat(5.0);
    let mut scene = common::floor_scene(2.0, Vec3::splat(0.5));
    scene.materials.push(Material {
        emission: le,
        ..Material::default()
    });
    // Facing down: counter-clockwise seen from below.
    common::quad(
        &mut scene,
        [
            Vec3::new(-a / 2.0, h, -b / 2.0),
            Vec3::new(a / 2.0, h, -b / 2.0),
            Vec3::new(a / 2.0, h, b / 2.0),
            Vec3::new(-a / 2.0, h, b / 2.0),
        ],
        1,
    );
    scene.finish(Path::new("<test>")).unwrap();
    let world = World::new(scene);
    let e = direct_irradiance(&world, Vec3::ZERO, Vec3::Y, Vec3::Y, 3, 400_000);
    let x = (a / (2.0 * h)) as f64;
    let y = (b / (2.0 * h)) as f64;
    let quarter = (x / (1.0 + x * x).sqrt() * (y / (1.0 + x * x).sqrt()).atan()
        + y / (1.0 + y * y).sqrt() * (x / (1.0 + y * y).sqrt()).atan())
        / (2.0 * PI);
    let expected = 5.0 * PI * 4.0 * quarter;
    assert!(
        ((e.x as f64 - expected) / expected).abs() < 0.006,
        "{} vs {expected}",
        e.x
    );
}
