//! The caps of the count flags: every count a command takes has a stated upper bound, which
//! clap checks as it parses (exit 2, "N is not in 1..=MAX"), so that no request allocates
//! without bound or runs for days.

use clap::builder::RangedU64ValueParser;

/// VPLs (or lights) a benchmark takes per configuration: 4M, within a few GB with the
/// hierarchy (a render takes up to `lgh_render::settings::MAX_VPLS` after its memory check).
pub const MAX_BENCH_VPLS: u64 = 1 << 22;

/// Rays of `bench rays`: 10M, about 1 GB of rays and hits.
pub const MAX_BENCH_RAYS: u64 = 10_000_000;

/// Timed runs or rounds of a benchmark.
pub const MAX_RUNS: u64 = 1000;

/// Frames of `bench temporal`.
pub const MAX_BENCH_FRAMES: u64 = 10_000;

/// A count in `1..=max`, as `usize`.
#[must_use]
pub fn count(max: u64) -> RangedU64ValueParser<usize> {
    RangedU64ValueParser::new().range(1..=max)
}

/// A count in `1..=max`, as `u32`.
#[must_use]
pub fn count_u32(max: u64) -> RangedU64ValueParser<u32> {
    RangedU64ValueParser::new().range(1..=max)
}
