//! Colour textures, stored as linear RGB, with the alpha channel where a texel is not opaque.

use glam::{Vec2, Vec3};

/// An RGB texture in linear space (sRGB-encoded images are decoded on load), sampled
/// bilinearly; what lies beyond its borders is the [`Wrap`] of the reference that reads it.
#[derive(Clone, Debug)]
pub struct Texture {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Row-major texels, top row first (the convention of image files and of glTF/OBJ `v = 0`
    /// at the top after flipping, see [`Texture::sample`]).
    pub texels: Vec<Vec3>,
    /// The alpha channel, 8 bits a texel in the order of `texels` (a coverage, not sRGB
    /// encoded); empty where every texel is opaque. Read by cut-outs ([`crate::Cutout`]).
    pub alpha: Vec<u8>,
    /// True if the texels are the stored 8-bit values / 255, not sRGB decoded: data, not
    /// colour (normal maps, [`crate::material::NormalMap`]).
    pub linear: bool,
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

/// The value of each 8-bit code: sRGB decoded ([`srgb_to_linear`]), or code / 255 for data.
#[must_use]
pub fn code_table(linear: bool) -> [f32; 256] {
    std::array::from_fn(|i| {
        let x = i as f32 / 255.0;
        if linear { x } else { srgb_to_linear(x) }
    })
}

/// The code whose value in `table` ([`code_table`]) is nearest to `x`: exact for a value
/// the table holds.
#[must_use]
pub fn nearest_code(table: &[f32; 256], x: f32) -> u8 {
    let i = table.partition_point(|&t| t < x).min(255);
    let below = i.saturating_sub(1);
    if (table[below] - x).abs() <= (table[i] - x).abs() {
        below as u8
    } else {
        i as u8
    }
}

/// What a texture reads outside [0, 1] along one axis: glTF's sampler wrap modes (`wrapS`,
/// `wrapT`), the MTL format's `-clamp on` and OBJ's default repeat.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// The texture tiles the plane (glTF `REPEAT`, the default of both formats).
    #[default]
    Repeat = 0,
    /// The border texels extend outwards (glTF `CLAMP_TO_EDGE`, MTL `-clamp on`).
    Clamp = 1,
    /// Every other tile is mirrored (glTF `MIRRORED_REPEAT`).
    Mirror = 2,
}

impl Wrap {
    /// The coordinate `t` brought into [0, 1] (into [0, 1) for `Repeat`).
    #[inline]
    #[must_use]
    pub fn coordinate(self, t: f32) -> f32 {
        match self {
            Self::Repeat => t.rem_euclid(1.0),
            Self::Clamp => t.clamp(0.0, 1.0),
            // A triangle wave of period 2: 0 at even integers, 1 at odd ones.
            Self::Mirror => 1.0 - (t.rem_euclid(2.0) - 1.0).abs(),
        }
    }

    /// The texel of index `i` of an axis of `n` texels. For `Mirror` the coordinate is
    /// already folded, so the one texel each side of the axis is its border texel, as GL's
    /// mirrored repeat reads it.
    #[inline]
    #[must_use]
    pub fn texel(self, i: i64, n: i64) -> usize {
        match self {
            Self::Repeat => i.rem_euclid(n) as usize,
            Self::Clamp | Self::Mirror => i.clamp(0, n - 1) as usize,
        }
    }

    /// Its code in the GPU's material words (`surface.wgsl`'s `wrap_coordinate`).
    #[must_use]
    pub fn code(self) -> u32 {
        self as u32
    }

    /// The wraps of u and v in one GPU word: u | v << 2 (`common.wgsl`'s `bilinear`).
    #[must_use]
    pub fn pair_code([u, v]: [Self; 2]) -> u32 {
        u.code() | v.code() << 2
    }
}

impl Texture {
    /// A texture from 8-bit sRGB-encoded RGB(A) bytes (`channels` = 3 or 4; with 4 the alpha
    /// is kept if a texel is not opaque). Returns `None` if the buffer is too small or a
    /// dimension is zero.
    #[must_use]
    pub fn from_srgb8(width: u32, height: u32, channels: usize, bytes: &[u8]) -> Option<Self> {
        Self::from_8bit(width, height, channels, bytes, false)
    }

    /// A texture of data (a normal map) from 8-bit RGB(A) bytes, each value read as
    /// value / 255 (`channels` as in [`Texture::from_srgb8`]).
    #[must_use]
    pub fn from_linear8(width: u32, height: u32, channels: usize, bytes: &[u8]) -> Option<Self> {
        Self::from_8bit(width, height, channels, bytes, true)
    }

    /// The 8-bit value of each channel of each texel: the bytes the texture was made from
    /// (exact for a texture of 8-bit values, the nearest code otherwise), RGBA.
    #[must_use]
    pub fn codes(&self) -> Vec<u8> {
        let table = code_table(self.linear);
        let code = |x: f32| nearest_code(&table, x);
        self.texels
            .iter()
            .enumerate()
            .flat_map(|(k, c)| {
                let a = self.alpha.get(k).copied().unwrap_or(255);
                [code(c.x), code(c.y), code(c.z), a]
            })
            .collect()
    }

    /// This texture's 8-bit values read as data ([`Texture::from_linear8`]).
    #[must_use]
    pub fn as_linear(&self) -> Self {
        if self.linear {
            return self.clone();
        }
        let bytes = self.codes();
        Self::from_linear8(self.width, self.height, 4, &bytes).unwrap_or_else(|| self.clone())
    }

    fn from_8bit(
        width: u32,
        height: u32,
        channels: usize,
        bytes: &[u8],
        linear: bool,
    ) -> Option<Self> {
        let n = width as usize * height as usize;
        if n == 0 || channels < 3 || bytes.len() < n * channels {
            return None;
        }
        let lut = code_table(linear);
        let pixels = || bytes.chunks_exact(channels).take(n);
        let texels = pixels()
            .map(|p| Vec3::new(lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]))
            .collect();
        let mut alpha = Vec::new();
        if channels >= 4 && pixels().any(|p| p[3] < 255) {
            alpha = pixels().map(|p| p[3]).collect();
        }
        Some(Self {
            width,
            height,
            texels,
            alpha,
            linear,
        })
    }

    /// True if some texel is not opaque.
    #[must_use]
    pub fn has_alpha(&self) -> bool {
        !self.alpha.is_empty()
    }

    /// Bilinear lookup at texture coordinate `uv` (u right, v up as in OBJ and after the glTF
    /// loader's flip), wrapping around at the borders.
    #[must_use]
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        self.sample_wrapped(uv, [Wrap::Repeat; 2])
    }

    /// Bilinear lookup at texture coordinate `uv` with the wrap of u and of v. The glTF
    /// loader's flip of v (v' = 1 - v) commutes with every wrap, so glTF's modes apply to
    /// v' unchanged.
    #[must_use]
    pub fn sample_wrapped(&self, uv: Vec2, wrap: [Wrap; 2]) -> Vec3 {
        let c = self.bilinear(uv, wrap, |i| self.texels[i], Vec3::lerp);
        if c.is_finite() { c } else { Vec3::ZERO }
    }

    /// The alpha at `uv` in [0, 1], bilinear as [`Texture::sample_wrapped`] reads colour; 1
    /// for a texture without alpha.
    #[must_use]
    pub fn alpha_at(&self, uv: Vec2, wrap: [Wrap; 2]) -> f32 {
        if self.alpha.is_empty() {
            return 1.0;
        }
        let a = self.bilinear(
            uv,
            wrap,
            |i| f32::from(self.alpha[i]),
            |a, b, t| a + (b - a) * t,
        );
        if a.is_finite() { a / 255.0 } else { 1.0 }
    }

    /// The bilinear weighting of the four texels (row-major indices, read by `at`) around
    /// `uv`, blended by `lerp`.
    #[inline]
    fn bilinear<T: Copy>(
        &self,
        uv: Vec2,
        [wu, wv]: [Wrap; 2],
        at: impl Fn(usize) -> T,
        lerp: impl Fn(T, T, f32) -> T,
    ) -> T {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = wu.coordinate(uv.x) * w as f32 - 0.5;
        let y = (1.0 - wv.coordinate(uv.y)) * h as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let at = |xi: i64, yi: i64| at(wv.texel(yi, h) * w as usize + wu.texel(xi, w));
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = lerp(at(x0, y0), at(x0 + 1, y0), fx);
        let bottom = lerp(at(x0, y0 + 1), at(x0 + 1, y0 + 1), fx);
        lerp(top, bottom, fy)
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

    /// A 2 x 1 texture, black then white, read at texel centres beyond its borders: past
    /// u = 1 repeat starts black again, clamp stays white, mirror turns back to black; the
    /// same in v.
    #[test]
    fn wraps_read_beyond_the_borders_as_their_modes_say() {
        let t = Texture::from_srgb8(2, 1, 3, &[0, 0, 0, 255, 255, 255]).unwrap();
        let tv = Texture::from_srgb8(1, 2, 3, &[255, 255, 255, 0, 0, 0]).unwrap();
        let lum = |c: Vec3| c.x;
        for (wrap, at) in [
            (
                Wrap::Repeat,
                [(1.25, 0.0), (1.75, 1.0), (-0.25, 1.0), (-0.75, 0.0)],
            ),
            (
                Wrap::Clamp,
                [(1.25, 1.0), (1.75, 1.0), (-0.25, 0.0), (-0.75, 0.0)],
            ),
            (
                Wrap::Mirror,
                [(1.25, 1.0), (1.75, 0.0), (-0.25, 0.0), (-0.75, 1.0)],
            ),
        ] {
            for (u, want) in at {
                let got = lum(t.sample_wrapped(Vec2::new(u, 0.3), [wrap, Wrap::Repeat]));
                assert!((got - want).abs() < 1e-6, "{wrap:?} u {u}: {got}");
                // The texture turned on its side: v up, so its bottom (black) row is v = 0.
                let got = lum(tv.sample_wrapped(Vec2::new(0.3, u), [Wrap::Repeat, wrap]));
                assert!((got - want).abs() < 1e-6, "{wrap:?} v {u}: {got}");
            }
        }
        // Inside [0, 1] the three agree.
        for u in [0.05, 0.4, 0.5, 0.77, 0.95] {
            let r = t.sample(Vec2::new(u, 0.5));
            for wrap in [Wrap::Clamp, Wrap::Mirror] {
                let got = t.sample_wrapped(Vec2::new(u, 0.5), [wrap; 2]);
                let inner = (0.25..=0.75).contains(&u);
                assert!(
                    !inner || (got - r).abs().max_element() < 1e-6,
                    "{wrap:?} {u}"
                );
            }
        }
    }

    /// glTF's flip of v commutes with every wrap: wrap(1 - v) = 1 - wrap(v) (for repeat up
    /// to the integer at 1).
    #[test]
    fn the_flip_of_v_commutes_with_each_wrap() {
        for wrap in [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror] {
            for v in [-2.3f32, -1.0, -0.4, 0.0, 0.2, 0.5, 1.7, 3.25] {
                let (a, b) = (wrap.coordinate(1.0 - v), 1.0 - wrap.coordinate(v));
                let d = (a - b).abs();
                assert!(d < 1e-5 || (wrap == Wrap::Repeat && (d - 1.0).abs() < 1e-5));
            }
        }
    }
}
