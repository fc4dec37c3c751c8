//! Furnace-style tests of the VPL energy: in a closed box of albedo rho lit by a point light of
//! power P, the VPLs of bounce b carry P rho^b in total.

use crate::common;

use std::path::Path;

use glam::Vec3;
use lgh_render::World;
use lgh_render::passes::vpl_gen::{PathNumbers, generate_vpls};

fn world(rho: f32, intensity: f32) -> World {
    let mut s = common::furnace_scene(rho, Vec3::splat(intensity));
    s.finish(Path::new("<test>")).unwrap();
    World::new(s)
}

/// One bounce involves no Russian roulette: every path's flux is exactly P / M x rho.
#[test]
fn one_bounce_carries_exactly_p_rho() {
    let w = world(0.5, 2.0);
    let p = 4.0 * std::f64::consts::PI * 2.0;
    let set = generate_vpls(&w, 5000, 1, 1, PathNumbers::Sobol);
    assert_eq!(set.vpls.len(), 5000);
    assert_eq!(set.paths, 5000);
    let total = set.vpls.total_flux().x as f64;
    assert!((total - p * 0.5).abs() < 1e-3 * p, "{total}");
}

/// Two and three bounces with Russian roulette: the mean over 24 seeds of the total flux is
/// within 4 standard errors of P (rho + rho^2 [+ rho^3]), and within 2%.
#[test]
fn multi_bounce_energy_is_a_geometric_series() {
    let rho = 0.6f64;
    let w = world(rho as f32, 1.0);
    let p = 4.0 * std::f64::consts::PI;
    for (bounces, expected) in [(2u32, rho + rho * rho), (3, rho + rho * rho + rho.powi(3))] {
        let totals: Vec<f64> = (0..24)
            .map(|seed| {
                generate_vpls(&w, 4000, bounces, seed, PathNumbers::Sobol)
                    .vpls
                    .total_flux()
                    .y as f64
            })
            .collect();
        let (m, s) = common::mean_std(&totals);
        let se = s / (totals.len() as f64).sqrt();
        let e = p * expected;
        assert!(
            (m - e).abs() < 4.0 * se && (m - e).abs() < 0.02 * e,
            "bounces {bounces}: mean {m}, expected {e}, std err {se}"
        );
    }
}
