//! lgh's frame on the GPU from the lighting loop to the ratio estimator in one submission:
//! the loop ([`super::record_loop`]) and the estimator after it ([`crate::ratio::record`]);
//! the images stay on the GPU from the loop on, and a frame shown on the GPU
//! ([`crate::display`]) adds its direct light and showing to the same submission.

use glam::Vec4;
use lgh_core::timing::Timings;
use lgh_render::methods::MethodInputs;
use lgh_render::methods::lgh::tables::LghTables;
use lgh_render::shading::ratio::{RatioFilter, Shadowed};

use super::{Loop, OnGpu, gpu_timings, record_loop};
use lgh_render::display::Displayed;

use crate::context::{GpuContext, GpuError};
use crate::display::{self, Part, Shown};
use crate::ratio::{self, Frame};

/// What the loop's submission ends with.
pub(super) enum Shaded {
    /// The estimator's images read back: the result and the lights per pixel.
    Read(Shadowed, Vec<u32>),
    /// The frame shown on the GPU ([`crate::display`]): nothing else comes back.
    Shown(Displayed),
}

/// The loop and the ratio estimator of the frame with loop inputs `tables` (and what the GPU
/// holds of it, `held`) and the ratio
/// estimator's settings `filter` ([`ratio::supported`] must hold), and where the frame is
/// `shown`, its direct light and showing: the result (read back, or shown) and the timings
/// ("lighting", "lighting_kernel", "interleave_blur", "shadow_filter", the direct light's
/// and "show" from the GPU's timestamps where it has them, "composite" on the CPU,
/// "gpu_transfer" the rest).
pub(super) fn shade<'c>(
    ctx: &'c GpuContext,
    inputs: &MethodInputs,
    tables: &LghTables,
    held: OnGpu<'c>,
    filter: &RatioFilter,
    shown: Option<&Shown<'_>>,
) -> Result<(Shaded, Timings), GpuError> {
    let g = inputs.gbuffer;
    let Loop {
        mut batch,
        out,
        fill,
        gbuffer,
        start,
        upload_ms,
        before,
    } = record_loop(ctx, inputs, tables, held)?;
    let frame = Frame {
        gbuffer: &gbuffer,
        g,
        radius: inputs.world.radius,
    };
    let result = ratio::record(
        ctx,
        &mut batch,
        &frame,
        &out,
        tables.k,
        filter,
        fill.as_ref(),
    )?;
    if let Some(fill) = fill {
        fill.keep_in(&mut batch);
    }
    if let Some(shown) = shown {
        let indirect = match &result {
            Some(r) => Part::Ratio(r),
            None => Part::Unshadowed(&out),
        };
        let recorded = display::record_frame(ctx, &mut batch, inputs, shown, &gbuffer, indirect)?;
        let (reads, gpu) = batch.finish()?;
        let t = gpu_timings(&gpu, start, upload_ms, 0.0, &before);
        return Ok((Shaded::Shown(recorded.finish(&reads)), t));
    }
    let read = result.as_ref().unwrap_or(&out);
    batch.read(read.buffer(), 48 * g.len() as u64)?;
    let (reads, gpu) = batch.finish()?;
    let planes: &[[Vec4; 3]] = reads.first().map_or(&[], |r| bytemuck::cast_slice(r));
    let (shadowed, overdraw, composite_ms) = ratio::unpack(planes, tables.k, g);
    let mut t = gpu_timings(&gpu, start, upload_ms, composite_ms, &before);
    t.push("composite", composite_ms);
    Ok((Shaded::Read(shadowed, overdraw), t))
}
