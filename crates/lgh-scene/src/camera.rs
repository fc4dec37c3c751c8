//! A pinhole camera.

use glam::{Vec2, Vec3};

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
        }
    }
}

impl CameraFrame {
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
            Vec2::new((x + 1.0) * 0.5 * self.size.x, (1.0 - y) * 0.5 * self.size.y),
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
    }
}
