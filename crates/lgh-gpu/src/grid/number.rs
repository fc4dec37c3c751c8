//! A build's emitted records numbered as the CPU keeps them (`shaders/grid/kept.wgsl`): a
//! flag per record (a positive intensity; the read-back drops the others,
//! `transfer::unpack`), and the flags' exclusive [`scan`](crate::scan), which is each
//! record's grid index. The passes that make the frame's tables on the GPU from the records
//! (the shaded lights, the unbiased estimate's lookups) read it; where the grid is not read
//! back, the index at each level's first record gives the grid's level ranges.

use super::{GridParams, record};
use crate::batch::Batch;
use crate::context::{GpuContext, GpuError};
use crate::pool::Lease;

/// The numbering of a build's records.
pub struct Numbered<'c> {
    /// Per record, the kept records before it (its grid index where it is kept).
    pub index: Lease<'c>,
    /// In its first word, the number of kept records.
    pub total: Lease<'c>,
}

/// Records into `batch` the numbering of the first `count` (> 0) of `records`.
///
/// # Errors
/// A buffer cannot be had, or the dispatch or scan is too large.
pub(super) fn number<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    records: &Lease<'c>,
    count: u32,
) -> Result<Numbered<'c>, GpuError> {
    let kept = ctx.output("grid kept", 4 * u64::from(count))?;
    let out = Numbered {
        index: ctx.output("grid index", 4 * u64::from(count))?,
        total: ctx.output("grid total", 16)?,
    };
    let p = GridParams {
        n: count,
        ..GridParams::default()
    };
    record(
        ctx,
        batch,
        "grid_number",
        "grid kept",
        &p,
        vec![records.binding(), kept.binding()],
    )?;
    crate::scan::record(
        ctx,
        batch,
        &kept,
        &out.index,
        &out.total,
        count as usize,
        false,
    )?;
    batch.keep(kept);
    Ok(out)
}

/// Records into `batch` the copy into a new buffer of where each level's grid lights start
/// (the grid's `level_start`): the index at the first record of each level, records
/// `level_records[l - 1]` of level l, then the total.
///
/// # Errors
/// A buffer cannot be had.
pub(super) fn level_starts<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    numbered: &Numbered<'c>,
    level_records: &[u32],
) -> Result<Lease<'c>, GpuError> {
    let out = ctx.output("grid level starts", 4 * (level_records.len() as u64 + 1))?;
    let count: u64 = level_records.iter().map(|&c| u64::from(c)).sum();
    let mut at = 0u64;
    for (l, &c) in level_records.iter().enumerate() {
        // A level without records at the end starts at the total.
        if at < count {
            batch.copy(&numbered.index, 4 * at, &out, 4 * l as u64, 4);
        } else {
            batch.copy(&numbered.total, 0, &out, 4 * l as u64, 4);
        }
        at += u64::from(c);
    }
    let top = 4 * level_records.len() as u64;
    batch.copy(&numbered.total, 0, &out, top, 4);
    Ok(out)
}
