//! Frame sequences: animation, determinism, temporal filtering.

use lgh_render::denoise::temporal::{TemporalSettings, TemporalTarget};
use lgh_render::methods::lgh::LGH;
use lgh_render::sequence::{Sequence, flicker};
use lgh_render::{Component, Frame, RenderSettings, Silent, World};

fn moving_light_world() -> World {
    let mut scene = lgh_scene::cornell::cornell_moving_light();
    scene.finish(std::path::Path::new("<built-in>")).unwrap();
    World::new(scene)
}

fn settings(seed: u64) -> RenderSettings {
    RenderSettings {
        width: 64,
        height: 36,
        vpls: 3000,
        seed,
        area_samples: 1,
        method: LGH,
        ..RenderSettings::default()
    }
}

/// Renders frames 0..3 at 1 frame per second with the temporal filter.
fn three_frames() -> Vec<Frame> {
    let mut world = moving_light_world();
    let mut seq = Sequence::new(Some(TemporalSettings::default()));
    (0..3)
        .map(|f| {
            world.set_time(f as f32).unwrap();
            seq.render(&world, &settings(10 + f), &Silent).unwrap()
        })
        .collect()
}

/// The same seed gives the same three frames (VPLs regenerated, hierarchy rebuilt, temporal
/// history carried), and the moving light changes the image from frame to frame.
#[test]
fn an_animated_sequence_is_deterministic_and_moves() {
    let (a, b) = (three_frames(), three_frames());
    for (fa, fb) in a.iter().zip(&b) {
        assert_eq!(fa.image, fb.image);
    }
    // The light goes from x = 0.08 to 0.48, which the camera (looking along +z) sees from
    // right to left: the image's right half gets darker, the left brighter.
    let half = |f: &Frame, left: bool| -> f64 {
        let w = f.image.width as usize;
        f.direct
            .pixels
            .iter()
            .enumerate()
            .filter(|(i, _)| (i % w < w / 2) == left)
            .map(|(_, p)| f64::from(p.x + p.y + p.z))
            .sum()
    };
    assert!(half(&a[2], true) > 1.2 * half(&a[0], true));
    assert!(half(&a[0], false) > 1.2 * half(&a[2], false));
}

/// A static view with VPLs regenerated every frame flickers. The flicker has two shares: the
/// unshadowed lighting A (measured with shadows off) and the shadow ratio. With the paper's
/// LGH, the paper's shadow-ratio filter removes at least 3/4 of the ratio's share (it cannot
/// touch A's); with its history clamped to the filtered ratio's neighbourhood it removed
/// about a third. The filter on the whole indirect light (alpha 0.1) cuts the flicker at
/// least 3x, with the paper's LGH and with the defaults (whose ratio also carries the
/// correction of A, so that the ratio filter alone calms less of it).
#[test]
fn temporal_filtering_reduces_flicker() {
    let mut world = World::new({
        let mut s = lgh_scene::cornell::cornell_box();
        s.finish(std::path::Path::new("<built-in>")).unwrap();
        s
    });
    world.set_time(0.0).unwrap();
    let run = |taa: Option<TemporalSettings>, shadow_samples: u32, paper: bool| {
        let mut seq = Sequence::new(taa);
        let mut prev: Option<Vec<glam::Vec3>> = None;
        let mut total = 0.0;
        for f in 0..8u64 {
            let mut s = RenderSettings {
                component: Component::Indirect,
                area_samples: 0,
                ..settings(100 + f)
            };
            s.shadows.samples = Some(shadow_samples);
            if paper {
                s.lgh = crate::common::paper_lgh();
                s.tiling = crate::common::no_interleave();
            }
            let frame = seq.render(&world, &s, &Silent).unwrap();
            if let Some(p) = &prev {
                total += flicker(p, &frame.indirect.pixels);
            }
            prev = Some(frame.indirect.pixels);
        }
        total / 7.0
    };
    let k = RenderSettings::default().shadow_samples();
    let indirect_taa = TemporalSettings {
        target: TemporalTarget::Indirect,
        ..TemporalSettings::default()
    };
    let without = run(None, k, true);
    let unshadowed = run(None, 0, true);
    let ratio = run(Some(TemporalSettings::default()), k, true);
    let indirect = run(Some(indirect_taa), k, true);
    eprintln!(
        "flicker without {without}, of A alone {unshadowed}, ratio TAA {ratio}, indirect TAA {indirect}"
    );
    assert!(without > 0.01, "{without}");
    assert!(unshadowed < without, "{unshadowed} vs {without}");
    assert!(
        ratio - unshadowed < 0.25 * (without - unshadowed),
        "ratio TAA {ratio}, A alone {unshadowed}, without {without}"
    );
    let (without_d, indirect_d) = (run(None, k, false), run(Some(indirect_taa), k, false));
    eprintln!("defaults: flicker without {without_d}, indirect TAA {indirect_d}");
    assert!(indirect_d < without_d / 3.0, "{indirect_d} vs {without_d}");
    assert!(indirect < without / 3.0, "{indirect} vs {without}");
}

/// A rigidly moving object: the same seed gives the same frames (mesh posed, BVH rebuilt,
/// VPLs regenerated), and the block's motion changes the image.
#[test]
fn a_moving_object_sequence_is_deterministic_and_moves() {
    let run = || {
        let mut scene = lgh_scene::cornell::cornell_moving_block();
        scene.finish(std::path::Path::new("<built-in>")).unwrap();
        let mut world = World::new(scene);
        let mut seq = Sequence::new(None);
        [0.0f32, 2.0]
            .iter()
            .map(|&t| {
                world.set_time(t).unwrap();
                seq.render(&world, &settings(3), &Silent).unwrap()
            })
            .collect::<Vec<_>>()
    };
    let (a, b) = (run(), run());
    for (fa, fb) in a.iter().zip(&b) {
        assert_eq!(fa.image, fb.image);
    }
    let changed = a[0]
        .image
        .pixels
        .iter()
        .zip(&a[1].image.pixels)
        .filter(|(p, q)| (**p - **q).abs().max_element() > 0.05 * p.max_element().max(1e-3))
        .count();
    assert!(
        changed > a[0].image.pixels.len() / 20,
        "only {changed} pixels changed"
    );
}

/// A frame handed back with `recycle` lends its G-buffer planes to the next frame, which must
/// not change that frame, even after a frame of another size or a different view.
#[test]
fn recycled_frames_do_not_change_the_next_ones() {
    let mut world = moving_light_world();
    let mut seq = Sequence::new(None);
    for (f, (w, h)) in [(64, 36), (64, 36), (40, 30), (64, 36)]
        .into_iter()
        .enumerate()
    {
        world.set_time(f as f32 * 0.7).unwrap();
        let s = RenderSettings {
            width: w,
            height: h,
            ..settings(f as u64)
        };
        let frame = seq.render(&world, &s, &Silent).unwrap();
        let fresh = lgh_render::render_frame(&world, &s, &Silent).unwrap();
        assert_eq!(frame.image, fresh.image, "frame {f}");
        assert_eq!(frame.gbuffer.depth, fresh.gbuffer.depth, "frame {f}");
        seq.recycle(frame);
    }
}

/// A frame whose camera and geometry are those of the G-buffer handed back reuses its planes
/// as they are (a viewer whose light moves): a mark left in them survives. A moved camera,
/// or a G-buffer whose view is unknown, is traced again and equals a fresh one.
#[test]
fn the_gbuffer_is_reused_only_for_the_same_view() {
    use lgh_render::FrameMemory;
    use lgh_render::passes::gbuffer::GBuffer;
    let mut world = moving_light_world();
    let s = settings(3);
    let mut memory = FrameMemory::default();
    let render = |world: &World, memory: &mut FrameMemory| {
        lgh_render::render_frame_with(world, &s, &Silent, memory).unwrap()
    };
    let fresh = |world: &World, g: &GBuffer| {
        let camera = world.scene.camera().frame(s.width, s.height);
        let f = GBuffer::render(world, &camera, s.width, s.height);
        (&f.position, &f.normal, &f.albedo, &f.depth, &f.emission)
            == (&g.position, &g.normal, &g.albedo, &g.depth, &g.emission)
    };
    let mark = glam::Vec3::splat(7.0);
    let mut g = render(&world, &mut memory).gbuffer;
    assert!(fresh(&world, &g));
    g.albedo[0] = mark;
    memory.recycle_gbuffer(g);
    // The light moves, the camera stays: the planes are reused, mark and all.
    let camera = world.scene.camera();
    let lights = world.scene.lights.clone();
    let mut turned = lights.clone();
    for l in &mut turned {
        if let lgh_scene::Light::Point { position, .. } = l {
            position.x += 0.1;
        }
    }
    world.set_view(camera.clone(), turned);
    let mut g = render(&world, &mut memory).gbuffer;
    assert_eq!(g.albedo[0], mark);
    // With the view unknown, traced again.
    g.view = None;
    memory.recycle_gbuffer(g);
    let g = render(&world, &mut memory).gbuffer;
    assert!(fresh(&world, &g));
    let mut g = g;
    g.albedo[0] = mark;
    memory.recycle_gbuffer(g);
    // The camera moves: traced again.
    let mut moved = camera;
    moved.position += glam::Vec3::new(0.1, 0.05, 0.0);
    world.set_view(moved, lights);
    let g = render(&world, &mut memory).gbuffer;
    assert!(fresh(&world, &g));
    assert_ne!(g.albedo[0], mark);
}
