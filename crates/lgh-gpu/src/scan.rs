//! An exclusive prefix sum on the GPU (`shaders/scan/`): each workgroup scans 1024
//! elements, one workgroup scans the block totals, and the blocks get their offsets. The
//! sums are of integers, so the result is exact and the same from run to run. The hierarchy
//! build numbers its marked vertices with it ([`crate::grid`]).

use crate::batch::Batch;
use crate::context::{GpuContext, GpuError};
use crate::pool::Lease;

/// Elements one workgroup of the first step scans.
const BLOCK: usize = 1024;

/// The parameters of the scan's kernels (`ScanParams` in `shaders/scan/common.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct ScanParams {
    n: u32,
    popcount: u32,
    pad: [u32; 2],
}

/// The WGSL sources of the scan's three kernels.
#[must_use]
pub fn sources() -> [String; 3] {
    let common = include_str!("shaders/scan/common.wgsl");
    [
        crate::kernel(&[common, include_str!("shaders/scan/local.wgsl")]),
        crate::kernel(&[common, include_str!("shaders/scan/blocks.wgsl")]),
        crate::kernel(&[common, include_str!("shaders/scan/add.wgsl")]),
    ]
}

/// Records into `batch` the exclusive prefix sum of the first `n` words of `src` into
/// `dst` (of the words' population counts with `popcount`), and its total into the first
/// word of `total`. The block totals' buffer is kept by the batch.
///
/// # Errors
/// More than 64M elements (the block totals must fit one workgroup's loop and one
/// dispatch), or a buffer could not be leased.
pub fn record<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    src: &Lease<'c>,
    dst: &Lease<'c>,
    total: &Lease<'c>,
    n: usize,
    popcount: bool,
) -> Result<(), GpuError> {
    let blocks = n.div_ceil(BLOCK).max(1);
    let groups = u32::try_from(blocks)
        .ok()
        .filter(|&g| g <= ctx.limits.max_compute_workgroups_per_dimension)
        .ok_or_else(|| GpuError::TooLarge(format!("a scan of {n} elements")))?;
    let sums = ctx.output("scan blocks", 4 * blocks as u64)?;
    let params = batch.uniform(&ScanParams {
        n: n as u32,
        popcount: u32::from(popcount),
        pad: [0; 2],
    })?;
    let block_params = batch.uniform(&ScanParams {
        n: blocks as u32,
        ..ScanParams::default()
    })?;
    let [local, over, add] = sources();
    let local = ctx.pipeline("scan local", || local);
    let over = ctx.pipeline("scan blocks", || over);
    let add = ctx.pipeline("scan add", || add);
    let bind = ctx.bind_group(
        &local,
        vec![
            params.as_entire_binding(),
            src.binding(),
            dst.binding(),
            sums.binding(),
        ],
    );
    batch.dispatch_groups("scan", &local, &bind, groups);
    let bind = ctx.bind_group(
        &over,
        vec![
            block_params.as_entire_binding(),
            sums.binding(),
            total.binding(),
        ],
    );
    batch.dispatch_groups("scan", &over, &bind, 1);
    let bind = ctx.bind_group(
        &add,
        vec![params.as_entire_binding(), dst.binding(), sums.binding()],
    );
    batch.dispatch_groups("scan", &add, &bind, groups);
    batch.keep(sums);
    Ok(())
}
