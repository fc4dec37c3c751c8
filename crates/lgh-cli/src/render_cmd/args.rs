//! The arguments of `lgh render`: the output, the sequence and the process; every rendering
//! setting comes from the library's [`RenderSettings`] (flattened).

use std::path::{Path, PathBuf};

use clap::Args;
use lgh_render::RenderSettings;
use lgh_render::denoise::temporal::TemporalSettings;
pub use lgh_render::settings::{Device, parse_size};

/// Render a scene to an image.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Scene file: .toml (scene file), .gltf, .glb or .obj, or a built-in scene:
    /// builtin:cornell (the default), builtin:cornell-moving-light (animated: a point light
    /// crosses the room in 2 s), builtin:cornell-moving-block (animated: the tall block turns
    /// 90 degrees and slides 10 cm in 2 s) or builtin:emitter-room (2688 emissive triangles,
    /// for the pt methods).
    pub scene: Option<PathBuf>,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "640x360", value_parser = parse_size, allow_hyphen_values = true)]
    pub size: (u32, u32),
    /// Output image: .png (exposure, ACES filmic tone map, sRGB) or .exr (linear radiance).
    #[arg(long, short, default_value = "lgh.png")]
    pub out: PathBuf,
    /// Write statistics (sizes, counts, per-pass timings in ms) as JSON to this file.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// lgh, slc: write the per-pixel lights evaluated (the LGH paper's overdraw, Fig. 5) as a
    /// colour map with a legend bar to this PNG.
    #[arg(long)]
    pub heatmap: Option<PathBuf>,
    /// The rendering settings.
    #[command(flatten)]
    pub settings: RenderSettings,
    /// The ray tracer.
    #[command(flatten)]
    pub accel: lgh_render::world::accel::AccelChoice,
    /// Where the frame is computed: cpu, or gpu (wgpu compute shaders on a Vulkan, Metal or
    /// DX12 adapter). On the GPU: the G-buffer, the VPLs (Sobol path numbers), the edge
    /// resolve's rays, the direct light, and the methods brute, brute-unshadowed, lgh and
    /// lgh-unshadowed (lgh's default estimate only) with lgh's hierarchy build, shadow rays
    /// and filters; lgh's tables and the composite stay on the CPU.
    #[arg(long, value_enum, default_value_t = Device::Cpu)]
    pub device: Device,
    /// Render N frames of the (static) view with independent VPL sets (seeds derived from
    /// --seed; for lgh also a random grid offset each), each sampling its pixels at its own
    /// sub-pixel offset, and write their mean: a progressive render that converges, edges
    /// anti-aliased, as N grows. For brute it is the brute force over the union of
    /// the N VPL sets, so the two are comparable. Without --shadow-samples, frames take 16
    /// shadow samples (the shadow filter shrinks as N grows).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub accumulate: u32,
    /// Render a sequence of frames A..B (B excluded, e.g. 0..48) of the scene's animation;
    /// --out must then contain #### (replaced by the zero-padded frame number). VPLs and all
    /// random numbers are new in every frame (seed + frame number).
    #[arg(long, value_parser = parse_frames)]
    pub frames: Option<(u32, u32)>,
    /// With --taa: render this many frames before A, unwritten, as the temporal filter's
    /// history, so that a chunk of a sequence starting at A matches one long run (a farm
    /// renders a sequence in chunks).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=1000))]
    pub warmup: u32,
    /// Render only tile I of N (I from 1 to N; the frame cut into a grid of about square
    /// tiles: 4 = 2 x 2, 9 = 3 x 3, 6 = 2 x 3) for a render farm. The piece goes to --out,
    /// which must be an .exr, with a side file OUT.json saying where it lies; `lgh merge`
    /// joins the pieces, which equal the whole frame bit for bit.
    #[arg(long = "tile", value_parser = parse_tile, conflicts_with = "region")]
    pub piece: Option<(u32, u32)>,
    /// Render only the pixels x0..x1 by y0..y1 (half-open) of the frame, as --tile does.
    #[arg(long, value_parser = lgh_render::region::Region::parse)]
    pub region: Option<lgh_render::region::Region>,
    /// Frames per second of the sequence (frame f shows time f / fps).
    #[arg(long, default_value_t = 24.0)]
    pub fps: f32,
    /// Temporal filtering of the shadows across the frames of a sequence (LGH paper 4.3).
    #[arg(long)]
    pub taa: bool,
    /// The temporal filter.
    #[command(flatten)]
    pub temporal: TemporalSettings,
    /// Refuse renders estimated to need more memory than this (e.g. 8G, 512MB, 2GiB).
    /// Default: the memory the system has available.
    #[arg(long, value_parser = lgh_render::budget::parse_bytes)]
    pub max_memory: Option<u64>,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// No progress bars and no summary.
    #[arg(long, short)]
    pub quiet: bool,
}

impl RenderArgs {
    /// The rendering settings with the image size of `--size` and the piece of `--tile` or
    /// `--region`.
    ///
    /// # Errors
    /// A tile or region that does not fit the frame.
    pub fn render_settings(&self) -> Result<RenderSettings, String> {
        let (width, height) = self.size;
        let region = match (self.piece, self.region) {
            (Some((i, n)), _) => Some(lgh_render::region::Region::tile(i, n, width, height)?),
            (None, Some(r)) => {
                r.check(width, height)?;
                Some(r)
            }
            (None, None) => None,
        };
        Ok(RenderSettings {
            width,
            height,
            region,
            ..self.settings.clone()
        })
    }

    /// With `--accumulate N` (N > 1), frames take
    /// [`lgh_render::accumulate::ACCUMULATE_SHADOW_SAMPLES`] shadow samples unless
    /// `--shadow-samples` was `given` (by its argument id) or is 0 (no shadows).
    pub fn use_accumulation_defaults(&mut self, given: impl Fn(&str) -> bool) {
        let shadows = &mut self.settings.shadows;
        if self.accumulate > 1 && !given("samples") && shadows.samples != Some(0) {
            shadows.samples = Some(lgh_render::accumulate::ACCUMULATE_SHADOW_SAMPLES);
        }
    }
}

/// The longest sequence `--frames` takes.
pub const MAX_FRAMES: u32 = 1_000_000;

/// Parses `I/N` (tile I of N).
pub fn parse_tile(s: &str) -> Result<(u32, u32), String> {
    let parse = |(i, n): (&str, &str)| Some((i.trim().parse().ok()?, n.trim().parse().ok()?));
    match s.split_once('/').and_then(parse) {
        Some((i, n)) if (1..=n).contains(&i) && n <= 65_536 => Ok((i, n)),
        _ => Err(format!(
            "'{s}': expected I/N with 1 <= I <= N <= 65536 (e.g. 3/4)"
        )),
    }
}

/// Parses `A..B` (frames A to B - 1).
pub fn parse_frames(s: &str) -> Result<(u32, u32), String> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| format!("'{s}' is not A..B (e.g. 0..48)"))?;
    let a: u32 = a
        .trim()
        .parse()
        .map_err(|_| format!("'{s}': A is not a number"))?;
    let b: u32 = b
        .trim()
        .parse()
        .map_err(|_| format!("'{s}': B is not a number"))?;
    if b <= a {
        return Err(format!("'{s}': B must be larger than A"));
    }
    if b - a > MAX_FRAMES {
        return Err(format!("'{s}': at most {MAX_FRAMES} frames"));
    }
    Ok((a, b))
}

/// The output path of frame `f`: the first run of '#' in the file name of `pattern` replaced by `f`, zero-padded to
/// the run's length.
#[must_use]
pub fn frame_path(pattern: &Path, f: u32) -> PathBuf {
    let Some(name) = pattern.file_name().map(|n| n.to_string_lossy()) else {
        return pattern.to_path_buf();
    };
    let Some(start) = name.find('#') else {
        return pattern.to_path_buf();
    };
    let len = name[start..].chars().take_while(|&c| c == '#').count();
    let out = format!("{}{f:0len$}{}", &name[..start], &name[start + len..]);
    pattern.with_file_name(out)
}

#[cfg(test)]
mod tests {
    use super::{frame_path, parse_frames, parse_size};

    #[test]
    fn sizes() {
        assert_eq!(parse_size("640x360"), Ok((640, 360)));
        assert!(parse_size("0x10").is_err());
        assert!(parse_size("640").is_err());
        assert!(parse_size("ax3").is_err());
    }

    #[test]
    fn frames_and_their_paths() {
        assert_eq!(parse_frames("0..48"), Ok((0, 48)));
        assert!(parse_frames("5..5").is_err());
        assert!(parse_frames("0..4000000000").is_err());
        let p = frame_path(std::path::Path::new("out/f_####.png"), 7);
        assert_eq!(p, std::path::PathBuf::from("out/f_0007.png"));
        // A '#' in a folder's name is not a frame number.
        let p = frame_path(std::path::Path::new("take#2/f_##.png"), 7);
        assert_eq!(p, std::path::PathBuf::from("take#2/f_07.png"));
        let p = frame_path(std::path::Path::new("take#2/still.png"), 7);
        assert_eq!(p, std::path::PathBuf::from("take#2/still.png"));
    }
}
