//! The temporal filter of the shadow ratio on a shown frame (`shaders/taa.wgsl`; lgh-render's
//! `denoise::temporal::TemporalFilter` with `TemporalTarget::ShadowRatio`, LGH 2019 section
//! 4.3): the ratio estimator's filtered ratio blended with the previous frame's, reprojected
//! through the previous camera, in the frame's submission. The history (values, normals and
//! depths, two buffers each, written and read in turn) stays on the GPU, one per thread, as
//! the running mean does.

use std::collections::HashMap;
use std::sync::{Mutex, PoisonError};
use std::thread::ThreadId;

use lgh_render::display::TaaRequest;
use lgh_render::passes::gbuffer::GBuffer;
use lgh_scene::camera::CameraFrame;

use crate::batch::Batch;
use crate::context::{GpuContext, GpuError};
use crate::gbuffer::GpuGBuffer;
use crate::pool::Lease;
use crate::primary::GpuCamera;

/// `Params` of `taa.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    pixels: u32,
    width: u32,
    height: u32,
    history: u32,
    alpha: f32,
    depth_tolerance: f32,
    normal_cos: f32,
    _p0: u32,
}

/// A thread's history: the buffers of values and of normals with depths (index `last`
/// holds the last frame's), the camera and view it was seen with, and its size.
#[derive(Debug)]
struct History {
    values: [wgpu::Buffer; 2],
    depth_normals: [wgpu::Buffer; 2],
    last: usize,
    camera: CameraFrame,
    view: Option<(u64, CameraFrame)>,
    size: (u32, u32),
}

/// Each thread's history.
#[derive(Debug, Default)]
pub(crate) struct Histories(Mutex<HashMap<ThreadId, History>>);

fn source() -> String {
    crate::kernel(&[
        include_str!("../shaders/camera.wgsl"),
        include_str!("../shaders/taa.wgsl"),
    ])
}

/// Records the temporal filter of the filtered ratio in `result` (the ratio estimator's
/// result of the frame with G-buffer `g`, seen through `camera`) into `batch` (timed
/// "temporal"), against this thread's history (none where `taa.restart`, or where the
/// last one had another size); the history becomes this frame's.
///
/// # Errors
/// The image exceeds one dispatch.
pub(crate) fn record<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    (g, gbuffer): (&GBuffer, &GpuGBuffer),
    camera: &CameraFrame,
    result: &Lease<'c>,
    taa: &TaaRequest,
) -> Result<(), GpuError> {
    let n = g.len();
    let size = (g.width, g.height);
    let mut all = ctx
        .display_states()
        .histories
        .0
        .lock()
        .unwrap_or_else(PoisonError::into_inner);
    let id = std::thread::current().id();
    let old = all.remove(&id).filter(|h| h.size == size);
    let (history, mode, previous) = match old {
        Some(h) => {
            let same = g.view.is_some() && h.view == g.view;
            let mode = if taa.restart {
                0
            } else if same {
                2
            } else {
                1
            };
            let previous = h.camera;
            (h, mode, previous)
        }
        None => {
            let buffer = |label| {
                ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: (16 * n as u64).max(16),
                    usage: GpuContext::STORAGE,
                    mapped_at_creation: false,
                })
            };
            let h = History {
                values: [buffer("taa values"), buffer("taa values")],
                depth_normals: [buffer("taa depths"), buffer("taa depths")],
                last: 0,
                camera: *camera,
                view: None,
                size,
            };
            (h, 0, *camera)
        }
    };
    let s = &taa.settings;
    let params = batch.uniform(&Params {
        pixels: n as u32,
        width: g.width,
        height: g.height,
        history: mode,
        alpha: s.alpha,
        depth_tolerance: s.depth_tolerance,
        normal_cos: s.normal_cos,
        _p0: 0,
    })?;
    let previous = batch.uniform(&GpuCamera::new(&previous, g.width, g.height))?;
    let (old, new) = (history.last, 1 - history.last);
    let pipeline = ctx.pipeline("taa", source);
    let bind = ctx.bind_group(
        &pipeline,
        vec![
            params.as_entire_binding(),
            previous.as_entire_binding(),
            gbuffer.binding(),
            result.binding(),
            history.values[old].as_entire_binding(),
            history.depth_normals[old].as_entire_binding(),
            history.values[new].as_entire_binding(),
            history.depth_normals[new].as_entire_binding(),
        ],
    );
    batch.dispatch("temporal", &pipeline, &bind, n)?;
    if all.len() >= super::MAX_THREADS {
        all.clear();
    }
    all.insert(
        id,
        History {
            last: new,
            camera: *camera,
            view: g.view,
            ..history
        },
    );
    Ok(())
}
