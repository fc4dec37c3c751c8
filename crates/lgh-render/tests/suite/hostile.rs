//! Geometry and lights that invite division by zero: no NaN or Inf may reach an image or the
//! statistics, whatever the method.

use glam::Vec3;
use lgh_render::methods::Illumination;
use lgh_render::{METHODS, RenderSettings, World};
use lgh_scene::{Light, Material, Scene};

use crate::common::{floor_corners, floor_scene, quad, render};

/// A floor with a second floor coincident with it (z-fighting), a sliver triangle just above
/// the zero-area cut, a tiny emissive triangle (an area light of area 1e-10), a point light
/// lying on the floor, one at the camera, and a zero-power light.
fn hostile_scene() -> Scene {
    let mut scene = floor_scene(1.0, Vec3::splat(0.7));
    quad(&mut scene, floor_corners(1.0), 0);
    scene.materials.push(Material {
        emission: Vec3::splat(1e6),
        ..Material::default()
    });
    let tiny = 1e-5;
    quad(
        &mut scene,
        [
            Vec3::new(0.2, 0.5, 0.2),
            Vec3::new(0.2 + tiny, 0.5, 0.2),
            Vec3::new(0.2 + tiny, 0.5, 0.2 + tiny),
            Vec3::new(0.2, 0.5, 0.2 + tiny),
        ],
        1,
    );
    quad(
        &mut scene,
        [
            Vec3::new(-0.5, 0.3, 0.0),
            Vec3::new(0.5, 0.3, 0.0),
            Vec3::new(0.5, 0.3 + 1e-6, 1e-6),
            Vec3::new(-0.5, 0.3, 1e-6),
        ],
        0,
    );
    let camera = scene.camera.clone().map_or(Vec3::Y, |c| c.position);
    scene.lights.extend([
        Light::Point {
            position: Vec3::new(0.1, 0.0, -0.1),
            intensity: Vec3::splat(5.0),
        },
        Light::Point {
            position: camera,
            intensity: Vec3::splat(5.0),
        },
        Light::Point {
            position: Vec3::new(0.0, 1.0, 0.0),
            intensity: Vec3::ZERO,
        },
    ]);
    scene.finish(std::path::Path::new("<hostile>")).unwrap();
    scene
}

#[test]
fn degenerate_geometry_and_lights_give_finite_images_and_stats_with_every_method() {
    let scene = hostile_scene();
    assert!(
        scene
            .report
            .warnings
            .iter()
            .any(|w| w.contains("zero power")),
        "{:?}",
        scene.report.warnings
    );
    let world = World::new(scene);
    for &method in METHODS {
        for interleave in [None, Some(2)] {
            let s = RenderSettings {
                width: 24,
                height: 16,
                vpls: 400,
                method,
                pt: lgh_render::methods::pt::PtSettings {
                    spp: 2,
                    ..Default::default()
                },
                tiling: lgh_render::settings::Tiling {
                    interleave,
                    ..Default::default()
                },
                ..RenderSettings::default()
            };
            let frame = render(&world, &s);
            let name = method.name();
            assert!(
                frame.image.pixels.iter().all(|p| p.is_finite()),
                "{name}: non-finite pixel"
            );
            // (The path tracers shade area lights only, and this one is tiny.)
            if method.illumination() == Illumination::FromVpls {
                assert!(
                    frame.image.pixels.iter().any(|p| p.max_element() > 0.0),
                    "{name}"
                );
            }
            // The statistics are JSON numbers (serde_json writes NaN as null; none may be).
            if let Some(stats) = &frame.method.stats {
                let json = stats.to_json().to_string();
                assert!(!json.contains("null"), "{name}: {json}");
            }
            for (pass, ms) in &frame.timings.0 {
                assert!(ms.is_finite(), "{name}: {pass}");
            }
        }
    }
}
