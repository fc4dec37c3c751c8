//! The viewer without a window: the frame loop, the key script and the light motion of the
//! window, frame after frame, then the statistics and the screenshot.

use std::path::Path;
use std::time::Instant;

use anyhow::{Result, bail};
use lgh_scene::Scene;

use crate::ViewArgs;
use crate::engine::{FrameLoop, ShownFrame};
use crate::state::{ViewState, action_of_key};
use lgh_render::settings::Device;

/// Per-frame records of a run, for the statistics.
#[derive(Debug, Default)]
pub struct Record {
    frames: Vec<ShownFrame>,
    started: Option<Instant>,
}

impl Record {
    /// Starts the clock.
    pub fn start(&mut self) {
        self.started = Some(Instant::now());
    }

    /// Records a shown frame (its image is kept only for the last one).
    pub fn push(&mut self, mut frame: ShownFrame) {
        if let Some(last) = self.frames.last_mut() {
            last.image.pixels = Vec::new();
            last.pixels = Vec::new();
        }
        frame.pixels.shrink_to_fit();
        self.frames.push(frame);
    }

    /// The last frame.
    #[must_use]
    pub fn last(&self) -> Option<&ShownFrame> {
        self.frames.last()
    }

    /// The statistics: `fps` over the wall time since [`Record::start`], the median per pass.
    #[must_use]
    pub fn stats(&self, args: &ViewArgs, state: &ViewState) -> serde_json::Value {
        let secs = self.started.map_or(0.0, |s| s.elapsed().as_secs_f64());
        let n = self.frames.len();
        let mut passes: Vec<(String, Vec<f64>)> = Vec::new();
        for f in &self.frames {
            for (name, ms) in f.timings.iter().chain([&("frame".to_string(), f.ms)]) {
                match passes.iter_mut().find(|(p, _)| p == name) {
                    Some((_, v)) => v.push(*ms),
                    None => passes.push((name.clone(), vec![*ms])),
                }
            }
        }
        let medians: serde_json::Map<String, serde_json::Value> = passes
            .into_iter()
            .map(|(name, mut v)| {
                v.sort_by(f64::total_cmp);
                (name, v[v.len() / 2].into())
            })
            .collect();
        serde_json::json!({
            "fps": if secs > 0.0 { n as f64 / secs } else { 0.0 },
            "frames": n,
            "seconds": secs,
            "median_ms": medians,
            "vpls": self.last().map(|f| f.vpls),
            "grid_lights": self.last().and_then(|f| f.grid_lights),
            "device": self.last().map(|f| f.device),
            "light_speed_degrees": args.light_speed,
            "taa": state.taa,
            "settings": state.settings,
        })
    }
}

/// Advances the script before frame `frame`: the key of that frame, and the light motion.
pub fn script_step(args: &ViewArgs, state: &mut ViewState, frame: u64) {
    if let Some(key) = args.keys.get(frame as usize)
        && let Some(action) = action_of_key(key)
    {
        state.apply(action);
    }
    if args.light_speed != 0.0 {
        state.light_angle += args.light_speed.to_radians();
        state.version += 1;
    }
}

/// Checks the keys of the script.
///
/// # Errors
/// A key has no action.
pub fn check_keys(keys: &[String]) -> Result<()> {
    let display_only = |k: &str| k.eq_ignore_ascii_case("h") || k.eq_ignore_ascii_case("o");
    if let Some(k) = keys
        .iter()
        .find(|k| action_of_key(k).is_none() && !display_only(k))
    {
        bail!("--keys: '{k}' is not a key of the viewer (see the controls in `lgh view --help`)");
    }
    Ok(())
}

/// Writes the screenshot and the statistics asked for.
///
/// # Errors
/// A file cannot be written.
pub fn finish(args: &ViewArgs, state: &ViewState, record: &Record) -> Result<()> {
    if let (Some(path), Some(last)) = (&args.screenshot, record.last()) {
        if last.image.pixels.is_empty() {
            // A frame shown on the GPU: its packed pixels are the PNG's (an EXR screenshot
            // brings the linear image back, `FrameLoop::with_linear`).
            let rgb: Vec<u8> = last
                .pixels
                .iter()
                .flat_map(|p| [(p >> 16) as u8, (p >> 8) as u8, *p as u8])
                .collect();
            let (w, h) = (last.image.width, last.image.height);
            lgh_render::image::save_png(path, w, h, &rgb)?;
        } else {
            last.image.save(path, last.exposure)?;
        }
    }
    if let Some(path) = &args.stats {
        write_json(path, &record.stats(args, state))?;
    }
    Ok(())
}

fn write_json(path: &Path, v: &serde_json::Value) -> Result<()> {
    let text = serde_json::to_string_pretty(v)? + "\n";
    Ok(lgh_render::output::write_output(path, text.as_bytes())?)
}

/// Runs `args.frames` frames of `scene` without a window.
///
/// # Errors
/// Bad settings, a failed frame, or an output that cannot be written.
pub fn run(args: &ViewArgs, scene: Scene) -> Result<()> {
    let Some(frames) = args.frames else {
        bail!("--headless needs --frames N");
    };
    let (mut engine, mut state) = start(args, scene)?;
    let mut record = Record::default();
    record.start();
    for f in 0..frames {
        script_step(args, &mut state, f);
        let shown = engine.render(&state)?;
        state.saw(&shown);
        record.push(shown);
    }
    finish(args, &state, &record)
}

/// The frame loop and the starting view of `args` over `scene`.
///
/// # Errors
/// The settings or the key script are invalid.
pub fn start(args: &ViewArgs, scene: Scene) -> Result<(FrameLoop, ViewState)> {
    let settings = args.render_settings();
    settings.validate()?;
    args.check()?;
    let camera = scene.camera();
    let backend = match (args.device, args.backend) {
        (Device::Cpu, _) => None,
        (Device::Gpu, Some(map)) => Some(map),
        (Device::Gpu, None) => bail!("--device gpu: this program has no GPU backend"),
    };
    use lgh_render::image::ImageFormat;
    let exr = args
        .screenshot
        .as_ref()
        .is_some_and(|p| matches!(ImageFormat::from_path(p), Ok(ImageFormat::Exr)));
    let engine = FrameLoop::new(scene, settings.exposure, args.accel.kind())?
        .with_backend(backend)
        .with_linear(exr);
    let state = ViewState::new(settings, &camera, engine.world().radius, args.taa);
    Ok((engine, state))
}
