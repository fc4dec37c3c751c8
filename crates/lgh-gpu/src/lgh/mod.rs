//! `lgh` with its lighting loop on the GPU (`shaders/lgh.wgsl`; Lin & Yuksel 2019 sections
//! 3.2, 3.3 and Appendix A): per pixel the unshadowed sum A over its tile's lights, k shadow
//! samples by stratified selection, the unbiased estimate's targets (the walk to an S_1
//! light, a representative VPL by contribution) and one shadow ray each through the uploaded
//! BVH, giving S and U.
//!
//! With shadow samples, the hierarchies are built on the GPU ([`crate::grid`]) and stay
//! there: only their level ranges come back
//! ([`keep_grid`](crate::grid::GpuGridBuilder::keep_grid)), and what the
//! loop reads is made on the GPU from what the builds hold ([`crate::grid::Held`]): the
//! shaded lights' table and the binning's spheres (`lights.rs`), the unbiased estimate's
//! vertex rows and descent (`lookups.rs`), the S_1 lights' representatives and the VPLs
//! these index (`held.rs`). The lights are binned into tiles on the GPU ([`crate::bins`],
//! the CPU's lists) in the loop's submission; the steps after it (the interleaving blur,
//! the ratio estimator with its a-trous filter) run on the GPU in the loop's submission
//! ([`crate::ratio`]), and the CPU composites ([`LghFrame::finish_shadowed`]), or, for a
//! frame shown on the GPU (`IndirectMethod::render_shown`, the viewer), the same submission
//! goes on to the direct light, the temporal filter and the showing ([`crate::display`]),
//! and only the frame's packed pixels come back. Where a step
//! needs the grids on the CPU (lists longer than the GPU's binning holds: the CPU bins
//! them; a grid built on the CPU beside ones on the GPU; a table past the adapter's
//! buffers, sized for the most children a light may have), the frame is made again with the
//! grids read back, and the CPU makes the shaded lights and tables as the CPU method does
//! ([`LghFrame::prepare_with`], [`LghFrame::tables`]); so does a frame without shadow
//! samples. A blur wider than the GPU's takes the CPU's (the loop's images read back,
//! [`LghFrame::finish_with`]).
//! It runs lgh's default estimate (unbiased, representative targets drawn at the ray,
//! stratified selection); other settings are refused with a clear error.

use std::sync::Arc;
use std::time::Instant;

use glam::{Vec3, Vec4};
use lgh_core::lighting_grid::GridError;
use lgh_core::timing::Timings;
use lgh_render::denoise::atrous::AtrousParams;
use lgh_render::memory::FrameMemory;
use lgh_render::methods::lgh::tables::LghTables;
use lgh_render::methods::lgh::{
    DEFAULT_SHADOW_SAMPLES, Estimator, JitterAt, LGH, LGH_UNSHADOWED, LghFrame, LghSettings,
    LoopResult, Prepared, ShadowTarget,
};
use lgh_render::methods::{IndirectMethod, Method, MethodInputs, MethodOutput};
use lgh_render::passes::gbuffer::GBuffer;
use lgh_render::settings::RenderError;
use lgh_render::shading::shadow_pass::ShadowEstimates;
use rayon::prelude::*;

use crate::batch::{Batch, PassTimes};
use crate::bins::GpuBins;
use crate::context::{GpuContext, GpuError};
use crate::display::Shown;
use crate::fill::Fill;
use crate::gbuffer::GpuGBuffer;
use crate::pool::Lease;
use chain::Shaded;
use lgh_render::denoise::temporal::TemporalTarget;
use lgh_render::direct::render_direct;
use lgh_render::display::{Displayed, ShowInputs};

mod chain;
mod held;
mod lights;
mod lookups;
#[cfg(test)]
mod testing;
mod upload;

pub use lights::sources as light_table_sources;
pub use lookups::sources as lookup_sources;
use upload::{Params, Tables};

/// The lighting grid hierarchy with its lighting loop and shadow rays on the GPU.
pub const LGH_GPU: Method = Method::new(&GpuLgh { cpu: LGH });
/// The lighting grid hierarchy without shadows, its lighting loop on the GPU.
pub const LGH_UNSHADOWED_GPU: Method = Method::new(&GpuLgh {
    cpu: LGH_UNSHADOWED,
});

/// The GPU version of the CPU method `cpu` (its name, defaults and settings are the CPU's).
struct GpuLgh {
    cpu: Method,
}

impl IndirectMethod for GpuLgh {
    fn name(&self) -> &'static str {
        self.cpu.get().name()
    }

    fn about(&self) -> &'static str {
        "Lighting grid hierarchy, its lighting loop and shadow rays on the GPU"
    }

    fn default_shadow_samples(&self) -> u32 {
        self.cpu.get().default_shadow_samples()
    }

    crate::gpu_frame_passes!(vpls: vpl_places);

    fn render(
        &self,
        inputs: &MethodInputs,
        memory: &mut FrameMemory,
    ) -> Result<MethodOutput, RenderError> {
        Ok(self.render_or_show(inputs, memory, None)?.0)
    }

    fn render_shown(
        &self,
        inputs: &MethodInputs,
        show: &ShowInputs,
        memory: &mut FrameMemory,
    ) -> Result<Option<(MethodOutput, Displayed)>, RenderError> {
        let (world, g, s) = (inputs.world, inputs.gbuffer, inputs.settings);
        // The GPU's temporal filter runs on the shadow ratio alone.
        let k = s.shadows.k(self.cpu == LGH, DEFAULT_SHADOW_SAMPLES);
        let target = show.request.taa.map(|t| t.settings.target);
        if target.is_some_and(|t| k == 0 || t != TemporalTarget::ShadowRatio) {
            return Ok(None);
        }
        // The direct light where the GPU's pass does not run the scene, on the CPU.
        let host_direct = if show.direct && !crate::direct::supported(world, s) {
            let (seed, samples, mode) = (s.seed, s.area_samples, s.direct);
            let filter = &mut memory.direct_filter;
            let g = g.planes()?;
            Some(render_direct(world, g, seed, samples, mode, filter, inputs.progress).radiance)
        } else {
            None
        };
        let shown = Shown {
            inputs: show,
            host_direct: host_direct.as_deref(),
        };
        let (mut out, displayed) = self.render_or_show(inputs, memory, Some(&shown))?;
        if let Some(displayed) = displayed {
            return Ok(Some((out, displayed)));
        }
        // The frame's indirect light came back (a frame made with its grids on the CPU):
        // shown in a submission of its own.
        let fail = |e: GpuError| RenderError::Backend(e.to_string());
        let ctx = GpuContext::shared().map_err(fail)?;
        let (displayed, gpu) =
            crate::display::show_frame(ctx, inputs, &shown, &out).map_err(fail)?;
        // A shown frame's output holds no images.
        (out.radiance, out.unshadowed, out.shadow_ratio) = (Vec::new(), None, None);
        out.lights_per_pixel = None;
        for (name, ms) in gpu {
            out.timings.push(name, ms);
        }
        Ok(Some((out, displayed)))
    }
}

impl GpuLgh {
    /// The frame of `inputs`, and where it is `shown`, shown on the GPU if its images
    /// stayed there (else they come back in the output, for the caller to show).
    fn render_or_show(
        &self,
        inputs: &MethodInputs,
        memory: &mut FrameMemory,
        shown: Option<&Shown<'_>>,
    ) -> Result<(MethodOutput, Option<Displayed>), RenderError> {
        let shadowed = self.cpu == LGH;
        if inputs.settings.shadows.k(shadowed, DEFAULT_SHADOW_SAMPLES) > 0 {
            supported(&inputs.settings.lgh)?;
        }
        let fail = |e: GpuError| RenderError::Backend(e.to_string());
        let ctx = GpuContext::shared().map_err(fail)?;
        // With shadow samples every step after the build runs on the GPU from what the
        // builds hold, and the grids stay there; where a step cannot (a grid built on the
        // CPU beside ones on the GPU, lists too long for the GPU's binning), the frame is
        // made again with the grids read back.
        let s = inputs.settings;
        let resident =
            s.shadows.k(shadowed, DEFAULT_SHADOW_SAMPLES) > 0 && s.lgh.only_level.is_none();
        if resident {
            match frame(ctx, inputs, memory, shadowed, true, shown) {
                Err(Attempt::Again) => {}
                Err(Attempt::Failed(e)) => return Err(e),
                Ok(output) => return Ok(output),
            }
        }
        // VPLs kept on the GPU without a copy here (`vpl_places`) are read back first.
        let read;
        let inputs = if inputs.vpls.len() < inputs.vpl_count {
            read = crate::vpls::read_back_kept(ctx, inputs.world, s, inputs.vpl_count)
                .map_err(fail)?;
            &MethodInputs {
                vpls: &read,
                vpl_count: read.len(),
                vpl_bins: None,
                ..*inputs
            }
        } else {
            inputs
        };
        match frame(ctx, inputs, memory, shadowed, false, shown) {
            Ok(output) => Ok(output),
            Err(Attempt::Failed(e)) => Err(e),
            Err(Attempt::Again) => Err(RenderError::Backend(
                "lgh on the GPU: the hierarchies' grids are not on the CPU".into(),
            )),
        }
    }

    /// Where the frame's VPLs go: kept on the GPU for the hierarchy build, and where the
    /// frame's every later pass runs on the GPU (shadow samples with lgh's default
    /// estimate, every level shown, a construction the GPU builds) not read
    /// back at all. Where the frame has to be made with its grids on the CPU after all
    /// ([`Attempt::Again`]), they are read back then.
    fn vpl_places(&self, s: &lgh_render::RenderSettings) -> (bool, bool) {
        let l = &s.lgh;
        let only_grid = self.cpu == LGH
            && s.shadows.k(true, DEFAULT_SHADOW_SAMPLES) > 0
            && supported(l).is_ok()
            && l.only_level.is_none()
            && l.construction != lgh_core::lighting_grid::Construction::GatherFromS1;
        (true, only_grid)
    }
}

/// `inputs` with the G-buffer's planes on the CPU ([`GBuffer::planes`]: read back where
/// the GPU kept them), for the steps that fall back to the CPU.
fn planes_on_cpu<'a>(inputs: &MethodInputs<'a>) -> Result<MethodInputs<'a>, RenderError> {
    Ok(MethodInputs {
        gbuffer: inputs.gbuffer.planes()?,
        ..*inputs
    })
}

/// Why a GPU lgh frame did not come out.
enum Attempt {
    /// It needs its grids on the CPU: make it again with them read back.
    Again,
    /// It failed.
    Failed(RenderError),
}

impl From<RenderError> for Attempt {
    fn from(e: RenderError) -> Self {
        Self::Failed(e)
    }
}

/// The frame of `inputs` with its lighting loop on the GPU, its grids kept on the GPU
/// where `resident` (else read back: the CPU then makes what the GPU cannot).
fn frame(
    ctx: &GpuContext,
    inputs: &MethodInputs,
    memory: &mut FrameMemory,
    shadowed: bool,
    resident: bool,
    shown: Option<&Shown<'_>>,
) -> Result<(MethodOutput, Option<Displayed>), Attempt> {
    let fail = |e: GpuError| RenderError::Backend(e.to_string());
    // A frame that comes back is composed on the CPU, from the planes.
    let on_cpu;
    let inputs = if shown.is_none() {
        on_cpu = planes_on_cpu(inputs)?;
        &on_cpu
    } else {
        inputs
    };
    // The hierarchies built on the GPU (the gather construction on the CPU).
    // Their representatives and the VPLs these index stay on the GPU for the loop.
    let mut builder = crate::grid::GpuGridBuilder::new(ctx);
    builder.keep_representatives(true);
    builder.keep_grid(resident);
    let prepared = match LghFrame::prepare_with(inputs, shadowed, memory, true, Some(&mut builder))
    {
        Ok(p) => p,
        Err(GridError::KeptOnDevice) => return Err(Attempt::Again),
        Err(e) => return Err(RenderError::Backend(e.to_string()).into()),
    };
    let hierarchies = builder.take_held();
    drop(builder);
    #[cfg(test)]
    if resident && tests::AGAIN.with(std::cell::Cell::get) {
        return Err(Attempt::Again);
    }
    let mut frame = match prepared {
        Prepared::Dark(output) => return Ok((output, None)),
        Prepared::Frame(frame) => frame,
    };
    let g = inputs.gbuffer;
    // The shaded lights' table and spheres made on the GPU from what the builds hold
    // (else packed on the CPU), in the tile binning's first submission.
    let mut first = Batch::new(ctx);
    let made = {
        let t = frame.tables(g.width, g.height).ok_or_else(missing_tables)?;
        lights::record(ctx, &mut first, inputs, &t, &hierarchies, t.light_count).map_err(fail)?
    };
    let (mut table, spheres) = match made {
        Some(l) => (Some(l.table), Some((l.spheres, l.flags))),
        None if !frame.lights_on_cpu() => return Err(Attempt::Again),
        None => (None, None),
    };
    // The tile binning on the GPU; lists larger than its buffers on the CPU (and the
    // table, whose making may not have been submitted, packed on the CPU). Before it, the
    // masks of the pixels that fill their cut recombination windows, whose guests count in
    // the tiles' bounds (where the GPU runs the blur; [`crate::fill`]).
    let gbuffer = ctx.gbuffer(g).map_err(fail)?;
    let filter = frame.ratio_filter(inputs);
    let mut fill = match filter.interleave_blur {
        Some(p) if crate::ratio::supported(&filter) => {
            let size = (&*gbuffer, g.width, g.height);
            let below = inputs.settings.lgh.fill_below;
            Fill::record_masks(ctx, &mut first, size, &p, below).map_err(fail)?
        }
        _ => None,
    };
    let sp = frame.spheres();
    let masks = fill.as_ref().map(Fill::masks);
    let bins = crate::bins::record(ctx, first, g, inputs.camera, &gbuffer, &sp, spheres, masks);
    let bins = match bins {
        Ok(bins) => Some(bins),
        Err(GpuError::TooLarge(_)) if !frame.lights_on_cpu() => return Err(Attempt::Again),
        Err(GpuError::TooLarge(_)) => {
            // The CPU's lists hold no guests: the frame does not fill.
            frame.bin_on_cpu(&planes_on_cpu(inputs)?, memory);
            (table, fill) = (None, None);
            None
        }
        Err(e) => return Err(fail(e).into()),
    };
    let tables = frame.tables(g.width, g.height).ok_or_else(missing_tables)?;
    let held = OnGpu {
        bins,
        hierarchies,
        lights: table,
        fill,
        before: Vec::new(),
    };
    // A buffer past the adapter's limits with the grids on the GPU (the lookups' slots
    // hold 27 children a light): again with the grids read back, the CPU's tables exact.
    let fail = |e: GpuError| match e {
        GpuError::TooLarge(_) if resident => Attempt::Again,
        e => Attempt::Failed(RenderError::Backend(e.to_string())),
    };
    if crate::ratio::supported(&filter) {
        // The loop, the blur and the ratio estimator in one submission.
        let (shaded, timings) =
            chain::shade(ctx, inputs, &tables, held, &filter, shown).map_err(fail)?;
        return Ok(match shaded {
            Shaded::Read(result, overdraw) => {
                let out = frame.finish_shadowed(inputs, result, overdraw, timings);
                (out, None)
            }
            Shaded::Shown(displayed) => (frame.finish_shown(timings), Some(displayed)),
        });
    }
    let shaded = lighting_loop(ctx, inputs, &tables, held).map_err(fail)?;
    let out = frame.finish_with(&planes_on_cpu(inputs)?, shaded, memory, Some(gpu_atrous));
    Ok((out, None))
}

/// The error of a frame prepared without the loop's tables.
fn missing_tables() -> RenderError {
    RenderError::Backend("lgh on the GPU: the hierarchies' tables are missing".into())
}

/// The ratio estimator's a-trous filter on the GPU ([`crate::atrous`]); false (the CPU's
/// filter then runs) if the GPU fails.
fn gpu_atrous(
    s: &mut [Vec3],
    u: &mut [Vec3],
    a: Option<&[Vec3]>,
    g: &GBuffer,
    params: &AtrousParams,
) -> bool {
    GpuContext::shared()
        .and_then(|ctx| crate::atrous::filter_ratio_pair(ctx, s, u, a, g, params))
        .is_ok()
}

/// Refuses the settings whose shadow estimate the GPU loop does not run yet (it runs the
/// default: the unbiased estimate, representative targets drawn at the ray, stratified
/// selection).
///
/// # Errors
/// The first setting it does not run, named by its flag.
pub fn supported(s: &LghSettings) -> Result<(), RenderError> {
    let refuse = |what: &str| {
        Err(RenderError::Backend(format!(
            "lgh on the GPU runs the default shadow estimate only; {what} needs --device cpu"
        )))
    };
    if s.estimator != Estimator::Unbiased {
        return refuse("--estimator paper");
    }
    if s.shadow_target != ShadowTarget::Representative {
        return refuse("--shadow-target centroid");
    }
    if s.jitter != JitterAt::Ray {
        return refuse("--jitter-at candidate");
    }
    if !s.selection.is_stratified() {
        return refuse("--selection streaming");
    }
    Ok(())
}

/// The WGSL source of the kernel (with the BVH traversal).
#[must_use]
pub fn source() -> String {
    crate::kernel(&[
        include_str!("../shaders/shaded_light.wgsl"),
        include_str!("../shaders/lgh.wgsl"),
        include_str!("../shaders/bvh.wgsl"),
    ])
}

/// What the GPU holds of a frame before its loop: the tile lists, where it binned them,
/// and of each hierarchy, where it built it, the VPLs and representatives
/// ([`crate::grid::GpuGridBuilder::take_held`]).
pub(super) struct OnGpu<'c> {
    pub bins: Option<GpuBins<'c>>,
    pub hierarchies: Vec<Option<crate::grid::Held<'c>>>,
    /// The shaded lights' table, where the GPU made it ([`lights::record`]).
    pub lights: Option<Lease<'c>>,
    /// The masks of the pixels that fill their cut recombination windows, where they do
    /// (and the lists were binned on the GPU with their guests).
    pub fill: Option<Fill<'c>>,
    /// Submissions before the loop's, by name, with their wall times in milliseconds.
    pub before: Vec<(&'static str, f64)>,
}

/// The lighting loop recorded into a batch, with the buffers it reads and writes.
pub(super) struct Loop<'c> {
    pub batch: Batch<'c>,
    /// Per pixel: A (w: overdraw), S (w: rays), U.
    pub out: Lease<'c>,
    /// The filling of cut recombination windows, its guests recorded after the loop.
    pub fill: Option<Fill<'c>>,
    pub gbuffer: Arc<GpuGBuffer>,
    /// When the frame's GPU work began, and the milliseconds spent packing and uploading.
    pub start: Instant,
    pub upload_ms: f64,
    /// The submissions before the loop's (the shaded lights' table, the tile binning's
    /// counts, [`GpuBins::counts_ms`]), by name, with their wall times in milliseconds.
    pub before: Vec<(&'static str, f64)>,
}

/// Packs and uploads the loop's inputs `tables` and records the loop (timed "lighting")
/// after the passes of the GPU's tile bins (the CPU's bins in `tables` without them), with
/// the hierarchies' VPLs where the GPU holds them (`held`).
pub(super) fn record_loop<'c>(
    ctx: &'c GpuContext,
    inputs: &MethodInputs,
    tables: &LghTables,
    held: OnGpu<'c>,
) -> Result<Loop<'c>, GpuError> {
    let OnGpu {
        bins,
        hierarchies,
        lights,
        mut fill,
        mut before,
    } = held;
    let start = Instant::now();
    let g = inputs.gbuffer;
    let n = g.len();
    let scene = ctx.scene(inputs.world)?;
    let packed = Tables::new(tables, lights.is_none())?;
    let (mut batch, lists, layout, tiles) = match (bins, &tables.bins) {
        (Some(b), _) => {
            // The first submission on the wall clock; the shares of the shaded lights' table
            // and the fill's masks from the GPU's timestamps, where it has them.
            before.push(("tile_counts", b.counts_ms));
            let shares = ["light_table", "fill_masks"];
            before.extend(b.first.iter().filter(|(name, _)| shares.contains(name)));
            (b.batch, b.lists, b.layout, Some(b.tiles))
        }
        (None, Some(flat)) => (
            Batch::new(ctx),
            ctx.upload_parts("light lists", &packed.list_parts(flat))?,
            Tables::list_layout(flat),
            None,
        ),
        (None, None) => {
            return Err(GpuError::Failed(
                "lgh on the GPU: the lights are not binned".into(),
            ));
        }
    };
    let params = Params::new(inputs, tables, &packed, layout)?;
    let params = batch.uniform(&params)?;
    let gbuffer = ctx.gbuffer(g)?;
    let words = packed.words(ctx, &mut batch, tables)?;
    lookups::record(ctx, &mut batch, tables, &packed, &hierarchies, &words)?;
    let (slots, reps) = held::join(ctx, &mut batch, tables, hierarchies)?;
    let lights = match lights {
        Some(table) => table,
        None => ctx.upload("lights", &packed.lights)?,
    };
    let buffers = vec![lights, lists, words, reps, slots];
    // Every pixel's three words are written by the kernel: no clearing.
    let out = ctx.output("A, S, U", 48 * n as u64)?;
    let pipeline = ctx.pipeline("lgh", source);
    let mut resources = scene.bindings(params.as_entire_binding(), &gbuffer);
    resources.extend(buffers.iter().map(Lease::binding));
    resources.push(out.binding());
    let bind = ctx.bind_group(&pipeline, resources);
    batch.dispatch("lighting", &pipeline, &bind, n)?;
    // The guests of cut windows, from the lists binned with them (on the GPU).
    match (&mut fill, tiles) {
        (Some(f), Some(tiles)) => {
            let lists = crate::fill::Lists {
                lights: &buffers[0],
                lists: &buffers[1],
                list_lights: layout.lights,
                tiles,
            };
            f.record_guests(ctx, &mut batch, &gbuffer, &lists, tables.eps2, &out)?;
        }
        _ => fill = None,
    }
    for lease in buffers {
        batch.keep(lease);
    }
    Ok(Loop {
        batch,
        out,
        fill,
        gbuffer,
        start,
        upload_ms: start.elapsed().as_secs_f64() * 1e3,
        before,
    })
}

/// The GPU's pass times as the frame's timings, with "gpu_transfer" the rest of the wall
/// time since `start` less `cpu_ms` (CPU work timed apart) and "gpu_upload" its part before
/// the submission (`upload_ms`: packing and writing the tables); without timestamps,
/// "lighting" stands for all of the GPU's work. The submissions `before` the loop's (wall
/// times) come first.
pub(super) fn gpu_timings(
    gpu: &PassTimes,
    start: Instant,
    upload_ms: f64,
    cpu_ms: f64,
    before: &[(&'static str, f64)],
) -> Timings {
    let mut t = Timings::default();
    for &(name, ms) in before {
        t.push(name, ms);
    }
    let wall = start.elapsed().as_secs_f64() * 1e3 - cpu_ms;
    if gpu.is_empty() {
        t.push("lighting", (wall - upload_ms).max(0.0));
        t.push("gpu_transfer", upload_ms);
        return t;
    }
    for &(name, ms) in gpu {
        t.push(name, ms);
        if name == "lighting" {
            // The kernel alone ("lighting" gets the CPU's preparation of the lights added).
            t.push("lighting_kernel", ms);
        }
    }
    let gpu_ms: f64 = gpu.iter().map(|(_, ms)| ms).sum();
    t.push("gpu_transfer", (wall - gpu_ms).max(0.0));
    // Of which the packing and upload of the tables before the submission.
    t.push("gpu_upload", upload_ms);
    t
}

/// The lighting loop of the frame whose inputs are `tables`, on the GPU, read back for the
/// CPU's blur and ratio estimator: A, the overdraw, S and U of every pixel, with the
/// timings of [`gpu_timings`].
fn lighting_loop<'c>(
    ctx: &'c GpuContext,
    inputs: &MethodInputs,
    tables: &LghTables,
    held: OnGpu<'c>,
) -> Result<LoopResult, GpuError> {
    let n = inputs.gbuffer.len();
    let Loop {
        mut batch,
        out,
        start,
        upload_ms,
        before,
        ..
    } = record_loop(ctx, inputs, tables, held)?;
    batch.read(out.buffer(), out.bytes())?;
    let (reads, gpu) = batch.finish()?;
    let result: &[Vec4] = reads.first().map_or(&[], |r| bytemuck::cast_slice(r));
    let result = &result[..(3 * n).min(result.len())];
    let k = tables.k as usize;
    let plane = |c: usize| -> Vec<Vec3> {
        if k == 0 && c > 0 {
            return Vec::new();
        }
        result.par_chunks(3).map(|p| p[c].truncate()).collect()
    };
    Ok(LoopResult {
        a: plane(0),
        overdraw: result.par_chunks(3).map(|p| p[0].w as u32).collect(),
        estimates: ShadowEstimates {
            k,
            s: plane(1),
            u: plane(2),
            rays: result.par_chunks(3).map(|p| p[1].w as u64).sum(),
        },
        // This frame's blur runs on the CPU (wider than the GPU's), which takes no guests
        // from the GPU: its cut recombination windows are not filled.
        filled: None,
        timings: gpu_timings(&gpu, start, upload_ms, 0.0, &before),
    })
}

#[cfg(test)]
mod tests;
