//! The interleaving blur on the GPU (`shaders/discontinuities.wgsl`, `shaders/blur.wgsl`,
//! `shaders/blur_keys.wgsl`): lgh-render's `shading::interleave::{discontinuities,
//! blur_n_stopped}` (LGH 2019 section 4.3;
//! docs/design.md, "Interleaved sampling"), recorded into a frame's batch so that the
//! lighting loop's images stay on the GPU from the loop to the ratio estimator's filter.

use lgh_render::shading::interleave::BlurParams;

use crate::batch::Batch;
use crate::context::{GpuContext, GpuError};
use crate::gbuffer::GpuGBuffer;
use crate::pool::Lease;

/// The widest blur the kernel takes (its weights fill five vec4s).
pub const MAX_RADIUS: u32 = 19;

/// `Params` of `discontinuities.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct JumpParams {
    width: u32,
    height: u32,
    z_diff: f32,
    n_diff: f32,
    a_n_diff: f32,
    _pad: [f32; 3],
}

/// `Params` of `blur.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BlurUniform {
    width: u32,
    height: u32,
    vertical: u32,
    radius: u32,
    phases: u32,
    planes: u32,
    plane_first: u32,
    plane_count: u32,
    weights: [f32; 20],
    a_diff: f32,
    /// 0: the jumps of `n_diff` (bits 1, 2); 2: those of `a_n_diff` (bits 4, 8).
    jump_shift: u32,
    _pad: [f32; 2],
}

/// `Params` of `blur_keys.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct KeyParams {
    pixels: u32,
    planes: u32,
    plane: u32,
    _pad: u32,
}

/// The WGSL source of the blur kernel.
#[must_use]
pub fn blur_source() -> String {
    crate::kernel(&[include_str!("../shaders/blur.wgsl")])
}

/// The WGSL source of the kernel of the keys of A.
#[must_use]
pub fn keys_source() -> String {
    crate::kernel(&[include_str!("../shaders/blur_keys.wgsl")])
}

/// The WGSL source of the discontinuity kernel.
#[must_use]
pub fn discontinuities_source() -> String {
    crate::kernel(&[include_str!("../shaders/discontinuities.wgsl")])
}

/// True if the GPU blur takes `p` (its radius at most [`MAX_RADIUS`]).
#[must_use]
pub fn supported(p: &BlurParams) -> bool {
    p.radius <= MAX_RADIUS
}

/// Images blurred in place: `planes` vec4s per pixel, of which `first..first + count` are
/// blurred with `params`; where `params.a_diff` > 0 the walks stop on the keys of plane 0
/// (A, blurred by an earlier group) smoothed by the same walks.
pub(crate) struct Planes {
    pub first: u32,
    pub count: u32,
    pub params: BlurParams,
}

/// The discontinuities of `p` in the G-buffer `g`, read back (one byte a pixel, the bits of
/// lgh-render's `shading::interleave::discontinuities`, which they equal bit for bit): for
/// tests and tools.
///
/// # Errors
/// The G-buffer cannot be uploaded, the image exceeds one dispatch, or the read fails.
pub fn discontinuities(
    ctx: &GpuContext,
    g: &lgh_render::passes::gbuffer::GBuffer,
    p: &BlurParams,
) -> Result<Vec<u8>, GpuError> {
    let gbuffer = ctx.gbuffer(g)?;
    let mut batch = Batch::new(ctx);
    let jumps = ctx.output("jumps", 4 * g.len() as u64)?;
    record_jumps(ctx, &mut batch, (&gbuffer, g.width, g.height), p, &jumps)?;
    batch.read(jumps.buffer(), 4 * g.len() as u64)?;
    batch.keep(jumps);
    let (reads, _) = batch.finish()?;
    let words: &[u32] = reads.first().map_or(&[], |r| bytemuck::cast_slice(r));
    Ok(words.iter().map(|&w| w as u8).collect())
}

/// Records the discontinuities of `p` (its z and normal thresholds; the crease bits with
/// [`BlurParams::crease_n_diff`]) of the G-buffer `g` (`gbuffer`, `width` x `height`) into
/// `jumps` (one word a pixel), as lgh-render's `shading::interleave::discontinuities`.
///
/// # Errors
/// The image exceeds one dispatch.
pub(crate) fn record_jumps(
    ctx: &GpuContext,
    batch: &mut Batch<'_>,
    (gbuffer, width, height): (&GpuGBuffer, u32, u32),
    p: &BlurParams,
    jumps: &Lease<'_>,
) -> Result<(), GpuError> {
    let pipeline = ctx.pipeline("discontinuities", discontinuities_source);
    let uniform = batch.uniform(&JumpParams {
        width,
        height,
        z_diff: p.z_diff,
        n_diff: p.n_diff,
        a_n_diff: p.crease_n_diff(),
        _pad: [0.0; 3],
    })?;
    let bind = ctx.bind_group(
        &pipeline,
        vec![
            uniform.as_entire_binding(),
            gbuffer.binding(),
            jumps.binding(),
        ],
    );
    batch.dispatch(
        "interleave_blur",
        &pipeline,
        &bind,
        (width * height) as usize,
    )
}

/// Records the blur of `images` (`planes` vec4s per pixel, in place through `scratch` of the
/// same size) into `batch`, with the discontinuities `jumps` of the groups' thresholds
/// ([`record_jumps`]): per group the pass along x and the pass along y, a group with a stop
/// on A after the keys of plane 0 as the groups before left it, smoothed by the group's own
/// walks. Where pixels fill their cut recombination windows (`fill`), their A is made
/// after the group that recombines A (plane 0 with the crease bits, [`crate::fill`]).
///
/// # Errors
/// A radius above [`MAX_RADIUS`], or the image exceeds one dispatch.
#[allow(clippy::too_many_arguments)]
pub(crate) fn record<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    g: (&GpuGBuffer, u32, u32),
    images: &Lease<'_>,
    scratch: &Lease<'_>,
    jumps: &Lease<'_>,
    planes: u32,
    groups: &[Planes],
    fill: Option<&crate::fill::Fill<'_>>,
) -> Result<(), GpuError> {
    let n = (g.1 * g.2) as usize;
    let keys = ctx.output("blur keys", 4 * n as u64)?;
    let blur = Blur {
        g,
        scratch,
        jumps,
        keys: &keys,
        planes,
    };
    for group in groups {
        let p = &group.params;
        if !supported(p) {
            return Err(GpuError::TooLarge(format!(
                "a blur radius of {} (the GPU's blur takes {MAX_RADIUS})",
                p.radius
            )));
        }
        if p.a_diff > 0.0 {
            // The keys of A smoothed by the group's own walks (lgh-render's
            // `Stop::SmoothedA`): plane 0 of a copy of the images, blurred without the stop.
            let bytes = 16 * u64::from(planes) * n as u64;
            let smooth = ctx.output("blur keys' A", bytes)?;
            batch.copy(images, 0, &smooth, 0, bytes);
            let plain = BlurParams { a_diff: 0.0, ..*p };
            blur.record(ctx, batch, &smooth, (0, 1), &plain)?;
            record_keys(ctx, batch, &smooth, &keys, (n as u32, planes))?;
            batch.keep(smooth);
        }
        blur.record(ctx, batch, images, (group.first, group.count), p)?;
        if let Some(fill) = fill.filter(|_| group.first == 0 && p.creases) {
            fill.record_recombine(ctx, batch, g, images, planes)?;
        }
    }
    batch.keep(keys);
    Ok(())
}

/// What every group's blur shares: the G-buffer and its size, the scratch image, the jumps,
/// the keys of A, and the vec4s per pixel.
struct Blur<'a> {
    g: (&'a GpuGBuffer, u32, u32),
    scratch: &'a Lease<'a>,
    jumps: &'a Lease<'a>,
    keys: &'a Lease<'a>,
    planes: u32,
}

impl Blur<'_> {
    /// Records the pass along x and the pass along y of planes `first..first + count` of
    /// `images` with `p` (stopping on the keys where `p.a_diff` > 0).
    fn record<'c>(
        &self,
        ctx: &'c GpuContext,
        batch: &mut Batch<'c>,
        images: &Lease<'_>,
        (first, count): (u32, u32),
        p: &BlurParams,
    ) -> Result<(), GpuError> {
        let (gbuffer, width, height) = self.g;
        let pipeline = ctx.pipeline("blur", blur_source);
        // lgh-render's weights, computed alike.
        let mut weights = [0.0f32; 20];
        for (k, w) in weights.iter_mut().enumerate().take(p.radius as usize + 1) {
            *w = (-((k * k) as f32) / (2.0 * p.sigma * p.sigma)).exp();
        }
        for vertical in [0, 1] {
            let (from, to) = if vertical == 0 {
                (images.binding(), self.scratch.binding())
            } else {
                (self.scratch.binding(), images.binding())
            };
            let uniform = batch.uniform(&BlurUniform {
                width,
                height,
                vertical,
                radius: p.radius,
                phases: p.phases,
                planes: self.planes,
                plane_first: first,
                plane_count: count,
                weights,
                a_diff: p.a_diff,
                jump_shift: if p.creases { 2 } else { 0 },
                _pad: [0.0; 2],
            })?;
            let bind = ctx.bind_group(
                &pipeline,
                vec![
                    uniform.as_entire_binding(),
                    gbuffer.binding(),
                    self.jumps.binding(),
                    from,
                    to,
                    self.keys.binding(),
                ],
            );
            batch.dispatch(
                "interleave_blur",
                &pipeline,
                &bind,
                (width * height) as usize,
            )?;
        }
        Ok(())
    }
}

/// Records the keys of plane 0 of `images` (`planes` vec4s per pixel, `pixels` of them)
/// into `keys`.
fn record_keys(
    ctx: &GpuContext,
    batch: &mut Batch<'_>,
    images: &Lease<'_>,
    keys: &Lease<'_>,
    (pixels, planes): (u32, u32),
) -> Result<(), GpuError> {
    let pipeline = ctx.pipeline("blur keys", keys_source);
    let uniform = batch.uniform(&KeyParams {
        pixels,
        planes,
        plane: 0,
        _pad: 0,
    })?;
    let bind = ctx.bind_group(
        &pipeline,
        vec![
            uniform.as_entire_binding(),
            images.binding(),
            keys.binding(),
        ],
    );
    batch.dispatch("interleave_blur", &pipeline, &bind, pixels as usize)
}
