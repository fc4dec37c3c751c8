//! `lgh-fuzz`: the long fuzz run of every lgh loader (see the library's docs).
//!
//! ```text
//! cargo run --release -p lgh-fuzz -- --cases 1000000
//! ```
//! prints the counts and every finding, saves each finding's input under `--findings`, and
//! exits with code 1 if there was any.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;

/// Mutation fuzzing of lgh's loaders: glTF, GLB, OBJ, MTL, TOML scene files, PNG textures,
/// EXR and PNG images.
#[derive(Debug, Parser)]
#[command(name = "lgh-fuzz", version, about)]
struct Args {
    /// Number of cases.
    #[arg(long, default_value_t = 100_000)]
    cases: u64,
    /// The run's seed (case i of a seed is always the same input).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The first case number (to replay one: --first i --cases 1).
    #[arg(long, default_value_t = 0)]
    first: u64,
    /// Folder for the cases' files (removed after each case).
    #[arg(long, default_value_os_t = std::env::temp_dir().join("lgh-fuzz"))]
    work_dir: PathBuf,
    /// Folder where the input of each finding is saved.
    #[arg(long, default_value = "fuzz-findings")]
    findings: PathBuf,
    /// Write the seed files (scene.gltf, scene.glb, scene.obj, scene.mtl, texture.png,
    /// scene.toml, image.exr) to this folder and exit: with a finding's input in place of
    /// its seed, they reproduce it with `lgh render` or `lgh diff`.
    #[arg(long)]
    write_seeds: Option<PathBuf>,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
}

fn main() -> ExitCode {
    let args = Args::parse();
    if args.threads > 0
        && let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(args.threads)
            .build_global()
    {
        eprintln!("error: --threads {}: {e}", args.threads);
        return ExitCode::from(2);
    }
    if let Some(dir) = &args.write_seeds {
        return match lgh_fuzz::write_seeds(dir) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {}: {e}", dir.display());
                ExitCode::from(2)
            }
        };
    }
    let start = Instant::now();
    let step = (args.cases / 20).max(1000);
    let report = lgh_fuzz::run(args.seed, args.first, args.cases, &args.work_dir, &|n| {
        if n % step < 1000 {
            eprintln!("{n} cases, {:.0} s", start.elapsed().as_secs_f64());
        }
    });
    let secs = start.elapsed().as_secs_f64();
    println!(
        "{} cases in {secs:.0} s ({:.0} per second): {} loaded, {} refused with an error \
         ({} of them panics a loader contained), {} findings; slowest case {:.0} ms",
        report.cases,
        report.cases as f64 / secs.max(1e-9),
        report.loaded,
        report.refused,
        report.contained_panics,
        report.findings.len(),
        report.max_ms
    );
    let hostile = lgh_fuzz::hostile::run(&args.work_dir.join("hostile"));
    let hostile_findings: Vec<_> = hostile.iter().filter(|o| o.result.is_err()).collect();
    println!(
        "{} hostile cases (special files, bombs, instancing): {} findings",
        hostile.len(),
        hostile_findings.len()
    );
    for o in &hostile_findings {
        println!("hostile case {} ({:?}): {:?}", o.name, o.class, o.result);
    }
    if report.findings.is_empty() && hostile_findings.is_empty() {
        return ExitCode::SUCCESS;
    }
    let _ = std::fs::create_dir_all(&args.findings);
    for f in &report.findings {
        let path = args
            .findings
            .join(format!("case-{}-{:?}.bin", f.case, f.target).to_lowercase());
        let _ = std::fs::write(&path, &f.input);
        println!(
            "case {} ({:?}): {} -> {}",
            f.case,
            f.target,
            f.what,
            path.display()
        );
    }
    ExitCode::from(1)
}
