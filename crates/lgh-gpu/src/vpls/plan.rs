//! How many light paths a batch of VPL generation traces, and the yields that plan them.
//!
//! The VPL set is the paths in order of their number up to the first that brings the VPLs
//! to the target, whatever the batches (the compaction cuts at the target, and a batch
//! starts at the first path not yet kept), so the plan only decides how many times the CPU
//! waits for a count. With nothing known, the first batch is planned as if every path left
//! `bounces` VPLs (too few paths: a second batch follows, planned from the first's yield).
//! A context remembers the yield (paths per VPL) of the last generation over the same
//! scene geometry, lights and bounces ([`Yields`]), so that a viewer's or a benchmark's next
//! frame plans one batch that usually suffices, with 5% to spare; a stale yield only costs
//! a second batch or a few paths that are traced and not kept.

use std::collections::HashMap;
use std::sync::{Mutex, PoisonError};

/// The most paths of one batch (as the CPU's).
pub(super) const MAX_BATCH: u64 = 1 << 20;
/// The fewest.
pub(super) const MIN_BATCH: u64 = 1024;
/// The margin on a planned batch.
const MARGIN: f64 = 1.05;

/// What a yield is remembered for: the scene's geometry ([`lgh_render::World::geometry_id`]),
/// its number of lights and the bounces.
pub(crate) type YieldKey = (u64, usize, u32);

/// The paths per VPL of the last generation for each key, kept by a context.
#[derive(Debug, Default)]
pub(crate) struct Yields(Mutex<HashMap<YieldKey, f64>>);

impl Yields {
    /// The yield remembered for `key`.
    pub(crate) fn get(&self, key: YieldKey) -> Option<f64> {
        let map = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        map.get(&key).copied()
    }

    /// Remembers `paths` per `vpls` for `key` (nothing without VPLs).
    pub(crate) fn set(&self, key: YieldKey, paths: u64, vpls: u64) {
        if paths == 0 || vpls == 0 {
            return;
        }
        let mut map = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        // A few scenes at a time: a benchmark's or a test's.
        if map.len() >= 64 {
            map.clear();
        }
        map.insert(key, paths as f64 / vpls as f64);
    }

    /// Forgets the yield of `key` (tests: the first batch planned as if nothing were known).
    #[cfg(test)]
    pub(crate) fn forget(&self, key: YieldKey) {
        let mut map = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        map.remove(&key);
    }
}

/// The next batch: its number of paths, and whether it is expected to bring the VPLs to
/// the target (planned from a yield and not cut by the limits), so that what follows the
/// paths can be recorded in its submission.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Planned {
    pub(super) paths: u64,
    pub(super) last: bool,
}

/// The next batch after `paths` paths that left `done` VPLs, `missing` more wanted:
/// planned from the VPLs per path seen so far, else from the remembered yield `known`
/// (paths per VPL), else as if every path left `bounces` VPLs; within [`MIN_BATCH`] and
/// `max_batch`, and no further than `left` paths.
pub(super) fn next_batch(
    (paths, done, missing): (u64, u64, u64),
    known: Option<f64>,
    bounces: u32,
    (max_batch, left): (u64, u64),
) -> Planned {
    let missing = missing as f64;
    let per_vpl = if paths > 0 {
        Some(paths as f64 / done.max(1) as f64)
    } else {
        known.filter(|y| y.is_finite() && *y > 0.0)
    };
    let planned = match per_vpl {
        Some(y) => (MARGIN * missing * y).ceil(),
        None => (missing / f64::from(bounces.max(1))).ceil(),
    };
    let n = (planned as u64)
        .clamp(MIN_BATCH, max_batch.max(1))
        .min(left);
    Planned {
        paths: n,
        last: per_vpl.is_some() && n as f64 >= planned,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first batch without a yield plans `bounces` VPLs a path and is not expected to
    /// be the last; with one, or after a batch, 5% to spare and expected last; cut by the
    /// limits, not expected last.
    #[test]
    fn batches_are_planned_from_what_is_known() {
        let none = next_batch((0, 0, 30_000), None, 3, (MAX_BATCH, u64::MAX));
        assert_eq!(
            none,
            Planned {
                paths: 10_000,
                last: false
            }
        );
        let known = next_batch((0, 0, 30_000), Some(2.0), 3, (MAX_BATCH, u64::MAX));
        assert_eq!(
            known,
            Planned {
                paths: 63_000,
                last: true
            }
        );
        let after = next_batch((10_000, 5_000, 25_000), Some(9.0), 3, (MAX_BATCH, u64::MAX));
        assert_eq!(
            after,
            Planned {
                paths: 52_500,
                last: true
            }
        );
        let cut = next_batch((0, 0, 30_000), Some(2.0), 3, (50_000, u64::MAX));
        assert_eq!(
            cut,
            Planned {
                paths: 50_000,
                last: false
            }
        );
        let end = next_batch((0, 0, 30_000), Some(2.0), 3, (MAX_BATCH, 40_000));
        assert_eq!(
            end,
            Planned {
                paths: 40_000,
                last: false
            }
        );
        let small = next_batch((0, 0, 10), Some(2.0), 3, (MAX_BATCH, u64::MAX));
        assert_eq!(
            small,
            Planned {
                paths: MIN_BATCH,
                last: true
            }
        );
        let bad = next_batch((0, 0, 30_000), Some(f64::NAN), 3, (MAX_BATCH, u64::MAX));
        assert!(!bad.last);
        let y = Yields::default();
        y.set((1, 2, 3), 10, 25);
        assert_eq!(y.get((1, 2, 3)), Some(0.4));
        assert_eq!(y.get((1, 2, 4)), None);
        y.set((1, 2, 4), 10, 0);
        assert_eq!(y.get((1, 2, 4)), None);
    }
}
