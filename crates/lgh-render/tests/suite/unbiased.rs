//! `lgh`'s unbiased estimate (docs/design.md, "Unbiased estimate"): the mean of the image
//! agrees with the brute force over the same VPLs where the paper's estimate is biased (its
//! convergence pixel by pixel is in `accumulate.rs`).

use lgh_render::image::ImageFormat;
use lgh_render::image::metrics::{diff, display_bytes, flip_mean};
use lgh_render::methods::brute::BRUTE;
use lgh_render::methods::lgh::{Estimator, LGH, LghSettings};
use lgh_render::settings::{ShadowFilter, ShadowSettings, Tiling};
use lgh_render::{Image, RenderSettings, World};

use crate::common;

/// The project's two rooms joined by a doorway (scenes/test/two-rooms.toml): a point light
/// in one room, the camera in the other, which only light through the doorway reaches.
fn two_rooms() -> World {
    common::test_scene_world("two-rooms.toml")
}

/// The indirect light of `method` at 80x45 with 3000 VPLs of seed `seed`.
fn render(world: &World, method: lgh_render::Method, lgh: LghSettings, seed: u64) -> Image {
    let s = RenderSettings {
        width: 80,
        height: 45,
        seed,
        lgh,
        ..common::small_indirect(method, 3000)
    };
    common::render(world, &s).indirect
}

/// The bias bound of the quality issue on a closed two-room scene: over three seeds the
/// mean rel_bias of `lgh` at its defaults against the brute force over the same VPLs is
/// within 3% (measured -0.2%: +0.9, -1.0, -0.6%), while the paper's estimate at the same
/// levels is at least 8% dark (measured -17%: light behind the dividing wall counts in A
/// and in U, and the shadow rays of the candidates from S_2 up decide the ratio of all).
#[test]
fn two_rooms_mean_is_within_three_percent() {
    let world = two_rooms();
    let (mut unbiased, mut paper) = (0.0, 0.0);
    for seed in 1..=3 {
        let reference = render(&world, BRUTE, LghSettings::default(), seed);
        let bias = |lgh| {
            diff(&render(&world, LGH, lgh, seed), &reference)
                .unwrap()
                .rel_bias
        };
        unbiased += bias(LghSettings::default()) / 3.0;
        paper += bias(LghSettings {
            estimator: Estimator::Paper,
            ..LghSettings::default()
        }) / 3.0;
    }
    eprintln!("two rooms, mean rel_bias: unbiased {unbiased:+.4}, paper {paper:+.4}");
    assert!(unbiased.abs() <= 0.03, "unbiased {unbiased}");
    assert!(paper < -0.08, "paper {paper}");
}

/// The shares of the unbiased estimate weigh each grid light by its geometry term at the
/// pixel (docs/design.md, "Unbiased estimate"), so that no sample drawn through a grid light
/// at a grazing angle weighs hundreds of times the pixel's mean. On the two rooms (160x90,
/// 10,000 VPLs, lgh's defaults) the mean FLIP against the brute force over the same VPLs
/// over three seeds is at most 0.084: measured 0.080 (0.0845, 0.0781, 0.0773), and 0.088
/// (0.0923, 0.0857, 0.0859) with shares by blending weight alone.
#[test]
fn geometry_weighted_shares_lower_the_error() {
    let world = two_rooms();
    let mut flip = 0.0;
    for seed in 1..=3 {
        let settings = |method| RenderSettings {
            width: 160,
            height: 90,
            seed,
            ..common::small_indirect(method, 10_000)
        };
        let bytes = |i: &Image| display_bytes(i, ImageFormat::Exr, world.scene.exposure);
        let reference = common::render(&world, &settings(BRUTE)).indirect;
        let image = common::render(&world, &settings(LGH)).indirect;
        flip += flip_mean(&bytes(&image), &bytes(&reference), 160, 90).expect("flip") / 3.0;
    }
    eprintln!("two rooms, 160x90, 10K VPLs: mean FLIP {flip:.4}");
    assert!(flip <= 0.084, "FLIP {flip}");
}

/// Lambda_i sums the shares of the two levels admitted at the VPL's own distance
/// (`Partition::admits`), so a sample drawn through a grid light of any other level must
/// weigh zero, or its light counts on top of the shares that already sum to one. Without
/// the filters and interleaving, with 16 samples a pixel and alpha 1 (where a centroid's
/// distance and its VPL's most often fall in different levels), the mean rel_bias over
/// three seeds against the brute force over the same VPLs is within 1.5%: measured -0.6%
/// (-0.8, -0.4, -0.6%), and +2.9% (+2.2, +3.3, +3.2%) when such samples keep their weight.
#[test]
fn samples_of_levels_not_admitted_weigh_nothing() {
    let world = two_rooms();
    let mut bias = 0.0;
    for seed in 0..3 {
        let settings = |method| RenderSettings {
            width: 80,
            height: 45,
            seed,
            lgh: LghSettings {
                alpha: 1.0,
                ..LghSettings::default()
            },
            shadows: ShadowSettings {
                samples: Some(16),
                filter: ShadowFilter::None,
                ..ShadowSettings::default()
            },
            tiling: Tiling {
                interleave: Some(1),
                ..Tiling::default()
            },
            ..common::small_indirect(method, 3000)
        };
        let reference = common::render(&world, &settings(BRUTE)).indirect;
        let image = common::render(&world, &settings(LGH)).indirect;
        bias += diff(&image, &reference).unwrap().rel_bias / 3.0;
    }
    eprintln!("two rooms, alpha 1, k = 16, no filters: mean rel_bias {bias:+.4}");
    assert!(bias.abs() <= 0.015, "rel_bias {bias}");
}
