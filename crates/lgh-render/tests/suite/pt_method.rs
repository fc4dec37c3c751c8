//! The many-area-light path tracer (Tokuyoshi & Harada 2016, section 5): light sampling by
//! stochastic light culling (tree, reservoir sampling, RIS, Eq. 10 density) is unbiased.

use crate::common;
use lgh_render::methods::pt::PT_CLAMPED;
use lgh_render::methods::pt::PT_SLC;
use lgh_render::methods::pt::PT_UNIFORM;

use lgh_render::methods::pt::PtSettings;
use lgh_render::{Component, Method, RenderSettings, Silent, World, render_frame};

fn room() -> World {
    let mut scene = lgh_scene::emitter_room::emitter_room(6);
    scene.finish(std::path::Path::new("<built-in>")).unwrap();
    World::new(scene)
}

/// Image total (sum of all channels) of one render.
fn total(world: &World, method: Method, seed: u64, spp: u32, error_bound: f32) -> f64 {
    let s = RenderSettings {
        width: 24,
        height: 16,
        seed,
        method,
        component: Component::Indirect,
        error_bound: Some(error_bound),
        pt: PtSettings {
            spp,
            ..PtSettings::default()
        },
        ..RenderSettings::default()
    };
    let f = render_frame(world, &s, &Silent).unwrap();
    f.image
        .pixels
        .iter()
        .map(|p| f64::from(p.x + p.y + p.z))
        .sum()
}

/// `pt-slc` (small k = 8 and ranges short enough that pixels see a few dozen of the 392
/// triangle lights, so reservoir sampling, RIS and the range roulette are all exercised) and
/// `pt-uniform` estimate the same image: over 10 independent seeds each, the image totals
/// agree within 4 combined standard errors. `pt-clamped`, even with ranges so short that a
/// point overlaps about one light, agrees too: light beyond a clamped range is still found by
/// BSDF sampling, whose MIS weight is then 1, so clamping costs variance, not energy (the
/// paper's darker clamped images come from light sampling alone).
#[test]
fn pt_slc_and_pt_uniform_converge_to_the_same_image() {
    let world = room();
    assert!(world.lights.emitters.len() > 300);
    let runs = |method: Method, eb: f32| -> Vec<f64> {
        (0..10)
            .map(|seed| total(&world, method, seed, 24, eb))
            .collect()
    };
    let eb = 0.002;
    let (ms, ss) = common::mean_std(&runs(PT_SLC, eb));
    let (mu, su) = common::mean_std(&runs(PT_UNIFORM, eb));
    let se = ((ss * ss + su * su) / 10.0).sqrt();
    eprintln!("pt-slc {ms} (sd {ss}), pt-uniform {mu} (sd {su}), combined se {se}");
    assert!(ss > 0.0 && su > 0.0);
    assert!((ms - mu).abs() < 4.0 * se, "{ms} vs {mu} (se {se})");
    assert!(se < 0.02 * mu, "too noisy to mean anything: se {se}");
    let (mc, sc) = common::mean_std(&runs(PT_CLAMPED, 500.0));
    let se_c = ((sc * sc + su * su) / 10.0).sqrt();
    eprintln!("pt-clamped {mc} (sd {sc})");
    assert!((mc - mu).abs() < 4.0 * se_c, "{mc} vs {mu} (se {se_c})");
}
