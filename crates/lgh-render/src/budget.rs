//! How much memory a render needs, estimated before anything large is allocated, so that a
//! request the machine cannot hold is refused with a clear error instead of swapping or
//! aborting (see docs/design.md, "Memory budget").
//!
//! The figures are upper bounds per item, measured as peak resident memory on renders of the
//! built-in and shared scenes (image planes, G-buffer, reservoirs, VPLs with their lighting
//! grid hierarchy, the BVH) with a margin; the test suite checks that a render stays within its
//! estimate.

use lgh_scene::Scene;

use crate::settings::RenderSettings;

/// Bytes a render holds besides its scene-dependent parts (program, thread stacks, tables).
pub const BASE_BYTES: u64 = 48 << 20;
/// Bytes per pixel of a frame: image planes, G-buffer, reservoirs, filter buffers.
pub const BYTES_PER_PIXEL: u64 = 320;
/// Bytes per VPL: the VPL itself and its share of every level of the lighting grid hierarchy
/// (or of the light tree of `slc`).
pub const BYTES_PER_VPL: u64 = 680;
/// Bytes per triangle: the mesh as loaded and its BVH.
pub const BYTES_PER_TRIANGLE: u64 = 400;

/// The memory a render needs, by part, in bytes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct MemoryEstimate {
    /// The fixed part ([`BASE_BYTES`]).
    pub base: u64,
    /// The scene: triangles with their BVH, and textures.
    pub scene: u64,
    /// Image-sized buffers of all frames held at once.
    pub pixels: u64,
    /// VPLs and their hierarchy.
    pub vpls: u64,
}

impl MemoryEstimate {
    /// The estimate for rendering `scene` with `settings`, holding `frames_held` frames at
    /// once (1 for a single frame; 2 for accumulation and temporally filtered sequences,
    /// which keep a running mean or a history beside the frame).
    #[must_use]
    pub fn new(scene: &Scene, settings: &RenderSettings, frames_held: u64) -> Self {
        let texels: u64 = scene.textures.iter().map(|t| t.texels.len() as u64).sum();
        let pixels = u64::from(settings.width) * u64::from(settings.height);
        Self {
            base: BASE_BYTES,
            scene: scene.mesh.len() as u64 * BYTES_PER_TRIANGLE
                + texels * std::mem::size_of::<glam::Vec3>() as u64,
            pixels: pixels
                .saturating_mul(BYTES_PER_PIXEL)
                .saturating_mul(frames_held.max(1)),
            vpls: (settings.vpls as u64 + u64::from(settings.bounces))
                .saturating_mul(BYTES_PER_VPL),
        }
    }

    /// The whole estimate.
    #[must_use]
    pub fn total(&self) -> u64 {
        self.base
            .saturating_add(self.scene)
            .saturating_add(self.pixels)
            .saturating_add(self.vpls)
    }
}

impl std::fmt::Display for MemoryEstimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} (image buffers {}, VPLs and hierarchy {}, scene and BVH {})",
            Bytes(self.total()),
            Bytes(self.pixels),
            Bytes(self.vpls),
            Bytes(self.scene)
        )
    }
}

/// A byte count printed for people: `1.5 GB`, `320 MB`, `12 kB`, `100 B` (powers of 1000).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bytes(pub u64);

impl std::fmt::Display for Bytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let b = self.0 as f64;
        match self.0 {
            0..1_000 => write!(f, "{} B", self.0),
            1_000..1_000_000 => write!(f, "{:.0} kB", b / 1e3),
            1_000_000..1_000_000_000 => write!(f, "{:.0} MB", b / 1e6),
            _ => write!(f, "{:.1} GB", b / 1e9),
        }
    }
}

/// Parses a byte count: a number with an optional unit `B`, `k`/`kB`, `M`/`MB`, `G`/`GB`,
/// `T`/`TB` (powers of 1000) or `KiB`, `MiB`, `GiB`, `TiB` (powers of 1024).
///
/// # Errors
/// The text is not a positive number with one of those units.
pub fn parse_bytes(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let value: f64 = num
        .parse()
        .map_err(|_| format!("'{s}' is not a size (e.g. 8G, 512MB, 2GiB)"))?;
    let scale: f64 = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kb" => 1e3,
        "m" | "mb" => 1e6,
        "g" | "gb" => 1e9,
        "t" | "tb" => 1e12,
        "kib" => 1024.0,
        "mib" => 1024.0 * 1024.0,
        "gib" => 1024.0 * 1024.0 * 1024.0,
        "tib" => 1024.0 * 1024.0 * 1024.0 * 1024.0,
        _ => {
            return Err(format!(
                "'{s}': unknown unit (use B, kB, MB, GB, TB or KiB..TiB)"
            ));
        }
    };
    let bytes = value * scale;
    if !(1.0..1.8e19).contains(&bytes) {
        return Err(format!("'{s}': must be a positive size"));
    }
    Ok(bytes as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_print() {
        assert_eq!(parse_bytes("8G"), Ok(8_000_000_000));
        assert_eq!(parse_bytes("512 MB"), Ok(512_000_000));
        assert_eq!(parse_bytes("2GiB"), Ok(2 << 30));
        assert_eq!(parse_bytes("100"), Ok(100));
        assert!(parse_bytes("-1G").is_err());
        assert!(parse_bytes("0").is_err());
        assert!(parse_bytes("lots").is_err());
        assert!(parse_bytes("3 parsecs").is_err());
        assert_eq!(Bytes(1_500_000_000).to_string(), "1.5 GB");
        assert_eq!(Bytes(320_000_000).to_string(), "320 MB");
        assert_eq!(Bytes(999).to_string(), "999 B");
    }

    #[test]
    fn the_estimate_grows_with_pixels_vpls_and_frames() {
        let mut scene = lgh_scene::cornell::cornell_box();
        scene.finish(std::path::Path::new("<built-in>")).unwrap();
        let small = RenderSettings {
            width: 64,
            height: 36,
            vpls: 1000,
            ..RenderSettings::default()
        };
        let big = RenderSettings {
            width: 1280,
            height: 720,
            vpls: 4_000_000,
            ..small.clone()
        };
        let a = MemoryEstimate::new(&scene, &small, 1);
        let b = MemoryEstimate::new(&scene, &big, 1);
        assert!(b.pixels > 100 * a.pixels && b.vpls > 1000 * a.vpls);
        assert_eq!(MemoryEstimate::new(&scene, &big, 2).pixels, 2 * b.pixels);
        assert!(b.total() > 1_000_000_000, "{b}");
    }
}
