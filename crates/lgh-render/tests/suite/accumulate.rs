//! `--accumulate`: the mean of N frames with independent VPL sets converges.

use lgh_render::accumulate::render_accumulated;
use lgh_render::image::metrics::diff;
use lgh_render::methods::brute::BRUTE;
use lgh_render::methods::lgh::LGH;
use lgh_render::{FrameMemory, Image, RenderSettings, Silent, World};

use crate::common;

/// The indirect light of `method` accumulated over `n` frames (64x36, `vpls` a frame).
fn accumulated(world: &World, method: lgh_render::Method, vpls: usize, n: u32) -> Image {
    let s = RenderSettings {
        width: 64,
        height: 36,
        ..common::small_indirect(method, vpls)
    };
    render_accumulated(world, &s, n, &Silent, &mut FrameMemory::default())
        .unwrap()
        .indirect
}

/// The brute force accumulated over N frames of 500 VPLs is the brute force over their
/// union: its error against a 16,000-VPL brute force (accumulated over 16 frames, so
/// anti-aliased like the means) falls like 1 / sqrt(N) (VPL noise and aliasing);
/// asserted: N = 16 at most 0.4 of N = 1 (1 / sqrt(16) = 0.25, plus the reference's own
/// noise). And `lgh` accumulated over N frames converges to the brute force accumulated over
/// the same N (its estimate is unbiased, and the filters shrink as N grows): rel_rmse at
/// N = 16 below 0.35 of N = 1 and below 0.08 (the quality issue's target). Measured at 64x36
/// with 2000 VPLs a frame: 0.37 -> 0.040 when the bound was set at 0.3; since the ratio
/// estimator's stops on A (docs/design.md, "A-trous filter") 0.156 -> 0.047 (0.155 -> 0.047
/// with Embree's rays, 0.301 of N = 1): the single frame is far closer to the brute force,
/// and the a-trous weight on A keeps a little more noise in the one pass left at N = 16
/// (0.039 without it here; on the two rooms at 160x90 it lowers the 16-frame error, 0.039 ->
/// 0.037). The bound on the ratio is 0.35 since.
#[test]
fn accumulation_converges() {
    let world = common::cornell_world();
    // 16,000 VPLs as 16 frames of 1000: the same sub-pixel offsets as the N = 16 means, so
    // the reference is anti-aliased like them.
    let fine = accumulated(&world, BRUTE, 1000, 16);
    let e = |n| {
        diff(&accumulated(&world, BRUTE, 500, n), &fine)
            .unwrap()
            .rel_rmse
    };
    let (e1, e16) = (e(1), e(16));
    eprintln!("brute accumulated vs 16K VPLs: N=1 {e1}, N=16 {e16}");
    assert!(e16 < 0.4 * e1, "{e1} -> {e16}");
    let lgh = |n| {
        diff(
            &accumulated(&world, LGH, 2000, n),
            &accumulated(&world, BRUTE, 2000, n),
        )
        .unwrap()
        .rel_rmse
    };
    let (l1, l16) = (lgh(1), lgh(16));
    eprintln!("lgh vs brute, both accumulated: N=1 {l1}, N=16 {l16}");
    assert!(l16 < 0.35 * l1 && l16 < 0.08, "{l1} -> {l16}");
}

/// One accumulated frame is the plain render, and the mean is the same with 1 and 2
/// threads.
#[test]
fn accumulation_is_deterministic() {
    let world = common::cornell_world();
    let s = RenderSettings {
        width: 40,
        height: 24,
        ..common::small_indirect(LGH, 1500)
    };
    let plain = common::render(&world, &s);
    let one = render_accumulated(&world, &s, 1, &Silent, &mut FrameMemory::default()).unwrap();
    assert_eq!(one.image, plain.image);
    let pool = |t| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
    };
    let run = || render_accumulated(&world, &s, 3, &Silent, &mut FrameMemory::default()).unwrap();
    let (a, b) = (pool(1).install(run), pool(2).install(run));
    assert_eq!(a.image, b.image);
    assert_ne!(a.image, plain.image);
}

/// The direct light of `world` seen with `base` at 64x36, 4 x 4 supersampled: the same view
/// at 256x144 (pixel centres only), box-filtered.
fn supersampled(world: &World, base: &RenderSettings) -> Image {
    let big = lgh_render::render_frame(
        world,
        &RenderSettings {
            width: 256,
            height: 144,
            edge_samples: 1,
            ..base.clone()
        },
        &Silent,
    )
    .unwrap()
    .image;
    let mut pixels = vec![glam::Vec3::ZERO; 64 * 36];
    for y in 0..144 {
        for x in 0..256 {
            pixels[(y / 4) * 64 + x / 4] += big.get(x as u32, y as u32) / 16.0;
        }
    }
    Image::from_pixels(64, 36, pixels)
}

/// The direct light at 64x36 with 16 stratified area samples, sampled at pixel centres.
fn direct_64x36() -> RenderSettings {
    RenderSettings {
        width: 64,
        height: 36,
        component: lgh_render::Component::Direct,
        area_samples: 16,
        edge_samples: 1,
        ..RenderSettings::default()
    }
}

/// Frames of an accumulation sample their pixels at Roberts' R2 offsets, so the mean is
/// anti-aliased: the direct light of the Cornell box accumulated over 16 frames at 64x36 is
/// closer to a 4 x 4 supersampled reference than one frame at the pixel centres is:
/// rel_rmse at most 0.5 of one frame's (the box edges alias in one frame).
#[test]
fn accumulation_is_anti_aliased() {
    let world = common::cornell_world();
    let base = direct_64x36();
    let reference = supersampled(&world, &base);
    let mean = |n| {
        render_accumulated(&world, &base, n, &Silent, &mut FrameMemory::default())
            .unwrap()
            .image
    };
    let one = diff(&mean(1), &reference).unwrap().rel_rmse;
    let sixteen = diff(&mean(16), &reference).unwrap().rel_rmse;
    assert!(sixteen < 0.5 * one, "16 frames {sixteen} against one {one}");
    assert_eq!(lgh_render::accumulate::subpixel_jitter(0), glam::Vec2::ZERO);
}

/// One frame resolves its edges from sub-pixel rays (`--edge-samples`, the default 8):
/// against the 4 x 4 supersampled reference its rel_rmse is at most 0.5 of the frame
/// sampled at pixel centres on the Cornell box (silhouettes of boxes; measured 0.28), and
/// at most 0.75 on the test scene of two rooms (measured 0.59: the hard shadows of its
/// point light alias too, and they are no geometric edge); and an accumulation does not
/// resolve its frames (it jitters them).
#[test]
fn one_frame_resolves_its_edges() {
    let scenes = [
        ("cornell", common::cornell_world(), 0.5),
        (
            "two-rooms",
            common::test_scene_world("two-rooms.toml"),
            0.75,
        ),
    ];
    for (name, world, most) in scenes {
        let base = direct_64x36();
        let reference = supersampled(&world, &base);
        let frame = |edge_samples| {
            common::render(
                &world,
                &RenderSettings {
                    edge_samples,
                    ..base.clone()
                },
            )
        };
        let centres = diff(&frame(1).image, &reference).unwrap().rel_rmse;
        let resolved = frame(lgh_render::passes::edge_aa::DEFAULT_EDGE_SAMPLES);
        let aa = diff(&resolved.image, &reference).unwrap().rel_rmse;
        assert!(
            aa < most * centres,
            "{name}: resolved {aa} against centres {centres}"
        );
        assert!(resolved.timings.get("edge_aa").is_some());
    }
    let s = lgh_render::accumulate::frame_settings(&RenderSettings::default(), 1, 4);
    assert_eq!(s.edge_samples, 1);
}
