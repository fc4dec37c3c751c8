//! lgh's frame on the GPU from the lighting loop to the ratio estimator in one submission:
//! the loop ([`super::record_loop`]) and the estimator after it ([`crate::ratio::record`]);
//! the images stay on the GPU from the loop on.

use glam::Vec4;
use lgh_core::timing::Timings;
use lgh_render::methods::MethodInputs;
use lgh_render::methods::lgh::tables::LghTables;
use lgh_render::shading::ratio::{RatioFilter, Shadowed};

use super::{Loop, OnGpu, gpu_timings, record_loop};
use crate::context::{GpuContext, GpuError};
use crate::ratio::{self, Frame};

/// The loop and the ratio estimator of the frame with loop inputs `tables` (and what the GPU
/// holds of it, `held`) and the ratio
/// estimator's settings `filter` ([`ratio::supported`] must hold): the result, the lights
/// per pixel and the timings ("lighting", "lighting_kernel", "interleave_blur",
/// "shadow_filter" from the GPU's timestamps where it has them, "composite" on the CPU,
/// "gpu_transfer" the rest).
pub(super) fn shade<'c>(
    ctx: &'c GpuContext,
    inputs: &MethodInputs,
    tables: &LghTables,
    held: OnGpu<'c>,
    filter: &RatioFilter,
) -> Result<(Shadowed, Vec<u32>, Timings), GpuError> {
    let g = inputs.gbuffer;
    let Loop {
        mut batch,
        out,
        gbuffer,
        start,
        upload_ms,
        before,
        ..
    } = record_loop(ctx, inputs, tables, held)?;
    let frame = Frame {
        gbuffer: &gbuffer,
        g,
        radius: inputs.world.radius,
    };
    let result = ratio::record(ctx, &mut batch, &frame, &out, tables.k, filter)?;
    let read = result.as_ref().unwrap_or(&out);
    batch.read(read.buffer(), 48 * g.len() as u64)?;
    let (reads, gpu) = batch.finish()?;
    let planes: &[[Vec4; 3]] = reads.first().map_or(&[], |r| bytemuck::cast_slice(r));
    let (shadowed, overdraw, composite_ms) = ratio::unpack(planes, tables.k, g);
    let mut t = gpu_timings(&gpu, start, upload_ms, composite_ms, &before);
    t.push("composite", composite_ms);
    Ok((shadowed, overdraw, t))
}
