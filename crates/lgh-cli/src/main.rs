//! `lgh`: render scenes with many lights, compare images, measure speed.
//!
//! Every error is one line on stderr naming the file or flag and the problem, with exit code 2.
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod bench_build;
mod bench_cmd;
mod bench_equal_time;
mod bench_plot;
mod bench_quality;
mod bench_reference;
mod bench_render;
mod bench_slc;
mod bench_temporal;
mod caps;
mod diff_cmd;
mod heatmap;
mod merge_cmd;
mod progress_bar;
mod render_cmd;
mod scene_arg;
mod sysmem;

use std::process::ExitCode;

use clap::parser::ValueSource;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

/// The process's allocator: jemalloc, set in `.cargo/config.toml` never to hand freed pages back
/// to the system, so that a frame's buffers reuse the pages of the frame before instead of
/// faulting fresh ones in (docs/performance.md, "Allocator").
#[cfg(not(target_env = "msvc"))]
#[global_allocator]
static ALLOCATOR: tikv_jemallocator::Jemalloc = tikv_jemallocator::Jemalloc;

/// Real-time-style global illumination with many lights, on the CPU: lighting grid hierarchy
/// (Lin & Yuksel 2019), stochastic light culling (Tokuyoshi & Harada 2016) and a brute-force
/// reference.
#[derive(Debug, Parser)]
#[command(name = "lgh", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Render a scene (the built-in Cornell box if none is given) to PNG or EXR.
    // Negative numbers are values, so that `--alpha -1` gets "must be a positive number".
    #[command(allow_negative_numbers = true)]
    Render(Box<render_cmd::RenderArgs>),
    /// Fly through a scene in a window while it renders (or --headless); keys change the
    /// method and its settings, and move the camera and the light.
    #[command(allow_negative_numbers = true, after_help = lgh_view::state::controls_help())]
    View(Box<lgh_view::ViewArgs>),
    /// Compare image A against reference B (EXR or PNG, same size).
    Diff(diff_cmd::DiffArgs),
    /// Measure performance.
    #[command(allow_negative_numbers = true)]
    Bench(Box<bench_cmd::BenchArgs>),
    /// Join the pieces of a frame rendered with `lgh render --tile I/N` (render farms):
    /// they must belong to one frame, share its settings and cover it once.
    Merge(merge_cmd::MergeArgs),
}

/// The last line of defence: a panic (a bug, since no input should cause one) prints one line
/// instead of a stack trace; a closed stdout (`lgh bench ... | head`) ends the program quietly,
/// as a Unix tool's SIGPIPE would.
fn install_panic_hook() {
    std::panic::set_hook(Box::new(|info| {
        let message = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| (*s).to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_default();
        if message.contains("Broken pipe") {
            std::process::exit(0);
        }
        let place = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        eprintln!("error: internal error{place}: {message} (please report it)");
    }));
}

fn main() -> ExitCode {
    install_panic_hook();
    // An interrupted run leaves no `.partial` file behind (lgh_render::output). Without a
    // handler (it cannot be installed) Ctrl-C still stops the process.
    let _ = ctrlc::set_handler(|| {
        lgh_render::output::remove_partial_files();
        std::process::exit(130);
    });
    let matches = Cli::command().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    let result = match cli.command {
        Command::Render(mut a) => {
            a.use_accumulation_defaults(|id| given(&matches, "render", id));
            render_cmd::run(&a)
        }
        Command::View(mut a) => {
            // Flags given on the command line keep their values; the others start at the
            // viewer's interactive defaults.
            a.use_interactive_defaults(|id| given(&matches, "view", id));
            view(*a)
        }
        Command::Diff(a) => diff_cmd::run(&a),
        Command::Merge(a) => merge_cmd::run(&a),
        Command::Bench(a) => bench_cmd::run(&a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

/// True if argument `id` of subcommand `command` was given on the command line.
fn given(matches: &clap::ArgMatches, command: &str, id: &str) -> bool {
    matches
        .subcommand_matches(command)
        .is_some_and(|m| m.value_source(id) == Some(ValueSource::CommandLine))
}

/// `lgh view`: loads the scene (default: the Cornell box with a point light, which can be
/// moved) and runs the viewer.
fn view(mut args: lgh_view::ViewArgs) -> anyhow::Result<()> {
    set_threads(args.threads)?;
    args.check()?;
    if args.device == lgh_render::settings::Device::Gpu {
        let device = lgh_gpu::GpuContext::shared()?.adapter_name();
        eprintln!("GPU: {device}");
        args.backend = Some(lgh_gpu::gpu_method_for);
    }
    let default = std::path::PathBuf::from("builtin:cornell-moving-light");
    let scene = scene_arg::load_scene(Some(args.scene.as_ref().unwrap_or(&default)))?;
    // The viewer holds two frames (the accumulated or filtered history beside the new one).
    let estimate = lgh_render::budget::MemoryEstimate::new(&scene, &args.render_settings(), 2);
    sysmem::check(&estimate, args.max_memory)?;
    if args.headless {
        lgh_view::headless::run(&args, scene)
    } else {
        lgh_view::window::run(args, scene)
    }
}

/// The most worker threads `--threads` takes.
const MAX_THREADS: usize = 256;

/// Sets the number of worker threads (0 = one per core).
fn set_threads(threads: usize) -> anyhow::Result<usize> {
    if threads > MAX_THREADS {
        anyhow::bail!("--threads {threads}: at most {MAX_THREADS}");
    }
    if threads > 0 {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global()
            .map_err(|e| anyhow::anyhow!("--threads {threads}: {e}"))?;
    }
    Ok(rayon::current_num_threads())
}
