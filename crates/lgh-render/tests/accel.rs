//! The BVH against a plain loop over all triangles, on random scenes and rays.

use glam::{Mat4, Vec3};
use lgh_render::accel::Accel;
use lgh_scene::Mesh;
use lgh_scene::mesh::Primitive;
use proptest::prelude::*;

/// Moller-Trumbore, written independently of the BVH's own triangle test.
fn brute_closest(mesh: &Mesh, o: Vec3, d: Vec3, t_max: f32) -> Option<(f32, usize)> {
    let mut best: Option<(f32, usize)> = None;
    for t in 0..mesh.len() {
        let [a, b, c] = mesh.vertices(t);
        let e1 = b - a;
        let e2 = c - a;
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-12 {
            continue;
        }
        let inv = 1.0 / det;
        let s = o - a;
        let u = s.dot(p) * inv;
        let q = s.cross(e1);
        let v = d.dot(q) * inv;
        let tt = e2.dot(q) * inv;
        let inside = u >= 0.0 && v >= 0.0 && u + v <= 1.0 && tt > 0.0 && tt < t_max;
        if inside && best.is_none_or(|(bt, _)| tt < bt) {
            best = Some((tt, t));
        }
    }
    best
}

fn random_mesh(coords: &[f32]) -> Mesh {
    let positions: Vec<Vec3> = coords
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    let n = positions.len() as u32 / 3;
    let prim = Primitive {
        positions,
        indices: (0..n).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect(),
        ..Default::default()
    };
    let mut m = Mesh::default();
    m.append(&prim, Mat4::IDENTITY);
    m
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn bvh_matches_brute_force(
        coords in prop::collection::vec(-1.0f32..1.0, 9 * 4..9 * 60),
        rays in prop::collection::vec((-2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0, -1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0), 32),
    ) {
        let mesh = random_mesh(&coords);
        let accel = Accel::build(&mesh);
        let mut disagreements = 0;
        for &(ox, oy, oz, dx, dy, dz) in &rays {
            let d = Vec3::new(dx, dy, dz);
            if d.length() < 1e-3 { continue; }
            let d = d.normalize();
            let o = Vec3::new(ox, oy, oz);
            let reference = brute_closest(&mesh, o, d, 10.0);
            let hit = accel.intersect(o, d, 10.0);
            match (reference, hit) {
                (None, None) => {}
                (Some((t, _)), Some(h)) => {
                    prop_assert!((t - h.t).abs() < 1e-3 * t.max(1.0), "t {} vs {}", t, h.t);
                    // The barycentrics reproduce the hit point.
                    let [a, b, c] = mesh.vertices(h.triangle as usize);
                    let p = a * (1.0 - h.bary.x - h.bary.y) + b * h.bary.x + c * h.bary.y;
                    prop_assert!((p - (o + d * h.t)).length() < 1e-3);
                }
                // Grazing hits on an edge may differ between two exact-enough tests.
                _ => disagreements += 1,
            }
            prop_assert_eq!(accel.occluded(o, d, 10.0), hit.is_some());
        }
        prop_assert!(disagreements <= 1, "{} rays disagree", disagreements);
    }
}

#[test]
fn occlusion_respects_t_max() {
    let mesh = random_mesh(&[-1.0, -1.0, 1.0, 1.0, -1.0, 1.0, 0.0, 1.0, 1.0]);
    let accel = Accel::build(&mesh);
    assert!(accel.occluded(Vec3::ZERO, Vec3::Z, 1.5));
    assert!(!accel.occluded(Vec3::ZERO, Vec3::Z, 0.5));
    let h = accel.intersect(Vec3::ZERO, Vec3::Z, 5.0).unwrap();
    assert!((h.t - 1.0).abs() < 1e-6);
    assert_eq!(h.triangle, 0);
}
