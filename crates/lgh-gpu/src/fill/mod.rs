//! Cut recombination windows filled on the GPU (`shaders/fill/`): lgh-render's
//! `shading::interleave::fill` (an extension of the interleaved sampling of LGH 2019 section
//! 4.3; docs/design.md, "Filling cut windows"), so that the GPU frame is the CPU's estimator
//! under interleaving.
//!
//! A pixel whose recombination window reaches fewer than `fill_below` n^2 of the n^2
//! sub-images shades the missed ones itself: its A becomes
//!
//! A(x) = (sum over the reached sub-images s of m_s + sum over the missed s of A_s(x)) / n^2,
//!
//! m_s the Gaussian-weighted mean of sub-image s's raw A over the window's taps, A_s(x) the
//! lights of sub-image s's list of the pixel's tile at the pixel. The passes, each recorded
//! into the frame's batches:
//!
//! 1. [`Fill::record_masks`], before the tile binning: the blur's discontinuities (kept for
//!    the interleaving blur) and per pixel the mask of the sub-images its window misses
//!    (`masks.wgsl`), which the binning reads to put the guests in the tiles' bounds
//!    ([`crate::bins::record`]).
//! 2. `Fill::record_guests`, after the lighting loop: each guest sums its missed
//!    sub-images' lists at itself (`guests.wgsl`), and the loop's raw A is kept.
//! 3. `Fill::record_recombine`, after the blur that recombines A
//!    (`interleave::record`): A of the pixels that fill (`recombine.wgsl`).
//!
//! Every pixel sums its own terms in a fixed order: the result does not depend on
//! scheduling.

use lgh_render::passes::gbuffer::GBuffer;
use lgh_render::shading::interleave::BlurParams;

use crate::batch::Batch;
use crate::context::{GpuContext, GpuError};
use crate::gbuffer::GpuGBuffer;
use crate::pool::Lease;

/// The largest interleaving n whose masks the GPU holds (64 sub-images, two words).
pub const MAX_PHASES: u32 = 8;

/// `FillParams` of `shaders/fill/window.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct FillParams {
    width: u32,
    height: u32,
    radius: u32,
    n: u32,
    limit: f32,
    sigma: f32,
    planes: u32,
    _p0: u32,
}

/// `GuestParams` of `shaders/fill/guests.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GuestParams {
    width: u32,
    height: u32,
    n: u32,
    tile: u32,
    tiles_x: u32,
    tiles_y: u32,
    list_lights: u32,
    eps2: f32,
}

/// The WGSL sources of the kernels: masks, guests, recombine.
#[must_use]
pub fn sources() -> [String; 3] {
    let window = include_str!("../shaders/fill/window.wgsl");
    let bits = include_str!("../shaders/fill/bits.wgsl");
    [
        crate::kernel(&[window, include_str!("../shaders/fill/masks.wgsl")]),
        crate::kernel(&[
            bits,
            include_str!("../shaders/shaded_light.wgsl"),
            include_str!("../shaders/fill/guests.wgsl"),
        ]),
        crate::kernel(&[window, include_str!("../shaders/fill/recombine.wgsl")]),
    ]
}

/// The kernels, by their place in [`sources`].
#[derive(Clone, Copy)]
enum Kernel {
    Masks = 0,
    Guests = 1,
    Recombine = 2,
}

impl Kernel {
    /// The pipeline's name, and the pass's timing name.
    fn names(self) -> (&'static str, &'static str) {
        match self {
            Self::Masks => ("fill masks", "fill_masks"),
            Self::Guests => ("fill guests", "fill_guests"),
            // The recombination counts as the blur's.
            Self::Recombine => ("fill recombine", "interleave_blur"),
        }
    }
}

/// Records `kernel` over `pixels` invocations with `bindings` (its uniform first).
fn record_kernel(
    ctx: &GpuContext,
    batch: &mut Batch<'_>,
    kernel: Kernel,
    bindings: Vec<wgpu::BindingResource<'_>>,
    pixels: usize,
) -> Result<(), GpuError> {
    let (name, timing) = kernel.names();
    let pipeline = ctx.pipeline(name, || {
        let mut all = sources();
        std::mem::take(&mut all[kernel as usize])
    });
    let bind = ctx.bind_group(&pipeline, bindings);
    batch.dispatch(timing, &pipeline, &bind, pixels)
}

/// Where a frame's loop reads its lights: the lights' table and the binned lists, where the
/// lists' lights start in it, and the tiles (edge in full-resolution pixels, tiles along x
/// and y; [`crate::bins::GpuBins::tiles`]).
pub(crate) struct Lists<'a> {
    pub lights: &'a Lease<'a>,
    pub lists: &'a Lease<'a>,
    pub list_lights: u32,
    pub tiles: [u32; 3],
}

/// A frame's filling of cut windows on the GPU: the discontinuities and masks, and after
/// the loop the raw A and the guests' sums.
pub struct Fill<'c> {
    jumps: Lease<'c>,
    masks: Lease<'c>,
    window: FillParams,
    /// Per pixel the loop's A and the guests' sum, once [`Fill::record_guests`] ran.
    shaded: Option<Lease<'c>>,
}

impl<'c> Fill<'c> {
    /// Records the discontinuities of the interleaving blur `wide` (its recombination's walks,
    /// [`BlurParams::recombination`]) and the masks of the pixels of `g` (`gbuffer`, `width`
    /// x `height`) whose windows reach fewer than `below` n^2 sub-images; `None` where
    /// nothing fills (no interleaving, `below` 0, n above [`MAX_PHASES`], or a walk longer
    /// than the GPU's blur).
    ///
    /// # Errors
    /// The image exceeds one dispatch, or a buffer the adapter's limits.
    pub fn record_masks(
        ctx: &'c GpuContext,
        batch: &mut Batch<'c>,
        g: (&GpuGBuffer, u32, u32),
        wide: &BlurParams,
        below: f32,
    ) -> Result<Option<Self>, GpuError> {
        let p = wide.recombination();
        let n = p.phases;
        if n <= 1 || n > MAX_PHASES || below <= 0.0 || !crate::interleave::supported(&p) {
            return Ok(None);
        }
        let (gbuffer, width, height) = g;
        let pixels = u64::from(width) * u64::from(height);
        let jumps = ctx.output("jumps", 4 * pixels)?;
        crate::interleave::record_jumps(ctx, batch, g, &p, &jumps)?;
        let masks = ctx.output("fill masks", 8 * pixels)?;
        let window = FillParams {
            width,
            height,
            radius: p.radius,
            n,
            limit: below * (n * n) as f32,
            sigma: p.sigma,
            planes: 0,
            _p0: 0,
        };
        let uniform = batch.uniform(&window)?;
        let bindings = vec![
            uniform.as_entire_binding(),
            gbuffer.binding(),
            jumps.binding(),
            masks.binding(),
        ];
        record_kernel(ctx, batch, Kernel::Masks, bindings, pixels as usize)?;
        Ok(Some(Self {
            jumps,
            masks,
            window,
            shaded: None,
        }))
    }

    /// Per pixel, the sub-images it shades as a guest (two words a pixel).
    #[must_use]
    pub fn masks(&self) -> &Lease<'c> {
        &self.masks
    }

    /// The blur's discontinuities, one word a pixel.
    pub(crate) fn jumps(&self) -> &Lease<'c> {
        &self.jumps
    }

    /// Records the guests' sums after the lighting loop that wrote `asu` (per pixel A, S, U)
    /// from the binned `lists` (binned with [`Fill::masks`]), with the clamp `eps2`.
    ///
    /// # Errors
    /// The image exceeds one dispatch, or a buffer the adapter's limits.
    pub(crate) fn record_guests(
        &mut self,
        ctx: &'c GpuContext,
        batch: &mut Batch<'c>,
        gbuffer: &GpuGBuffer,
        lists: &Lists<'_>,
        eps2: f32,
        asu: &Lease<'_>,
    ) -> Result<(), GpuError> {
        let w = &self.window;
        let pixels = u64::from(w.width) * u64::from(w.height);
        let shaded = ctx.output("fill A and guests", 32 * pixels)?;
        let [tile, tiles_x, tiles_y] = lists.tiles;
        let uniform = batch.uniform(&GuestParams {
            width: w.width,
            height: w.height,
            n: w.n,
            tile,
            tiles_x,
            tiles_y,
            list_lights: lists.list_lights,
            eps2,
        })?;
        let bindings = vec![
            uniform.as_entire_binding(),
            gbuffer.binding(),
            lists.lights.binding(),
            lists.lists.binding(),
            self.masks.binding(),
            asu.binding(),
            shaded.binding(),
        ];
        record_kernel(ctx, batch, Kernel::Guests, bindings, pixels as usize)?;
        self.shaded = Some(shaded);
        Ok(())
    }

    /// Records A of the pixels that fill their windows into plane 0 of `images` (`planes`
    /// vec4s per pixel), after the blur that recombined A; nothing before
    /// [`Fill::record_guests`].
    ///
    /// # Errors
    /// The image exceeds one dispatch.
    pub(crate) fn record_recombine(
        &self,
        ctx: &GpuContext,
        batch: &mut Batch<'_>,
        (gbuffer, _, _): (&GpuGBuffer, u32, u32),
        images: &Lease<'_>,
        planes: u32,
    ) -> Result<(), GpuError> {
        let Some(shaded) = &self.shaded else {
            return Ok(());
        };
        let w = &self.window;
        let uniform = batch.uniform(&FillParams { planes, ..*w })?;
        let bindings = vec![
            uniform.as_entire_binding(),
            gbuffer.binding(),
            self.jumps.binding(),
            self.masks.binding(),
            shaded.binding(),
            images.binding(),
        ];
        let pixels = (w.width * w.height) as usize;
        record_kernel(ctx, batch, Kernel::Recombine, bindings, pixels)
    }

    /// Hands the buffers to `batch`, which keeps them until its submission is done.
    pub(crate) fn keep_in(self, batch: &mut Batch<'c>) {
        batch.keep(self.jumps);
        batch.keep(self.masks);
        if let Some(shaded) = self.shaded {
            batch.keep(shaded);
        }
    }
}

/// The masks of [`Fill::record_masks`] for the G-buffer `g` under the blur `wide`, read
/// back (bit s = sub-image s): lgh-render's `missed_sub_images` on the GPU, for tests and
/// tools; `None` where nothing fills.
///
/// # Errors
/// The GPU failed.
pub fn missed_sub_images(
    ctx: &GpuContext,
    g: &GBuffer,
    wide: &BlurParams,
    below: f32,
) -> Result<Option<Vec<u64>>, GpuError> {
    let gbuffer = ctx.gbuffer(g)?;
    let mut batch = Batch::new(ctx);
    let Some(fill) =
        Fill::record_masks(ctx, &mut batch, (&gbuffer, g.width, g.height), wide, below)?
    else {
        return Ok(None);
    };
    batch.read(fill.masks.buffer(), 8 * g.len() as u64)?;
    fill.keep_in(&mut batch);
    let (reads, _) = batch.finish()?;
    let words: &[u32] = reads.first().map_or(&[], |r| bytemuck::cast_slice(r));
    Ok(Some(
        words
            .chunks_exact(2)
            .map(|w| u64::from(w[0]) | u64::from(w[1]) << 32)
            .collect(),
    ))
}
