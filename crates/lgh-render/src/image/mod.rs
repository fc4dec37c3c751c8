//! Linear RGB images and their files: OpenEXR (linear, full float) and PNG (tone-mapped
//! sRGB, see [`tonemap`]); image differences in [`metrics`].

use std::path::{Path, PathBuf};

use glam::Vec3;
use lgh_core::color::finite_or_zero;
use rayon::prelude::*;

use crate::settings::MAX_PIXELS;

pub mod heat;
pub mod metrics;
pub mod tonemap;

use tonemap::tonemap_to_srgb8;

/// A linear RGB image, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels (linear radiance).
    pub pixels: Vec<Vec3>,
}

/// A problem reading or writing an image file.
#[derive(Debug, thiserror::Error)]
#[error("{}: {message}", path.display())]
pub struct ImageError {
    /// The file.
    pub path: PathBuf,
    /// What went wrong.
    pub message: String,
}

impl ImageError {
    fn new(path: &Path, message: impl Into<String>) -> Self {
        Self {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

/// The image file formats lgh writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// 8-bit sRGB PNG after exposure and tone mapping.
    Png,
    /// 32-bit float OpenEXR, linear radiance.
    Exr,
}

impl ImageFormat {
    /// The format named by a file's extension (`.png` or `.exr`, any case).
    ///
    /// # Errors
    /// Any other extension.
    pub fn from_path(path: &Path) -> Result<Self, ImageError> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("png") => Ok(Self::Png),
            Some("exr") => Ok(Self::Exr),
            _ => Err(ImageError::new(
                path,
                "unsupported image extension (expected .png or .exr)",
            )),
        }
    }
}

impl Image {
    /// A black image.
    #[must_use]
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    /// An image from pixels; every non-finite component becomes zero.
    #[must_use]
    pub fn from_pixels(width: u32, height: u32, mut pixels: Vec<Vec3>) -> Self {
        debug_assert_eq!(pixels.len(), width as usize * height as usize);
        pixels.par_iter_mut().for_each(|p| *p = finite_or_zero(*p));
        Self {
            width,
            height,
            pixels,
        }
    }

    /// The pixel at (x, y).
    #[must_use]
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Writes the image; the format follows the extension. `exposure` scales the radiance
    /// before tone mapping (PNG only). The file appears whole or not at all, and only a
    /// regular file is ever replaced (see [`crate::output`]).
    ///
    /// # Errors
    /// Unknown extension, missing folder, a path that is not a file, or a write error.
    pub fn save(&self, path: &Path, exposure: f32) -> Result<(), ImageError> {
        match ImageFormat::from_path(path)? {
            ImageFormat::Png => {
                let bytes = tonemap_to_srgb8(&self.pixels, exposure);
                save_png(path, self.width, self.height, &bytes)
            }
            ImageFormat::Exr => {
                let bytes = self
                    .encode_exr()
                    .map_err(|e| ImageError::new(path, format!("cannot encode EXR: {e}")))?;
                write_atomic(path, &bytes)
            }
        }
    }

    /// The image as the bytes of a linear 32-bit float OpenEXR file.
    fn encode_exr(&self) -> exr::error::Result<Vec<u8>> {
        use exr::prelude::{Image as ExrImage, SpecificChannels, Vec2, WritableImage};
        let w = self.width as usize;
        let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
            let p = finite_or_zero(self.pixels[y * w + x]);
            (p.x, p.y, p.z)
        });
        let mut out = std::io::Cursor::new(Vec::new());
        ExrImage::from_channels((w, self.height as usize), channels)
            .write()
            .to_buffered(&mut out)?;
        Ok(out.into_inner())
    }

    /// Reads an EXR (linear, first RGB(A) layer) or PNG (8- or 16-bit; the sRGB curve is
    /// undone, tone mapping is not) image.
    ///
    /// # Errors
    /// Missing or unreadable file, unsupported extension, more than [`MAX_LOAD_PIXELS`]
    /// pixels, or a pixel that is not finite (our outputs never hold one).
    pub fn load(path: &Path) -> Result<Self, ImageError> {
        let img = Self::load_any(path)?;
        let bad = img.pixels.iter().filter(|p| !p.is_finite()).count();
        if bad > 0 {
            return Err(ImageError::new(
                path,
                format!(
                    "{bad} of its {} pixels are not finite (NaN or infinite): no metric of it means anything",
                    img.pixels.len()
                ),
            ));
        }
        Ok(img)
    }

    /// [`Image::load`] before the check of its values.
    fn load_any(path: &Path) -> Result<Self, ImageError> {
        match std::fs::metadata(path) {
            Ok(m) if m.is_file() => {}
            Ok(_) => return Err(ImageError::new(path, "not a regular file")),
            Err(_) => return Err(ImageError::new(path, "file not found")),
        }
        match ImageFormat::from_path(path)? {
            ImageFormat::Exr => {
                check_exr_header(path)?;
                let img = exr::prelude::read_first_rgba_layer_from_file(
                    path,
                    |res, _| Image::new(res.width() as u32, res.height() as u32),
                    |img: &mut Image, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                        let w = img.width as usize;
                        img.pixels[pos.y() * w + pos.x()] = Vec3::new(r, g, b);
                    },
                )
                .map_err(|e| ImageError::new(path, format!("cannot read EXR: {e}")))?;
                Ok(img.layer_data.channel_data.pixels)
            }
            ImageFormat::Png => {
                let too_big = |e: String| ImageError::new(path, format!("cannot read PNG: {e}"));
                let (w, h) = image::image_dimensions(path).map_err(|e| too_big(e.to_string()))?;
                if u64::from(w) * u64::from(h) > MAX_LOAD_PIXELS {
                    return Err(ImageError::new(
                        path,
                        format!("PNG of {w}x{h} pixels: at most {MAX_LOAD_PIXELS} pixels"),
                    ));
                }
                let img = image::open(path)
                    .map_err(|e| ImageError::new(path, format!("cannot read PNG: {e}")))?
                    .to_rgb32f();
                let pixels = img
                    .pixels()
                    .map(|p| {
                        Vec3::new(
                            lgh_scene::texture::srgb_to_linear(p[0]),
                            lgh_scene::texture::srgb_to_linear(p[1]),
                            lgh_scene::texture::srgb_to_linear(p[2]),
                        )
                    })
                    .collect();
                Ok(Image::from_pixels(img.width(), img.height(), pixels))
            }
        }
    }
}

/// The most pixels an image read from a file may have: 16M (4096 x 4096; 5K, not 8K UHD),
/// so that `lgh diff` of two of them, FLIP's working planes included (about 110 bytes a
/// pixel, 1.8 GB measured at 4000 x 4000), stays under 2 GB. The size is checked from the
/// header, before any pixel is decoded.
pub const MAX_LOAD_PIXELS: u64 = 1 << 24;

/// Reads an EXR file's headers and refuses sizes that no real file of its length has, before
/// the `exr` crate allocates for them (it trusts the header: a hostile resolution aborts the
/// process on allocation): more pixels than [`MAX_LOAD_PIXELS`], or more chunks than the file has
/// room for in its offset table (8 bytes each).
fn check_exr_header(path: &Path) -> Result<(), ImageError> {
    const _: () = assert!(MAX_LOAD_PIXELS <= MAX_PIXELS);
    let len = std::fs::metadata(path).map_or(0, |m| m.len());
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| ImageError::new(path, format!("cannot read EXR: {e}")))?;
    for h in &meta.headers {
        let pixels = (h.layer_size.0 as u64).saturating_mul(h.layer_size.1 as u64);
        if pixels > MAX_LOAD_PIXELS {
            return Err(ImageError::new(
                path,
                format!(
                    "EXR layer of {}x{} pixels: at most {MAX_LOAD_PIXELS} pixels",
                    h.layer_size.0, h.layer_size.1
                ),
            ));
        }
        if (h.chunk_count as u64).saturating_mul(8) > len {
            return Err(ImageError::new(
                path,
                format!(
                    "EXR header promises {} chunks, more than a file of {len} bytes holds",
                    h.chunk_count
                ),
            ));
        }
    }
    Ok(())
}

/// Writes `bytes` to `path`, whole or not at all (see [`crate::output::write_output`]).
///
/// # Errors
/// The path cannot be written.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), ImageError> {
    crate::output::write_output(path, bytes).map_err(|e| ImageError::new(path, e.message))
}

/// Writes 8-bit sRGB `rgb` of `width` x `height` pixels as a PNG, whole or not at all (see
/// [`Image::save`]).
///
/// # Errors
/// A buffer of the wrong size, or the path cannot be written.
pub fn save_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), ImageError> {
    use image::ImageEncoder;
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(rgb, width, height, image::ExtendedColorType::Rgb8)
        .map_err(|e| ImageError::new(path, format!("cannot encode PNG: {e}")))?;
    write_atomic(path, &bytes)
}

/// Fails early, before any rendering, if `path` cannot be an output image: unknown
/// extension, a folder that does not exist or takes no new file, or a path that is a folder
/// or block device (see [`crate::output::check_output`]).
///
/// # Errors
/// As above, naming the path.
pub fn check_output_path(path: &Path) -> Result<(), ImageError> {
    ImageFormat::from_path(path)?;
    crate::output::check_output(path).map_err(|e| ImageError::new(path, e.message))
}
