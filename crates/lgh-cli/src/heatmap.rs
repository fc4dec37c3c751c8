//! The overdraw heat map (LGH paper Fig. 5): a colour per pixel from the number of lights
//! covering it, with a legend bar on the right running from 0 (bottom) to the maximum (top),
//! ticked at every quarter.

use std::path::Path;

use anyhow::Result;
use glam::Vec3;
use lgh_render::Image;

/// A blue-cyan-green-yellow-red ramp for t in [0, 1] (linear RGB).
fn ramp(t: f32) -> Vec3 {
    const STOPS: [Vec3; 5] = [
        Vec3::new(0.0, 0.0, 0.35),
        Vec3::new(0.0, 0.6, 1.0),
        Vec3::new(0.1, 0.9, 0.1),
        Vec3::new(1.0, 0.9, 0.0),
        Vec3::new(0.9, 0.0, 0.0),
    ];
    let x = t.clamp(0.0, 1.0) * 4.0;
    let i = (x.floor() as usize).min(3);
    STOPS[i].lerp(STOPS[i + 1], x - i as f32)
}

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
    // Exposure chosen so that the ramp's linear colours survive the tone map legibly.
    img.save(path, 1.6)?;
    Ok(max)
}
