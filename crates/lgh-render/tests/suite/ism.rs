//! Imperfect shadow maps with range-based point-cloud culling (Tokuyoshi & Harada 2016,
//! section 4.3, Program 1).

use crate::common;
use lgh_render::methods::brute::BRUTE;
use lgh_render::methods::slc::{SLC, SlcStats};
use lgh_render::settings::{ShadowSettings, Tiling};

use glam::Vec3;
use lgh_render::image::metrics::diff;
use lgh_render::methods::slc::SlcSettings;
use lgh_render::methods::slc::ism::{IsmSettings, PointCloud, ShadowMaps, keep_point};
use lgh_render::{Component, Frame, Method, RenderSettings, Silent, World, render_frame};

/// Program 1 keeps exactly the points that face away from the VPL, lie above its surface and
/// within its range.
#[test]
fn program_1_keeps_back_facing_points_above_the_vpl_within_range() {
    let (q, m) = (Vec3::ZERO, Vec3::Y);
    let p = Vec3::new(0.0, 1.0, 0.0);
    assert!(
        keep_point(p, Vec3::Y, q, m, 4.0),
        "back-facing, above, in range"
    );
    assert!(
        !keep_point(p, -Vec3::Y, q, m, 4.0),
        "faces the VPL: front-face culled"
    );
    assert!(!keep_point(p, Vec3::Y, q, m, 0.5), "beyond the range");
    assert!(
        !keep_point(-p, -Vec3::Y, q, m, 4.0),
        "below the VPL's surface"
    );
}

/// Maps built from VPLs on the Cornell box's surfaces agree with ray-traced visibility for
/// point pairs that face each other: measured 0.91 of lit pairs found lit and 0.81 of
/// shadowed pairs found shadowed (4096 points per map); the bounds are 0.85 and 0.7. An empty
/// map would score 1 and 0, a full one 0 and 1.
#[test]
fn maps_agree_with_ray_traced_visibility() {
    let world = common::cornell_world();
    let cloud = PointCloud::sample(&world, 1 << 16, 1);
    let vpls = PointCloud::sample(&world, 300, 2);
    let receivers = PointCloud::sample(&world, 400, 3);
    let range = vec![10.0; vpls.position.len()];
    let settings = IsmSettings {
        points_per_map: 4096,
        ..IsmSettings::default()
    };
    let maps = ShadowMaps::build(&cloud, &vpls.position, &vpls.normal, &range, &settings, 4);
    let (mut lit, mut lit_ok, mut dark, mut dark_ok) = (0, 0, 0, 0);
    for i in 0..vpls.position.len() {
        let (q, m) = (vpls.position[i], vpls.normal[i]);
        for r in 0..receivers.position.len() {
            let (x, n) = (receivers.position[r], receivers.normal[r]);
            let d = x - q;
            if d.dot(m) <= 1e-3 || d.dot(n) >= -1e-3 || d.length() < 0.05 {
                continue; // not facing each other, or too close to judge
            }
            let visible = !world.occluded_between(x, n, q, m);
            let found = maps.visible(i, x);
            if visible {
                lit += 1;
                lit_ok += usize::from(found);
            } else {
                dark += 1;
                dark_ok += usize::from(!found);
            }
        }
    }
    let (lit_rate, dark_rate) = (lit_ok as f64 / lit as f64, dark_ok as f64 / dark as f64);
    eprintln!(
        "lit pairs {lit}: {lit_rate:.3} found lit; shadowed pairs {dark}: {dark_rate:.3} found shadowed"
    );
    assert!(
        dark > 1000 && lit > 1000,
        "{lit} lit and {dark} shadowed pairs"
    );
    assert!(lit_rate > 0.85, "{lit_rate}");
    assert!(dark_rate > 0.7, "{dark_rate}");
}

fn slc(vpls: usize, ism: bool, shadow_samples: u32, method: Method) -> Frame {
    let world: World = common::cornell_world();
    let s = RenderSettings {
        width: 64,
        height: 40,
        vpls,
        area_samples: 0,
        method,
        component: Component::Indirect,
        tiling: Tiling {
            interleave: Some(1),
            ..Tiling::default()
        },
        shadows: ShadowSettings {
            samples: Some(shadow_samples),
            ..ShadowSettings::default()
        },
        slc: SlcSettings {
            ism,
            ..SlcSettings::default()
        },
        ..RenderSettings::default()
    };
    render_frame(&world, &s, &Silent).unwrap()
}

/// The culling makes the splatting sublinear (the paper's Fig. 7): with 8x the VPLs at the
/// same error bound, 8x the points are tested but, since the stochastic ranges shrink, far
/// fewer than 8x are splatted (measured: 1.7x; bound 5x).
#[test]
fn range_culling_makes_splatting_sublinear() {
    let points = |vpls| {
        let f = slc(vpls, true, 0, SLC);
        let s = f.stats::<SlcStats>().unwrap();
        (s.ism_points_tested.unwrap(), s.ism_points_splatted.unwrap())
    };
    let (t1, s1) = points(1000);
    let (t8, s8) = points(8000);
    eprintln!("1K VPLs: {t1} tested, {s1} splatted; 8K: {t8} tested, {s8} splatted");
    assert!((t8 as f64 / t1 as f64 - 8.0).abs() < 0.1);
    assert!(s1 > 0 && (s8 as f64) < 5.0 * s1 as f64);
}

/// Against brute force with exact shadows, the maps remove most of the unshadowed image's
/// excess light: measured relative bias +9.0% unshadowed, -2.2% with maps (bound: at most a
/// third of the unshadowed bias in size).
#[test]
fn shadow_maps_darken_slc_towards_the_shadowed_reference() {
    let reference = slc(2000, false, 0, BRUTE).image;
    let unshadowed = diff(&slc(2000, false, 0, SLC).image, &reference).unwrap();
    let maps = diff(&slc(2000, true, 0, SLC).image, &reference).unwrap();
    eprintln!("unshadowed {unshadowed:?}\nmaps {maps:?}");
    assert!(unshadowed.rel_bias > 0.05, "{unshadowed:?}");
    assert!(maps.rel_bias.abs() < unshadowed.rel_bias / 3.0, "{maps:?}");
}
