//! `lgh`'s unbiased estimate (docs/design.md, "Unbiased estimate"): the mean of the image
//! agrees with the brute force over the same VPLs where the paper's estimate is biased (its
//! convergence pixel by pixel is in `accumulate.rs`).

use lgh_render::image::metrics::diff;
use lgh_render::methods::brute::BRUTE;
use lgh_render::methods::lgh::{Estimator, LGH, LghSettings};
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
