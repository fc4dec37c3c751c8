//! A pinhole camera.

use glam::{Vec2, Vec3};

/// The vertical field of view, in degrees, of a camera that does not give one: a scene
/// file's `[camera]` without `fov`, and the camera that frames a scene without any.
pub const DEFAULT_FOV_DEGREES: f32 = 45.0;

/// Pinhole camera: position, the point it looks at, the up vector and the vertical field of
/// view in degrees. The image's aspect ratio comes from the render size.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub position: Vec3,
    /// A point the camera looks at (the image centre).
    pub look_at: Vec3,
    /// Approximate up direction.
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_degrees: f32,
}

/// A camera set up for one image size: maps pixel positions to ray directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraFrame {
    /// Eye position.
    pub origin: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    right: Vec3,
    up: Vec3,
    scale: Vec2,
    size: Vec2,
    /// Offset of every pixel's sample point from its centre, in pixels (zero: the centre).
    jitter: Vec2,
}

impl Camera {
    /// True if the camera is usable: finite numbers, a viewing direction, an up vector not
    /// parallel to it and a field of view in (0, 180).
    #[must_use]
    pub fn is_valid(&self) -> bool {
        let f = self.look_at - self.position;
        self.position.is_finite()
            && self.look_at.is_finite()
            && self.up.is_finite()
            && f.length() > 0.0
            && f.normalize().cross(self.up.normalize_or_zero()).length() > 1e-4
            && self.fov_y_degrees > 0.0
            && self.fov_y_degrees < 180.0
    }

    /// The frame for a `width` x `height` image.
    #[must_use]
    pub fn frame(&self, width: u32, height: u32) -> CameraFrame {
        let forward = (self.look_at - self.position).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        let tan_y = (self.fov_y_degrees.to_radians() * 0.5).tan();
        let aspect = width as f32 / height.max(1) as f32;
        CameraFrame {
            origin: self.position,
            forward,
            right,
            up,
            scale: Vec2::new(tan_y * aspect, tan_y),
            size: Vec2::new(width as f32, height as f32),
            jitter: Vec2::ZERO,
        }
    }
}

impl CameraFrame {
    /// The same camera with every pixel's sample point moved by `jitter` pixels from its
    /// centre (each component in [-0.5, 0.5)): frames of an accumulation at different
    /// offsets average to an anti-aliased image. [`CameraFrame::project`] and
    /// [`CameraFrame::sphere_bounds`] answer in the pixel grid, so that a point projects to
    /// the pixel whose (moved) sample point it is nearest.
    #[must_use]
    pub fn with_jitter(self, jitter: Vec2) -> Self {
        Self { jitter, ..self }
    }

    /// What [`CameraFrame::direction`] and [`CameraFrame::sample_point`] compute from, for
    /// a backend that generates the same primary rays itself (lgh-gpu's G-buffer kernel):
    /// the unit right and up vectors, the image-plane half-extents at unit distance
    /// (`scale`: tan(fov_x / 2), tan(fov_y / 2)), the image size in pixels and the jitter.
    #[must_use]
    pub fn ray_basis(&self) -> (Vec3, Vec3, Vec2, Vec2, Vec2) {
        (self.right, self.up, self.scale, self.size, self.jitter)
    }

    /// The sample point of pixel (x, y): its centre moved by the jitter.
    #[inline]
    #[must_use]
    pub fn sample_point(&self, x: u32, y: u32) -> Vec2 {
        Vec2::new(x as f32 + 0.5, y as f32 + 0.5) + self.jitter
    }

    /// Unit direction through the image point `pixel` (in pixels, (0, 0) = top-left corner of
    /// the image, so a pixel centre is (x + 0.5, y + 0.5)).
    #[inline]
    #[must_use]
    pub fn direction(&self, pixel: Vec2) -> Vec3 {
        let ndc = Vec2::new(
            2.0 * pixel.x / self.size.x - 1.0,
            1.0 - 2.0 * pixel.y / self.size.y,
        );
        (self.forward + self.right * (ndc.x * self.scale.x) + self.up * (ndc.y * self.scale.y))
            .normalize()
    }

    /// The image-plane rectangle [x0, y0, x1, y1] (pixels, not clipped to the image) of the
    /// sphere (`c`, `r`): the projections of its silhouette's tangent lines, which bound the
    /// projection of every point of the ball exactly (a box of the ball's bounding cube is up
    /// to about twice as wide). `None` if the ball reaches the plane of the eye (then its
    /// projection is unbounded) or the numbers are not finite.
    ///
    /// Per image axis a (right or up) the ball's points x/z lie between the slopes of the
    /// two lines through the eye tangent to the circle of the ball in the plane of a and the
    /// viewing direction: m = (c_a c_z +- r sqrt(c_a^2 + c_z^2 - r^2)) / (c_z^2 - r^2), with
    /// c_a, c_z the centre's offset from the eye along a and along the viewing direction.
    #[must_use]
    pub fn sphere_bounds(&self, c: Vec3, r: f32) -> Option<[f32; 4]> {
        let d = c - self.origin;
        let cz = d.dot(self.forward);
        let (cx, cy) = (d.dot(self.right), d.dot(self.up));
        let den = cz * cz - r * r;
        // Relative margin for the rounding of the slopes (a few f32 epsilons of the terms).
        const MARGIN: f32 = 1e-5;
        if !(cz > r && den > MARGIN * cz * cz && cx.is_finite() && cy.is_finite()) {
            return None;
        }
        let slopes = |ca: f32| {
            let root = r * (ca * ca + den).sqrt();
            let mid = ca * cz;
            let slack = MARGIN * (mid.abs() + root) + f32::MIN_POSITIVE;
            ((mid - root - slack) / den, (mid + root + slack) / den)
        };
        let (x_lo, x_hi) = slopes(cx);
        let (y_lo, y_hi) = slopes(cy);
        let px = |m: f32| (m / self.scale.x + 1.0) * 0.5 * self.size.x - self.jitter.x;
        let py = |m: f32| (1.0 - m / self.scale.y) * 0.5 * self.size.y - self.jitter.y;
        let rect = [px(x_lo), py(y_hi), px(x_hi), py(y_lo)];
        rect.iter().all(|v| v.is_finite()).then_some(rect)
    }

    /// Projects a world point to image coordinates (pixels) and its depth along the viewing
    /// direction; `None` behind the camera.
    #[must_use]
    pub fn project(&self, p: Vec3) -> Option<(Vec2, f32)> {
        let d = p - self.origin;
        let z = d.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let x = d.dot(self.right) / (z * self.scale.x);
        let y = d.dot(self.up) / (z * self.scale.y);
        Some((
            Vec2::new((x + 1.0) * 0.5 * self.size.x, (1.0 - y) * 0.5 * self.size.y) - self.jitter,
            z,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_pixel_looks_forward_and_projection_inverts_direction() {
        let cam = Camera {
            position: Vec3::new(1.0, 2.0, 3.0),
            look_at: Vec3::new(1.0, 2.0, 0.0),
            up: Vec3::Y,
            fov_y_degrees: 60.0,
        };
        let f = cam.frame(200, 100);
        let d = f.direction(Vec2::new(100.0, 50.0));
        assert!((d - Vec3::NEG_Z).length() < 1e-6);
        let px = Vec2::new(37.5, 81.25);
        let p = f.origin + f.direction(px) * 5.0;
        let (q, _) = f.project(p).unwrap();
        assert!((q - px).length() < 1e-3);
        // +x is to the right when looking down -z with +y up.
        let (r, _) = f.project(Vec3::new(2.0, 2.0, 0.0)).unwrap();
        assert!(r.x > 100.0);
        // A jittered frame projects a pixel's sample point back to that pixel's centre.
        let j = f.with_jitter(Vec2::new(0.3, -0.4));
        let p = j.origin + j.direction(j.sample_point(37, 81)) * 5.0;
        let (q, _) = j.project(p).unwrap();
        assert!((q - Vec2::new(37.5, 81.5)).length() < 1e-3, "{q}");
    }

    /// A point of `Vec3` with coordinates in [-s/2, s/2).
    fn offset(s: f32) -> impl proptest::strategy::Strategy<Value = Vec3> {
        use proptest::strategy::Strategy;
        (-0.5f32..0.5, -0.5f32..0.5, -0.5f32..0.5).prop_map(move |(x, y, z)| Vec3::new(x, y, z) * s)
    }

    /// `n` points spread evenly over the unit sphere (a Fibonacci lattice).
    fn lattice(n: usize) -> impl Iterator<Item = Vec3> {
        let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
        (0..n).map(move |k| {
            let z = 1.0 - 2.0 * (k as f32 + 0.5) / n as f32;
            let s = (1.0 - z * z).max(0.0).sqrt();
            let phi = golden * k as f32;
            Vec3::new(s * phi.cos(), s * phi.sin(), z)
        })
    }

    proptest::proptest! {
        // A fixed seed: CI runs the same cases every time (a failure is a regression, not luck);
        // change the seed locally to explore.
        #![proptest_config(proptest::prelude::ProptestConfig {
            cases: 256,
            rng_seed: proptest::test_runner::RngSeed::Fixed(2019),
            ..proptest::prelude::ProptestConfig::default()
        })]
        /// The sphere's rectangle holds the projection of every point of the ball (on its
        /// surface and on a sphere inside), and is tight: the points reach within 2% of each
        /// side (balls at least their radius away from the plane of the eye; nearer, the
        /// extremes lie on a sliver of the ball that the lattice may miss). Spheres that
        /// reach the plane of the eye have no rectangle.
        #[test]
        fn sphere_bounds_hold_the_ball_tightly(
            position in offset(10.0),
            look_at in offset(10.0),
            tilt in offset(0.5),
            fov_y_degrees in 20.0f32..140.0,
            ahead in 0.2f32..8.2,
            aside in offset(6.0),
            r in 0.01f32..3.0,
        ) {
            let cam = Camera { position, look_at, up: Vec3::Y + tilt, fov_y_degrees };
            proptest::prop_assume!(cam.is_valid());
            let f = cam.frame(320, 180);
            let c = f.origin + f.forward * ahead + aside;
            let cz = (c - f.origin).dot(f.forward);
            let Some([x0, y0, x1, y1]) = f.sphere_bounds(c, r) else {
                proptest::prop_assert!(cz <= r * 1.001, "no bounds for a ball in front");
                return Ok(());
            };
            proptest::prop_assert!(cz > r, "bounds for a ball that reaches the eye");
            let (mut lo, mut hi) = (Vec2::splat(f32::MAX), Vec2::splat(f32::MIN));
            for (k, dir) in lattice(4000).enumerate() {
                let p = c + dir * if k % 2 == 0 { r } else { 0.5 * r };
                let (q, _) = f.project(p).unwrap();
                let tol = 1e-3 * (1.0 + q.abs().max_element());
                proptest::prop_assert!(
                    q.x >= x0 - tol && q.x <= x1 + tol && q.y >= y0 - tol && q.y <= y1 + tol,
                    "{} outside [{}, {}, {}, {}]", q, x0, y0, x1, y1
                );
                lo = lo.min(q);
                hi = hi.max(q);
            }
            if cz >= 2.0 * r {
                let (w, h) = (x1 - x0, y1 - y0);
                for (got, want, size) in [(lo.x, x0, w), (hi.x, x1, w), (lo.y, y0, h), (hi.y, y1, h)] {
                    proptest::prop_assert!((got - want).abs() <= 0.02 * size, "loose side: {} vs {}", got, want);
                }
            }
        }
    }
}
