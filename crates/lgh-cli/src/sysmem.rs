//! Memory of the machine and of this process (Linux /proc), and the memory limit of
//! `lgh render`: the machine's available memory (or `--max-memory`)
//! against the library's estimate, checked before the large allocations; and the peak
//! memory the process reached, for `--stats`.

use anyhow::{Result, bail};
use lgh_render::budget::{Bytes, MemoryEstimate};

/// Memory the system can give without swapping (`MemAvailable` of /proc/meminfo); `None`
/// where that is not known (not Linux).
#[must_use]
pub fn available_bytes() -> Option<u64> {
    proc_field("/proc/meminfo", "MemAvailable:")
}

/// The peak resident memory of this process so far (`VmHWM` of /proc/self/status); `None`
/// where that is not known.
#[must_use]
pub fn peak_bytes() -> Option<u64> {
    proc_field("/proc/self/status", "VmHWM:")
}

/// The resident memory of this process now (`VmRSS`).
#[must_use]
pub fn rss_bytes() -> Option<u64> {
    proc_field("/proc/self/status", "VmRSS:")
}

/// Resets the peak resident memory to the current one (Linux `clear_refs`), and returns the
/// current one; `None` where that is not possible or `LGH_NO_RSS` is set.
pub fn reset_peak() -> Option<u64> {
    if std::env::var_os("LGH_NO_RSS").is_some() {
        return None;
    }
    std::fs::write("/proc/self/clear_refs", "5").ok()?;
    rss_bytes()
}

/// A `kB` field of a /proc file, in bytes.
fn proc_field(path: &str, key: &str) -> Option<u64> {
    let text = std::fs::read_to_string(path).ok()?;
    let line = text.lines().find(|l| l.starts_with(key))?;
    let kb: u64 = line[key.len()..]
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kb * 1024)
}

/// Refuses a render whose estimate exceeds `max` (`--max-memory`), or else the available
/// memory; without either limit, everything passes.
pub fn check(estimate: &MemoryEstimate, max: Option<u64>) -> Result<()> {
    let (limit, what) = match max {
        Some(m) => (m, "--max-memory"),
        None => match available_bytes() {
            Some(a) => (a, "the available memory"),
            None => return Ok(()),
        },
    };
    if estimate.total() > limit {
        bail!(
            "the render needs about {estimate}, more than {what} ({}); lower --size or --vpls{}",
            Bytes(limit),
            if max.is_some() {
                ", or raise --max-memory"
            } else {
                ", or set --max-memory to try anyway"
            }
        );
    }
    Ok(())
}
