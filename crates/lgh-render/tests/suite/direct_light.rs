//! Direct light from area lights: the analytic estimator (closed-form unshadowed light times
//! the filtered shadow ratio, Heitz et al. 2018) against the sampled one.

use std::f32::consts::FRAC_1_PI;
use std::path::Path;

use glam::Vec3;
use lgh_render::direct::{DirectMode, analytic_emitters, analytic_indices, analytic_irradiance};
use lgh_render::image::metrics::diff;
use lgh_render::{Component, Frame, RenderSettings, World};
use lgh_scene::Material;

use crate::common;

/// The direct light of `world` at `width` x `height` (emission excluded from nothing: the
/// `direct` image holds the reflected direct light alone).
fn direct(world: &World, mode: DirectMode, samples: u32, seed: u64, size: (u32, u32)) -> Frame {
    let s = RenderSettings {
        width: size.0,
        height: size.1,
        vpls: 1,
        seed,
        direct: mode,
        area_samples: samples,
        component: Component::Direct,
        // Each pixel's shaded point, not the mean over its area (edge anti-aliasing).
        edge_samples: 1,
        ..RenderSettings::default()
    };
    common::render(world, &s)
}

/// A floor under a downward-facing square area light, nothing in between: every sample is
/// visible, so S = U in every pixel, the filtered ratio is exactly 1, and the direct light is
/// exactly albedo / pi x the closed-form irradiance, bit for bit.
#[test]
fn without_occluders_the_analytic_estimator_is_exact() {
    let mut scene = common::floor_scene(2.0, Vec3::splat(0.6));
    scene.materials.push(Material {
        albedo: Vec3::ZERO,
        emission: Vec3::new(4.0, 3.0, 2.0),
        ..Material::default()
    });
    // Facing down (counter-clockwise seen from below), off to one side of the camera.
    let (y, x0, x1, z0, z1) = (1.5, 0.3, 1.1, -0.6, 0.4);
    common::quad(
        &mut scene,
        [
            Vec3::new(x0, y, z0),
            Vec3::new(x1, y, z0),
            Vec3::new(x1, y, z1),
            Vec3::new(x0, y, z1),
        ],
        1,
    );
    scene.finish(Path::new("<test>")).unwrap();
    let world = World::new(scene);
    assert_eq!(world.lights.emitters.len(), 2);
    let f = direct(&world, DirectMode::Analytic, 8, 3, (48, 32));
    let analytic = analytic_indices(&analytic_emitters(&world.lights));
    let g = &f.gbuffer;
    let mut lit = 0;
    for i in 0..g.len() {
        if !g.is_hit(i) || g.normal[i].y < 0.99 {
            continue;
        }
        let e = analytic_irradiance(&world.lights, &analytic, g.position[i], g.normal[i]);
        let expected = g.albedo[i] * FRAC_1_PI * e;
        assert_eq!(f.direct.pixels[i], expected, "pixel {i}");
        lit += usize::from(expected.x > 0.0);
    }
    assert!(lit > 500, "{lit} lit floor pixels");
}

/// On the Cornell box (soft shadows of the blocks): the analytic estimator is consistent
/// with the converged sampled estimator. The image mean over 12 seeds agrees with the
/// reference (1024 samples a pixel) within 4 standard errors plus 0.5% (the filter's
/// blur of the penumbrae is the 0.5%); the mean image comes closer to the reference per
/// pixel than one frame does; and one frame of the analytic estimator is closer to the
/// reference than one frame of the sampled estimator at the same sample count.
#[test]
fn analytic_direct_light_converges_to_the_sampled_reference() {
    let world = common::cornell_world();
    let size = (64, 36);
    let reference = direct(&world, DirectMode::Sampled, 1024, 1000, size).direct;
    let mean = |img: &lgh_render::Image| {
        img.pixels
            .iter()
            .map(|p| f64::from(p.x + p.y + p.z))
            .sum::<f64>()
            / img.pixels.len() as f64
    };
    let ref_mean = mean(&reference);
    let seeds = 12;
    let mut means = Vec::new();
    let mut avg = vec![Vec3::ZERO; reference.pixels.len()];
    let mut first = None;
    for seed in 0..seeds {
        let f = direct(&world, DirectMode::Analytic, 8, seed, size);
        means.push(mean(&f.direct));
        for (a, p) in avg.iter_mut().zip(&f.direct.pixels) {
            *a += *p / seeds as f32;
        }
        first.get_or_insert(f.direct);
    }
    let (m, sd) = common::mean_std(&means);
    let se = sd / f64::from(seeds as u32).sqrt();
    eprintln!("analytic mean {m} +- {se}, reference {ref_mean}");
    assert!(
        (m - ref_mean).abs() < 4.0 * se + 0.005 * ref_mean,
        "{m} vs {ref_mean} (se {se})"
    );
    let first = first.unwrap();
    let one = diff(&first, &reference).unwrap().rel_rmse;
    let averaged = diff(
        &lgh_render::Image::from_pixels(size.0, size.1, avg),
        &reference,
    )
    .unwrap()
    .rel_rmse;
    let sampled = diff(
        &direct(&world, DirectMode::Sampled, 8, 0, size).direct,
        &reference,
    )
    .unwrap()
    .rel_rmse;
    eprintln!(
        "rel_rmse: one analytic frame {one}, mean of {seeds} {averaged}, one sampled {sampled}"
    );
    assert!(averaged < 0.7 * one, "{averaged} vs {one}");
    assert!(one < 0.8 * sampled, "analytic {one} vs sampled {sampled}");
}

/// Point and directional lights are exact and never filtered: with no area light the
/// analytic and sampled estimators give the same image, bit for bit.
#[test]
fn punctual_lights_are_untouched_by_the_estimator() {
    let mut scene = common::floor_scene(2.0, Vec3::splat(0.5));
    scene.lights.push(lgh_scene::Light::Point {
        position: Vec3::new(0.3, 1.0, 0.2),
        intensity: Vec3::splat(2.0),
    });
    scene.finish(Path::new("<test>")).unwrap();
    let world = World::new(scene);
    let a = direct(&world, DirectMode::Analytic, 8, 1, (32, 24));
    let s = direct(&world, DirectMode::Sampled, 8, 1, (32, 24));
    assert_eq!(a.direct, s.direct);
    assert!(a.direct.pixels.iter().any(|p| p.x > 0.0));
}

/// Past `EXACT_PUNCTUAL` lights, each pixel samples `PUNCTUAL_SAMPLES` of them by power: the
/// mean over many stratification offsets equals the exact sum (the sum of the scene's lights
/// one at a time), within 1% (fixed lights and points; the estimate's relative standard
/// error over 2000 offsets is below 0.3% here).
#[test]
fn many_punctual_lights_are_sampled_without_bias() {
    use lgh_render::direct::{EXACT_PUNCTUAL, punctual_irradiance};
    let mut scene = common::floor_scene(2.0, Vec3::splat(0.6));
    let n = 3 * EXACT_PUNCTUAL;
    let mut rng = lgh_core::rng::Rng::new(&[7]);
    let mut lights = Vec::new();
    for i in 0..n {
        let p = Vec3::new(
            rng.next_f32() * 4.0 - 2.0,
            0.5 + rng.next_f32(),
            rng.next_f32() * 4.0 - 2.0,
        );
        let power = 0.2 + 3.0 * rng.next_f32() * (i % 3) as f32;
        lights.push(lgh_scene::Light::Point {
            position: p,
            intensity: Vec3::new(power, 0.5 * power, 0.2),
        });
    }
    scene.lights = lights.clone();
    scene.finish(Path::new("<test>")).unwrap();
    let world = World::new(scene.clone());
    let (n_, ng) = (Vec3::Y, Vec3::Y);
    for p in [
        Vec3::ZERO,
        Vec3::new(1.2, 0.0, -0.7),
        Vec3::new(-1.5, 0.0, 1.5),
    ] {
        let exact: Vec3 = lights
            .iter()
            .map(|l| {
                let mut one = scene.clone();
                one.lights = vec![l.clone()];
                punctual_irradiance(&World::new(one), p, n_, ng, 0.5)
            })
            .sum();
        let m = 2000;
        let mean: Vec3 = (0..m)
            .map(|k| punctual_irradiance(&world, p, n_, ng, (k as f32 + 0.5) / m as f32))
            .sum::<Vec3>()
            / m as f32;
        let rel = ((mean - exact).abs() / exact).max_element();
        assert!(
            rel < 0.01,
            "at {p}: mean {mean} against exact {exact} ({rel})"
        );
    }
}
