//! The build's first step (`shaders/grid/mark.wgsl`, `counts.wgsl`): every light marks the
//! vertices it gives a non-zero weight at resolutions 0..`resolutions`, a scan numbers
//! them, and each resolution's count comes back with the largest intensity component (one
//! wait). The level rule chooses l_max from the counts, and the next step sizes its buffers
//! by them.

use super::GridParams;
use crate::batch::{Batch, PassTimes, Words};
use crate::context::{GpuContext, GpuError};
use crate::pool::Lease;

/// The marks of resolutions 0..`resolutions()` and what was learnt from them.
pub(super) struct Marks<'c> {
    /// The first word of each resolution's bit set (one more at the end), on the CPU and
    /// on the GPU.
    pub starts: Vec<u32>,
    pub word_start: Lease<'c>,
    /// The bit sets and the scan of their population counts.
    pub bits: Lease<'c>,
    pub prefix: Lease<'c>,
    /// The marked vertices per resolution.
    counts: Vec<usize>,
    /// The largest intensity component of the lights.
    pub imax: f32,
}

impl Marks<'_> {
    /// The resolutions marked.
    pub fn resolutions(&self) -> u32 {
        self.counts.len() as u32
    }

    /// The vertices of resolution `k`, if it was marked.
    pub fn count(&self, k: u32) -> Option<usize> {
        self.counts.get(k as usize).copied()
    }
}

/// The first word of each resolution's bit set, for `count` resolutions (count + 1 entries).
fn word_starts(count: u32) -> Vec<u32> {
    let mut starts = vec![0u32];
    let mut at = 0u64;
    for k in 0..count {
        let side = (1u64 << k) + 1;
        at += (side * side * side).div_ceil(32);
        starts.push(at as u32);
    }
    starts
}

/// Marks recorded into a batch and not yet read back ([`record`]).
pub(super) struct Pending<'c> {
    starts: Vec<u32>,
    word_start: Lease<'c>,
    bits: Lease<'c>,
    prefix: Lease<'c>,
    resolutions: u32,
    /// The batch's read-back that holds the counts.
    read: usize,
}

/// Records into `batch` the marks of the `n` uploaded `lights` at resolutions
/// 0..`resolutions` (grid placed by `base`), their numbering and the counts' read-back.
///
/// # Errors
/// A buffer could not be leased.
pub(super) fn record<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    lights: &Lease<'c>,
    base: &GridParams,
    n: usize,
    resolutions: u32,
) -> Result<Pending<'c>, GpuError> {
    let starts = word_starts(resolutions);
    let words = starts[resolutions as usize] as usize;
    let word_start = ctx.upload("grid word starts", &starts)?;
    let bits = ctx.output("grid bits", 4 * words as u64)?;
    let prefix = ctx.output("grid prefix", 4 * words as u64)?;
    let total = ctx.output("grid total", 16)?;
    let misc = ctx.output("grid misc", 4 * 16)?;
    batch.clear_lease(&bits);
    batch.clear_lease(&misc);
    let p = GridParams {
        n: n as u32,
        count: resolutions,
        ..*base
    };
    super::record(
        ctx,
        batch,
        "grid_mark",
        "grid mark",
        &p,
        vec![
            lights.binding(),
            word_start.binding(),
            bits.binding(),
            misc.binding(),
        ],
    )?;
    crate::scan::record(ctx, batch, &bits, &prefix, &total, words, true)?;
    super::record(
        ctx,
        batch,
        "grid_counts",
        "grid counts",
        &GridParams {
            n: resolutions,
            ..p
        },
        vec![
            word_start.binding(),
            prefix.binding(),
            total.binding(),
            misc.binding(),
        ],
    )?;
    let read = batch.reads();
    batch.read(misc.buffer(), misc.bytes())?;
    batch.keep(total);
    batch.keep(misc);
    Ok(Pending {
        starts,
        word_start,
        bits,
        prefix,
        resolutions,
        read,
    })
}

impl<'c> Pending<'c> {
    /// The marks, with the counts from the read-backs `reads` of the batch they were
    /// recorded in.
    pub(super) fn finish(self, reads: &[Vec<Words>]) -> Marks<'c> {
        let misc: &[u32] = reads
            .get(self.read)
            .map_or(&[], |r| bytemuck::cast_slice(r));
        let counts = (0..self.resolutions as usize)
            .map(|k| misc.get(1 + k).copied().unwrap_or(0) as usize)
            .collect();
        Marks {
            starts: self.starts,
            word_start: self.word_start,
            bits: self.bits,
            prefix: self.prefix,
            counts,
            imax: f32::from_bits(misc.first().copied().unwrap_or(0)),
        }
    }
}

/// Marks the `n` uploaded `lights` at resolutions 0..`resolutions` (grid placed by `base`),
/// numbers the marks and reads back the counts, in a batch of its own (one wait); the GPU's
/// pass times go to `passes`.
///
/// # Errors
/// A buffer could not be leased, or the GPU failed.
pub(super) fn mark<'c>(
    ctx: &'c GpuContext,
    lights: &Lease<'c>,
    base: &GridParams,
    n: usize,
    resolutions: u32,
    passes: &mut PassTimes,
) -> Result<Marks<'c>, GpuError> {
    let mut batch = Batch::new(ctx);
    let pending = record(ctx, &mut batch, lights, base, n, resolutions)?;
    let (reads, gpu) = batch.finish()?;
    passes.extend(gpu);
    Ok(pending.finish(&reads))
}
