//! Frames shown on the GPU (lgh-render's `display`; `lgh view --device gpu`): a frame's
//! emission, direct and indirect light composed where they were computed
//! (`shaders/display_compose.wgsl`), its edges resolved (`display_edges.wgsl`), added to a
//! running mean kept on the GPU and tone-mapped (`display_show.wgsl`), recorded into the
//! frame's last submission, so that only the packed pixels come back: 4 bytes a pixel
//! instead of the 64 of the loop's result and the direct light (59 MB at 1280x720).
//!
//! The same pixels as the CPU's display ([`lgh_render::display::RunningMean`]) from the same
//! parts, up to the GPU's float rounding: the parts add in the CPU's order, and the mean is
//! the sum times 1 / frames. Each thread keeps its own running mean (the viewer's worker
//! thread; tests that run side by side).

use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::ThreadId;

use glam::{Vec3, Vec4};
use lgh_render::display::{DisplayRequest, Displayed, ShowEdges, ShowInputs};
use lgh_render::methods::{MethodInputs, MethodOutput};
use lgh_render::passes::edge_aa::EdgeResolve;
use lgh_render::passes::gbuffer::GBuffer;

use crate::batch::{Batch, PassTimes, Words};
use crate::context::{GpuContext, GpuError};
use crate::gbuffer::{GpuEmission, GpuGBuffer};
use crate::pool::Lease;

pub(crate) mod taa;

/// One part of a shown frame's image.
#[derive(Clone, Copy)]
pub(crate) enum Part<'a, 'c> {
    /// Not in the image.
    Zero,
    /// Radiance per pixel on the CPU (uploaded).
    Host(&'a [Vec3]),
    /// Radiance per pixel on the GPU, one vec4 a pixel.
    Radiance(&'a Lease<'c>),
    /// The ratio estimator's result on the GPU ([`crate::ratio::record`]'s: three vec4s a
    /// pixel, A, the raw and the filtered ratio): albedo / pi x A x the filtered ratio.
    Ratio(&'a Lease<'c>),
    /// A alone on the GPU (the first of three vec4s a pixel): albedo / pi x A.
    Unshadowed(&'a Lease<'c>),
}

/// The edge resolve a shown frame applies.
pub(crate) enum Edges<'a, 'c> {
    /// None.
    None,
    /// Found before (on the CPU, or on the GPU and read back), in pixel order.
    Resolved(&'a EdgeResolve),
    /// Found on the GPU in the frame's work ([`crate::edges::record`]): its list in the
    /// scheduler's order (each edge pixel writes only itself, so the order does not
    /// matter) and its count stay there.
    Found(crate::edges::Found<'c>),
}

/// `Params` of `display_compose.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ComposeParams {
    pixels: u32,
    emission: u32,
    direct: u32,
    indirect: u32,
}

/// `Params` of `display_edges.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct EdgeParams {
    edges: u32,
    width: u32,
    height: u32,
    mode: u32,
    inv_samples: f32,
    _p: [u32; 3],
}

/// `Params` of `display_show.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ShowParams {
    pixels: u32,
    restart: u32,
    inv_frames: f32,
    exposure: f32,
}

/// The most threads whose running means (and temporal histories) are kept at a time; past
/// that, all are dropped and start again (a viewer shows its frames on one thread).
pub(crate) const MAX_THREADS: usize = 8;

/// A thread's running mean on the GPU.
#[derive(Debug)]
struct Sum {
    buffer: wgpu::Buffer,
    pixels: usize,
    frames: u32,
}

/// The G-buffer on the GPU whose emission was uploaded last, and that upload (`None`: zero).
type ShownEmission = (Arc<GpuGBuffer>, Option<Arc<wgpu::Buffer>>);

/// What the context keeps for shown frames: each thread's running mean, and the emission
/// of the last G-buffer shown (uploaded once while the view stands still; `None` where it
/// is zero everywhere).
#[derive(Debug, Default)]
pub(crate) struct DisplayStates {
    sums: Mutex<HashMap<ThreadId, Sum>>,
    /// Each thread's history of the temporal filter.
    pub(crate) histories: taa::Histories,
    emission: Mutex<Option<ShownEmission>>,
}

/// A shown frame recorded into a batch, to be read from its read-backs
/// ([`Recorded::finish`]).
#[derive(Debug)]
pub(crate) struct Recorded {
    /// The index of the packed pixels among the batch's read-backs (the sum follows where
    /// the linear mean was asked for).
    read: usize,
    pixels: usize,
    frames: u32,
    linear: bool,
}

impl Recorded {
    /// The shown frame from the batch's read-backs `reads`.
    pub(crate) fn finish(&self, reads: &[Vec<Words>]) -> Displayed {
        let empty: &[Words] = &[];
        let at = |k: usize| reads.get(k).map_or(empty, Vec::as_slice);
        let packed: &[u32] = bytemuck::cast_slice(at(self.read));
        let mut pixels = packed.to_vec();
        pixels.resize(self.pixels, 0);
        let mean = self.linear.then(|| {
            let sum: &[Vec4] = bytemuck::cast_slice(at(self.read + 1));
            let inv = 1.0 / self.frames as f32;
            let mut mean: Vec<Vec3> = sum.iter().map(|s| s.truncate() * inv).collect();
            mean.resize(self.pixels, Vec3::ZERO);
            mean
        });
        Displayed {
            pixels,
            frames: self.frames,
            mean,
        }
    }
}

/// The WGSL sources of the three kernels.
fn compose_source() -> String {
    crate::kernel(&[include_str!("../shaders/display_compose.wgsl")])
}

fn edges_source() -> String {
    crate::kernel(&[include_str!("../shaders/display_edges.wgsl")])
}

fn show_source() -> String {
    crate::kernel(&[include_str!("../shaders/display_show.wgsl")])
}

/// The frame's parts: the image is emission (where `emission`) + direct + indirect.
pub(crate) struct Parts<'a, 'c> {
    pub emission: bool,
    pub direct: Part<'a, 'c>,
    pub indirect: Part<'a, 'c>,
}

/// Records the showing of the frame of G-buffer `g` (on the GPU: `gbuffer`) from `parts`,
/// with `edges` resolved, into `batch` (timed "show"), with the read-backs of the packed
/// pixels and, where `request.linear`, of the running sum.
///
/// # Errors
/// A buffer could not be leased, or the image exceeds one dispatch.
pub(crate) fn record<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    g: &GBuffer,
    gbuffer: &Arc<GpuGBuffer>,
    parts: &Parts<'_, 'c>,
    edges: Edges<'_, 'c>,
    request: &DisplayRequest,
) -> Result<Recorded, GpuError> {
    let n = g.len();
    let image = ctx.output("shown image", 16 * n as u64)?;
    // A zero part (and no emission) is bound to a stand-in; the parts on the CPU are
    // uploaded.
    let stand_in = ctx.output("no part", 16)?;
    let upload = |v: &[Vec3]| -> Result<Lease<'c>, GpuError> {
        let rows: Vec<Vec4> = v.iter().map(|c| c.extend(0.0)).collect();
        ctx.upload("shown part", &rows)
    };
    let mut uploads = Vec::new();
    let mut bound = Vec::new();
    for part in [parts.direct, parts.indirect] {
        let mode = match part {
            Part::Zero => 0,
            Part::Host(v) => {
                uploads.push(upload(v)?);
                1
            }
            Part::Radiance(_) => 1,
            Part::Ratio(_) => 2,
            Part::Unshadowed(_) => 3,
        };
        bound.push(mode);
    }
    let emission = if parts.emission {
        emission_of(ctx, g, gbuffer)?
    } else {
        None
    };
    let params = batch.uniform(&ComposeParams {
        pixels: n as u32,
        emission: u32::from(emission.is_some()),
        direct: bound[0],
        indirect: bound[1],
    })?;
    let mut uploaded = uploads.iter();
    let mut bindings = Vec::new();
    for part in [parts.direct, parts.indirect] {
        bindings.push(match part {
            Part::Zero => stand_in.binding(),
            Part::Host(_) => uploaded.next().map_or(stand_in.binding(), Lease::binding),
            Part::Radiance(l) | Part::Ratio(l) | Part::Unshadowed(l) => l.binding(),
        });
    }
    let pipeline = ctx.pipeline("display_compose", compose_source);
    let mut resources = vec![
        params.as_entire_binding(),
        gbuffer.binding(),
        emission
            .as_ref()
            .and_then(EmissionBuffer::binding)
            .unwrap_or_else(|| stand_in.binding()),
    ];
    resources.extend(bindings);
    resources.push(image.binding());
    let bind = ctx.bind_group(&pipeline, resources);
    batch.dispatch("show", &pipeline, &bind, n)?;
    record_edges(ctx, batch, &image, edges, (g.width, g.height))?;
    let (sum, restart, frames) = running_sum(ctx, n, request.restart);
    let show = batch.uniform(&ShowParams {
        pixels: n as u32,
        restart: u32::from(restart),
        inv_frames: 1.0 / frames as f32,
        exposure: request.exposure,
    })?;
    let packed = ctx.output("shown pixels", 4 * n as u64)?;
    let pipeline = ctx.pipeline("display_show", show_source);
    let bind = ctx.bind_group(
        &pipeline,
        vec![
            show.as_entire_binding(),
            image.binding(),
            sum.as_entire_binding(),
            packed.binding(),
        ],
    );
    batch.dispatch("show", &pipeline, &bind, n)?;
    let read = batch.reads();
    batch.read(packed.buffer(), packed.bytes())?;
    if request.linear {
        batch.read(&sum, 16 * n as u64)?;
    }
    for lease in uploads.into_iter().chain([image, stand_in, packed]) {
        batch.keep(lease);
    }
    Ok(Recorded {
        read,
        pixels: n,
        frames,
        linear: request.linear,
    })
}

/// Records the edge resolve of `edges` over the `width` x `height` `image` (nothing for
/// none, or for a resolve found before that is empty or of another size). A list found
/// on the GPU is applied over as many entries as the image has pixels, each invocation
/// past the list's count (read on the GPU) doing nothing.
fn record_edges<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    image: &Lease<'c>,
    edges: Edges<'_, 'c>,
    (width, height): (u32, u32),
) -> Result<(), GpuError> {
    let (list, count, entries, samples) = match edges {
        Edges::Resolved(edges) if edges.edge_pixels() > 0 && edges.size() == (width, height) => {
            let rows: Vec<[u32; 4]> = edges
                .edges()
                .iter()
                .map(|&(p, c)| {
                    let word = |k: usize| {
                        (0..4).fold(0u32, |w, j| {
                            w | (u32::from(c.get(4 * k + j).copied().unwrap_or(0)) << (8 * j))
                        })
                    };
                    [p, word(0), word(1), word(2)]
                })
                .collect();
            let count = ctx.upload("edge count", &[rows.len() as u32, 0, 0, 0])?;
            (
                ctx.upload("edge pixels", &rows)?,
                count,
                rows.len(),
                edges.samples(),
            )
        }
        Edges::Found(found) => {
            let n = width as usize * height as usize;
            (found.list, found.count, n, found.samples)
        }
        Edges::Resolved(_) | Edges::None => return Ok(()),
    };
    let resolved = ctx.output("resolved edges", (16 * entries as u64).max(16))?;
    let pipeline = ctx.pipeline("display_edges", edges_source);
    for mode in 0..2 {
        let params = batch.uniform(&EdgeParams {
            edges: entries as u32,
            width,
            height,
            mode,
            inv_samples: 1.0 / samples as f32,
            _p: [0; 3],
        })?;
        let bind = ctx.bind_group(
            &pipeline,
            vec![
                params.as_entire_binding(),
                list.binding(),
                image.binding(),
                resolved.binding(),
                count.binding(),
            ],
        );
        batch.dispatch("show", &pipeline, &bind, entries)?;
    }
    batch.keep(list);
    batch.keep(count);
    batch.keep(resolved);
    Ok(())
}

/// The emission of `g` on the GPU (`None` where it is zero everywhere): the primary rays'
/// where the GPU traced them, else uploaded once per G-buffer on the GPU.
fn emission_of(
    ctx: &GpuContext,
    g: &GBuffer,
    gbuffer: &Arc<GpuGBuffer>,
) -> Result<Option<EmissionBuffer>, GpuError> {
    match gbuffer.emission() {
        GpuEmission::Zero => return Ok(None),
        GpuEmission::Kept(_) => return Ok(Some(EmissionBuffer::Traced(Arc::clone(gbuffer)))),
        GpuEmission::OnCpu => {}
    }
    let states = ctx.display_states();
    let mut last = states
        .emission
        .lock()
        .unwrap_or_else(PoisonError::into_inner);
    if let Some((at, buffer)) = last.as_ref()
        && Arc::ptr_eq(at, gbuffer)
    {
        return Ok(buffer.clone().map(EmissionBuffer::Uploaded));
    }
    let buffer = if g.emission.iter().any(|e| *e != Vec3::ZERO) {
        let rows: Vec<Vec4> = g.emission.iter().map(|e| e.extend(0.0)).collect();
        Some(Arc::new(ctx.storage("emission", &rows)?))
    } else {
        None
    };
    *last = Some((Arc::clone(gbuffer), buffer.clone()));
    Ok(buffer.map(EmissionBuffer::Uploaded))
}

/// A G-buffer's emission on the GPU.
enum EmissionBuffer {
    /// Traced with the G-buffer (held by it).
    Traced(Arc<GpuGBuffer>),
    /// Uploaded from its planes.
    Uploaded(Arc<wgpu::Buffer>),
}

impl EmissionBuffer {
    fn binding(&self) -> Option<wgpu::BindingResource<'_>> {
        match self {
            Self::Traced(g) => match g.emission() {
                GpuEmission::Kept(b) => Some(b.as_entire_binding()),
                _ => None,
            },
            Self::Uploaded(b) => Some(b.as_entire_binding()),
        }
    }
}

/// This thread's running sum for a frame of `pixels` pixels: the buffer, whether this frame
/// restarts it, and the frames in the mean with this one.
fn running_sum(ctx: &GpuContext, pixels: usize, restart: bool) -> (wgpu::Buffer, bool, u32) {
    let states = ctx.display_states();
    let mut sums = states.sums.lock().unwrap_or_else(PoisonError::into_inner);
    let id = std::thread::current().id();
    let sum = match sums.remove(&id) {
        Some(s) if s.pixels == pixels && !restart && s.frames > 0 => Sum {
            frames: s.frames + 1,
            ..s
        },
        Some(s) if s.pixels == pixels => Sum { frames: 1, ..s },
        _ => Sum {
            buffer: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("running sum"),
                size: (16 * pixels as u64).max(16),
                usage: GpuContext::STORAGE,
                mapped_at_creation: false,
            }),
            pixels,
            frames: 1,
        },
    };
    let out = (sum.buffer.clone(), sum.frames == 1, sum.frames);
    if sums.len() >= MAX_THREADS {
        // Threads that showed frames and ended leave their means: past a few, start over.
        sums.clear();
    }
    sums.insert(id, sum);
    out
}

/// A frame to show: what the recipe asks, and the frame's direct light where the CPU
/// computed it (the GPU's direct pass does not run the scene: [`crate::direct::supported`]).
#[derive(Clone, Copy)]
pub(crate) struct Shown<'a> {
    pub inputs: &'a ShowInputs<'a>,
    pub host_direct: Option<&'a [Vec3]>,
}

/// Records the direct light of the frame of `inputs` (on the GPU, or `shown.host_direct`)
/// where it is asked for, and the frame's showing with the indirect light `indirect`, into
/// `batch`; where the ratio estimator's result is that light and the request asks for it,
/// its temporal filter first ([`taa`]).
///
/// # Errors
/// As [`record`].
pub(crate) fn record_frame<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    inputs: &MethodInputs,
    shown: &Shown<'_>,
    gbuffer: &Arc<GpuGBuffer>,
    indirect: Part<'_, 'c>,
) -> Result<Recorded, GpuError> {
    let (world, g, s) = (inputs.world, inputs.gbuffer, inputs.settings);
    if let (Some(taa), Part::Ratio(result)) = (&shown.inputs.request.taa, indirect) {
        taa::record(ctx, batch, (g, gbuffer), inputs.camera, result, taa)?;
    }
    let on_gpu = shown.inputs.direct && shown.host_direct.is_none();
    let lease = if on_gpu {
        crate::direct::record_direct(ctx, batch, world, g, s)?
    } else {
        None
    };
    let direct = match (&lease, shown.host_direct) {
        (Some(l), _) => Part::Radiance(l),
        (None, Some(v)) if shown.inputs.direct => Part::Host(v),
        _ => Part::Zero,
    };
    let parts = Parts {
        emission: shown.inputs.emission,
        direct,
        indirect,
    };
    let edges = match shown.inputs.edges {
        ShowEdges::None => Edges::None,
        ShowEdges::Resolved(e) => Edges::Resolved(e),
        ShowEdges::Find(samples) => {
            let (camera, size) = (inputs.camera, (g.width, g.height));
            Edges::Found(crate::edges::record(
                ctx, batch, world, camera, gbuffer, size, samples,
            )?)
        }
    };
    let recorded = record(ctx, batch, g, gbuffer, &parts, edges, &shown.inputs.request)?;
    if let Some(lease) = lease {
        batch.keep(lease);
    }
    Ok(recorded)
}

/// Shows the frame of `inputs` whose indirect light came back to the CPU (`out`), in a
/// submission of its own: the shown frame and the GPU's pass times. Where the request asks
/// for the temporal filter and `out` holds A and the ratios, they are uploaded as the
/// ratio estimator's result (the filter's input) instead of the radiance.
///
/// # Errors
/// As [`record`], or the GPU failed.
pub(crate) fn show_frame(
    ctx: &GpuContext,
    inputs: &MethodInputs,
    shown: &Shown<'_>,
    out: &MethodOutput,
) -> Result<(Displayed, PassTimes), GpuError> {
    let g = inputs.gbuffer;
    let gbuffer = ctx.gbuffer(g)?;
    let mut batch = Batch::new(ctx);
    let n = g.len();
    let planes = match (
        &shown.inputs.request.taa,
        &out.unshadowed,
        &out.shadow_ratio,
    ) {
        (Some(_), Some(a), Some(r)) if a.len() == n => {
            let rows: Vec<[Vec4; 3]> = (0..n)
                .map(|p| {
                    let at = |v: &[Vec3]| v.get(p).copied().unwrap_or(Vec3::ONE).extend(0.0);
                    [a[p].extend(0.0), at(&r.raw), at(&r.filtered)]
                })
                .collect();
            Some(ctx.upload("ratio result", &rows)?)
        }
        _ => None,
    };
    let part = match (&planes, out.radiance.len() == n) {
        (Some(p), _) => Part::Ratio(p),
        (None, true) => Part::Host(&out.radiance),
        (None, false) => Part::Zero,
    };
    let recorded = record_frame(ctx, &mut batch, inputs, shown, &gbuffer, part)?;
    let (reads, times) = batch.finish()?;
    Ok((recorded.finish(&reads), times))
}

/// Shows an image made of parts on the CPU on the GPU, as a shown frame's parts are shown
/// (the emission of `g` where `emission`, `direct`, `indirect`; empty parts are zero):
/// for tests against the CPU's display.
///
/// # Errors
/// A buffer could not be leased, the image exceeds one dispatch, or the GPU failed.
pub fn show_parts(
    ctx: &GpuContext,
    g: &GBuffer,
    (emission, direct, indirect): (bool, &[Vec3], &[Vec3]),
    edges: Option<&EdgeResolve>,
    request: &DisplayRequest,
) -> Result<Displayed, GpuError> {
    let gbuffer = ctx.gbuffer(g)?;
    let parts = Parts {
        emission,
        direct: host_part(direct),
        indirect: host_part(indirect),
    };
    let mut batch = Batch::new(ctx);
    let edges = edges.map_or(Edges::None, Edges::Resolved);
    let recorded = record(ctx, &mut batch, g, &gbuffer, &parts, edges, request)?;
    let (reads, _) = batch.finish()?;
    Ok(recorded.finish(&reads))
}

/// An image on the CPU as a part: zero where empty.
fn host_part<'a, 'c>(v: &'a [Vec3]) -> Part<'a, 'c> {
    if v.is_empty() {
        Part::Zero
    } else {
        Part::Host(v)
    }
}
