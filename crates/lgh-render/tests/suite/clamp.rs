//! The 1/d^2 clamp that grows as VPLs get fewer (`--vpl-clamp`, docs/design.md "Clamps").

use lgh_render::methods::clamp_eps;
use lgh_render::methods::lgh::LGH;
use lgh_render::{Component, RenderSettings};

use crate::common;

/// eps = R max(0.01, min(C / sqrt(N), 0.05)): 0.04 R at 10,000 VPLs with the default C = 4,
/// the fixed 0.01 R from 160,000 VPLs and with C = 0, at most 0.05 R, and an accumulation of
/// F frames uses the clamp of all their VPLs.
#[test]
fn the_clamp_shrinks_with_the_vpls_to_the_fixed_one() {
    let s = RenderSettings::default();
    let eps = |s: &RenderSettings, n| clamp_eps(s, n, 2.0) / 2.0;
    assert!((eps(&s, 10_000) - 0.04).abs() < 1e-6);
    assert!((eps(&s, 160_000) - 0.01).abs() < 1e-6);
    assert!((eps(&s, 1_000_000) - 0.01).abs() < 1e-6);
    assert!((eps(&s, 100) - 0.05).abs() < 1e-6);
    assert!((eps(&s, 0) - 0.01).abs() < 1e-6);
    let fixed = RenderSettings {
        vpl_clamp: 0.0,
        ..RenderSettings::default()
    };
    assert!((eps(&fixed, 10_000) - 0.01).abs() < 1e-6);
    let frame = lgh_render::accumulate::frame_settings(&s, 3, 16);
    assert!((eps(&frame, 10_000) - eps(&s, 160_000)).abs() < 1e-6);
}

/// The brightest pixel along the junction of the Cornell box's back wall and ceiling,
/// against the median of its neighbours along the junction: a VPL on the ceiling that
/// lands near the wall lights the wall below it from a few eps and draws a dot.
fn junction_speckle(vpl_clamp: f32) -> f32 {
    let world = common::cornell_world();
    let s = RenderSettings {
        width: 320,
        height: 180,
        method: LGH,
        component: Component::Indirect,
        area_samples: 0,
        edge_samples: 1,
        vpl_clamp,
        ..RenderSettings::default()
    };
    let f = common::render(&world, &s);
    let g = &f.gbuffer;
    let (w, h) = (g.width as usize, g.height as usize);
    let forward = f.camera.forward;
    let back_wall = |i: usize| g.is_hit(i) && g.geo_normal[i].dot(forward) < -0.95;
    let ceiling = |i: usize| g.is_hit(i) && g.geo_normal[i].y < -0.95;
    // Per column, the luminance of the back wall's top pixel, just under the ceiling.
    let mut row: Vec<f32> = Vec::new();
    for x in 0..w {
        for y in 1..h {
            let i = y * w + x;
            if back_wall(i) && ceiling(i - w) {
                let p = f.indirect.pixels[i + w];
                row.push(p.x + p.y + p.z);
                break;
            }
        }
    }
    assert!(row.len() > 100, "the junction spans {} columns", row.len());
    let mut worst = 0.0f32;
    for (k, &v) in row.iter().enumerate() {
        let mut near: Vec<f32> = row[k.saturating_sub(6)..(k + 7).min(row.len())].to_vec();
        near.sort_by(f32::total_cmp);
        worst = worst.max(v / near[near.len() / 2].max(1e-6));
    }
    worst
}

/// The default image's junction of back wall and ceiling shows no dots (the newcomer's
/// finding of the quality issue): at 10,000 VPLs no pixel along it is more than 1.25 times
/// the median of its 13 neighbours with the default clamp (measured 1.06), where the fixed
/// clamp of the LGH authors (`--vpl-clamp 0`) gives dots above 1.4 (measured 1.67: the
/// test can fail).
#[test]
fn the_default_image_has_no_dots_along_the_junction() {
    let fixed = junction_speckle(0.0);
    let default = junction_speckle(lgh_render::settings::DEFAULT_VPL_CLAMP);
    assert!(
        fixed > 1.4,
        "the fixed clamp's dots are gone ({fixed}): the test cannot fail"
    );
    assert!(default < 1.25, "dots along the junction: {default}");
}
