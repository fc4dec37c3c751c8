//! Rendering one rectangle of a frame, for render farms: the pieces of a frame, rendered
//! apart and merged, equal the whole frame bit for bit.
//!
//! A piece is the whole frame's computation restricted to the rectangle and a guard band
//! around it: the G-buffer is traced for the whole frame (one primary ray a pixel, a small
//! part of a frame), then every pixel beyond the band is cleared, so that no pass shades it.
//! Every random choice is keyed by the pixel's index in the whole frame, and tiles and
//! interleaving patterns are laid on the whole frame, so a pixel of the rectangle sees
//! exactly what it sees in the whole frame as long as every filter that reaches it reads
//! only pixels of the band: the band is the sum of the reach of the filters, scaled by the
//! interleaving (the sub-images' filters step `n` pixels at a time), plus a light-binning
//! tile ([`guard_band`]). VPLs and the hierarchy depend only on the scene and the seed, so
//! each piece builds the same ones.

/// A rectangle of pixels, `x0..x1` by `y0..y1` (half-open), in a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Region {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub y1: u32,
}

impl Region {
    /// The whole `width` x `height` frame.
    #[must_use]
    pub fn whole(width: u32, height: u32) -> Self {
        Self {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }

    /// Tile `index` (1-based) of `count` tiles of a `width` x `height` frame: a grid of `rows`
    /// x `count / rows`, `rows` the largest divisor of `count` not above its square root (4:
    /// 2 x 2, 9: 3 x 3, 6: 2 x 3), numbered along rows from the top left.
    ///
    /// # Errors
    /// `index` not in `1..=count`, or more tiles than pixels along a side.
    pub fn tile(index: u32, count: u32, width: u32, height: u32) -> Result<Self, String> {
        if count == 0 || index == 0 || index > count {
            return Err(format!("tile {index}/{count}: expected 1 <= I <= N"));
        }
        let rows = (1..=count)
            .take_while(|r| r * r <= count)
            .filter(|r| count.is_multiple_of(*r))
            .last()
            .unwrap_or(1);
        let cols = count / rows;
        if cols > width || rows > height {
            return Err(format!(
                "tile {index}/{count}: {cols} x {rows} tiles do not fit {width}x{height} pixels"
            ));
        }
        let (i, r) = ((index - 1) % cols, (index - 1) / cols);
        let edge = |k: u32, parts: u32, size: u32| {
            (u64::from(size) * u64::from(k) / u64::from(parts)) as u32
        };
        Ok(Self {
            x0: edge(i, cols, width),
            x1: edge(i + 1, cols, width),
            y0: edge(r, rows, height),
            y1: edge(r + 1, rows, height),
        })
    }

    /// Parses `x0,y0,x1,y1`.
    ///
    /// # Errors
    /// Not four integers.
    pub fn parse(s: &str) -> Result<Self, String> {
        let v: Vec<u32> = s
            .split(',')
            .map(|t| t.trim().parse::<u32>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("'{s}': expected x0,y0,x1,y1 (four pixel coordinates)"))?;
        match v[..] {
            [x0, y0, x1, y1] => Ok(Self { x0, y0, x1, y1 }),
            _ => Err(format!(
                "'{s}': expected x0,y0,x1,y1 (four pixel coordinates)"
            )),
        }
    }

    /// Width in pixels.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.x1.saturating_sub(self.x0)
    }

    /// Height in pixels.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.y1.saturating_sub(self.y0)
    }

    /// Checks that the rectangle is not empty and lies in a `width` x `height` frame.
    ///
    /// # Errors
    /// As above, with the rectangle.
    pub fn check(&self, width: u32, height: u32) -> Result<(), String> {
        if self.x0 >= self.x1 || self.y0 >= self.y1 || self.x1 > width || self.y1 > height {
            return Err(format!(
                "region {},{},{},{}: not a non-empty rectangle inside the {width}x{height} frame",
                self.x0, self.y0, self.x1, self.y1
            ));
        }
        Ok(())
    }

    /// True if pixel (x, y) lies in the rectangle.
    #[must_use]
    pub fn contains(&self, x: u32, y: u32) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&y)
    }

    /// The rectangle grown by `band` pixels on every side, within a `width` x `height` frame.
    #[must_use]
    pub fn grown(&self, band: u32, width: u32, height: u32) -> Self {
        Self {
            x0: self.x0.saturating_sub(band),
            y0: self.y0.saturating_sub(band),
            x1: self.x1.saturating_add(band).min(width),
            y1: self.y1.saturating_add(band).min(height),
        }
    }

    /// True if the two rectangles share a pixel.
    #[must_use]
    pub fn overlaps(&self, other: &Self) -> bool {
        self.x0 < other.x1 && other.x0 < self.x1 && self.y0 < other.y1 && other.y0 < self.y1
    }
}

/// The guard band of a piece rendered with `s`, in pixels (see the module documentation).
/// For the tiled methods: the reach of the shadow filter's a-trous passes (a 5 x 5 kernel at
/// steps 1, 2, 4, ...: 2 (2^p - 1) pixels), of the blur that recombines interleaved
/// sub-images, one light-binning tile in full-resolution pixels (its lights depend on all
/// its pixels), 8 for the direct light's filter and 1 for the edge resolve
/// ([`crate::passes::edge_aa`]): 95 pixels at lgh's defaults (tiles of 16 pixels), 207 at
/// slc's (tiles of 16 sub-image pixels, 8 x 8 interleaving). The per-pixel methods (brute,
/// the path tracers) need only the direct light's filter and the resolve. Measured on the
/// default scene at 480x270, lgh and slc pieces were exact from a band of 96 pixels.
#[must_use]
pub fn guard_band(s: &crate::RenderSettings) -> u32 {
    use crate::methods::{lgh, slc};
    let method = s.method;
    let tile = if [lgh::LGH, lgh::LGH_UNSHADOWED].contains(&method) {
        // lgh's tiles are 16 full-resolution pixels unless set in sub-image pixels.
        let n = s
            .tiling
            .interleave
            .unwrap_or(lgh::DEFAULT_INTERLEAVE)
            .max(1);
        s.tiling.tile.map_or(16, |t| t.saturating_mul(n))
    } else if [slc::SLC, slc::SLC_CLAMPED].contains(&method) {
        let n = s
            .tiling
            .interleave
            .unwrap_or(slc::DEFAULT_INTERLEAVE)
            .max(1);
        s.tiling.tile.unwrap_or(16).saturating_mul(n)
    } else {
        return 9;
    };
    let passes = s
        .shadows
        .filter_passes
        .min(crate::denoise::atrous::MAX_PASSES);
    let atrous = 2 * ((1u32 << passes) - 1);
    atrous
        .saturating_add(s.tiling.blur.radius)
        .saturating_add(tile)
        .saturating_add(9)
}

/// The pixels a piece of a frame shades (`s.region` grown by its [`guard_band`], within
/// the frame), or `None` for a whole frame.
#[must_use]
pub fn shaded_rect(s: &crate::RenderSettings) -> Option<Region> {
    s.region.map(|r| r.grown(guard_band(s), s.width, s.height))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_band_at_the_defaults() {
        use crate::methods::{brute, lgh, slc};
        let band = |method| {
            guard_band(&crate::RenderSettings {
                method,
                ..crate::RenderSettings::default()
            })
        };
        assert_eq!(band(lgh::LGH), 95);
        assert_eq!(band(slc::SLC), 207);
        assert_eq!(band(brute::BRUTE), 9);
    }
}
