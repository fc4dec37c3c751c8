//! The brute-force indirect light converges like a Monte Carlo estimator: doubling the VPL
//! count halves its variance.

use std::path::Path;

use lgh_render::metrics::diff;
use lgh_render::{Component, Method, RenderSettings, Silent, World, render_frame};

/// Mean squared error against a 64k-VPL render, averaged over 8 seeds, for 1000 and 2000 VPLs.
/// The expected ratio is 2 (minus a little, because the reference has its own variance, 1/64
/// of the 1000-VPL one). With 8 seeds x 648 pixels, the ratio's spread is about +-0.3;
/// the accepted range is [1.5, 2.6].
#[test]
fn doubling_vpls_halves_the_variance() {
    let mut scene = lgh_scene::cornell::cornell_box();
    scene.finish(Path::new("<built-in>")).unwrap();
    let world = World::new(scene);
    let base = RenderSettings {
        width: 36,
        height: 18,
        area_samples: 0,
        method: Method::Brute,
        component: Component::Indirect,
        ..RenderSettings::default()
    };
    let render = |vpls: usize, seed: u64| {
        render_frame(
            &world,
            &RenderSettings {
                vpls,
                seed,
                ..base.clone()
            },
            &Silent,
        )
        .unwrap()
        .image
    };
    let reference = render(64_000, 1000);
    let mse = |vpls: usize| {
        (0..8)
            .map(|seed| diff(&render(vpls, seed), &reference).unwrap().rmse.powi(2))
            .sum::<f64>()
            / 8.0
    };
    let ratio = mse(1000) / mse(2000);
    eprintln!("variance ratio 1000 vs 2000 VPLs: {ratio:.3}");
    assert!((1.5..2.6).contains(&ratio), "variance ratio {ratio}");
}
