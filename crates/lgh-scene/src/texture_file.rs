//! Texture images decoded within a budget: a small file can promise a huge image (a 31 KB
//! 1-bit PNG decodes to 3.9 GB of texels), so the header's size is checked against
//! [`MAX_TEXTURE_TEXELS`] and what is left of the scene's [`MAX_SCENE_TEXELS`] before any
//! pixel is decoded, and the decoder itself is limited to that allocation.

use std::io::{BufRead, Cursor, Seek};
use std::path::Path;

use image::{DynamicImage, ImageReader, Limits};

use crate::Texture;

/// Texels one texture may have: 64M (8192 x 8192), 768 MiB as linear RGB.
pub const MAX_TEXTURE_TEXELS: u64 = 1 << 26;

/// Texels all textures of a scene may have together: 128M, 1.5 GiB as linear RGB.
pub const MAX_SCENE_TEXELS: u64 = 1 << 27;

/// Why a texture was not decoded.
#[derive(Debug)]
pub(crate) enum TextureError {
    /// The image is larger than the budget allows: the scene cannot be loaded as asked.
    OverBudget(String),
    /// The image cannot be read or decoded: the material colour stands in.
    Unreadable(String),
}

impl std::fmt::Display for TextureError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::OverBudget(m) | Self::Unreadable(m) => f.write_str(m),
        }
    }
}

/// What is left of a scene's texel budget as its textures are decoded.
#[derive(Debug)]
pub(crate) struct TexelBudget {
    /// Texels one texture may have.
    per_texture: u64,
    /// Texels left for the scene's other textures.
    left: u64,
}

impl Default for TexelBudget {
    fn default() -> Self {
        Self {
            per_texture: MAX_TEXTURE_TEXELS,
            left: MAX_SCENE_TEXELS,
        }
    }
}

impl TexelBudget {
    /// Decodes the image file at `path` as an sRGB texture (with its alpha channel).
    pub(crate) fn decode_file(&mut self, path: &Path) -> Result<Texture, TextureError> {
        self.decode_file_as(path, colour)
    }

    /// Decodes the image file at `path` as a cut-out's mask (an OBJ `map_d`): its alpha
    /// channel if it has one, else its grey level, as 8-bit coverage.
    pub(crate) fn decode_mask_file(&mut self, path: &Path) -> Result<Texture, TextureError> {
        self.decode_file_as(path, mask)
    }

    /// Decodes the image file at `path`, made a texture by `convert`.
    fn decode_file_as(
        &mut self,
        path: &Path,
        convert: fn(DynamicImage) -> Option<Texture>,
    ) -> Result<Texture, TextureError> {
        crate::file_kind::regular_file(path).map_err(|e| TextureError::Unreadable(e.message))?;
        let open = || -> Result<_, String> {
            ImageReader::open(path)
                .map_err(|e| e.to_string())?
                .with_guessed_format()
                .map_err(|e| e.to_string())
        };
        self.decode(open, convert)
    }

    /// Decodes an image held in memory (a glTF buffer view or data URI).
    pub(crate) fn decode_bytes(&mut self, bytes: &[u8]) -> Result<Texture, TextureError> {
        let open = || {
            ImageReader::new(Cursor::new(bytes))
                .with_guessed_format()
                .map_err(|e| e.to_string())
        };
        self.decode(open, colour)
    }

    /// Reads the size from the header of one reader, checks it, then decodes with a second
    /// reader limited to that size.
    fn decode<R: BufRead + Seek>(
        &mut self,
        open: impl Fn() -> Result<ImageReader<R>, String>,
        convert: fn(DynamicImage) -> Option<Texture>,
    ) -> Result<Texture, TextureError> {
        let unreadable = TextureError::Unreadable;
        let (w, h) = open()
            .map_err(unreadable)?
            .into_dimensions()
            .map_err(|e| unreadable(e.to_string()))?;
        let texels = u64::from(w) * u64::from(h);
        if texels > self.per_texture {
            return Err(TextureError::OverBudget(format!(
                "{w}x{h} texels, more than the {} a texture may have",
                self.per_texture
            )));
        }
        if texels > self.left {
            return Err(TextureError::OverBudget(format!(
                "{w}x{h} texels, more than the {} left of the {MAX_SCENE_TEXELS} all textures of a scene may have",
                self.left
            )));
        }
        let mut reader = open().map_err(unreadable)?;
        let mut limits = Limits::default();
        limits.max_image_width = Some(w);
        limits.max_image_height = Some(h);
        // The widest decoded pixel: 4 channels of 32-bit float.
        limits.max_alloc = Some(texels * 16 + (1 << 20));
        reader.limits(limits);
        let image = reader.decode().map_err(|e| unreadable(e.to_string()))?;
        let tex = convert(image).ok_or_else(|| unreadable("an empty image".into()))?;
        self.left -= texels;
        Ok(tex)
    }
}

/// An image as an sRGB colour texture, with its alpha channel if it has one.
fn colour(image: DynamicImage) -> Option<Texture> {
    if image.color().has_alpha() {
        let rgba = image.to_rgba8();
        Texture::from_srgb8(rgba.width(), rgba.height(), 4, rgba.as_raw())
    } else {
        let rgb = image.to_rgb8();
        Texture::from_srgb8(rgb.width(), rgb.height(), 3, rgb.as_raw())
    }
}

/// An image as a mask: its alpha where it has an alpha channel, else its grey level, as the
/// texture's alpha (8-bit coverage, not sRGB decoded), and as its colour.
fn mask(image: DynamicImage) -> Option<Texture> {
    if image.color().has_alpha() {
        return colour(image);
    }
    let grey = image.to_luma8();
    let rgba: Vec<u8> = grey.as_raw().iter().flat_map(|&l| [l, l, l, l]).collect();
    Texture::from_srgb8(grey.width(), grey.height(), 4, &rgba)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(w: u32, h: u32) -> Vec<u8> {
        let mut bytes = Vec::new();
        image::RgbImage::new(w, h)
            .write_to(&mut Cursor::new(&mut bytes), image::ImageFormat::Png)
            .unwrap();
        bytes
    }

    /// A texture over the per-texture cap is refused from its header (the CLI test of issue
    /// 38 does it with a real 9000 x 9000 bomb).
    #[test]
    fn a_huge_image_is_refused_before_decoding() {
        let mut budget = TexelBudget {
            per_texture: 15,
            left: 100,
        };
        let e = budget.decode_bytes(&png(4, 4)).unwrap_err().to_string();
        assert!(e.contains("4x4 texels, more than the 15"), "{e}");
        assert_eq!(budget.left, 100);
        assert!(budget.decode_bytes(&png(3, 5)).is_ok());
    }

    #[test]
    fn the_scene_budget_runs_out() {
        let mut budget = TexelBudget {
            per_texture: MAX_TEXTURE_TEXELS,
            left: 3,
        };
        let bytes = png(2, 1);
        assert!(budget.decode_bytes(&bytes).is_ok());
        assert_eq!(budget.left, 1);
        let e = budget.decode_bytes(&bytes).unwrap_err();
        assert!(
            matches!(&e, TextureError::OverBudget(m) if m.contains("left of the")),
            "{e}"
        );
    }
}
