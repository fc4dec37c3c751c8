//! `lgh render --stats`: what a render did, as JSON. The method's own statistics (serde data
//! from the library) are merged at the top level, the settings are kept whole.

use std::path::Path;

use anyhow::Result;
use lgh_render::budget::MemoryEstimate;
use lgh_render::passes::vpl_gen::PathNumbers;
use lgh_render::{Frame, Method, RenderSettings};
use serde::Serialize;

/// The statistics of one rendered frame.
#[derive(Debug, Serialize)]
pub struct FrameReport<'a> {
    /// Scene name.
    pub scene: &'a str,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// VPLs made.
    pub vpls: usize,
    /// VPLs asked for.
    pub vpls_requested: usize,
    /// Light paths traced for them.
    pub light_paths: u64,
    /// Bounces per light path.
    pub bounces: u32,
    /// Numbers of the light paths.
    pub path_numbers: PathNumbers,
    /// The indirect-lighting method.
    pub method: Method,
    /// Seed.
    pub seed: u64,
    /// Worker threads.
    pub threads: usize,
    /// Triangles in the BVH.
    pub triangles: usize,
    /// Triangles with an alpha cut-out.
    pub cut_out_triangles: usize,
    /// The ray tracer (`obvhs` or `embree`).
    pub accel: &'static str,
    /// Where the indirect light was computed: `cpu`, or the GPU adapter's name.
    pub device: String,
    /// Frames averaged (`--accumulate`).
    pub accumulated_frames: u32,
    /// Per-pass wall times in ms, summed over the frames (`total` includes the BVH build).
    pub timings_ms: serde_json::Map<String, serde_json::Value>,
    /// Memory: the estimate made before rendering, the peak the process reached.
    pub memory: MemoryReport,
    /// The method's own statistics.
    #[serde(flatten)]
    pub method_stats: serde_json::Map<String, serde_json::Value>,
    /// Every setting of the frame.
    pub settings: &'a RenderSettings,
}

/// What the frame's report needs beyond the frame.
pub struct ReportContext<'a> {
    /// Scene name.
    pub scene: &'a str,
    /// The settings rendered with.
    pub settings: &'a RenderSettings,
    /// Worker threads.
    pub threads: usize,
    /// Triangles in the BVH.
    pub triangles: usize,
    /// Triangles with an alpha cut-out.
    pub cut_out_triangles: usize,
    /// The ray tracer.
    pub accel: &'static str,
    /// `cpu`, or the GPU adapter's name.
    pub device: String,
    /// Scene loading time.
    pub load_ms: f64,
    /// BVH build time.
    pub bvh_ms: f64,
    /// Frames averaged.
    pub frames: u32,
    /// The memory estimate checked before rendering.
    pub estimate: MemoryEstimate,
}

/// The memory of a render, in bytes.
#[derive(Debug, Serialize)]
pub struct MemoryReport {
    /// The estimate checked before rendering (its total), and its parts.
    pub estimate_bytes: u64,
    /// The parts of the estimate.
    pub estimate: MemoryEstimate,
    /// The peak resident memory of the process (Linux; null elsewhere).
    pub peak_bytes: Option<u64>,
    /// The peak divided by the VPLs made: the cost of a VPL with its hierarchy where VPLs
    /// dominate.
    pub peak_bytes_per_vpl: Option<f64>,
}

impl<'a> FrameReport<'a> {
    /// The report of `frame`.
    #[must_use]
    pub fn new(frame: &Frame, c: &ReportContext<'a>) -> Self {
        let mut timings = serde_json::Map::new();
        timings.insert("scene_load".into(), c.load_ms.into());
        timings.insert("bvh_build".into(), c.bvh_ms.into());
        for (name, ms) in &frame.timings.0 {
            let ms = if name == "total" { ms + c.bvh_ms } else { *ms };
            timings.insert(name.clone(), ms.into());
        }
        let method_stats = match frame.method.stats.as_ref().map(|s| s.to_json()) {
            Some(serde_json::Value::Object(m)) => m,
            _ => serde_json::Map::new(),
        };
        let s = c.settings;
        Self {
            scene: c.scene,
            width: s.width,
            height: s.height,
            vpls: frame.vpls.len(),
            vpls_requested: s.vpls,
            light_paths: frame.vpls.paths,
            bounces: s.bounces,
            path_numbers: s.path_numbers,
            method: s.method,
            seed: s.seed,
            threads: c.threads,
            triangles: c.triangles,
            cut_out_triangles: c.cut_out_triangles,
            accel: c.accel,
            device: c.device.clone(),
            accumulated_frames: c.frames,
            timings_ms: timings,
            memory: MemoryReport {
                estimate_bytes: c.estimate.total(),
                estimate: c.estimate,
                peak_bytes: crate::sysmem::peak_bytes(),
                peak_bytes_per_vpl: crate::sysmem::peak_bytes()
                    .filter(|_| !frame.vpls.is_empty())
                    .map(|p| p as f64 / frame.vpls.len() as f64),
            },
            method_stats,
            settings: s,
        }
    }
}

/// Writes `value` as pretty JSON to `path`. Like the images, the file appears whole or not at all (written under a temporary name in
/// the same folder, then renamed).
///
/// # Errors
/// The file cannot be written.
pub fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    let text = serde_json::to_string_pretty(value)? + "\n";
    Ok(lgh_render::output::write_output(path, text.as_bytes())?)
}
