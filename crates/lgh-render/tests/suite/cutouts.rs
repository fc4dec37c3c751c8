//! Alpha cut-outs (docs/design.md, "Alpha cut-outs"): a square held above a floor whose
//! left half is cut away by its texture's alpha is, to every ray of every tracer, the right
//! half alone: the same hits for rays, the same image for each method.

use glam::{Mat4, Vec2, Vec3};
use lgh_render::image::metrics::diff;
use lgh_render::methods::brute::BRUTE;
use lgh_render::world::accel::{AccelKind, BuildUse};
use lgh_render::{Method, RenderSettings, World};
use lgh_scene::mesh::Primitive;
use lgh_scene::texture::Wrap;
use lgh_scene::{Camera, Cutout, Cutouts, Light, Material, Scene, Texture};

use crate::common;

/// The square above the floor: y = 1, x and z in [x0, 1] (facing down), u = (x + 1) / 2.
fn square(scene: &mut Scene, x0: f32, material: u32) {
    let c = |x: f32, z: f32| Vec3::new(x, 1.0, z);
    let u = |x: f32| Vec2::new((x + 1.0) / 2.0, 0.5);
    let prim = Primitive {
        positions: vec![c(x0, -1.0), c(1.0, -1.0), c(1.0, 1.0), c(x0, 1.0)],
        uvs: vec![u(x0), u(1.0), u(1.0), u(x0)],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        material,
        ..Default::default()
    };
    scene.mesh.append(&prim, Mat4::IDENTITY, "square");
}

/// A floor of half-size 3 lit by a point light above a square at y = 1: with `cut`, the
/// whole square x in [-1, 1] with its left half (u < 0.5, x < 0) cut away by a 2 x 1
/// texture of alpha 0 and 1 (clamped: alpha is 1 from u = 0.5 on); without, the right
/// half alone. `opaque` keeps the texture but drops the cut-out.
fn scene(cut: bool, opaque: bool) -> Scene {
    let mut scene = common::floor_scene(3.0, Vec3::splat(0.7));
    scene.textures.push(
        Texture::from_srgb8(2, 1, 4, &[200, 200, 200, 0, 200, 200, 200, 255]).expect("texture"),
    );
    let cutout = Cutout::new(Some(0), [Wrap::Clamp; 2], 1.0, 0.5);
    scene.materials.push(Material {
        albedo: Vec3::new(0.8, 0.3, 0.2),
        cutout: (cut && !opaque).then_some(cutout),
        ..Material::default()
    });
    square(&mut scene, if cut { -1.0 } else { 0.0 }, 1);
    scene.lights.push(Light::Point {
        position: Vec3::new(-0.3, 2.5, 0.2),
        intensity: Vec3::splat(20.0),
    });
    scene.camera = Some(Camera {
        position: Vec3::new(0.5, 4.0, 3.5),
        look_at: Vec3::new(0.0, 0.3, 0.0),
        up: Vec3::Y,
        fov_y_degrees: 55.0,
    });
    scene
        .finish(std::path::Path::new("<cut-out square>"))
        .expect("scene");
    scene
}

/// Rays straight down through the square hit it where x > 0 and the floor where x < 0,
/// for every tracer of this build, for closest hits and for occlusion.
#[test]
fn rays_pass_through_the_cut_half() {
    let s = scene(true, false);
    let cutouts = Cutouts::of(&s).map(std::sync::Arc::new);
    assert_eq!(cutouts.as_ref().map(|c| c.len()), Some(2));
    for kind in AccelKind::available() {
        let a = lgh_render::world::accel::Accel::build_cut(
            &s.mesh,
            cutouts.clone(),
            kind,
            BuildUse::Still,
        )
        .expect("builds");
        assert_eq!(a.cut_out(), 2);
        for i in 0..40 {
            for j in 0..9 {
                let x = -0.975 + i as f32 * 0.05;
                let o = Vec3::new(x, 2.0, -0.9 + j as f32 * 0.2);
                let h = a.intersect(o, Vec3::NEG_Y, 10.0).expect("a hit");
                let want = if x > 0.0 { 1.0 } else { 2.0 };
                assert!((h.t - want).abs() < 1e-4, "{kind} at {o}: {h:?}");
                assert_eq!(a.occluded(o, Vec3::NEG_Y, 1.5), x > 0.0, "{kind} at {o}");
            }
        }
    }
}

/// The cut square renders as the half square alone (brute force, lgh and slc, direct and
/// indirect light, every tracer): rel_rmse within 0.01; the same square without its
/// cut-out differs by far more, so the comparison can fail.
#[test]
fn a_cut_square_renders_as_its_solid_half() {
    let methods: [Method; 3] = [
        BRUTE,
        lgh_render::methods::lgh::LGH,
        lgh_render::methods::slc::SLC,
    ];
    for kind in AccelKind::available() {
        let world = |cut, opaque| World::with_accel(scene(cut, opaque), kind).expect("builds");
        let (cut, half, opaque) = (world(true, false), world(false, false), world(true, true));
        for method in methods {
            let settings = RenderSettings {
                width: 64,
                height: 48,
                vpls: 2000,
                method,
                ..RenderSettings::default()
            };
            let img = |w: &World| common::render(w, &settings).image;
            let (c, h, o) = (img(&cut), img(&half), img(&opaque));
            let same = diff(&c, &h).expect("same size");
            let other = diff(&o, &h).expect("same size");
            eprintln!("{kind} {method:?}: cut {same:?}, opaque {other:?}");
            assert!(same.rel_rmse < 0.01, "{kind} {method:?}: {same:?}");
            assert!(other.rel_rmse > 0.1, "{kind} {method:?}: {other:?}");
        }
    }
}

/// The imperfect shadow maps' point cloud (slc's `--shadows ism`) has no point where the
/// square is cut away, about as many on its solid half as on the half square alone, and
/// the area of the surface that is there.
#[test]
fn the_point_cloud_skips_the_cut_half() {
    use lgh_render::methods::slc::ism::PointCloud;
    let (cut, half) = (
        World::new(scene(true, false)),
        World::new(scene(false, false)),
    );
    let n = 1 << 15;
    let (pc, ph) = (
        PointCloud::sample(&cut, n, 4),
        PointCloud::sample(&half, n, 4),
    );
    let on_square = |p: &PointCloud| p.position.iter().filter(|q| q.y > 0.5).count();
    assert!(pc.position.iter().all(|q| q.y < 0.5 || q.x >= -1e-4));
    let (a, b) = (on_square(&pc) as f64, on_square(&ph) as f64);
    // The half square is 2 of the 36 + 2 m^2: about 1,725 points; binomial noise ~40.
    assert!((a - b).abs() < 5.0 * b.sqrt(), "{a} against {b}");
    assert!(
        (pc.area / ph.area - 1.0).abs() < 0.01,
        "{} {}",
        pc.area,
        ph.area
    );
}
