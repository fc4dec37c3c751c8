//! The Embree backend against obvhs (built with the `embree` feature only; CI runs it): the
//! same closest hits and occlusion for random rays on every scene, the same brute-force
//! image, and a moving object rebuilt with Embree.

use glam::Vec3;
use lgh_core::rng::Rng;
use lgh_render::image::ImageFormat;
use lgh_render::image::metrics::{diff, display_bytes, flip_mean};
use lgh_render::methods::brute::BRUTE;
use lgh_render::world::accel::{Accel, AccelKind, BuildUse};
use lgh_render::{RenderSettings, World};
use lgh_scene::{Mesh, Scene};

use crate::common;

/// How the two backends compared on a set of rays.
#[derive(Debug, Default)]
struct Agreement {
    rays: usize,
    /// Hits at the same distance on different triangles: an edge shared by both, or
    /// coincident triangles (walls modelled twice), where either answer is right.
    ties: usize,
    /// Disagreements on rays that graze an edge or a segment's end (either answer is right
    /// to within rounding).
    grazing: usize,
    /// Disagreements elsewhere.
    wrong: usize,
}

/// Smallest barycentric coordinate of the hit: near 0 on an edge.
fn edge_distance(h: &lgh_render::world::accel::Hit) -> f32 {
    (1.0 - h.bary.x - h.bary.y).min(h.bary.x).min(h.bary.y)
}

/// Traces `n` random rays (origins uniform in the scene's box, directions uniform) and as
/// many random segments between points of the box through both backends.
fn compare(mesh: &Mesh, n: usize, seed: u64) -> Agreement {
    let a = Accel::build_with(mesh, AccelKind::Obvhs, BuildUse::Still).expect("obvhs");
    let e = Accel::build_with(mesh, AccelKind::Embree, BuildUse::Still).expect("embree");
    let (lo, hi) = mesh.bounds();
    let (lo, size) = (lo - 0.05 * (hi - lo), 1.1 * (hi - lo));
    let mut agree = Agreement::default();
    let mut rng = Rng::new(&[seed, 0xe4b]);
    let point =
        |rng: &mut Rng| lo + size * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    let eps = 1e-4;
    for _ in 0..n {
        let o = point(&mut rng);
        let d = lgh_core::sampling::uniform_sphere(rng.next_2d());
        agree.rays += 1;
        let (ha, he) = (
            a.intersect(o, d, f32::INFINITY),
            e.intersect(o, d, f32::INFINITY),
        );
        match (ha, he) {
            (None, None) => {}
            (Some(x), Some(y))
                if x.triangle == y.triangle && (x.t - y.t).abs() <= eps * x.t.max(1e-3) => {}
            // The same distance on another triangle: an edge shared by both, or overlapping
            // triangles.
            (Some(x), Some(y)) if (x.t - y.t).abs() <= eps * x.t.max(1e-3) => agree.ties += 1,
            (Some(h), None) | (None, Some(h)) if edge_distance(&h) < 1e-4 => agree.grazing += 1,
            _ => agree.wrong += 1,
        }
        // A segment to another point of the box.
        let b = point(&mut rng);
        let len = (b - o).length();
        if len < 1e-6 {
            continue;
        }
        let d = (b - o) / len;
        agree.rays += 1;
        if a.occluded(o, d, len) != e.occluded(o, d, len) {
            let near_end = ha.or(he).is_some_and(|h| (h.t - len).abs() <= eps * len);
            let first = a.intersect(o, d, len).or(e.intersect(o, d, len));
            let at_edge =
                first.is_some_and(|h| edge_distance(&h) < 1e-4 || (h.t - len).abs() <= eps * len);
            if near_end || at_edge {
                agree.grazing += 1;
            } else {
                agree.wrong += 1;
            }
        }
    }
    agree
}

fn assert_agree(name: &str, mesh: &Mesh, n: usize) {
    let r = compare(mesh, n, 7);
    eprintln!("{name}: {r:?}");
    assert!(
        r.wrong as f64 <= 1e-4 * r.rays as f64,
        "{name}: {} of {} rays disagree away from edges ({r:?})",
        r.wrong,
        r.rays
    );
}

fn cornell() -> Scene {
    common::cornell_scene()
}

#[test]
fn backends_agree_on_a_million_rays_of_the_builtin_and_test_scenes() {
    assert_agree("cornell", &cornell().mesh, 500_000);
    for t in [
        "test/two-rooms.toml",
        "test/colonnade.toml",
        "test/clutter.toml",
    ] {
        assert_agree(t, &common::project_scene(t).mesh, 500_000);
    }
}

#[test]
#[cfg_attr(
    not(lgh_scenes),
    ignore = "needs LGH_SCENES (the shared scenes folder)"
)]
fn backends_agree_on_a_million_rays_of_the_shared_scenes() {
    for t in ["sponza.toml", "conference.toml", "cornell-box.toml"] {
        assert_agree(t, &common::project_scene(t).mesh, 500_000);
    }
}

/// The brute force with Embree's shadow rays and with obvhs's, over the same VPLs: equal to
/// within FLIP 0.002 on the built-in Cornell box and the two-rooms scene.
#[test]
fn brute_force_images_agree() {
    let settings = RenderSettings {
        method: BRUTE,
        width: 64,
        height: 36,
        vpls: 3000,
        ..RenderSettings::default()
    };
    for (name, scene) in [
        ("cornell", cornell()),
        ("two-rooms", common::project_scene("test/two-rooms.toml")),
    ] {
        let images: Vec<_> = [AccelKind::Obvhs, AccelKind::Embree]
            .into_iter()
            .map(|k| {
                let w = World::with_accel(scene.clone(), k).expect("builds");
                assert_eq!(w.accel.kind(), k);
                crate::common::render(&w, &settings).image
            })
            .collect();
        let m = diff(&images[1], &images[0]).expect("same size");
        let bytes = |i| display_bytes(&images[i], ImageFormat::Exr, scene.exposure);
        let flip = flip_mean(&bytes(1), &bytes(0), 64, 36).expect("flip");
        eprintln!("{name}: {m:?}, FLIP {flip}");
        assert!(flip <= 0.002, "{name}: FLIP {flip}");
        assert!(m.rel_rmse <= 0.01, "{name}: {m:?}");
    }
}

/// A moving object rebuilds Embree's BVH (fast build) each time: hits agree with obvhs on the
/// posed mesh.
#[test]
fn moving_objects_rebuild_embree_too() {
    let mut scene = lgh_scene::cornell::cornell_moving_block();
    scene
        .finish(std::path::Path::new("<built-in cornell-moving-block>"))
        .expect("scene");
    let mut world = World::with_accel(scene, AccelKind::Embree).expect("embree");
    world.set_time(1.5).unwrap();
    assert_eq!(world.accel.kind(), AccelKind::Embree);
    let r = compare(&world.scene.mesh, 50_000, 3);
    assert!(r.wrong as f64 <= 1e-4 * r.rays as f64, "{r:?}");
    // The rebuilt Embree BVH is the posed mesh's: the same hits as obvhs built on it.
    let obvhs =
        Accel::build_with(&world.scene.mesh, AccelKind::Obvhs, BuildUse::Still).expect("obvhs");
    let mut rng = Rng::new(&[11]);
    let mut same = 0;
    for _ in 0..2000 {
        let o = Vec3::new(
            0.1 + 0.3 * rng.next_f32(),
            0.1 + 0.3 * rng.next_f32(),
            0.1 + 0.3 * rng.next_f32(),
        );
        let d = lgh_core::sampling::uniform_sphere(rng.next_2d());
        let (x, y) = (
            world.accel.intersect(o, d, 10.0),
            obvhs.intersect(o, d, 10.0),
        );
        same += usize::from(x.map(|h| h.triangle) == y.map(|h| h.triangle));
    }
    assert!(same >= 1995, "{same} of 2000");
}
