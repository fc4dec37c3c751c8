//! Primary rays into the G-buffer on the GPU (`shaders/primary.wgsl`): one ray per pixel
//! through the BVH in compute, the closest hit's surface from [`crate::surfaces`], written
//! in the packed layout the frame's other passes read ([`crate::gbuffer`]). The packed
//! buffer stays on the GPU as the context's G-buffer, and is read back into the CPU's
//! planes for the passes that run there, or, for a frame that the GPU shows
//! ([`trace_gbuffer_on_device`]), only when one of them asks for the planes.
//!
//! The rays are the CPU's (`CameraFrame::direction`); the triangle test is Moller-Trumbore
//! in `f32` where the CPU's tracer is obvhs's or Embree's, so a ray that grazes a shared
//! edge may take the other triangle, and positions differ in the last bits.

use std::sync::Arc;

use glam::Vec4;
use lgh_render::World;
use lgh_render::passes::gbuffer::GBuffer;
use lgh_scene::camera::CameraFrame;

use crate::batch::Batch;
use crate::context::{GpuContext, GpuError};
use crate::gbuffer::{GpuEmission, GpuGBuffer};
use crate::pool::Lease;

/// `Camera` of `shaders/camera.wgsl`: what `CameraFrame::direction` computes from.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct GpuCamera {
    origin: [f32; 3],
    width: u32,
    forward: [f32; 3],
    height: u32,
    right: [f32; 3],
    jitter_x: f32,
    up: [f32; 3],
    jitter_y: f32,
    scale: [f32; 2],
    size: [f32; 2],
}

impl GpuCamera {
    /// The camera `camera` for a `width` x `height` image.
    pub(crate) fn new(camera: &CameraFrame, width: u32, height: u32) -> Self {
        let (right, up, scale, size, jitter) = camera.ray_basis();
        Self {
            origin: camera.origin.into(),
            width,
            forward: camera.forward.into(),
            height,
            right: right.into(),
            jitter_x: jitter.x,
            up: up.into(),
            jitter_y: jitter.y,
            scale: scale.into(),
            size: size.into(),
        }
    }
}

/// Bytes per pixel of the emission.
const EMISSION_BYTES: u64 = 16;

/// The WGSL source of the kernel (with the surface evaluation and the BVH traversal).
#[must_use]
pub fn source() -> String {
    crate::kernel(&[
        include_str!("../shaders/primary.wgsl"),
        include_str!("../shaders/camera.wgsl"),
        include_str!("../shaders/surface.wgsl"),
        include_str!("../shaders/bvh.wgsl"),
    ])
}

/// Traces `g`'s primary rays for `world` seen by `camera` at `width` x `height` on the GPU
/// and fills its planes, as `GBuffer::render_into` does on the CPU; the packed G-buffer
/// stays on the GPU for the frame's passes ([`GpuContext::gbuffer`] returns it for `g`).
///
/// # Errors
/// The scene or the image does not fit the adapter's limits, or the GPU failed.
pub fn trace_gbuffer(
    ctx: &GpuContext,
    world: &World,
    camera: &CameraFrame,
    width: u32,
    height: u32,
    g: &mut GBuffer,
) -> Result<(), GpuError> {
    trace(ctx, world, camera, (width, height), Some(g)).map(drop)
}

/// [`trace_gbuffer`] with the planes left on the GPU ([`GBuffer::defer_planes`]): they
/// cross to the CPU when code there asks for them ([`GBuffer::planes`]), and not at all
/// for a frame that the GPU shows. The emission is kept on the GPU even where it is zero
/// everywhere (which only its read-back would tell).
///
/// # Errors
/// As [`trace_gbuffer`].
pub fn trace_gbuffer_on_device(
    ctx: &'static GpuContext,
    world: &World,
    camera: &CameraFrame,
    width: u32,
    height: u32,
    g: &mut GBuffer,
) -> Result<(), GpuError> {
    let Some(gbuffer) = trace(ctx, world, camera, (width, height), None)? else {
        return Err(GpuError::Failed("the traced G-buffer is missing".into()));
    };
    let view = (world.geometry_id(), *camera);
    let reader = Arc::new(crate::gbuffer::OnDevice { ctx, gbuffer });
    g.defer_planes((width, height), view, reader);
    Ok(())
}

/// The primary rays of [`trace_gbuffer`]: with `g`, the planes read back into it, else
/// (`g` is `None`) left on the GPU, whose G-buffer comes back.
fn trace(
    ctx: &GpuContext,
    world: &World,
    camera: &CameraFrame,
    (width, height): (u32, u32),
    g: Option<&mut GBuffer>,
) -> Result<Option<Arc<GpuGBuffer>>, GpuError> {
    let n = width as usize * height as usize;
    let scene = ctx.scene(world)?;
    let surfaces = scene.surfaces(ctx, world)?;
    let (packed, bytes) = ctx.gbuffer_buffer(n)?;
    let emission: Lease<'_> = ctx.output("emission", (n as u64 * EMISSION_BYTES).max(16))?;
    let mut batch = Batch::new(ctx);
    let params = batch.uniform(&GpuCamera::new(camera, width, height))?;
    let pipeline = ctx.pipeline("primary", source);
    let mut resources = surfaces.bindings(params.as_entire_binding(), &scene);
    resources.extend([packed.as_entire_binding(), emission.binding()]);
    let bind = ctx.bind_group(&pipeline, resources);
    batch.dispatch("primary rays", &pipeline, &bind, n)?;
    let view = (world.geometry_id(), *camera);
    let Some(g) = g else {
        // Left on the GPU: the frame's later submissions read it there, in order.
        batch.submit();
        let kept = GpuEmission::Kept(emission.detach().into_buffer());
        return Ok(Some(ctx.adopt_gbuffer(packed, (width, height), view, kept)));
    };
    batch.read(&packed, bytes)?;
    batch.read(emission.buffer(), emission.bytes())?;
    let (reads, _) = batch.finish()?;
    let [pixels, emitted] = reads.as_slice() else {
        return Err(GpuError::Failed(
            "the G-buffer's read-back is missing".into(),
        ));
    };
    let pixels: &[[Vec4; 4]] = bytemuck::cast_slice(pixels);
    let emitted: &[Vec4] = bytemuck::cast_slice(emitted);
    crate::gbuffer::unpack(g, &pixels[..n], Some(&emitted[..n]));
    (g.width, g.height) = (width, height);
    g.view = Some(view);
    // The emission stays on the GPU for a frame shown there (`crate::display`).
    let seen = g.emission.iter().any(|e| *e != glam::Vec3::ZERO);
    let emission = if seen {
        GpuEmission::Kept(emission.detach().into_buffer())
    } else {
        GpuEmission::Zero
    };
    ctx.adopt_gbuffer(packed, (width, height), view, emission);
    Ok(None)
}

/// [`trace_gbuffer`] (or where `keep_on_device`, [`trace_gbuffer_on_device`]) for a GPU
/// method's [`lgh_render::methods::IndirectMethod::trace_gbuffer`] on the process's
/// context: `Ok(false)` (the CPU traces them) where the scene's surfaces or the image do
/// not fit the adapter's buffers.
///
/// # Errors
/// No adapter, or the GPU failed.
pub fn method_gbuffer(
    world: &World,
    camera: &CameraFrame,
    (width, height): (u32, u32),
    g: &mut GBuffer,
    keep_on_device: bool,
) -> Result<bool, lgh_render::settings::RenderError> {
    let fail = |e: GpuError| lgh_render::settings::RenderError::Backend(e.to_string());
    let ctx = GpuContext::shared().map_err(fail)?;
    let traced = if keep_on_device {
        trace_gbuffer_on_device(ctx, world, camera, width, height, g)
    } else {
        trace_gbuffer(ctx, world, camera, width, height, g)
    };
    match traced {
        Ok(()) => Ok(true),
        Err(GpuError::TooLarge(_)) => Ok(false),
        Err(e) => Err(fail(e)),
    }
}
