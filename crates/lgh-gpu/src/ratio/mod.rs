//! The ratio estimator on the GPU (lgh-render's `shading::ratio::shadowed_indirect_with`;
//! LGH 2019 section 3.3): from the unshadowed sum A and the shadow estimates S and U per
//! pixel, the interleaving blur (A over the n x n neighbourhood, S and U over the wide blur;
//! [`crate::interleave`]), the a-trous filter of S and U ([`crate::atrous`]) and the raw and
//! filtered ratios (`shaders/ratio.wgsl`), recorded into a frame's batch after the pass that
//! wrote A, S and U (lgh's lighting loop), so that the images stay on the GPU; the CPU
//! composites albedo / pi x A x ratio from what is read back.

use std::time::Instant;

use glam::{Vec3, Vec4};
use lgh_render::World;
use lgh_render::denoise::atrous::AtrousParams;
use lgh_render::passes::gbuffer::GBuffer;
use lgh_render::shading::ratio::{RatioFilter, ShadowRatio, Shadowed, composite};
use lgh_render::shading::shadow_pass::ShadowEstimates;
use rayon::prelude::*;

use crate::atrous::Geometry;
use crate::batch::Batch;
use crate::context::{GpuContext, GpuError};
use crate::gbuffer::GpuGBuffer;
use crate::interleave::{self, Planes};
use crate::pool::Lease;

/// `Params` of `ratio.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct RatioParams {
    pixels: u32,
    mode: u32,
    max_ratio: f32,
    _p0: u32,
}

/// The WGSL source of the ratio kernel.
#[must_use]
pub fn ratio_source() -> String {
    crate::kernel(&[include_str!("../shaders/ratio.wgsl")])
}

/// One pass of `ratio.wgsl` over the loop's images `asu`.
struct RatioPass<'a> {
    pipeline: &'a wgpu::ComputePipeline,
    pixels: u32,
    max_ratio: f32,
    asu: &'a Lease<'a>,
    result: &'a Lease<'a>,
}

impl RatioPass<'_> {
    /// Records mode `mode` (0: the filter's input into `pair`; 1: the result from the
    /// filtered `pair`), timed as "shadow_filter".
    fn record(
        &self,
        ctx: &GpuContext,
        batch: &mut Batch<'_>,
        mode: u32,
        pair: &Lease<'_>,
    ) -> Result<(), GpuError> {
        let uniform = batch.uniform(&RatioParams {
            pixels: self.pixels,
            mode,
            max_ratio: self.max_ratio,
            _p0: 0,
        })?;
        let bind = ctx.bind_group(
            self.pipeline,
            vec![
                uniform.as_entire_binding(),
                self.asu.binding(),
                pair.binding(),
                self.result.binding(),
            ],
        );
        batch.dispatch("shadow_filter", self.pipeline, &bind, self.pixels as usize)
    }
}

/// True if the GPU runs `filter` (its blur's radius within the GPU blur's).
pub fn supported(filter: &RatioFilter) -> bool {
    filter
        .interleave_blur
        .is_none_or(|p| interleave::supported(&p) && interleave::supported(&p.recombination()))
}

/// The frame the estimator works on: its G-buffer on the GPU and the CPU's, and the scene's
/// radius (the a-trous filter's position scale).
pub(crate) struct Frame<'a> {
    pub gbuffer: &'a GpuGBuffer,
    pub g: &'a GBuffer,
    pub radius: f32,
}

/// Records the estimator into `batch` after the pass that wrote `asu` (per pixel [A (w: the
/// lights shaded), S (w: rays), U]), with `k` shadow samples per pixel (0: A alone) and the
/// settings `filter`; [`supported`] must hold; where pixels fill their cut recombination
/// windows, `fill` ([`crate::fill`]) gives their A. The buffer to read back (3 vec4s per pixel,
/// for [`unpack`]): the result for k > 0, else `asu` itself, blurred in place.
///
/// # Errors
/// The image exceeds one dispatch.
pub(crate) fn record<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    frame: &Frame<'_>,
    asu: &Lease<'c>,
    k: u32,
    filter: &RatioFilter,
    fill: Option<&crate::fill::Fill<'_>>,
) -> Result<Option<Lease<'c>>, GpuError> {
    let g = frame.g;
    let n = g.len();
    let bytes = 48 * n as u64;
    if let Some(p) = filter.interleave_blur {
        let scratch = ctx.output("A, S, U (blur)", bytes)?;
        let size = (frame.gbuffer, g.width, g.height);
        // The discontinuities, once: those the fill's masks were made with, or here.
        let mut own = None;
        let jumps = match fill {
            Some(f) => f.jumps(),
            None => {
                let jumps = own.insert(ctx.output("jumps", 4 * n as u64)?);
                interleave::record_jumps(ctx, batch, size, &p, jumps)?;
                &*jumps
            }
        };
        let mut groups = vec![Planes {
            first: 0,
            count: 1,
            params: p.recombination(),
        }];
        if k > 0 {
            groups.push(Planes {
                first: 1,
                count: 2,
                params: p,
            });
        }
        interleave::record(ctx, batch, size, asu, &scratch, jumps, 3, &groups, fill)?;
        batch.keep(scratch);
        if let Some(jumps) = own {
            batch.keep(jumps);
        }
    }
    if k == 0 {
        return Ok(None);
    }
    let result = ctx.output("ratio result", bytes)?;
    let pair = [
        ctx.output("a-trous S, U", 32 * n as u64)?,
        ctx.output("a-trous S, U (next)", 32 * n as u64)?,
    ];
    let pipeline = ctx.pipeline("ratio", ratio_source);
    let ratio = RatioPass {
        pipeline: &pipeline,
        pixels: n as u32,
        max_ratio: filter.max_ratio,
        asu,
        result: &result,
    };
    ratio.record(ctx, batch, 0, &pair[0])?;
    let last = if filter.passes > 0 {
        let params = AtrousParams {
            passes: filter.passes,
            c_phi: filter.c_phi,
            a_phi: filter.a_phi,
            ..AtrousParams::lgh_defaults(frame.radius)
        };
        let geometry = Geometry {
            buffer: frame.gbuffer.buffer(),
            stride: 4,
            size: (g.width, g.height),
        };
        let pair = [&pair[0], &pair[1]];
        crate::atrous::record(ctx, batch, "shadow_filter", &geometry, pair, &params)?
    } else {
        0
    };
    ratio.record(ctx, batch, 1, &pair[last])?;
    for lease in pair {
        batch.keep(lease);
    }
    Ok(Some(result))
}

/// The estimator's output from the read-back `planes` (3 vec4s per pixel: [A, lights],
/// [raw ratio, rays], [filtered ratio, 0]; for k = 0 [A, lights], ...) of `g`: the
/// composite (on the CPU), A, the ratios and the rays; the lights per pixel; the
/// composite's milliseconds.
pub(crate) fn unpack(planes: &[[Vec4; 3]], k: u32, g: &GBuffer) -> (Shadowed, Vec<u32>, f64) {
    let n = g.len();
    let planes = &planes[..n.min(planes.len())];
    let a: Vec<Vec3> = planes.par_iter().map(|p| p[0].truncate()).collect();
    let overdraw: Vec<u32> = planes.par_iter().map(|p| p[0].w as u32).collect();
    let (ratio, rays) = if k > 0 {
        let ratio = ShadowRatio {
            raw: planes.par_iter().map(|p| p[1].truncate()).collect(),
            filtered: planes.par_iter().map(|p| p[2].truncate()).collect(),
        };
        (ratio, planes.par_iter().map(|p| p[1].w as u64).sum())
    } else {
        (ShadowRatio::unshadowed(n), 0)
    };
    let start = Instant::now();
    let indirect = composite(g, &a, &ratio.filtered);
    let ms = start.elapsed().as_secs_f64() * 1e3;
    let shadowed = Shadowed {
        indirect,
        unshadowed: a,
        ratio,
        rays,
    };
    (shadowed, overdraw, ms)
}

/// lgh-render's `shadowed_indirect_with` on the GPU, from A and the shadow estimates on the
/// CPU (uploaded); for other methods' estimates and for tests. `Ok(None)` where
/// [`supported`] is false.
///
/// # Errors
/// The frame exceeds the adapter's limits, or the GPU failed.
pub fn shadowed_indirect(
    ctx: &GpuContext,
    world: &World,
    g: &GBuffer,
    a: &[Vec3],
    estimates: &ShadowEstimates,
    filter: &RatioFilter,
) -> Result<Option<Shadowed>, GpuError> {
    if !supported(filter) {
        return Ok(None);
    }
    let n = g.len();
    let k = estimates.k as u32;
    let zero = Vec3::ZERO;
    let data: Vec<[Vec4; 3]> = (0..n)
        .into_par_iter()
        .map(|p| {
            let plane = |v: &[Vec3]| v.get(p).copied().unwrap_or(zero).extend(0.0);
            [a[p].extend(0.0), plane(&estimates.s), plane(&estimates.u)]
        })
        .collect();
    let gbuffer = ctx.gbuffer(g)?;
    let asu = ctx.upload("A, S, U", &data)?;
    let mut batch = Batch::new(ctx);
    let frame = Frame {
        gbuffer: &gbuffer,
        g,
        radius: world.radius,
    };
    let result = record(ctx, &mut batch, &frame, &asu, k, filter, None)?;
    let read = result.as_ref().unwrap_or(&asu);
    batch.read(read.buffer(), 48 * n as u64)?;
    let (reads, _) = batch.finish()?;
    let planes: &[[Vec4; 3]] = reads.first().map_or(&[], |r| bytemuck::cast_slice(r));
    let (mut shadowed, _, _) = unpack(planes, k, g);
    shadowed.rays = estimates.rays;
    Ok(Some(shadowed))
}
