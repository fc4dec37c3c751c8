//! Colour textures, stored as linear RGB.

use glam::{Vec2, Vec3};

/// An RGB texture in linear space (sRGB-encoded images are decoded on load), sampled
/// bilinearly with repeat wrapping.
#[derive(Clone, Debug)]
pub struct Texture {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Row-major texels, top row first (the convention of image files and of glTF/OBJ `v = 0`
    /// at the top after flipping, see [`Texture::sample`]).
    pub texels: Vec<Vec3>,
}

/// sRGB electro-optical transfer function: an encoded value in [0, 1] to linear.
#[inline]
#[must_use]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl Texture {
    /// A texture from 8-bit sRGB-encoded RGB(A) bytes (`channels` = 3 or 4, alpha ignored).
    /// Returns `None` if the buffer is too small or a dimension is zero.
    #[must_use]
    pub fn from_srgb8(width: u32, height: u32, channels: usize, bytes: &[u8]) -> Option<Self> {
        let n = width as usize * height as usize;
        if n == 0 || channels < 3 || bytes.len() < n * channels {
            return None;
        }
        let lut: Vec<f32> = (0..256).map(|i| srgb_to_linear(i as f32 / 255.0)).collect();
        let texels = bytes
            .chunks_exact(channels)
            .take(n)
            .map(|p| Vec3::new(lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]))
            .collect();
        Some(Self {
            width,
            height,
            texels,
        })
    }

    /// Bilinear lookup at texture coordinate `uv` (u right, v up as in OBJ and after the glTF
    /// loader's flip), wrapping around at the borders.
    #[must_use]
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = uv.x.rem_euclid(1.0) * w as f32 - 0.5;
        let y = (1.0 - uv.y.rem_euclid(1.0)) * h as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let at = |xi: i64, yi: i64| {
            let xi = xi.rem_euclid(w) as usize;
            let yi = yi.rem_euclid(h) as usize;
            self.texels[yi * w as usize + xi]
        };
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = at(x0, y0).lerp(at(x0 + 1, y0), fx);
        let bottom = at(x0, y0 + 1).lerp(at(x0 + 1, y0 + 1), fx);
        let c = top.lerp(bottom, fy);
        if c.is_finite() { c } else { Vec3::ZERO }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_endpoints_and_middle() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.5) - 0.214).abs() < 1e-3);
    }

    #[test]
    fn constant_texture_samples_constant_everywhere() {
        let t = Texture::from_srgb8(2, 2, 4, &[255u8; 16]).unwrap();
        for uv in [
            Vec2::new(0.0, 0.0),
            Vec2::new(0.99, 0.3),
            Vec2::new(-3.2, 7.5),
        ] {
            assert!((t.sample(uv) - Vec3::ONE).abs().max_element() < 1e-6);
        }
        assert!(Texture::from_srgb8(0, 2, 4, &[]).is_none());
    }
}
