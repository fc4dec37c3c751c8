//! The edge resolve's sub-pixel samples on the GPU (`shaders/edges.wgsl`; lgh-render's
//! `passes::edge_aa`, docs/design.md "Anti-aliasing"): one invocation per pixel finds
//! whether its 3 x 3 neighbourhood shows more than one surface and, for an edge pixel,
//! traces its sub-pixel rays and counts which neighbour each sample takes. The G-buffer is
//! the frame's on the GPU ([`GpuContext::gbuffer`]); the edge pixels come back as a list,
//! sorted by pixel on the CPU, so the resolve does not depend on scheduling.

use glam::Vec2;
use lgh_render::World;
use lgh_render::accumulate::subpixel_jitter;
use lgh_render::passes::edge_aa::{EdgeResolve, MAX_EDGE_SAMPLES};
use lgh_render::passes::gbuffer::GBuffer;
use lgh_scene::camera::CameraFrame;

use crate::batch::Batch;
use crate::context::{GpuContext, GpuError};
use crate::gbuffer::GpuGBuffer;
use crate::pool::Lease;
use crate::primary::GpuCamera;

/// `Params` of `shaders/edges.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    camera: GpuCamera,
    samples: u32,
    pad: [u32; 3],
    offsets: [[f32; 4]; MAX_EDGE_SAMPLES as usize / 2],
}

/// The WGSL source of the kernel.
#[must_use]
pub fn source() -> String {
    crate::kernel(&[
        include_str!("../shaders/edges.wgsl"),
        include_str!("../shaders/camera.wgsl"),
        include_str!("../shaders/surface.wgsl"),
        include_str!("../shaders/bvh.wgsl"),
    ])
}

/// `EdgeResolve::new(world, camera, g, samples, None)` with the samples traced on the GPU.
///
/// # Errors
/// The scene or the frame does not fit the adapter's limits, or the GPU failed.
pub fn edge_resolve(
    ctx: &GpuContext,
    world: &World,
    camera: &CameraFrame,
    g: &GBuffer,
    samples: u32,
) -> Result<EdgeResolve, GpuError> {
    let samples = samples.clamp(1, MAX_EDGE_SAMPLES);
    let (w, h) = (g.width, g.height);
    if samples == 1 || g.is_empty() {
        return Ok(EdgeResolve::from_edges(w, h, samples, Vec::new()));
    }
    let n = g.len();
    let gbuffer = ctx.gbuffer(g)?;
    let mut batch = Batch::new(ctx);
    let Found { list, count, .. } =
        record(ctx, &mut batch, world, camera, &gbuffer, (w, h), samples)?;
    batch.read(count.buffer(), 4)?;
    let (reads, _) = batch.finish()?;
    let edges = reads
        .first()
        .and_then(|r| bytemuck::cast_slice::<_, u32>(r).first().copied())
        .unwrap_or(0) as usize;
    if edges == 0 {
        return Ok(EdgeResolve::from_edges(w, h, samples, Vec::new()));
    }
    let mut batch = Batch::new(ctx);
    batch.read(list.buffer(), 16 * edges.min(n) as u64)?;
    let (reads, _) = batch.finish()?;
    let words: &[[u32; 4]] = reads.first().map_or(&[], |r| bytemuck::cast_slice(r));
    let list = words[..edges.min(words.len())]
        .iter()
        .map(|&[i, a, b, c]| {
            let [a, b] = [a, b].map(u32::to_le_bytes);
            (i, [a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3], c as u8])
        })
        .collect();
    Ok(EdgeResolve::from_edges(w, h, samples, list))
}

/// The edge pixels a frame found on the GPU ([`record`]): per edge pixel its index and its
/// nine counts, a byte each, four to a word (`display_edges.wgsl` reads them so), in the
/// scheduler's order; their number (one word); and the sub-pixel samples of each.
pub(crate) struct Found<'c> {
    pub list: Lease<'c>,
    pub count: Lease<'c>,
    pub samples: u32,
}

/// Records into `batch` the search for the edge pixels of the `width` x `height` G-buffer
/// `gbuffer` seen through `camera`, with `samples` (2 to [`MAX_EDGE_SAMPLES`]) sub-pixel
/// samples each: the list and count stay on the GPU.
///
/// # Errors
/// The scene or the frame does not fit the adapter's limits.
pub(crate) fn record<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    world: &World,
    camera: &CameraFrame,
    gbuffer: &GpuGBuffer,
    (w, h): (u32, u32),
    samples: u32,
) -> Result<Found<'c>, GpuError> {
    let samples = samples.clamp(1, MAX_EDGE_SAMPLES);
    let n = w as usize * h as usize;
    let scene = ctx.scene(world)?;
    let surfaces = scene.surfaces(ctx, world)?;
    let mut offsets = [[0.0f32; 4]; MAX_EDGE_SAMPLES as usize / 2];
    for s in 0..samples {
        let o: Vec2 = subpixel_jitter(s);
        let pair = &mut offsets[s as usize / 2];
        pair[2 * (s as usize % 2)] = o.x;
        pair[2 * (s as usize % 2) + 1] = o.y;
    }
    let params = batch.uniform(&Params {
        camera: GpuCamera::new(camera, w, h),
        samples,
        pad: [0; 3],
        offsets,
    })?;
    let list = ctx.output("edge pixels", (16 * n as u64).max(16))?;
    let count = ctx.output("edge count", 16)?;
    let pipeline = ctx.pipeline("edges", source);
    let mut resources = surfaces.bindings(params.as_entire_binding(), &scene);
    resources.extend([gbuffer.binding(), list.binding(), count.binding()]);
    let bind = ctx.bind_group(&pipeline, resources);
    batch.clear_lease(&count);
    batch.dispatch("edge samples", &pipeline, &bind, n)?;
    Ok(Found {
        list,
        count,
        samples,
    })
}

/// [`edge_resolve`] for a GPU method's
/// [`lgh_render::methods::IndirectMethod::edge_resolve`] on the process's context:
/// `Ok(None)` (the CPU finds it) where the scene or the frame does not fit the adapter.
///
/// # Errors
/// No adapter, or the GPU failed.
pub fn method_edge_resolve(
    world: &World,
    camera: &CameraFrame,
    g: &GBuffer,
    samples: u32,
) -> Result<Option<EdgeResolve>, lgh_render::settings::RenderError> {
    let fail = |e: GpuError| lgh_render::settings::RenderError::Backend(e.to_string());
    let ctx = GpuContext::shared().map_err(fail)?;
    match edge_resolve(ctx, world, camera, g, samples) {
        Ok(r) => Ok(Some(r)),
        Err(GpuError::TooLarge(_)) => Ok(None),
        Err(e) => Err(fail(e)),
    }
}
