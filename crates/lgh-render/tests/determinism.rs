//! The same seed gives bit-identical images with 1 and 2 threads.

use std::path::Path;

use lgh_render::{Method, RenderSettings, Silent, World, render_frame};

#[test]
fn one_and_two_threads_give_identical_images() {
    let mut scene = lgh_scene::cornell::cornell_box();
    scene.finish(Path::new("<built-in>")).unwrap();
    let world = World::new(scene);
    let settings = RenderSettings {
        width: 64,
        height: 36,
        vpls: 3000,
        seed: 11,
        area_samples: 4,
        method: Method::Brute,
        ..RenderSettings::default()
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render_frame(&world, &settings, &Silent).unwrap())
    };
    let a = run(1);
    let b = run(2);
    assert_eq!(a.vpls.vpls, b.vpls.vpls);
    assert_eq!(a.image, b.image);
    assert_eq!(a.direct, b.direct);
    assert!(a.indirect.pixels.iter().any(|p| p.x > 0.0));
    // A different seed gives a different image.
    let c = render_frame(
        &world,
        &RenderSettings {
            seed: 12,
            ..settings.clone()
        },
        &Silent,
    )
    .unwrap();
    assert_ne!(a.indirect, c.indirect);
}
