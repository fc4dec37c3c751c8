//! # lgh-fuzz: mutation fuzzing of every input lgh reads
//!
//! Each case takes the seed file of one [`Target`] (a small valid file of that format, see
//! [`seeds`]), applies one to four mutations ([`mutate`]: by bytes, or by structure for JSON
//! and text formats), writes it with the unmutated files it refers to, and runs the loader
//! the command line would run on it. A file that loads is then rendered (a 16x9 frame with 64
//! VPLs, the `lgh` method), and its image must be finite. Every case runs under
//! `catch_unwind`: a panic anywhere is a finding, as is a case slower than
//! [`SLOW_CASE_MS`]. Panics the glTF loader contains (and reports as an error) are counted
//! apart, since they are bugs of the `gltf` crate that lgh survives.
//!
//! Beside the mutations, [`hostile`] runs hand-made cases by class: special files where a
//! file is read, decompression and allocation bombs, instancing.
//!
//! Cases are numbered; case `i` of seed `s` is the same input on every machine and thread
//! count, so a finding is reproduced with `lgh-fuzz --seed s --first i --cases 1`.
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod hostile;
pub mod mutate;
pub mod seeds;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::time::Instant;

use lgh_core::rng::Rng;
use rayon::prelude::*;

/// A case slower than this is a finding.
pub const SLOW_CASE_MS: f64 = 2000.0;

/// The error message of the glTF loader for a panic it contained.
const CONTAINED: &str = "the loader failed on it";

/// What a case mutates, and so which loader it exercises.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// A `.gltf` with embedded buffers (JSON structure and bytes).
    Gltf,
    /// A `.glb` (header, chunks, binary buffer).
    Glb,
    /// An OBJ file (with its unmutated MTL and texture).
    Obj,
    /// The MTL file of an unmutated OBJ.
    Mtl,
    /// A TOML scene file over an unmutated OBJ.
    Toml,
    /// The PNG texture of an unmutated OBJ/MTL.
    Texture,
    /// An EXR image read by `lgh diff`.
    Exr,
    /// A PNG image read by `lgh diff`.
    Png,
}

/// Every target, in the order cases cycle through them.
pub const TARGETS: [Target; 8] = [
    Target::Gltf,
    Target::Glb,
    Target::Obj,
    Target::Mtl,
    Target::Toml,
    Target::Texture,
    Target::Exr,
    Target::Png,
];

/// The seed files, made once.
struct Seeds {
    gltf: Vec<u8>,
    glb: Vec<u8>,
    png: Vec<u8>,
    exr: Vec<u8>,
}

impl Seeds {
    fn new() -> Self {
        Self {
            gltf: seeds::gltf(),
            glb: seeds::glb(),
            png: seeds::png_texture(),
            exr: seeds::exr_image(),
        }
    }

    fn of(&self, t: Target) -> &[u8] {
        match t {
            Target::Gltf => &self.gltf,
            Target::Glb => &self.glb,
            Target::Obj => seeds::OBJ.as_bytes(),
            Target::Mtl => seeds::MTL.as_bytes(),
            Target::Toml => seeds::TOML.as_bytes(),
            Target::Texture | Target::Png => &self.png,
            Target::Exr => &self.exr,
        }
    }
}

/// A case that panicked or was slow.
#[derive(Clone, Debug)]
pub struct Finding {
    /// The case number.
    pub case: u64,
    /// Its target.
    pub target: Target,
    /// The panic message, or how slow it was.
    pub what: String,
    /// The mutated input, kept for a regression test.
    pub input: Vec<u8>,
}

/// The outcome of a run.
#[derive(Clone, Debug, Default)]
pub struct Report {
    /// Cases run.
    pub cases: u64,
    /// Cases whose input loaded (and was rendered or read).
    pub loaded: u64,
    /// Cases refused with an error.
    pub refused: u64,
    /// Panics the glTF loader contained, reported as errors.
    pub contained_panics: u64,
    /// Panics (not contained) and slow cases.
    pub findings: Vec<Finding>,
    /// The slowest case, in ms.
    pub max_ms: f64,
}

impl Report {
    fn merge(mut self, other: Self) -> Self {
        self.cases += other.cases;
        self.loaded += other.loaded;
        self.refused += other.refused;
        self.contained_panics += other.contained_panics;
        self.findings.extend(other.findings);
        self.max_ms = self.max_ms.max(other.max_ms);
        self
    }
}

/// How one case ended.
enum Outcome {
    Loaded,
    Refused(String),
}

/// The input of case `case` of run `seed`: its target and the mutated bytes.
#[must_use]
pub fn case_input(seed: u64, case: u64) -> (Target, Vec<u8>) {
    let seeds = Seeds::new();
    input_from(&seeds, seed, case)
}

fn input_from(seeds: &Seeds, seed: u64, case: u64) -> (Target, Vec<u8>) {
    let target = TARGETS[(case % TARGETS.len() as u64) as usize];
    let mut rng = Rng::new(&[seed, case, 0xf022]);
    let mut data = seeds.of(target).to_vec();
    let donor = seeds.of(TARGETS[mutate::below(&mut rng, TARGETS.len())]);
    for _ in 0..1 + mutate::below(&mut rng, 4) {
        let structural = mutate::below(&mut rng, 2) == 0;
        match target {
            Target::Gltf if structural => {
                mutate::mutate_json(&mut rng, &mut data);
            }
            Target::Obj | Target::Mtl | Target::Toml if structural => {
                mutate::mutate_text(&mut rng, &mut data);
            }
            _ => mutate::mutate_bytes(&mut rng, &mut data, donor),
        }
    }
    (target, data)
}

/// Writes the case's files into `dir` and runs the loader of `target` on them, then renders
/// what loaded.
fn run_input(seeds: &Seeds, target: Target, data: &[u8], dir: &Path) -> Outcome {
    let write = |name: &str, bytes: &[u8]| {
        let p = dir.join(name);
        let _ = std::fs::write(&p, bytes);
        p
    };
    // The files a case refers to, unmutated unless they are the target.
    let obj = |obj: &[u8], mtl: &[u8], png: &[u8]| {
        write("scene.mtl", mtl);
        write("texture.png", png);
        write("scene.obj", obj)
    };
    let o = seeds::OBJ.as_bytes();
    let m = seeds::MTL.as_bytes();
    let scene = match target {
        Target::Gltf => write("scene.gltf", data),
        Target::Glb => write("scene.glb", data),
        Target::Obj => obj(data, m, &seeds.png),
        Target::Mtl => obj(o, data, &seeds.png),
        Target::Texture => obj(o, m, data),
        Target::Toml => {
            obj(o, m, &seeds.png);
            write("scene.toml", data)
        }
        Target::Exr | Target::Png => {
            let name = if target == Target::Exr {
                "image.exr"
            } else {
                "image.png"
            };
            return match lgh_render::Image::load(&write(name, data)) {
                Ok(img) if img.pixels.iter().all(|p| p.is_finite()) => Outcome::Loaded,
                Ok(_) => Outcome::Refused("non-finite pixel read".into()),
                Err(e) => Outcome::Refused(e.to_string()),
            };
        }
    };
    match lgh_scene::load(&scene) {
        Ok(scene) => render(scene),
        Err(e) => Outcome::Refused(e.to_string()),
    }
}

/// Renders a loaded scene small and checks that the image is finite.
fn render(scene: lgh_scene::Scene) -> Outcome {
    let world = lgh_render::World::new(scene);
    let settings = lgh_render::RenderSettings {
        width: 16,
        height: 9,
        vpls: 64,
        ..lgh_render::RenderSettings::default()
    };
    match lgh_render::render_frame(&world, &settings, &lgh_render::Silent) {
        Ok(frame) if frame.image.pixels.iter().all(|p| p.is_finite()) => Outcome::Loaded,
        Ok(_) => Outcome::Refused("NON-FINITE PIXEL".into()),
        Err(e) => Outcome::Refused(e.to_string()),
    }
}

/// Writes every seed file into `dir` under the names the cases use.
///
/// # Errors
/// A file cannot be written.
pub fn write_seeds(dir: &Path) -> std::io::Result<()> {
    let seeds = Seeds::new();
    std::fs::create_dir_all(dir)?;
    for (name, bytes) in [
        ("scene.gltf", seeds.of(Target::Gltf)),
        ("scene.glb", seeds.of(Target::Glb)),
        ("scene.obj", seeds.of(Target::Obj)),
        ("scene.mtl", seeds.of(Target::Mtl)),
        ("scene.toml", seeds.of(Target::Toml)),
        ("texture.png", seeds.of(Target::Texture)),
        ("image.exr", seeds.of(Target::Exr)),
    ] {
        std::fs::write(dir.join(name), bytes)?;
    }
    Ok(())
}

/// A panic payload as text.
pub(crate) fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "panic".into())
}

/// Runs cases `first..first + cases` of run `seed` in parallel, each in a folder of its own
/// under `work_dir`; `on_progress` is called with the cases done so far, about
/// every thousand cases. Panic messages are kept off stderr while it runs.
#[must_use]
pub fn run(
    seed: u64,
    first: u64,
    cases: u64,
    work_dir: &Path,
    on_progress: &(dyn Fn(u64) + Sync),
) -> Report {
    let seeds = Seeds::new();
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let done = std::sync::atomic::AtomicU64::new(0);
    let report = (first..first + cases)
        .into_par_iter()
        .fold(Report::default, |mut report, case| {
            // A folder per case: a worker waiting inside a render may steal another case.
            let dir = work_dir.join(format!("case-{case}"));
            let _ = std::fs::create_dir_all(&dir);
            let (target, data) = input_from(&seeds, seed, case);
            let start = Instant::now();
            let outcome = catch_unwind(AssertUnwindSafe(|| run_input(&seeds, target, &data, &dir)));
            let ms = start.elapsed().as_secs_f64() * 1e3;
            report.cases += 1;
            report.max_ms = report.max_ms.max(ms);
            match outcome {
                Ok(Outcome::Loaded) => report.loaded += 1,
                Ok(Outcome::Refused(e)) if e.contains("NON-FINITE") => {
                    report.findings.push(Finding {
                        case,
                        target,
                        what: "non-finite pixel in the image".into(),
                        input: data.clone(),
                    });
                }
                Ok(Outcome::Refused(e)) => {
                    report.refused += 1;
                    if e.contains(CONTAINED) {
                        report.contained_panics += 1;
                    }
                }
                Err(payload) => report.findings.push(Finding {
                    case,
                    target,
                    what: format!("panic: {}", panic_text(payload.as_ref())),
                    input: data.clone(),
                }),
            }
            if ms > SLOW_CASE_MS {
                report.findings.push(Finding {
                    case,
                    target,
                    what: format!("slow: {ms:.0} ms"),
                    input: data,
                });
            }
            let _ = std::fs::remove_dir_all(&dir);
            let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if n.is_multiple_of(1000) {
                on_progress(n);
            }
            report
        })
        .reduce(Report::default, Report::merge);
    std::panic::set_hook(hook);
    report
}
