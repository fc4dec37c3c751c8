//! Memory of the machine and of this process (Linux /proc), and the memory limit of
//! `lgh render` and `lgh view`: the memory available to the process (or `--max-memory`)
//! against the library's estimate, checked before the large allocations; and the peak
//! memory the process reached, for `--stats`.

use anyhow::{Result, bail};
use lgh_render::budget::{Bytes, MemoryEstimate};

/// Memory this process can still take: the least of what the system can give without
/// swapping (`MemAvailable` of /proc/meminfo), what the process's cgroup leaves
/// (`memory.max - memory.current`, cgroup v2, or v1's `memory.limit_in_bytes - usage`),
/// and what its address-space limit leaves (`RLIMIT_AS` of /proc/self/limits less the
/// address space in use, `VmSize`); `None` where none is known (not Linux).
#[must_use]
pub fn available_bytes() -> Option<u64> {
    [
        proc_field("/proc/meminfo", "MemAvailable:"),
        cgroup_left(),
        address_space_left(),
    ]
    .into_iter()
    .flatten()
    .min()
}

/// What the cgroup's memory limit leaves, if it has one.
fn cgroup_left() -> Option<u64> {
    let number = |p: &str| -> Option<u64> { std::fs::read_to_string(p).ok()?.trim().parse().ok() };
    let v2 = || {
        let rel = std::fs::read_to_string("/proc/self/cgroup").ok()?;
        let path = rel
            .lines()
            .find_map(|l| l.strip_prefix("0::"))?
            .trim()
            .to_owned();
        let dir = format!("/sys/fs/cgroup{path}");
        let max = number(&format!("{dir}/memory.max"))?; // "max" (no limit) does not parse
        Some(max.saturating_sub(number(&format!("{dir}/memory.current")).unwrap_or(0)))
    };
    v2().or_else(|| {
        let max = number("/sys/fs/cgroup/memory/memory.limit_in_bytes")?;
        // v1 writes a huge number for "no limit".
        (max < 1 << 60).then(|| {
            max.saturating_sub(number("/sys/fs/cgroup/memory/memory.usage_in_bytes").unwrap_or(0))
        })
    })
}

/// What `RLIMIT_AS` leaves of the address space, if it is set.
fn address_space_left() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/limits").ok()?;
    let line = text.lines().find(|l| l.starts_with("Max address space"))?;
    let soft: u64 = line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()?; // "unlimited" does not parse
    Some(soft.saturating_sub(proc_field("/proc/self/status", "VmSize:").unwrap_or(0)))
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
