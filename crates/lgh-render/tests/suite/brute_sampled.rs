//! `brute-sampled` is an unbiased estimate of the brute force over the same VPLs: the mean of
//! many of its frames (independent strata, one VPL set) converges to the exact sum, its
//! error falls at least as fast as 1 / sqrt(rays), and its image does not depend on the
//! thread count.

use glam::Vec3;
use lgh_render::methods::brute::sampled::render_brute_sampled;
use lgh_render::methods::brute::{BRUTE_SAMPLED, render_brute};
use lgh_render::passes::gbuffer::GBuffer;
use lgh_render::passes::vpl_gen::{PathNumbers, generate_vpls};
use lgh_render::{RenderSettings, Silent};

use crate::common::{render_on, small_indirect, test_scene_world};

/// Luminance with the project's weights.
fn lum(c: Vec3) -> f64 {
    f64::from(lgh_core::color::luminance(c))
}

/// The two rooms (light through a doorway: half of the VPLs' light is occluded at many
/// pixels), 64 x 36, 3,000 VPLs: the exact brute force and `seeds` sampled frames of
/// `rays` rays, each with its own strata.
fn frames(rays: u32, seeds: u64) -> (Vec<Vec3>, Vec<Vec<Vec3>>, GBuffer) {
    let world = test_scene_world("two-rooms.toml");
    let (w, h) = (64, 36);
    let g = GBuffer::render(&world, &world.scene.camera().frame(w, h), w, h);
    let vpls = generate_vpls(&world, 3000, 3, 7, PathNumbers::Sobol).vpls;
    let eps = 0.01 * world.radius;
    let exact = render_brute(&world, &g, &vpls, eps, true, &Silent);
    let sampled = (0..seeds)
        .map(|seed| render_brute_sampled(&world, &g, &vpls, eps, rays, seed, &Silent))
        .collect();
    (exact, sampled, g)
}

/// The mean over 64 sets of strata (8 rays a pixel) equals the exact sum: over the whole
/// image and over each of 16 blocks of 16 x 9 pixels, within 4.5 standard errors (the
/// standard error estimated from the 64 frames' own spread; each block's sum is a mean of
/// 64 independent frames, near normal). A weight of c_j / p_j that missed the stratum's
/// mass, or strata that skip a VPL, fail it.
#[test]
fn the_mean_of_sampled_frames_is_the_brute_force() {
    let seeds = 64;
    let (exact, sampled, g) = frames(8, seeds);
    let mut checked = 0;
    for (bx, by) in (0..4).flat_map(|by| (0..4).map(move |bx| (bx, by))) {
        let pixels: Vec<usize> = (0..9)
            .flat_map(|y| (0..16).map(move |x| (by * 9 + y) * 64 + bx * 16 + x))
            .filter(|&i| g.is_hit(i))
            .collect();
        let want: f64 = pixels.iter().map(|&i| lum(exact[i])).sum();
        let sums: Vec<f64> = sampled
            .iter()
            .map(|f| pixels.iter().map(|&i| lum(f[i])).sum())
            .collect();
        let (mean, sd) = crate::common::mean_std(&sums);
        let se = sd / (seeds as f64).sqrt();
        assert!(
            (mean - want).abs() <= 4.5 * se + 1e-6 * want,
            "block ({bx}, {by}): mean {mean} vs exact {want}, standard error {se}"
        );
        checked += usize::from(want > 0.0);
    }
    assert!(checked >= 12, "only {checked} lit blocks");
    let want: f64 = exact.iter().map(|&c| lum(c)).sum();
    let totals: Vec<f64> = sampled
        .iter()
        .map(|f| f.iter().map(|&c| lum(c)).sum())
        .collect();
    let (mean, sd) = crate::common::mean_std(&totals);
    let se = sd / (seeds as f64).sqrt();
    eprintln!("total {mean} vs {want}, standard error {se}");
    assert!((mean - want).abs() <= 4.5 * se, "total {mean} vs {want}");
    // Visibility is sampled: the frames differ (a test that could not tell a copy of the
    // exact sum from an estimate would pass anything).
    assert!(sd > 1e-4 * want, "no spread: {sd}");
}

/// Four times the rays cut the squared error against the exact sum at least threefold
/// (1 / rays would be four; stratification can only help).
#[test]
fn more_rays_less_visibility_noise() {
    let mse = |rays: u32| {
        let (exact, sampled, _) = frames(rays, 4);
        sampled
            .iter()
            .flat_map(|f| {
                f.iter()
                    .zip(&exact)
                    .map(|(&a, &b)| (lum(a) - lum(b)).powi(2))
            })
            .sum::<f64>()
    };
    let (m4, m16) = (mse(4), mse(16));
    eprintln!(
        "squared error, 4 rays {m4}, 16 rays {m16}: ratio {}",
        m4 / m16
    );
    assert!(m4 / m16 >= 3.0, "4 rays {m4}, 16 rays {m16}");
}

/// The same seed gives the same image on one thread and on three.
#[test]
fn sampled_frames_do_not_depend_on_the_thread_count() {
    let world = test_scene_world("two-rooms.toml");
    let s = RenderSettings {
        brute_rays: 16,
        ..small_indirect(BRUTE_SAMPLED, 500)
    };
    let a = render_on(&world, &s, 1).image;
    let b = render_on(&world, &s, 3).image;
    assert_eq!(a.pixels, b.pixels);
    assert!(a.pixels.iter().any(|&p| p != Vec3::ZERO));
}
