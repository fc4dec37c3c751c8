//! Direct light on the GPU (`shaders/direct.wgsl`, `shaders/direct_composite.wgsl`): the
//! estimator of lgh-render's `direct::render_direct` (its module docs: punctual lights
//! exactly, area lights by stratified samples, the analytic emitters through the ratio
//! estimator of Heitz, Hill & McGuire 2018 with its one a-trous pass), in one submission:
//! samples, filter (the a-trous pass of [`crate::atrous`], reading the uploaded G-buffer),
//! composite.
//!
//! The same estimator with its own random streams: the frame's point set is the CPU's
//! ([`frame_points`]); each pixel's digital shift is drawn on the GPU. A scene with more
//! punctual lights than [`EXACT_PUNCTUAL`] (which the CPU samples by power) runs its direct
//! light on the CPU.

use std::time::Instant;

use glam::{Vec3, Vec4};
use lgh_core::timing::Timings;
use lgh_render::direct::{
    DirectMode, DirectOutput, EXACT_PUNCTUAL, analytic_emitters, analytic_indices, direct_filter,
    frame_points,
};
use lgh_render::passes::gbuffer::GBuffer;
use lgh_render::shading::ratio::RATIO_VISIBILITY;
use lgh_render::{RenderSettings, World};
use lgh_scene::Light;

use crate::atrous::{Geometry, record};
use crate::batch::Batch;
use crate::context::{GpuContext, GpuError};
use crate::pool::Lease;

/// Area samples per pixel the GPU pass takes at most (more run on the CPU).
pub const MAX_AREA_SAMPLES: u32 = 4096;

/// `Params` of `direct.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    pixels: u32,
    samples: u32,
    emitters: u32,
    punctual: u32,
    analytic: u32,
    cdf_base: u32,
    punctual_base: u32,
    analytic_base: u32,
    points_base: u32,
    seed_lo: u32,
    seed_hi: u32,
    _p0: u32,
    ray_eps: f32,
    far: f32,
    _p1: [f32; 2],
}

/// `Params` of `direct_composite.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CompositeParams {
    pixels: u32,
    analytic: u32,
    max_ratio: f32,
    _p0: u32,
}

/// The WGSL source of the sampling kernel (with the BVH traversal).
#[must_use]
pub fn source() -> String {
    crate::kernel(&[
        include_str!("../shaders/direct.wgsl"),
        include_str!("../shaders/bvh.wgsl"),
    ])
}

/// The WGSL source of the composite kernel.
#[must_use]
pub fn composite_source() -> String {
    crate::kernel(&[include_str!("../shaders/direct_composite.wgsl")])
}

/// The lights' tables of `direct.wgsl` (32-bit words, four a row) and where each starts.
struct LightTables {
    words: Vec<[u32; 4]>,
    params: Params,
}

/// Appends `values` four to a row.
fn push_words(words: &mut Vec<[u32; 4]>, values: impl IntoIterator<Item = u32>) -> u32 {
    let base = words.len() as u32;
    let values: Vec<u32> = values.into_iter().collect();
    for c in values.chunks(4) {
        let mut row = [0; 4];
        row[..c.len()].copy_from_slice(c);
        words.push(row);
    }
    base
}

fn row(v: Vec3, w: f32) -> [u32; 4] {
    Vec4::from((v, w)).to_array().map(f32::to_bits)
}

impl LightTables {
    fn new(world: &World, s: &RenderSettings, pixels: u32) -> Self {
        let lights = &world.lights;
        let analytic = match s.direct {
            DirectMode::Analytic if s.area_samples > 0 => analytic_emitters(lights),
            _ => Vec::new(),
        };
        let mut words = Vec::new();
        for (j, e) in lights.emitters.iter().enumerate() {
            let flag = if analytic.get(j).copied().unwrap_or(false) {
                1.0
            } else {
                0.0
            };
            words.extend([
                row(e.v0, e.area),
                row(e.e1, flag),
                row(e.e2, 0.0),
                row(e.normal, 0.0),
                row(e.radiance, 0.0),
            ]);
        }
        // The emitters' CDF, normalised (Distribution1D's, in f64 until rounded).
        let cdf: Vec<u32> = lights
            .emitter_distribution()
            .map(|d| {
                let mut sum = 0.0f64;
                (0..d.len())
                    .map(|i| {
                        sum += f64::from(d.pmf(i));
                        (sum as f32).to_bits()
                    })
                    .collect()
            })
            .unwrap_or_default();
        let emitters = if cdf.is_empty() {
            0
        } else {
            lights.emitters.len() as u32
        };
        let cdf_base = push_words(&mut words, cdf);
        let punctual_base = words.len() as u32;
        for l in &lights.punctual {
            words.extend(match *l {
                Light::Point {
                    position,
                    intensity,
                } => [
                    row(position, 0.0),
                    row(Vec3::ZERO, 0.0),
                    row(intensity, 0.0),
                ],
                Light::Spot {
                    position,
                    direction,
                    intensity,
                    cos_inner,
                    cos_outer,
                } => [
                    row(position, 1.0),
                    row(direction, cos_inner),
                    row(intensity, cos_outer),
                ],
                Light::Directional {
                    direction,
                    irradiance,
                } => [
                    row(Vec3::ZERO, 2.0),
                    row(direction, 0.0),
                    row(irradiance, 0.0),
                ],
            });
        }
        let indices = analytic_indices(&analytic);
        let analytic_base = push_words(&mut words, indices.iter().map(|&i| i as u32));
        let points = frame_points(s.seed, s.area_samples);
        let points_base = push_words(&mut words, points.iter().flatten().copied());
        let params = Params {
            pixels,
            samples: s.area_samples,
            emitters,
            punctual: lights.punctual.len() as u32,
            analytic: indices.len() as u32,
            cdf_base,
            punctual_base,
            analytic_base,
            points_base,
            seed_lo: s.seed as u32,
            seed_hi: (s.seed >> 32) as u32,
            _p0: 0,
            ray_eps: world.ray_epsilon,
            far: 4.0 * world.radius,
            _p1: [0.0; 2],
        };
        Self { words, params }
    }
}

/// True if the GPU pass runs the direct light of `world` with `s` (else the CPU's does).
#[must_use]
pub fn supported(world: &World, s: &RenderSettings) -> bool {
    world.lights.punctual.len() <= EXACT_PUNCTUAL && s.area_samples <= MAX_AREA_SAMPLES
}

/// The direct light of the frame with G-buffer `g`, on the GPU: radiance per pixel with
/// the times `direct_samples`, `direct_filter`, `direct_composite` (GPU timestamps, where
/// the adapter has them) and `direct_transfer` (packing, upload, read-back). `Ok(None)`
/// where [`supported`] is false.
///
/// # Errors
/// The frame exceeds the adapter's limits, or the GPU failed.
pub fn render_direct(
    ctx: &GpuContext,
    world: &World,
    g: &GBuffer,
    s: &RenderSettings,
) -> Result<Option<DirectOutput>, GpuError> {
    let start = Instant::now();
    let n = g.len();
    let mut batch = Batch::new(ctx);
    let Some(radiance) = record_direct(ctx, &mut batch, world, g, s)? else {
        return Ok(None);
    };
    batch.read(radiance.buffer(), radiance.bytes())?;
    let (reads, gpu) = batch.finish()?;
    let out: &[Vec4] = reads.first().map_or(&[], |r| bytemuck::cast_slice(r));
    let radiance: Vec<Vec3> = out.iter().take(n).map(|v| v.truncate()).collect();
    let mut timings = Timings::default();
    for &(name, ms) in &gpu {
        timings.push(name, ms);
    }
    let gpu_ms: f64 = gpu.iter().map(|(_, ms)| ms).sum();
    let wall = start.elapsed().as_secs_f64() * 1e3;
    timings.push("direct_transfer", (wall - gpu_ms).max(0.0));
    Ok(Some(DirectOutput { radiance, timings }))
}

/// Records the direct light of the frame with G-buffer `g` into `batch` (the passes
/// `direct_samples`, `direct_filter`, `direct_composite`): the buffer it writes, one vec4
/// of radiance a pixel, which stays on the GPU. `Ok(None)` where [`supported`] is false.
///
/// # Errors
/// The frame exceeds the adapter's limits.
pub(crate) fn record_direct<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    world: &World,
    g: &GBuffer,
    s: &RenderSettings,
) -> Result<Option<Lease<'c>>, GpuError> {
    if !supported(world, s) {
        return Ok(None);
    }
    let n = g.len();
    let scene = ctx.scene(world)?;
    let tables = LightTables::new(world, s, n as u32);
    let gbuf = ctx.gbuffer(g)?;
    let table = ctx.upload("direct lights", &tables.words)?;
    let lit = ctx.output("direct rest, analytic", 32 * n as u64)?;
    let pair = [
        ctx.output("direct S, U", 32 * n as u64)?,
        ctx.output("direct S, U (next)", 32 * n as u64)?,
    ];
    let radiance = ctx.output("direct radiance", 16 * n as u64)?;
    let params = batch.uniform(&tables.params)?;
    let pipeline = ctx.pipeline("direct", source);
    let mut resources = scene.bindings(params.as_entire_binding(), &gbuf);
    resources.extend([table.binding(), lit.binding(), pair[0].binding()]);
    let bind = ctx.bind_group(&pipeline, resources);
    batch.dispatch("direct_samples", &pipeline, &bind, n)?;
    let any_analytic = tables.params.analytic > 0;
    let last = if any_analytic {
        let geometry = Geometry {
            buffer: gbuf.buffer(),
            stride: 4,
            size: (g.width, g.height),
        };
        let filter = direct_filter(world.radius);
        record(
            ctx,
            batch,
            "direct_filter",
            &geometry,
            [&pair[0], &pair[1]],
            &filter,
        )?
    } else {
        0
    };
    let composite = batch.uniform(&CompositeParams {
        pixels: n as u32,
        analytic: u32::from(any_analytic),
        max_ratio: RATIO_VISIBILITY,
        _p0: 0,
    })?;
    let pipeline = ctx.pipeline("direct_composite", composite_source);
    let bind = ctx.bind_group(
        &pipeline,
        vec![
            composite.as_entire_binding(),
            gbuf.binding(),
            lit.binding(),
            pair[last].binding(),
            radiance.binding(),
        ],
    );
    batch.dispatch("direct_composite", &pipeline, &bind, n)?;
    let [a, b] = pair;
    for lease in [table, lit, a, b] {
        batch.keep(lease);
    }
    Ok(Some(radiance))
}

/// [`render_direct`] on the shared context, for the GPU methods' `IndirectMethod::direct`.
///
/// # Errors
/// No adapter, or as [`render_direct`].
pub(crate) fn method_direct(
    world: &World,
    g: &GBuffer,
    s: &RenderSettings,
) -> Result<Option<DirectOutput>, lgh_render::settings::RenderError> {
    let fail = |e: GpuError| lgh_render::settings::RenderError::Backend(e.to_string());
    let ctx = GpuContext::shared().map_err(fail)?;
    render_direct(ctx, world, g, s).map_err(fail)
}
