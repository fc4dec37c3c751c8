//! The same seed gives bit-identical images with 1 and 2 threads.

use crate::common;
use lgh_render::methods::brute::BRUTE;
use lgh_render::methods::lgh::{LGH, LghStats};
use lgh_render::methods::slc::{SLC, SlcStats};

use lgh_render::{RenderSettings, Silent, render_frame};

#[test]
fn one_and_two_threads_give_identical_images() {
    let world = common::cornell_world();
    let settings = RenderSettings {
        width: 64,
        height: 36,
        vpls: 3000,
        seed: 11,
        area_samples: 4,
        method: BRUTE,
        ..RenderSettings::default()
    };
    let a = common::render_on(&world, &settings, 1);
    let b = common::render_on(&world, &settings, 2);
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

/// The `lgh` method too (hierarchy build, binning, reservoirs, shadow rays, filter).
#[test]
fn lgh_is_identical_with_one_and_two_threads() {
    let world = common::cornell_world();
    let settings = RenderSettings {
        width: 64,
        height: 36,
        vpls: 20_000,
        seed: 3,
        area_samples: 2,
        method: LGH,
        ..RenderSettings::default()
    };
    let (a, b) = (
        common::render_on(&world, &settings, 1),
        common::render_on(&world, &settings, 2),
    );
    assert_eq!(a.image, b.image);
    assert_eq!(
        a.stats::<LghStats>().unwrap(),
        b.stats::<LghStats>().unwrap()
    );
}

/// The `slc` method with 4 x 4 interleaving and shadows (ranges, binning per sub-image,
/// reservoirs, blur, filter); a different frame seed gives a different image.
#[test]
fn slc_is_identical_with_one_and_two_threads() {
    let world = common::cornell_world();
    let mut settings = RenderSettings {
        width: 64,
        height: 36,
        vpls: 20_000,
        seed: 3,
        area_samples: 2,
        method: SLC,
        ..RenderSettings::default()
    };
    settings.tiling.interleave = Some(4);
    let (a, b) = (
        common::render_on(&world, &settings, 1),
        common::render_on(&world, &settings, 2),
    );
    assert_eq!(a.image, b.image);
    assert_eq!(
        a.stats::<SlcStats>().unwrap(),
        b.stats::<SlcStats>().unwrap()
    );
    settings.slc.frame_seed = 1;
    let c = common::render_on(&world, &settings, 2);
    assert_ne!(a.indirect, c.indirect);
}
