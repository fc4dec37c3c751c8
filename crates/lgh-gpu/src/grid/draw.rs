//! The S_1 lights' representatives drawn on the GPU in the build's submission
//! (`shaders/grid/cells.wgsl`, `cell_sort.wgsl`, `s1_keep.wgsl`, `draw.wgsl`): the same
//! draw as the CPU's `representative::s1_representatives` (LGH 2019 section 3.3 and
//! docs/design.md, "Shadow targets"), with the same hash, so that the slots are the CPU's
//! wherever the weights round alike.
//!
//! The draw visits the lights of the 8 cells around each S_1 vertex, each cell's by index
//! (the CPU's order; a float running total depends on it). The lights are put into runs by
//! cell with a counting sort (integer atomics: counts and run starts do not depend on the
//! order of anything), and each run is then sorted by index; a run longer than 4,096 lights
//! is left unsorted and flagged, and the CPU draws instead. The S_1 lights are numbered as
//! the grid numbers them (without the zero-intensity ones) by a scan of their kept flags.

use lgh_core::lighting_grid::representative::SLOTS;

use super::{GridParams, record};
use crate::batch::{Batch, Words};
use crate::context::{GpuContext, GpuError};
use crate::pool::Lease;
use crate::scan;

/// What the draw reads of the build.
pub(super) struct Inputs<'a, 'c> {
    /// Parameters with S_1's resolution (`k`), first vertex (`vert0`) and the seed.
    pub base: GridParams,
    /// The uploaded lights and their number.
    pub lights: &'a Lease<'c>,
    pub n: usize,
    /// S_1's vertices before compaction.
    pub s1: usize,
    /// Every vertex's key and sums.
    pub keys: &'a Lease<'c>,
    pub sums: &'a Lease<'c>,
}

/// The buffers to read back: the slots (`SLOTS` per kept S_1 light, at most `s1` lights)
/// and the flag (non-zero: a run was too long to sort, the draw is void).
pub(super) struct Drawn<'c> {
    pub slots: Lease<'c>,
    pub flag: Lease<'c>,
}

/// Records the cells' runs and the draw into `batch`.
///
/// # Errors
/// A buffer could not be leased, or a dispatch or scan is too large.
pub(super) fn record_draw<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    inputs: &Inputs<'_, 'c>,
) -> Result<Drawn<'c>, GpuError> {
    let Inputs {
        base,
        lights,
        n,
        s1,
        keys,
        sums,
    } = *inputs;
    let r = 1u64 << base.k;
    let words = (r * r * r).div_ceil(32) as usize;
    let word_bytes = 4 * words as u64;
    let light_bytes = 4 * n as u64;
    let cell_bits = ctx.output("grid cell bits", word_bytes)?;
    let cell_prefix = ctx.output("grid cell prefix", word_bytes)?;
    let cells = ctx.output("grid cell total", 16)?;
    let counts = ctx.output("grid cell counts", light_bytes)?;
    let starts = ctx.output("grid cell starts", light_bytes)?;
    let runs_total = ctx.output("grid runs total", 16)?;
    let fill = ctx.output("grid cell fill", light_bytes)?;
    let runs = ctx.output("grid runs", light_bytes)?;
    let flag = ctx.output("grid draw flag", 16)?;
    let keep = ctx.output("grid s1 keep", 4 * s1 as u64)?;
    let numbers = ctx.output("grid s1 numbers", 4 * s1 as u64)?;
    let kept = ctx.output("grid s1 kept", 16)?;
    let slots = ctx.output("grid slots", 4 * (SLOTS * s1) as u64)?;
    for lease in [&cell_bits, &counts, &fill, &flag] {
        batch.clear_lease(lease);
    }
    let over_lights = GridParams {
        n: n as u32,
        ..base
    };
    for pass in 0..3 {
        record(
            ctx,
            batch,
            "grid_cells",
            "grid cells",
            &GridParams {
                step: pass,
                ..over_lights
            },
            vec![
                lights.binding(),
                cell_bits.binding(),
                cell_prefix.binding(),
                counts.binding(),
                starts.binding(),
                fill.binding(),
                runs.binding(),
            ],
        )?;
        match pass {
            0 => scan::record(ctx, batch, &cell_bits, &cell_prefix, &cells, words, true)?,
            1 => scan::record(ctx, batch, &counts, &starts, &runs_total, n, false)?,
            _ => {}
        }
    }
    record(
        ctx,
        batch,
        "grid_cells",
        "grid cell sort",
        &over_lights,
        vec![
            counts.binding(),
            starts.binding(),
            cells.binding(),
            runs.binding(),
            flag.binding(),
        ],
    )?;
    let over_s1 = GridParams {
        n: s1 as u32,
        ..base
    };
    record(
        ctx,
        batch,
        "grid_draw",
        "grid s1 keep",
        &over_s1,
        vec![sums.binding(), keep.binding()],
    )?;
    scan::record(ctx, batch, &keep, &numbers, &kept, s1, false)?;
    record(
        ctx,
        batch,
        "grid_draw",
        "grid draw",
        &over_s1,
        vec![
            lights.binding(),
            keys.binding(),
            keep.binding(),
            numbers.binding(),
            cell_bits.binding(),
            cell_prefix.binding(),
            counts.binding(),
            starts.binding(),
            runs.binding(),
            slots.binding(),
        ],
    )?;
    for lease in [
        cell_bits,
        cell_prefix,
        cells,
        counts,
        starts,
        runs_total,
        fill,
        runs,
        keep,
        numbers,
        kept,
    ] {
        batch.keep(lease);
    }
    Ok(Drawn { slots, flag })
}

/// Whether the draw whose read-back flag is `flag` drew (no run was too long to sort).
pub(super) fn drew(flag: &[Words]) -> bool {
    let flag: &[u32] = bytemuck::cast_slice(flag);
    flag.first().copied().unwrap_or(1) == 0
}

/// The read-back slots of the `kept` S_1 lights into `out`; false (nothing drawn) if the
/// flag says a run was too long to sort.
pub(super) fn unpack_draw(
    slots: &[Words],
    flag: &[Words],
    kept: usize,
    out: &mut Vec<[u32; SLOTS]>,
) -> bool {
    if !drew(flag) {
        return false;
    }
    let words: &[u32] = bytemuck::cast_slice(slots);
    out.clear();
    out.extend(
        words
            .chunks_exact(SLOTS)
            .take(kept)
            .map(|c| std::array::from_fn(|s| c[s])),
    );
    out.len() == kept
}
