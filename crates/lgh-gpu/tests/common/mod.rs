//! What the GPU tests share: the scenes they run on (each test file uses part of it).
#![allow(dead_code)]

use lgh_render::World;

/// The default scene (None) and the project's three test scenes.
pub const SCENES: [Option<&str>; 4] = [
    None,
    Some("test/two-rooms.toml"),
    Some("test/colonnade.toml"),
    Some("test/clutter.toml"),
];

pub fn world(rel: Option<&str>) -> World {
    let scene = match rel {
        None => {
            let mut s = lgh_scene::cornell::cornell_box();
            s.finish(std::path::Path::new("<built-in cornell>"))
                .expect("scene");
            s
        }
        Some(r) => {
            let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../scenes")
                .join(r);
            lgh_scene::load(&p).expect("scene")
        }
    };
    World::new(scene)
}
