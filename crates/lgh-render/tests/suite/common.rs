//! Scenes built in code and helpers shared by the tests.

use glam::{Mat4, Vec2, Vec3};
use lgh_scene::mesh::Primitive;
use lgh_scene::{Camera, Light, Material, Scene};

/// Adds an axis-aligned quad given by four corners (counter-clockwise from the front).
pub fn quad(scene: &mut Scene, corners: [Vec3; 4], material: u32) {
    let prim = Primitive {
        positions: corners.to_vec(),
        uvs: vec![Vec2::ZERO; 4],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        material,
        ..Default::default()
    };
    scene.mesh.append(&prim, Mat4::IDENTITY, "mesh");
}

/// The corners of a square of half-size `s` at y = 0 facing up.
pub fn floor_corners(s: f32) -> [Vec3; 4] {
    [
        Vec3::new(-s, 0.0, -s),
        Vec3::new(-s, 0.0, s),
        Vec3::new(s, 0.0, s),
        Vec3::new(s, 0.0, -s),
    ]
}

/// A square floor of half-size `s` at y = 0 facing up, albedo `albedo`, seen from above.
pub fn floor_scene(s: f32, albedo: Vec3) -> Scene {
    let mut scene = Scene::new("floor");
    scene.materials.push(Material {
        albedo,
        ..Material::default()
    });
    quad(&mut scene, floor_corners(s), 0);
    scene.camera = Some(Camera {
        position: Vec3::new(0.0, 3.0 * s, 0.0),
        look_at: Vec3::ZERO,
        up: Vec3::Z,
        fov_y_degrees: 40.0,
    });
    scene
}

/// A closed cube [-1, 1]^3 whose six faces face inwards, all of albedo `rho`, with a point
/// light of intensity `intensity` at the centre and the camera inside.
pub fn furnace_scene(rho: f32, intensity: Vec3) -> Scene {
    let mut scene = Scene::new("furnace");
    scene.materials.push(Material {
        albedo: Vec3::splat(rho),
        ..Material::default()
    });
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    // Each face listed counter-clockwise as seen from inside the cube.
    let faces = [
        [
            c(-1., -1., -1.),
            c(1., -1., -1.),
            c(1., -1., 1.),
            c(-1., -1., 1.),
        ], // floor
        [
            c(-1., 1., -1.),
            c(-1., 1., 1.),
            c(1., 1., 1.),
            c(1., 1., -1.),
        ], // ceiling
        [
            c(-1., -1., -1.),
            c(-1., -1., 1.),
            c(-1., 1., 1.),
            c(-1., 1., -1.),
        ], // x = -1
        [
            c(1., -1., -1.),
            c(1., 1., -1.),
            c(1., 1., 1.),
            c(1., -1., 1.),
        ], // x = 1
        [
            c(-1., -1., -1.),
            c(-1., 1., -1.),
            c(1., 1., -1.),
            c(1., -1., -1.),
        ], // z = -1
        [
            c(-1., -1., 1.),
            c(1., -1., 1.),
            c(1., 1., 1.),
            c(-1., 1., 1.),
        ], // z = 1
    ];
    for f in faces {
        quad(&mut scene, f, 0);
    }
    scene.lights.push(Light::Point {
        position: Vec3::ZERO,
        intensity,
    });
    scene.camera = Some(Camera {
        position: Vec3::new(0.0, 0.0, 0.9),
        look_at: Vec3::ZERO,
        up: Vec3::Y,
        fov_y_degrees: 90.0,
    });
    scene
}

/// Mean and sample standard deviation.
pub fn mean_std(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    let v = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, v.sqrt())
}

/// The built-in Cornell box, finished.
pub fn cornell_scene() -> lgh_scene::Scene {
    let mut scene = lgh_scene::cornell::cornell_box();
    scene
        .finish(std::path::Path::new("<built-in>"))
        .expect("the built-in scene is valid");
    scene
}

/// The built-in Cornell box, finished and prepared.
pub fn cornell_world() -> lgh_render::World {
    lgh_render::World::new(cornell_scene())
}

/// A scene of the project's `scenes/` folder (`rel` from there), loaded and finished.
pub fn project_scene(rel: &str) -> lgh_scene::Scene {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(rel);
    lgh_scene::load(&p).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// A test scene of `scenes/test/` (`file`), prepared.
pub fn test_scene_world(file: &str) -> lgh_render::World {
    lgh_render::World::new(project_scene(&format!("test/{file}")))
}

/// Renders a frame on a pool of `threads` threads.
pub fn render_on(
    world: &lgh_render::World,
    settings: &lgh_render::RenderSettings,
    threads: usize,
) -> lgh_render::Frame {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
        .install(|| lgh_render::render_frame(world, settings, &lgh_render::Silent))
        .expect("render")
}

/// Settings for the indirect light of `method` alone on a 48x32 image with `vpls` VPLs (no
/// area-light samples).
pub fn small_indirect(method: lgh_render::Method, vpls: usize) -> lgh_render::RenderSettings {
    lgh_render::RenderSettings {
        width: 48,
        height: 32,
        vpls,
        area_samples: 0,
        method,
        component: lgh_render::Component::Indirect,
        ..lgh_render::RenderSettings::default()
    }
}

/// The paper's LGH (Lin & Yuksel 2019): its shadow estimate, alpha 1, S_1 the lowest level
/// shaded (the project's defaults differ; docs/design.md, "Defaults"); with
/// [`no_interleave`] its tiling.
pub fn paper_lgh() -> lgh_render::methods::lgh::LghSettings {
    lgh_render::methods::lgh::LghSettings::paper()
}

/// No interleaved sampling (the paper's default; the project's `lgh` interleaves 4 x 4).
pub fn no_interleave() -> lgh_render::settings::Tiling {
    lgh_render::settings::Tiling {
        interleave: Some(1),
        ..Default::default()
    }
}

/// Renders a frame on the global pool.
pub fn render(world: &lgh_render::World, s: &lgh_render::RenderSettings) -> lgh_render::Frame {
    lgh_render::render_frame(world, s, &lgh_render::Silent).expect("render")
}

/// The folder of the shared scenes, from `LGH_SCENES`. Tests that need it are marked
/// `#[cfg_attr(not(lgh_scenes), ignore = "...")]` (build.rs sets the cfg when the variable
/// is set at build time), so without it they show as ignored, and CI fails on any ignored
/// test.
pub fn shared_scenes() -> std::path::PathBuf {
    std::path::PathBuf::from(std::env::var_os("LGH_SCENES").expect("LGH_SCENES is set"))
}
