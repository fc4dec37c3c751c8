//! The camera a scene without one gets (`Scene::framing_camera`) sees a flat mesh at an
//! angle whichever axis it is flat along, and keeps the whole mesh in view.

use glam::Vec3;

/// The quadrilateral `corners` as an OBJ file (named `name` in a temporary folder) loaded
/// into a scene.
fn quad(name: &str, corners: [Vec3; 4]) -> lgh_scene::Scene {
    let obj = corners
        .iter()
        .map(|p| format!("v {} {} {}\n", p.x, p.y, p.z))
        .collect::<String>()
        + "f 1 2 3 4\n";
    let dir = std::env::temp_dir().join(format!("lgh-framing-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("quad.obj");
    std::fs::write(&path, obj).unwrap();
    let scene = lgh_scene::obj::load(&path);
    let _ = std::fs::remove_dir_all(&dir);
    scene.unwrap()
}

/// A unit square in the plane through the origin normal to `axis` (0 = x, 1 = y, 2 = z).
fn square(axis: usize) -> lgh_scene::Scene {
    let corner = |a: f32, b: f32| {
        let mut p = Vec3::ZERO;
        p[(axis + 1) % 3] = a;
        p[(axis + 2) % 3] = b;
        p
    };
    let corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)].map(|(a, b)| corner(a, b));
    quad(&format!("axis-{axis}"), corners)
}

#[test]
fn a_flat_mesh_is_never_seen_edge_on() {
    for axis in 0..3 {
        let scene = square(axis);
        let camera = scene.camera();
        let view = (camera.look_at - camera.position).normalize();
        let mut normal = Vec3::ZERO;
        normal[axis] = 1.0;
        // The cosine between the view and the square's normal: 0 is edge on.
        let cos = view.dot(normal).abs();
        assert!(cos > 0.3, "axis {axis}: cos {cos}");
        // The square's corners lie within the vertical field of view around the view
        // direction (the whole bounding sphere fits it).
        let half = (camera.fov_y_degrees.to_radians() * 0.5).cos();
        for &p in &scene.mesh.positions {
            let to = (p - camera.position).normalize();
            assert!(
                to.dot(view) >= half - 1e-5,
                "axis {axis}: corner {p} out of view"
            );
        }
    }
}

/// A square tilted so that the first view sees it nearly edge on is framed from another.
#[test]
fn a_tilted_flat_mesh_is_framed_from_the_view_that_sees_it() {
    // A square spanned by the first view's direction and a vector across it contains that
    // direction: the first view sees it edge on.
    let (turn, raise) = (30.0f32.to_radians(), 20.0f32.to_radians());
    let first = Vec3::new(
        turn.sin() * raise.cos(),
        raise.sin(),
        turn.cos() * raise.cos(),
    );
    let u = first;
    let v = first.cross(Vec3::Y).normalize();
    let camera = quad("tilted", [Vec3::ZERO, u, u + v, v]).camera();
    let view = (camera.look_at - camera.position).normalize();
    let normal = u.cross(v).normalize();
    let cos = view.dot(normal).abs();
    assert!(cos > 0.3, "cos {cos}");
}
