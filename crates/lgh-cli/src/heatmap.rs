//! The overdraw heat map (LGH paper Fig. 5): a colour per pixel from the number of lights
//! covering it, with a legend bar on the right running from 0 (bottom) to the maximum (top),
//! ticked at every quarter.

use std::path::Path;

use anyhow::Result;
use glam::Vec3;
use lgh_render::Image;
use lgh_render::image::heat::{HEAT_EXPOSURE, ramp};

/// Writes the heat map; returns the maximum overdraw (the top of the legend).
pub fn write(path: &Path, width: u32, height: u32, overdraw: &[u32]) -> Result<u32> {
    let max = overdraw.iter().copied().max().unwrap_or(0).max(1);
    let bar = 24u32;
    let (w, h) = (width + bar + 8, height);
    let mut img = Image::new(w, h);
    for y in 0..height {
        for x in 0..width {
            let o = overdraw[(y * width + x) as usize];
            img.pixels[(y * w + x) as usize] = ramp(o as f32 / max as f32);
        }
        let t = 1.0 - y as f32 / (height.max(2) - 1) as f32;
        let quarter = (0..=4).any(|q| (y as i64 - i64::from((height - 1) * q / 4)).abs() == 0);
        for x in width + 8..w {
            img.pixels[(y * w + x) as usize] = if quarter && x < width + 14 {
                Vec3::ONE
            } else {
                ramp(t)
            };
        }
    }
    img.save(path, HEAT_EXPOSURE)?;
    Ok(max)
}
