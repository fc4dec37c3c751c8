//! Unshadowed irradiance from a polygonal Lambertian emitter in closed form: Lambert's
//! edge-integral formula (Lambert 1760; as used by Heitz, Hill & McGuire 2018 for the
//! analytic term of their ratio estimator, and by Arvo 1995).
//!
//! A polygon of constant radiance L seen from x with normal n, clipped to the hemisphere
//! n . w >= 0, gives the irradiance E = L x P, with P its projected solid angle
//! (the integral of n . w over the directions w it covers):
//!
//! P = 1/2 |sum_i theta_i n . g_i|, theta_i = angle(u_i, u_i+1), g_i = (u_i x u_i+1) / |u_i x u_i+1|
//!
//! where u_i are the unit directions from x to the clipped polygon's vertices in order (the
//! sum of each edge's contribution by Stokes' theorem).

use glam::Vec3;

/// The projected solid angle P of triangle `tri` seen from `x` with unit normal `n`: the part
/// of the triangle above the plane through x normal to n, weighted by the cosine to n. Zero
/// where nothing of the triangle is above that plane. One-sidedness is the caller's: this
/// counts the triangle from either side.
#[must_use]
pub fn projected_solid_angle(x: Vec3, n: Vec3, tri: [Vec3; 3]) -> f32 {
    // Clip against the receiver's tangent plane (Sutherland-Hodgman: a triangle cut by a
    // plane keeps at most 4 vertices). Vertices are taken relative to x.
    let mut poly = [Vec3::ZERO; 4];
    let mut m = 0;
    for k in 0..3 {
        let (a, b) = (tri[k] - x, tri[(k + 1) % 3] - x);
        let (da, db) = (n.dot(a), n.dot(b));
        if da >= 0.0 {
            poly[m] = a;
            m += 1;
        }
        if (da >= 0.0) != (db >= 0.0) {
            poly[m] = a + (b - a) * (da / (da - db));
            m += 1;
        }
    }
    if m < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for k in 0..m {
        let (ua, ub) = (
            poly[k].normalize_or_zero(),
            poly[(k + 1) % m].normalize_or_zero(),
        );
        let c = ua.cross(ub);
        let len = c.length();
        if len > 0.0 {
            // atan2 of the sine and cosine: accurate for short edges, where acos is not.
            let theta = len.atan2(ua.dot(ub));
            sum += theta * n.dot(c) / len;
        }
    }
    0.5 * sum.abs()
}

#[cfg(test)]
mod tests {
    use super::*;
    use lgh_core::rng::Rng;
    use std::f32::consts::PI;

    /// The projected solid angle by a midpoint rule over the triangle's area: the integral
    /// of max(0, n . w) max(0, |n_t . w|) / d^2 over a fine grid of sub-triangles.
    fn quadrature(x: Vec3, n: Vec3, [a, b, c]: [Vec3; 3]) -> f64 {
        let steps = 160;
        let nt = (b - a).cross(c - a);
        let area = f64::from(nt.length()) / 2.0;
        let nt = nt.normalize();
        let mut sum = 0.0;
        let cells = (steps * steps) as f64;
        for i in 0..steps {
            for j in 0..steps - i {
                // Two sub-triangles per cell of the barycentric grid (one at the diagonal).
                for (di, dj, up) in [(1.0 / 3.0, 1.0 / 3.0, true), (2.0 / 3.0, 2.0 / 3.0, false)] {
                    if !up && i + j + 1 >= steps {
                        continue;
                    }
                    let s = (i as f32 + di) / steps as f32;
                    let t = (j as f32 + dj) / steps as f32;
                    let p = a + (b - a) * s + (c - a) * t;
                    let d = p - x;
                    let d2 = d.length_squared();
                    let w = d / d2.sqrt();
                    let f = n.dot(w).max(0.0) * nt.dot(w).abs() / d2;
                    sum += f64::from(f);
                }
            }
        }
        sum * area / cells
    }

    /// Random triangles and receivers (some triangles partly below the receiver's horizon,
    /// some wholly): the closed form matches the quadrature within 0.2% of the value (plus
    /// 1e-5 absolute), for receivers at least 0.5 triangle sizes away.
    #[test]
    fn matches_numerical_integration() {
        let mut rng = Rng::new(&[21, 1]);
        let mut v = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
        let mut clipped = 0;
        for _ in 0..60 {
            let tri = [v(), v(), v()];
            let centre = (tri[0] + tri[1] + tri[2]) / 3.0;
            let size = (tri[1] - tri[0]).length().max((tri[2] - tri[0]).length());
            let dir = v().normalize();
            let x = centre + dir * (0.5 + 2.0 * v().x.abs()) * size;
            let n = v().normalize();
            let exact = projected_solid_angle(x, n, tri);
            let numeric = quadrature(x, n, tri) as f32;
            assert!(
                (exact - numeric).abs() <= 2e-3 * numeric + 1e-5,
                "closed form {exact}, quadrature {numeric}"
            );
            let above = tri.iter().filter(|&&p| n.dot(p - x) > 0.0).count();
            clipped += usize::from(above == 1 || above == 2);
        }
        assert!(clipped > 10, "{clipped} triangles cut by the horizon");
    }

    /// A receiver below the corner of a parallel rectangle a x b at height h (two triangles)
    /// has the textbook form factor F = (1 / 2 pi) (A / sqrt(1 + A^2) atan(B / sqrt(1 + A^2))
    /// + B / sqrt(1 + B^2) atan(A / sqrt(1 + B^2))), A = a / h, B = b / h, and P = pi F.
    #[test]
    fn is_exact_below_the_corner_of_a_rectangle() {
        for (a, b, h) in [(1.0f64, 1.0, 1.0), (2.0, 0.5, 0.3), (0.2, 3.0, 1.7)] {
            let (aa, bb) = (a / h, b / h);
            let (sa, sb) = ((1.0 + aa * aa).sqrt(), (1.0 + bb * bb).sqrt());
            let f = (aa / sa * (bb / sa).atan() + bb / sb * (aa / sb).atan())
                / (2.0 * std::f64::consts::PI);
            let (a, b, h) = (a as f32, b as f32, h as f32);
            let corners = [
                Vec3::new(0.0, h, 0.0),
                Vec3::new(a, h, 0.0),
                Vec3::new(a, h, b),
                Vec3::new(0.0, h, b),
            ];
            let p =
                projected_solid_angle(Vec3::ZERO, Vec3::Y, [corners[0], corners[1], corners[2]])
                    + projected_solid_angle(
                        Vec3::ZERO,
                        Vec3::Y,
                        [corners[0], corners[2], corners[3]],
                    );
            let expected = (std::f64::consts::PI * f) as f32;
            assert!(
                (p - expected).abs() < 1e-5,
                "{a} x {b} at {h}: {p} vs {expected}"
            );
        }
        // Nothing above the horizon, and an (almost) infinite plane overhead: 0 and pi.
        let low = [
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(0.0, -1.0, 1.0),
        ];
        assert_eq!(projected_solid_angle(Vec3::ZERO, Vec3::Y, low), 0.0);
        let big = 1e4;
        let sky = projected_solid_angle(
            Vec3::ZERO,
            Vec3::Y,
            [
                Vec3::new(-big, 1.0, -big),
                Vec3::new(big, 1.0, -big),
                Vec3::new(0.0, 1.0, big),
            ],
        );
        assert!((sky - PI).abs() < 1e-3, "{sky}");
    }
}
