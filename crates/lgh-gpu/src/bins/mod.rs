//! The tile binning of `lgh`'s shaded lights on the GPU (Lin & Yuksel 2019 section 3.2;
//! lgh-render's `shading/tiles.rs`, whose lists it makes: the same lights, in the same
//! ascending order, so that the lighting loop's stratified selection walks them as the CPU
//! walks its own).
//!
//! The passes (`shaders/bins/`), in two submissions with one wait between them:
//!
//! 1. `bounds`: every list's tile bounds from the G-buffer on the GPU (one invocation a
//!    list, its pixels in the CPU's order); `count`: every light counts itself into the
//!    lists of the tiles it may reach (integer atomics); a [`scan`](crate::scan) of the
//!    counts gives the lists' starts, and their total comes back: the lists buffer's size.
//! 2. `write`: every light writes its index into its lists at slots from atomic cursors;
//!    `sort`: each list sorted ascending (a bitonic sort, one workgroup a list), which
//!    removes the scheduler's order; `pixels`: each pixel's list and the pixels sorted by
//!    list, from the image's shape. The lighting loop is recorded after them in the same
//!    submission ([`crate::lgh`]).
//!
//! The lists buffer is laid out as the loop reads it (`shaders/lgh.wgsl`): the lists'
//! starts, their lights, the pixels sorted by list, each pixel's list.

use std::time::Instant;

use glam::{Vec3, Vec4};
use lgh_render::methods::lgh::LightSpheres;
use lgh_render::passes::gbuffer::GBuffer;
use lgh_scene::camera::CameraFrame;

use crate::batch::{Batch, PassTimes};
use crate::context::{GpuContext, GpuError};
use crate::gbuffer::GpuGBuffer;
use crate::pool::Lease;
use crate::primary::GpuCamera;

/// Bytes of one list's tile bounds (`TileBounds` in `shaders/bins/common.wgsl`).
const BOUNDS_BYTES: u64 = 16 * 13;
/// A light listed nowhere (a negative or NaN radius), beside its sub-image.
const LISTED_NOWHERE: u32 = 0x1_0000;
/// A light of infinite reach, listed everywhere.
const REACHES_EVERYWHERE: u32 = 0x2_0000;
/// Workgroups of a dispatch at most; the kernels loop over their items with its stride.
const MAX_GROUPS: usize = 65_535;

/// `BinParams` of the shaders.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct BinParams {
    width: u32,
    height: u32,
    n: u32,
    tile: u32,
    tiles_x: u32,
    tiles_y: u32,
    lists: u32,
    lights: u32,
    lights_base: u32,
    order_base: u32,
    list_base: u32,
    /// 1 where the bounds count the guests of cut recombination windows ([`crate::fill`]).
    fill: u32,
}

/// Where the parts of the lists buffer start, in words.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ListLayout {
    /// The lists (their starts are words 0..=lists).
    pub lists: u32,
    /// The lists' lights.
    pub lights: u32,
    /// The pixels sorted by list.
    pub order: u32,
    /// Each pixel's list.
    pub pixel_lists: u32,
}

impl ListLayout {
    /// The words of the buffer.
    #[must_use]
    pub fn words(&self, pixels: usize) -> u64 {
        u64::from(self.pixel_lists) + pixels as u64
    }
}

/// The lights binned on the GPU: the lists buffer and its layout, with the second
/// submission's passes recorded in `batch` (the caller records what reads the lists after
/// them and submits), and the first submission's wall time in milliseconds.
pub struct GpuBins<'c> {
    /// The passes that finish the lists, not yet submitted.
    pub batch: Batch<'c>,
    /// The lists buffer.
    pub lists: Lease<'c>,
    /// Its layout.
    pub layout: ListLayout,
    /// The first submission (bounds and counts, after the work the caller recorded ahead of
    /// them) and its wait, on the wall clock.
    pub counts_ms: f64,
    /// The GPU's times of the first submission's passes (empty without timestamps).
    pub first: PassTimes,
    /// The tiles: their edge in full-resolution pixels, and how many along x and y (list
    /// l is tile (tx, ty) of sub-image s, l = s tiles_x tiles_y + ty tiles_x + tx).
    pub tiles: [u32; 3],
}

/// The WGSL sources of the kernels: bounds, count, write, sort, pixels.
#[must_use]
pub fn sources() -> [String; 5] {
    let common = include_str!("../shaders/bins/common.wgsl");
    let reach = include_str!("../shaders/bins/reach.wgsl");
    let camera = include_str!("../shaders/camera.wgsl");
    [
        crate::kernel(&[
            common,
            include_str!("../shaders/fill/bits.wgsl"),
            include_str!("../shaders/bins/bounds.wgsl"),
        ]),
        crate::kernel(&[
            common,
            camera,
            reach,
            include_str!("../shaders/bins/count.wgsl"),
        ]),
        crate::kernel(&[
            common,
            camera,
            reach,
            include_str!("../shaders/bins/write.wgsl"),
        ]),
        crate::kernel(&[common, include_str!("../shaders/bins/sort.wgsl")]),
        crate::kernel(&[common, include_str!("../shaders/bins/pixels.wgsl")]),
    ]
}

/// The spheres of `s` as the kernels read them: two `vec4`s a light, centre and radius
/// (finite), then the normal of the plane behind which it gives nothing (zero for none)
/// and the distance within which it gives nothing (`BinLights::facing`, `holes`); and per
/// light its sub-image with the flags for radii that are not.
pub(crate) fn pack_spheres(s: &LightSpheres) -> (Vec<Vec4>, Vec<u32>) {
    let spheres = s
        .centres
        .iter()
        .zip(s.radii)
        .enumerate()
        .flat_map(|(i, (c, &r))| {
            let m = s.facing.get(i).copied().unwrap_or(Vec3::ZERO);
            let hole = s.holes.get(i).copied().unwrap_or(0.0);
            [
                c.extend(if r.is_finite() { r } else { 0.0 }),
                m.extend(hole),
            ]
        })
        .collect();
    let flags = s
        .radii
        .iter()
        .zip(s.sub)
        .map(|(&r, &sub)| {
            let flag = if r.is_nan() || r < 0.0 {
                LISTED_NOWHERE
            } else if r.is_infinite() {
                REACHES_EVERYWHERE
            } else {
                0
            };
            u32::from(sub) | flag
        })
        .collect();
    (spheres, flags)
}

/// The count and write kernels' bindings: the uniform `u` (the write kernel's has the lists
/// buffer's layout), the camera, then the spheres, flags, bounds and counters.
fn reach<'a>(
    u: &'a crate::batch::Uniform,
    cam: &'a crate::batch::Uniform,
    leases: [&'a Lease<'_>; 4],
) -> Vec<wgpu::BindingResource<'a>> {
    let mut r = vec![u.as_entire_binding(), cam.as_entire_binding()];
    r.extend(leases.into_iter().map(Lease::binding));
    r
}

/// The workgroups of a dispatch over `items` (workgroups of 64, looping past the limit).
fn groups(items: usize) -> u32 {
    items.div_ceil(64).clamp(1, MAX_GROUPS) as u32
}

/// Bins the lights `spheres` over the G-buffer `g` (on the GPU as `gbuffer`) seen through
/// `camera`: submits and waits for the counts (in `first`, after the work already recorded
/// there), then records the lists' passes into the returned batch. The spheres as the
/// kernels read them (centre and finite radius; sub-image with flags) are packed from
/// `spheres` and uploaded, or are `on_gpu` already (made by the work in `first`). Where
/// pixels fill their cut recombination windows, `masks` (per pixel the sub-images it shades
/// as a guest, [`crate::fill`], made by the work in `first`) puts the guests in the tiles'
/// bounds, so that a sub-image's lists hold the lights that reach them.
///
/// # Errors
/// More lights, lists or list entries than the buffers or a u32 index hold (the caller
/// bins on the CPU instead), or the GPU failed.
#[allow(clippy::too_many_arguments)]
pub fn record<'c>(
    ctx: &'c GpuContext,
    first: Batch<'c>,
    g: &GBuffer,
    camera: &CameraFrame,
    gbuffer: &GpuGBuffer,
    spheres: &LightSpheres,
    on_gpu: Option<(Lease<'c>, Lease<'c>)>,
    masks: Option<&Lease<'c>>,
) -> Result<GpuBins<'c>, GpuError> {
    let start = Instant::now();
    let n = spheres.n.max(1);
    let tile = spheres.tile.max(1) * n;
    let (tiles_x, tiles_y) = (g.width.div_ceil(tile), g.height.div_ceil(tile));
    let too_large = |what: &str| GpuError::TooLarge(format!("tile binning: {what}"));
    let lists = u64::from(n * n) * u64::from(tiles_x) * u64::from(tiles_y);
    let lists = u32::try_from(lists).map_err(|_| too_large("lists"))?;
    let lights = u32::try_from(spheres.count).map_err(|_| too_large("lights"))?;
    let mut params = BinParams {
        width: g.width,
        height: g.height,
        n,
        tile,
        tiles_x,
        tiles_y,
        lists,
        lights,
        fill: u32::from(masks.is_some()),
        ..BinParams::default()
    };
    let [bounds_src, count_src, write_src, sort_src, pixels_src] = sources();
    // The first submission: bounds, counts, starts.
    let mut batch = first;
    let uniform = batch.uniform(&params)?;
    let cam = batch.uniform(&GpuCamera::new(camera, g.width, g.height))?;
    let (sphere_buf, flag_buf) = match on_gpu {
        Some(made) => made,
        None if spheres.centres.len() != spheres.count => {
            return Err(GpuError::Failed(
                "tile binning: the lights are on the GPU, but their spheres were not made".into(),
            ));
        }
        None => {
            let (packed, flags) = pack_spheres(spheres);
            (
                ctx.upload("bin spheres", &packed)?,
                ctx.upload("bin flags", &flags)?,
            )
        }
    };
    let bounds = ctx.output("tile bounds", BOUNDS_BYTES * u64::from(lists))?;
    let counts = ctx.output("bin counts", 4 * u64::from(lists))?;
    let starts = ctx.output("bin starts", 4 * u64::from(lists))?;
    let total = ctx.output("bin total", 16)?;
    // Without guests the masks are not read: a word stands in.
    let no_masks;
    let masks = match masks {
        Some(m) => m,
        None => {
            no_masks = ctx.output("no guest masks", 8)?;
            &no_masks
        }
    };
    let pipeline = ctx.pipeline("bin bounds", || bounds_src);
    let bind = ctx.bind_group(
        &pipeline,
        vec![
            uniform.as_entire_binding(),
            gbuffer.binding(),
            bounds.binding(),
            masks.binding(),
        ],
    );
    batch.dispatch_groups("tile_counts", &pipeline, &bind, groups(lists as usize));
    batch.clear_lease(&counts);
    let pipeline = ctx.pipeline("bin count", || count_src);
    let bind = ctx.bind_group(
        &pipeline,
        reach(&uniform, &cam, [&sphere_buf, &flag_buf, &bounds, &counts]),
    );
    batch.dispatch_groups("tile_counts", &pipeline, &bind, groups(lights as usize));
    crate::scan::record(
        ctx,
        &mut batch,
        &counts,
        &starts,
        &total,
        lists as usize,
        false,
    )?;
    batch.read(total.buffer(), 4)?;
    let (reads, first) = batch.finish()?;
    let entries = reads
        .first()
        .and_then(|r| bytemuck::cast_slice::<_, u32>(r).first().copied())
        .ok_or_else(|| GpuError::Failed("the tile counts' read-back is missing".into()))?;
    // The second: the lists.
    let pixels = g.len() as u64;
    let lights_base = u64::from(lists) + 1;
    let order_base = lights_base + u64::from(entries);
    let list_base = order_base + pixels;
    let words = list_base + pixels;
    if words > u64::from(u32::MAX) {
        return Err(too_large("list entries"));
    }
    params.lights_base = lights_base as u32;
    params.order_base = order_base as u32;
    params.list_base = list_base as u32;
    let layout = ListLayout {
        lists,
        lights: params.lights_base,
        order: params.order_base,
        pixel_lists: params.list_base,
    };
    let lists_buf = ctx.output("light lists", 4 * words)?;
    // This submission's own uniforms (a batch's live in its own buffers).
    let mut batch = Batch::new(ctx);
    let uniform = batch.uniform(&params)?;
    let cam = batch.uniform(&GpuCamera::new(camera, g.width, g.height))?;
    batch.copy(&starts, 0, &lists_buf, 0, 4 * u64::from(lists));
    batch.copy(&total, 0, &lists_buf, 4 * u64::from(lists), 4);
    batch.clear_lease(&counts);
    let pipeline = ctx.pipeline("bin write", || write_src);
    let mut resources = reach(&uniform, &cam, [&sphere_buf, &flag_buf, &bounds, &counts]);
    resources.push(lists_buf.binding());
    let bind = ctx.bind_group(&pipeline, resources);
    batch.dispatch_groups("tile_lists", &pipeline, &bind, groups(lights as usize));
    let own = vec![uniform.as_entire_binding(), lists_buf.binding()];
    let pipeline = ctx.pipeline("bin sort", || sort_src);
    let bind = ctx.bind_group(&pipeline, own.clone());
    batch.dispatch_groups(
        "tile_lists",
        &pipeline,
        &bind,
        lists.clamp(1, MAX_GROUPS as u32),
    );
    let pipeline = ctx.pipeline("bin pixels", || pixels_src);
    let bind = ctx.bind_group(&pipeline, own);
    batch.dispatch_groups("tile_lists", &pipeline, &bind, groups(pixels as usize));
    for lease in [sphere_buf, flag_buf, bounds, counts, starts, total] {
        batch.keep(lease);
    }
    Ok(GpuBins {
        batch,
        lists: lists_buf,
        layout,
        counts_ms: start.elapsed().as_secs_f64() * 1e3,
        first,
        tiles: [tile, tiles_x, tiles_y],
    })
}
