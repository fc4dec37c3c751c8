//! Stochastic light culling (Tokuyoshi & Harada 2016) against the brute force.

use crate::common;

use lgh_render::image::metrics::diff;
use lgh_render::methods::brute::{BRUTE, BRUTE_UNSHADOWED};
use lgh_render::methods::slc::{SLC, SLC_CLAMPED, SlcSettings, SlcStats};
use lgh_render::settings::{ShadowSettings, Tiling};
use lgh_render::{Frame, Image, Method, RenderSettings, World};

/// The indirect light of `method` (48x32, `vpls` VPLs) with `s`'s SLC, shadow and tiling
/// settings.
fn render(world: &World, method: Method, vpls: usize, s: RenderSettings) -> Frame {
    let s = RenderSettings { method, vpls, ..s };
    common::render(world, &s)
}

/// No interleaving, no shadows, and an error bound that cuts most ranges short: on this box,
/// with 2000 VPLs, a pixel evaluates about a quarter of them.
fn culled(frame_seed: u32, error_bound: f32) -> RenderSettings {
    RenderSettings {
        error_bound: Some(error_bound),
        tiling: Tiling {
            interleave: Some(1),
            ..Tiling::default()
        },
        shadows: ShadowSettings {
            samples: Some(0),
            ..ShadowSettings::default()
        },
        slc: SlcSettings {
            frame_seed,
            ..SlcSettings::default()
        },
        ..common::small_indirect(SLC, 0)
    }
}

/// The SLC statistics of a frame.
fn stats(f: &Frame) -> &SlcStats {
    f.stats::<SlcStats>().expect("slc statistics")
}

fn total(img: &Image) -> f64 {
    img.pixels.iter().map(|p| f64::from(p.x + p.y + p.z)).sum()
}

/// Unbiasedness (Eq. 2): over 48 frame seeds, the image total of `slc` is the brute-force
/// total within 4 standard errors of the mean (the seeds are independent; a single frame is
/// off by up to 20% here because all pixels share the lights' random ranges), and the
/// per-pixel average comes 3x closer to the reference than one frame.
#[test]
fn slc_converges_to_the_unshadowed_brute_force_over_frame_seeds() {
    let world = common::cornell_world();
    let reference = render(&world, BRUTE_UNSHADOWED, 2000, culled(0, 1.0)).image;
    let ref_total = total(&reference);
    let eb = 0.004;
    let seeds = 48;
    let mut totals = Vec::new();
    let mut mean = vec![glam::Vec3::ZERO; reference.pixels.len()];
    let mut first = None;
    let mut lights = 0.0;
    for fs in 0..seeds {
        let f = render(&world, SLC, 2000, culled(fs, eb));
        lights += stats(&f).avg_lights_per_pixel / f64::from(seeds);
        totals.push(total(&f.image));
        for (m, p) in mean.iter_mut().zip(&f.image.pixels) {
            *m += *p / seeds as f32;
        }
        first.get_or_insert(f.image);
    }
    let (m, sd) = common::mean_std(&totals);
    let se = sd / f64::from(seeds).sqrt();
    eprintln!(
        "slc total {m} +- {se} (sd {sd}), brute {ref_total}; lights per pixel {lights} of 2000"
    );
    assert!(lights < 1000.0, "the error bound should cull: {lights}");
    assert!(sd > 0.01 * ref_total, "the frames should differ: {sd}");
    assert!(
        (m - ref_total).abs() < 4.0 * se,
        "{m} vs {ref_total} (se {se})"
    );
    let one = diff(first.as_ref().unwrap(), &reference).unwrap().rel_rmse;
    let avg = diff(&Image::from_pixels(48, 32, mean), &reference)
        .unwrap()
        .rel_rmse;
    eprintln!("rel_rmse one frame {one}, mean of {seeds} frames {avg}");
    assert!(avg < one / 3.0, "{one} {avg}");
}

/// Clamped ranges (Appendix A) drop light beyond r_i: the image is darker than the brute
/// force, and by no more than the bound the ranges were made for, epsilon_max / E per pixel
/// and channel (Lambertian albedo <= 1).
#[test]
fn clamped_ranges_are_darker_within_their_error_bound() {
    let world = common::cornell_world();
    let reference = render(&world, BRUTE_UNSHADOWED, 2000, culled(0, 1.0)).image;
    // The clamped bound is N times tighter per light (Appendix A), so it needs a larger
    // epsilon_max than the stochastic ranges to cut inside this 0.55 m box.
    let eb = 0.2;
    let clamped = render(&world, SLC_CLAMPED, 2000, culled(0, eb));
    let lights = stats(&clamped).avg_lights_per_pixel;
    let m = diff(&clamped.image, &reference).unwrap();
    eprintln!("clamped: {m:?}, lights per pixel {lights}");
    assert!(lights < 1900.0, "the ranges should cut: {lights}");
    assert!(m.rel_bias < -0.005, "{m:?}");
    let worst = clamped
        .image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(a, b)| (*b - *a).max_element())
        .fold(f32::MIN, f32::max);
    let darkest = clamped
        .image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(a, b)| (*a - *b).max_element())
        .fold(f32::MIN, f32::max);
    assert!(worst <= eb * 1.001, "bias {worst} exceeds the bound {eb}");
    assert!(darkest <= 1e-6, "clamping never brightens: {darkest}");
}

/// Appendix A: at a fixed error bound the lights evaluated per pixel stay about constant
/// for the stochastic ranges (VPL intensity ~ 1/N, so alpha_i ~ N and the range area ~ 1/N)
/// while the clamped ranges do not shrink and the count grows with N. Measured here from
/// 1000 to 8000 VPLs: slc x1.5, clamped x8. (Each method keeps its own error bound fixed:
/// 0.004 for slc, 0.2 for clamped, whose ranges would otherwise exceed this small box.)
#[test]
fn stochastic_culling_cost_is_sublinear_and_clamped_linear() {
    let world = common::cornell_world();
    let lpp = |method: Method, n: usize| {
        let eb = if method == SLC { 0.004 } else { 0.2 };
        stats(&render(&world, method, n, culled(0, eb))).avg_lights_per_pixel
    };
    let (s1, s8) = (lpp(SLC, 1000), lpp(SLC, 8000));
    let (c1, c8) = (lpp(SLC_CLAMPED, 1000), lpp(SLC_CLAMPED, 8000));
    eprintln!("slc {s1} -> {s8}, clamped {c1} -> {c8}");
    assert!(s8 < 2.5 * s1, "stochastic: {s1} -> {s8}");
    assert!(c8 > 6.0 * c1, "clamped: {c1} -> {c8}");
}

/// With 4 x 4 interleaving every VPL is shaded by exactly one sub-image (with 16 times its
/// flux), so the image stays unbiased: over 24 frame seeds its total matches the
/// brute force within 4 standard errors plus 2% (interleaving adds per-pixel noise that the
/// blur spreads but does not remove).
#[test]
fn interleaved_slc_keeps_the_total() {
    let world = common::cornell_world();
    let reference = render(&world, BRUTE_UNSHADOWED, 2000, culled(0, 1.0)).image;
    let ref_total = total(&reference);
    let totals: Vec<f64> = (0..24)
        .map(|fs| {
            let s = RenderSettings {
                tiling: Tiling {
                    interleave: Some(4),
                    ..Tiling::default()
                },
                ..culled(fs, 0.004)
            };
            total(&render(&world, SLC, 2000, s).image)
        })
        .collect();
    let (m, sd) = common::mean_std(&totals);
    let se = sd / (totals.len() as f64).sqrt();
    eprintln!("interleaved total {m} +- {se}, brute {ref_total}");
    assert!(
        (m - ref_total).abs() < 4.0 * se + 0.02 * ref_total,
        "{m} vs {ref_total}"
    );
}

/// Shadowed SLC goes through the same ratio estimator as LGH: shadows darken the image (the
/// box's blocks occlude) towards the brute force with exact shadows.
#[test]
fn shadowed_slc_approaches_the_shadowed_brute_force() {
    let world = common::cornell_world();
    let brute = render(&world, BRUTE, 2000, culled(0, 1.0)).image;
    let unshadowed = render(&world, BRUTE_UNSHADOWED, 2000, culled(0, 1.0)).image;
    let s = RenderSettings {
        shadows: ShadowSettings::default(),
        ..culled(0, 0.0005)
    };
    let f = render(&world, SLC, 2000, s);
    assert!(stats(&f).shadow_rays > 0);
    let shadowed = diff(&f.image, &brute).unwrap();
    let vs_unshadowed = diff(&f.image, &unshadowed).unwrap();
    eprintln!("vs brute {shadowed:?}; vs unshadowed {vs_unshadowed:?}");
    assert!(shadowed.rel_bias.abs() < 0.05, "{shadowed:?}");
    assert!(vs_unshadowed.rel_bias < -0.05, "{vs_unshadowed:?}");
    assert!(shadowed.rel_rmse < vs_unshadowed.rel_rmse, "{shadowed:?}");
}
