//! Pieces of a frame for render farms (`--tile I/N`, `--region`): the rectangle's pixels,
//! cropped from the frame, written as a linear EXR with a JSON side file (`PIECE.exr.json`)
//! that says where the piece lies and how it was rendered, for `lgh merge`.

use std::path::{Path, PathBuf};

use anyhow::Result;
use glam::Vec3;
use lgh_render::region::Region;
use lgh_render::{Image, RenderSettings};
use serde::{Deserialize, Serialize};

/// The `format` of a side file.
pub const FORMAT: &str = "lgh-piece-1";

/// What a side file says about its piece.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PieceInfo {
    /// [`FORMAT`].
    pub format: String,
    /// The whole frame's width and height.
    pub frame_size: [u32; 2],
    /// The piece's rectangle in the frame.
    pub region: Region,
    /// The frame number of a sequence (`--frames`), else `None`.
    pub frame: Option<u32>,
    /// The scene as given on the command line.
    pub scene: String,
    /// The exposure that a PNG of the merged frame uses.
    pub exposure: f32,
    /// The render's settings as JSON (the same for all pieces of a frame).
    pub settings: serde_json::Value,
}

/// The side file of piece `path`: `path` with `.json` appended.
#[must_use]
pub fn side_path(path: &Path) -> PathBuf {
    let mut s = path.as_os_str().to_owned();
    s.push(".json");
    PathBuf::from(s)
}

/// The pixels of `region` of `image`.
#[must_use]
pub fn crop(image: &Image, region: &Region) -> Image {
    let mut pixels = Vec::with_capacity((region.width() * region.height()) as usize);
    for y in region.y0..region.y1 {
        for x in region.x0..region.x1 {
            pixels.push(image.get(x, y));
        }
    }
    Image::from_pixels(region.width(), region.height(), pixels)
}

/// Writes the piece of `image` (the frame rendered with `s.region`) to `path` (EXR) and
/// its side file.
pub fn write(
    path: &Path,
    image: &Image,
    s: &RenderSettings,
    scene: &str,
    exposure: f32,
    frame: Option<u32>,
) -> Result<()> {
    let region = s
        .region
        .ok_or_else(|| anyhow::anyhow!("internal: a piece without a region"))?;
    crop(image, &region).save(path, exposure)?;
    let info = PieceInfo {
        format: FORMAT.into(),
        frame_size: [s.width, s.height],
        region,
        frame,
        scene: scene.into(),
        exposure,
        settings: serde_json::to_value(s)?,
    };
    let text = serde_json::to_string_pretty(&info)? + "\n";
    lgh_render::output::write_output(&side_path(path), text.as_bytes())?;
    Ok(())
}

/// Pastes `piece` into `frame` at `region`.
pub fn paste(frame: &mut [Vec3], width: u32, piece: &Image, region: &Region) {
    for y in 0..piece.height {
        for x in 0..piece.width {
            let i = (region.y0 + y) as usize * width as usize + (region.x0 + x) as usize;
            frame[i] = piece.get(x, y);
        }
    }
}
