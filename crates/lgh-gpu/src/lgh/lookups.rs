//! The unbiased estimate's lookup tables made on the GPU (`shaders/lookups/`) from the
//! records a hierarchy build keeps ([`crate::grid::Held`]), for a frame whose CPU did not
//! make them ([`GridTables::lookups_on_device`]): where each vertex row of every level
//! starts among the grid lights (lgh_core's `row_starts`, which find a grid light by its
//! vertex for Lambda_i) and the children of every light of level >= 2 with the running sums
//! of their weights (lgh_core's [`Descent`], the walk down to an S_1 light; docs/design.md,
//! "Unbiased estimate"). The same tables as the CPU's of the same grid, in the same places
//! of the loop's words ([`super::upload::Tables`]), so that the grid's lookups are neither
//! made on the CPU nor uploaded.
//!
//! Per hierarchy, from its records as the build numbered them ([`crate::grid::Numbered`]):
//! 1. `rows`: one invocation per row entry, a binary search of its level's records by row
//!    (the first record of the row is kept for the next passes);
//! 2. `count`: one invocation per record, its children (at most 27) found as the CPU finds
//!    them (a vertex's row, then a binary search of its x among the row's records), written
//!    with their running sums into 27 slots per record of level >= 2, and counted;
//! 3. a [`scan`](crate::scan) of the counts: where each light's children start;
//! 4. `fill`: each light's children copied from its slots to their place, and its end
//!    written into the starts.
//!
//! Every value is written by one invocation from integer counts and sums in a fixed order,
//! so the tables do not depend on the scheduling. The running sums are the CPU's but for
//! rounding where the adapter fuses a multiply and an add (the luminance).
//!
//! [`Descent`]: lgh_core::lighting_grid::descent::Descent

use lgh_render::methods::lgh::tables::{GridTables, LghTables};

use super::upload::Tables;
use crate::batch::Batch;
use crate::context::{GpuContext, GpuError};
use crate::grid::Held;
use crate::pool::Lease;

/// Per-level entries of [`LookupParams`] (levels 1..=l_max + 1 at most 11, and room).
const LEVELS: usize = 12;

/// The most children of one light: the 27 vertices around twice its vertex.
pub(super) const MAX_CHILDREN: usize = 27;

/// `LookupParams` of `shaders/lookups/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct LookupParams {
    count: u32,
    l_max: u32,
    rows_base: u32,
    starts_base: u32,
    children_base: u32,
    row_entries: u32,
    _p: [u32; 2],
    start: [[u32; 4]; LEVELS],
}

/// The WGSL sources of the three kernels: rows, count, fill.
#[must_use]
pub fn sources() -> [String; 3] {
    let common = include_str!("../shaders/lookups/common.wgsl");
    let children = include_str!("../shaders/lookups/children.wgsl");
    [
        crate::kernel(&[common, include_str!("../shaders/lookups/rows.wgsl")]),
        crate::kernel(&[
            common,
            children,
            include_str!("../shaders/lookups/count.wgsl"),
        ]),
        crate::kernel(&[common, include_str!("../shaders/lookups/fill.wgsl")]),
    ]
}

/// Row entries of level `l` of a grid with `l_max` levels: `(r + 1)^2 + 1` for r cells per
/// axis (lgh-core's `row_starts`).
fn level_row_entries(l_max: u32, l: u32) -> u32 {
    let side = (1u32 << (l_max - l)) + 1;
    side * side + 1
}

/// Row entries of a grid with `l_max` levels, over its levels l >= 1.
#[must_use]
pub(super) fn row_entries(l_max: u32) -> usize {
    (1..=l_max)
        .map(|l| level_row_entries(l_max, l) as usize)
        .sum()
}

/// Records into `batch` the making of the lookup tables of every hierarchy of `t` whose
/// CPU did not make them, into `words` at the places `packed` gives them, from the records
/// its build holds and numbered (`held`, in hierarchy order).
///
/// # Errors
/// Such a hierarchy's records are not held, or a buffer, dispatch or scan cannot be had.
pub(super) fn record<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    t: &LghTables,
    packed: &Tables,
    held: &[Option<Held<'c>>],
    words: &Lease<'c>,
) -> Result<(), GpuError> {
    let [rows_src, count_src, fill_src] = sources();
    for (i, h) in t.hierarchies.iter().enumerate() {
        let grid: &GridTables = h.grid;
        if !grid.lookups_on_device {
            continue;
        }
        let Some(Some(Held {
            records: Some(records),
            level_records,
            numbered,
            ..
        })) = held.get(i)
        else {
            return Err(GpuError::Failed(
                "lgh on the GPU: a hierarchy's lookups are neither on the GPU nor in its tables"
                    .into(),
            ));
        };
        let l_max = grid.geometry.l_max;
        let (rows_base, starts_base, children_base) = packed.word_bases(i);
        let mut params = LookupParams {
            l_max,
            rows_base,
            starts_base,
            children_base,
            ..LookupParams::default()
        };
        let (mut at, mut entry) = (0u32, 0u32);
        for l in 1..=(l_max as usize).min(LEVELS - 2) {
            params.start[l] = [at, entry, 0, 0];
            at += level_records.get(l - 1).copied().unwrap_or(0);
            entry += level_row_entries(l_max, l as u32);
        }
        params.start[(l_max as usize + 1).min(LEVELS - 1)] = [at, entry, 0, 0];
        params.count = at;
        params.row_entries = entry;
        if at == 0 {
            // No records: every row starts at grid light 0, and there are no children.
            let zeros = ctx.upload("lookups zeros", &vec![0u32; entry as usize + 1])?;
            batch.copy(
                &zeros,
                0,
                words,
                4 * u64::from(rows_base),
                4 * u64::from(entry),
            );
            batch.copy(&zeros, 0, words, 4 * u64::from(starts_base), 4);
            batch.keep(zeros);
            continue;
        }
        let Some(numbers) = numbered else {
            return Err(GpuError::Failed(
                "lgh on the GPU: a hierarchy's records are not numbered".into(),
            ));
        };
        let uniform = batch.uniform(&params)?;
        let common = (&uniform, records, &numbers.index);
        let row_records = ctx.output("lookup row records", 4 * u64::from(entry))?;
        let pipeline = ctx.pipeline("lookups rows", || rows_src.clone());
        let bind = ctx.bind_group(
            &pipeline,
            bindings(common, &[&numbers.total, words, &row_records]),
        );
        batch.dispatch("lookups", &pipeline, &bind, entry as usize)?;
        let counts = ctx.output("lookup counts", 4 * u64::from(at))?;
        let offsets = ctx.output("lookup offsets", 4 * u64::from(at))?;
        let children = ctx.output("lookup children", 16)?;
        let parents = u64::from(at - params.start[2][0]);
        let scratch = ctx.output("lookup slots", 8 * MAX_CHILDREN as u64 * parents)?;
        let pipeline = ctx.pipeline("lookups count", || count_src.clone());
        let bind = ctx.bind_group(
            &pipeline,
            bindings(common, &[&row_records, &counts, &scratch]),
        );
        batch.dispatch("lookups", &pipeline, &bind, at as usize)?;
        crate::scan::record(ctx, batch, &counts, &offsets, &children, at as usize, false)?;
        let pipeline = ctx.pipeline("lookups fill", || fill_src.clone());
        let bind = ctx.bind_group(
            &pipeline,
            bindings(common, &[&counts, &scratch, &offsets, words]),
        );
        batch.dispatch("lookups", &pipeline, &bind, at as usize)?;
        for lease in [counts, offsets, children, scratch, row_records] {
            batch.keep(lease);
        }
    }
    Ok(())
}

/// The bindings of a lookups kernel: the uniform, the records and their numbers (`common`),
/// then the kernel's own buffers.
fn bindings<'a>(
    (uniform, records, index): (&'a crate::batch::Uniform, &'a Lease<'_>, &'a Lease<'_>),
    extra: &[&'a Lease<'_>],
) -> Vec<wgpu::BindingResource<'a>> {
    let mut all = vec![
        uniform.as_entire_binding(),
        records.binding(),
        index.binding(),
    ];
    all.extend(extra.iter().map(|l| l.binding()));
    all
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GpuGridBuilder;
    use crate::lgh::testing::{FrameInputs, cornell_and_two_rooms, prepare};
    use lgh_render::{RenderSettings, World};

    /// One hierarchy's lookups as read from the words: its vertex rows and descent starts,
    /// and its descent children (grid index, bits of the running sum).
    type Lookups = (Vec<u32>, Vec<[u32; 2]>);

    /// Per hierarchy of `world`'s frame of `s` built on the GPU: its lookups as the GPU
    /// makes them (`on_gpu`), or as the CPU makes them from the same grid read back.
    fn lookups(world: &World, s: &RenderSettings, on_gpu: bool) -> Vec<Lookups> {
        let made = FrameInputs::new(world, s);
        let inputs = made.inputs(world, s);
        let ctx = GpuContext::shared().expect("an adapter");
        let mut builder = GpuGridBuilder::new(ctx);
        builder.keep_representatives(on_gpu);
        let frame = prepare(&inputs, Some(&mut builder));
        let held = builder.take_held();
        let t = frame.tables(s.width, s.height).expect("tables");
        assert!(
            t.hierarchies
                .iter()
                .all(|h| h.grid.lookups_on_device == on_gpu)
        );
        let packed = Tables::new(&t, false).expect("packed");
        let mut batch = Batch::new(ctx);
        let all = packed.words(ctx, &mut batch, &t).expect("words");
        record(ctx, &mut batch, &t, &packed, &held, &all).expect("record");
        batch.read(all.buffer(), all.bytes()).expect("read");
        let (reads, _) = batch.finish().expect("gpu");
        let read: &[u32] = bytemuck::cast_slice(&reads[0]);
        (0..t.hierarchies.len())
            .map(|i| {
                let len = t.hierarchies[i].grid.len;
                let (rows, starts, children) = packed.word_bases(i);
                let (rows, starts, children) = (rows as usize, starts as usize, children as usize);
                let ends = read[starts + len] as usize;
                let pairs = read[children..children + 2 * ends]
                    .chunks(2)
                    .map(|p| [p[0], p[1]])
                    .collect();
                (read[rows..=starts + len].to_vec(), pairs)
            })
            .collect()
    }

    /// The GPU makes the CPU's vertex rows and descent of the same grid: the rows, the
    /// starts and the children equal, the running sums within 2e-7 relative (a fused
    /// multiply-add may round the luminance apart), on the default scene and two-rooms
    /// with one hierarchy and with six, at two VPL counts (more levels).
    #[test]
    #[cfg_attr(
        not(gpu_adapter),
        ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
    )]
    fn the_gpu_makes_the_cpus_lookups() {
        for world in &cornell_and_two_rooms() {
            for (normal_bins, vpls) in [(false, 3000), (true, 3000), (false, 40_000)] {
                let mut s = RenderSettings {
                    width: 32,
                    height: 18,
                    vpls,
                    ..RenderSettings::default()
                };
                s.lgh.normal_bins = normal_bins;
                let gpu = lookups(world, &s, true);
                let cpu = lookups(world, &s, false);
                assert_eq!(gpu.len(), cpu.len());
                let children: usize = cpu.iter().map(|(_, c)| c.len()).sum();
                assert!(children > 100, "{children} children");
                for (h, ((g, gc), (c, cc))) in gpu.iter().zip(&cpu).enumerate() {
                    assert_eq!(g, c, "hierarchy {h}: rows and starts");
                    assert_eq!(gc.len(), cc.len(), "hierarchy {h}: children");
                    for (k, (a, b)) in gc.iter().zip(cc).enumerate() {
                        assert_eq!(a[0], b[0], "hierarchy {h}, child {k}");
                        let (x, y) = (f32::from_bits(a[1]), f32::from_bits(b[1]));
                        assert!(
                            y > 0.0 && (x - y).abs() <= 2e-7 * y,
                            "hierarchy {h}, child {k}: sum {x} {y}"
                        );
                    }
                }
            }
        }
    }
}
