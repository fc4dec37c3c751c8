//! The a-trous filter of the ratio estimator on the GPU (`shaders/atrous.wgsl`): S and U
//! filtered with one set of edge-stopping weights (w_a on the key of A, which rides in U's
//! fourth component), pass after pass (lgh-render's
//! `denoise::atrous::filter_ratio_pair`, the same taps, weights and cut-off), one dispatch a
//! pass between two buffers.

use glam::{Vec3, Vec4};
use lgh_render::denoise::atrous::{AtrousParams, filter_guide, unshadowed_key};
use lgh_render::passes::gbuffer::GBuffer;

use rayon::prelude::*;

use crate::batch::Batch;
use crate::context::{GpuContext, GpuError};
use crate::pool::Lease;

/// `Params` of the shader.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    width: u32,
    height: u32,
    step: u32,
    geo_stride: u32,
    inv_c: f32,
    inv_n: f32,
    inv_p: f32,
    inv_a: f32,
}

/// The WGSL source of the kernel.
#[must_use]
pub fn source() -> String {
    crate::kernel(&[include_str!("../shaders/atrous.wgsl")])
}

/// The G-buffer as the filter reads it: per pixel `stride` vec4s, the position (w: 1 where
/// the pixel sees a surface) first, the normal second.
pub(crate) struct Geometry<'a> {
    /// The buffer.
    pub buffer: &'a wgpu::Buffer,
    /// Vec4s per pixel.
    pub stride: u32,
    /// Image width and height.
    pub size: (u32, u32),
}

/// Records the filter's passes into `batch` (timed as `name`) over the images `pair` (per
/// pixel S with its guide in w, then U with the key of A in w), the input in `pair[0]`, the
/// two buffers taking turns; returns the index in `pair` of the filtered images.
///
/// # Errors
/// The image exceeds one dispatch.
pub(crate) fn record(
    ctx: &GpuContext,
    batch: &mut Batch<'_>,
    name: &'static str,
    geo: &Geometry<'_>,
    pair: [&Lease<'_>; 2],
    params: &AtrousParams,
) -> Result<usize, GpuError> {
    let passes = params.passes.min(lgh_render::denoise::atrous::MAX_PASSES) as usize;
    let pipeline = ctx.pipeline("atrous", source);
    let (width, height) = geo.size;
    for pass in 0..passes {
        let uniform = batch.uniform(&Params {
            width,
            height,
            step: 1 << pass,
            geo_stride: geo.stride,
            inv_c: 4f32.powi(pass as i32) / params.c_phi,
            inv_n: 1.0 / params.n_phi,
            inv_p: 1.0 / params.p_phi,
            inv_a: if params.a_phi > 0.0 {
                1.0 / params.a_phi
            } else {
                0.0
            },
        })?;
        let (from, to) = (pair[pass % 2], pair[1 - pass % 2]);
        let bind = ctx.bind_group(
            &pipeline,
            vec![
                uniform.as_entire_binding(),
                geo.buffer.as_entire_binding(),
                from.binding(),
                to.binding(),
            ],
        );
        batch.dispatch(name, &pipeline, &bind, (width * height) as usize)?;
    }
    Ok(passes % 2)
}

/// Filters `s` and `u` (per pixel of `g`) in place with `params` (w_a on the unshadowed sums
/// `a` where given), on the GPU; pixels that see nothing keep their values.
///
/// # Errors
/// The image exceeds the adapter's limits, or the GPU failed.
pub fn filter_ratio_pair(
    ctx: &GpuContext,
    s: &mut [Vec3],
    u: &mut [Vec3],
    a: Option<&[Vec3]>,
    g: &GBuffer,
    params: &AtrousParams,
) -> Result<(), GpuError> {
    let n = g.len();
    if params.passes == 0 || n == 0 {
        return Ok(());
    }
    let values: Vec<[Vec4; 2]> = s
        .par_iter()
        .zip(u.par_iter())
        .enumerate()
        .map(|(i, (&s, &u))| {
            let key = a.map_or(0.0, |a| unshadowed_key(a[i]));
            [s.extend(filter_guide(s, u)), u.extend(key)]
        })
        .collect();
    let gbuffer = ctx.gbuffer(g)?;
    let pair = [
        ctx.upload("a-trous S, U", &values)?,
        ctx.output("a-trous S, U (next)", 32 * n as u64)?,
    ];
    let mut batch = Batch::new(ctx);
    let geometry = Geometry {
        buffer: gbuffer.buffer(),
        stride: 4,
        size: (g.width, g.height),
    };
    let last = record(
        ctx,
        &mut batch,
        "shadow_filter",
        &geometry,
        [&pair[0], &pair[1]],
        params,
    )?;
    batch.read(pair[last].buffer(), pair[last].bytes())?;
    let (reads, _) = batch.finish()?;
    let out: &[[Vec4; 2]] = reads
        .first()
        .map(|r| bytemuck::cast_slice(r))
        .unwrap_or_default();
    s.par_iter_mut()
        .zip(u.par_iter_mut())
        .zip(out.par_iter())
        .for_each(|((s, u), pair)| {
            *s = pair[0].truncate();
            *u = pair[1].truncate();
        });
    Ok(())
}
