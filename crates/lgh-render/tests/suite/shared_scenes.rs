//! Every scene file in `scenes/` loads and renders a small image, when `LGH_SCENES` names the
//! folder of the shared scenes (CI sets it; without it this test is ignored).

use std::path::PathBuf;

use lgh_render::image::metrics::mean_luminance;
use lgh_render::{RenderSettings, Silent, World, render_frame};

#[test]
#[cfg_attr(
    not(lgh_scenes),
    ignore = "needs LGH_SCENES (the shared scenes folder)"
)]
fn every_shared_scene_loads_and_renders() {
    assert!(crate::common::shared_scenes().is_dir());
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 4, "{files:?}");
    for f in files {
        let scene = lgh_scene::load(&f).unwrap_or_else(|e| panic!("{e}"));
        let world = World::new(scene);
        let settings = RenderSettings {
            width: 48,
            height: 27,
            vpls: 300,
            area_samples: 2,
            ..RenderSettings::default()
        };
        let frame = render_frame(&world, &settings, &Silent).unwrap();
        assert!(frame.image.pixels.iter().all(|p| p.is_finite()));
        assert!(mean_luminance(&frame.indirect) > 0.0, "{}", f.display());
        assert!(mean_luminance(&frame.image) > 0.0, "{}", f.display());
    }
}
