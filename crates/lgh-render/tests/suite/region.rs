//! Pieces of a frame (render farms): a region rendered alone equals the whole frame's pixels
//! bit for bit, and the pixels beyond its guard band are not shaded at all.

use lgh_render::region::{Region, guard_band};
use lgh_render::{RenderSettings, render_frame};

use crate::common;

#[test]
fn a_region_equals_the_whole_frame_and_shades_nothing_beyond_its_band() {
    let world = common::cornell_world();
    for method in [
        lgh_render::methods::lgh::LGH,
        lgh_render::methods::slc::SLC,
        lgh_render::methods::brute::BRUTE,
    ] {
        let mut s = RenderSettings {
            width: 320,
            height: 180,
            vpls: 500,
            method,
            ..RenderSettings::default()
        };
        s.tiling.interleave = Some(2);
        s.shadows.filter_passes = 3;
        let whole = render_frame(&world, &s, &lgh_render::Silent).unwrap();
        let region = Region::tile(5, 9, 320, 180).unwrap();
        let piece_settings = RenderSettings {
            region: Some(region),
            ..s.clone()
        };
        let band = guard_band(&piece_settings);
        assert!(band < 100, "{band}");
        let piece = render_frame(&world, &piece_settings, &lgh_render::Silent).unwrap();
        let grown = region.grown(band, 320, 180);
        let mut outside_lit = 0;
        for y in 0..180 {
            for x in 0..320 {
                let (a, b) = (piece.image.get(x, y), whole.image.get(x, y));
                if region.contains(x, y) {
                    assert_eq!(a, b, "{} at ({x}, {y})", method.name());
                } else if !grown.contains(x, y) && a != glam::Vec3::ZERO {
                    outside_lit += 1;
                }
            }
        }
        assert_eq!(
            outside_lit,
            0,
            "{}: pixels beyond the band were shaded",
            method.name()
        );
    }
}

#[test]
fn tiles_cut_the_frame_into_a_grid_once() {
    for (n, (w, h)) in [
        (4, (160, 90)),
        (9, (161, 91)),
        (6, (100, 40)),
        (7, (70, 30)),
    ] {
        let tiles: Vec<Region> = (1..=n).map(|i| Region::tile(i, n, w, h).unwrap()).collect();
        let area: u32 = tiles.iter().map(|t| t.width() * t.height()).sum();
        assert_eq!(area, w * h);
        for (i, a) in tiles.iter().enumerate() {
            assert!(tiles[..i].iter().all(|b| !a.overlaps(b)));
        }
    }
    assert_eq!(
        Region::tile(1, 4, 160, 90).unwrap(),
        Region {
            x0: 0,
            y0: 0,
            x1: 80,
            y1: 45
        }
    );
    assert!(Region::tile(0, 4, 160, 90).is_err());
    assert!(Region::tile(5, 4, 160, 90).is_err());
    assert!(Region::parse("1,2,3").is_err());
}

/// The same for `lgh` under 4 x 4 interleaving on the clutter scene, where pixels along the
/// boxes' edges fill their cut recombination windows (`lgh.fill_below`): the masks, the
/// guests' tile bounds and their sums near the region equal the whole frame's.
#[test]
fn a_region_with_filled_windows_equals_the_whole_frame() {
    let world = common::test_scene_world("clutter.toml");
    let mut s = RenderSettings {
        width: 160,
        height: 96,
        vpls: 4000,
        method: lgh_render::methods::lgh::LGH,
        ..RenderSettings::default()
    };
    s.tiling.interleave = Some(4);
    let whole = render_frame(&world, &s, &lgh_render::Silent).unwrap();
    let region = Region::tile(5, 9, 160, 96).unwrap();
    let piece = render_frame(
        &world,
        &RenderSettings {
            region: Some(region),
            ..s.clone()
        },
        &lgh_render::Silent,
    )
    .unwrap();
    let mut compared = 0;
    for y in 0..96 {
        for x in 0..160 {
            if region.contains(x, y) {
                assert_eq!(piece.image.get(x, y), whole.image.get(x, y), "({x}, {y})");
                compared += 1;
            }
        }
    }
    assert!(compared > 100, "{compared}");
}
