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
//! ([`crate::ratio`]), and the CPU composites ([`LghFrame::finish_shadowed`]). Where a step
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
use lgh_render::methods::lgh::settings::Selection;
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
use crate::gbuffer::GpuGBuffer;
use crate::pool::Lease;

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
            match frame(ctx, inputs, memory, shadowed, true) {
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
        match frame(ctx, inputs, memory, shadowed, false) {
            Ok(output) => Ok(output),
            Err(Attempt::Failed(e)) => Err(e),
            Err(Attempt::Again) => Err(RenderError::Backend(
                "lgh on the GPU: the hierarchies' grids are not on the CPU".into(),
            )),
        }
    }
}

impl GpuLgh {
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
) -> Result<MethodOutput, Attempt> {
    let fail = |e: GpuError| RenderError::Backend(e.to_string());
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
        Prepared::Dark(output) => return Ok(output),
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
    // table, whose making may not have been submitted, packed on the CPU).
    let gbuffer = ctx.gbuffer(g).map_err(fail)?;
    let sp = frame.spheres();
    let bins = match crate::bins::record(ctx, first, g, inputs.camera, &gbuffer, &sp, spheres) {
        Ok(bins) => Some(bins),
        Err(GpuError::TooLarge(_)) if !frame.lights_on_cpu() => return Err(Attempt::Again),
        Err(GpuError::TooLarge(_)) => {
            frame.bin_on_cpu(inputs, memory);
            table = None;
            None
        }
        Err(e) => return Err(fail(e).into()),
    };
    let tables = frame.tables(g.width, g.height).ok_or_else(missing_tables)?;
    let filter = frame.ratio_filter(inputs);
    let held = OnGpu {
        bins,
        hierarchies,
        lights: table,
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
        let (shadowed, overdraw, timings) =
            chain::shade(ctx, inputs, &tables, held, &filter).map_err(fail)?;
        return Ok(frame.finish_shadowed(inputs, shadowed, overdraw, timings));
    }
    let shaded = lighting_loop(ctx, inputs, &tables, held).map_err(fail)?;
    Ok(frame.finish_with(inputs, shaded, memory, Some(gpu_atrous)))
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
    if s.selection != Selection::Stratified {
        return refuse("--selection streaming");
    }
    Ok(())
}

/// The WGSL source of the kernel (with the BVH traversal).
#[must_use]
pub fn source() -> String {
    crate::kernel(&[
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
    /// Submissions before the loop's, by name, with their wall times in milliseconds.
    pub before: Vec<(&'static str, f64)>,
}

/// The lighting loop recorded into a batch, with the buffers it reads and writes.
pub(super) struct Loop<'c> {
    pub batch: Batch<'c>,
    /// Per pixel: A (w: overdraw), S (w: rays), U.
    pub out: Lease<'c>,
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
        mut before,
    } = held;
    let start = Instant::now();
    let g = inputs.gbuffer;
    let n = g.len();
    let scene = ctx.scene(inputs.world)?;
    let packed = Tables::new(tables, lights.is_none())?;
    let (mut batch, lists, layout) = match (bins, &tables.bins) {
        (Some(b), _) => {
            // The first submission on the wall clock; the shaded lights' table's share of
            // it from the GPU's timestamps, where it has them.
            before.push(("tile_counts", b.counts_ms));
            before.extend(b.first.iter().filter(|(name, _)| *name == "light_table"));
            (b.batch, b.lists, b.layout)
        }
        (None, Some(flat)) => (
            Batch::new(ctx),
            ctx.upload_parts("light lists", &packed.list_parts(flat))?,
            Tables::list_layout(flat),
        ),
        (None, None) => {
            return Err(GpuError::Failed(
                "lgh on the GPU: the lights are not binned".into(),
            ));
        }
    };
    let params = Params::new(inputs, tables, &packed, layout)?;
    let params = ctx.uniform("lgh params", &params);
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
    let mut resources = scene.bindings(&params, &gbuffer);
    resources.extend(buffers.iter().map(Lease::binding));
    resources.push(out.binding());
    let bind = ctx.bind_group(&pipeline, resources);
    batch.dispatch("lighting", &pipeline, &bind, n)?;
    for lease in buffers {
        batch.keep(lease);
    }
    Ok(Loop {
        batch,
        out,
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
        timings: gpu_timings(&gpu, start, upload_ms, 0.0, &before),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GpuGridBuilder;
    use crate::lgh::testing::{FrameInputs, cornell, cornell_and_two_rooms};
    use lgh_render::RenderSettings;

    thread_local! {
        /// Makes this thread's GPU frames with grids kept on the GPU end in
        /// [`Attempt::Again`] once their hierarchies are built, as a step that cannot run
        /// on the GPU (lists past its binning, a table past its buffers) ends them.
        pub(super) static AGAIN: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }

    /// A frame whose VPLs stay on the GPU, never read back, is the frame of the same VPLs
    /// read back, pixel for pixel: at the viewer's settings (S_1 lowest, and S_0 too; and
    /// with one hierarchy per normal bin, the VPLs split on the GPU), and
    /// where the frame has to be made with its grids on the CPU after all (one level shown
    /// alone; a step that ends the frame on the GPU after its builds), from the kept
    /// light-path records or, where those are gone, traced again.
    #[test]
    #[cfg_attr(
        not(gpu_adapter),
        ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
    )]
    fn vpls_kept_on_the_gpu_give_the_frame_of_the_vpls_read_back() {
        let ctx = GpuContext::shared().expect("an adapter");
        let none = lgh_core::vpl::Vpls::default();
        let render = |inputs: &MethodInputs| {
            let mut memory = FrameMemory::default();
            let out = LGH_GPU.get().render(inputs, &mut memory).expect("frame");
            let stats = out.stats::<lgh_render::methods::lgh::LghStats>();
            (out.radiance.clone(), stats.expect("stats").grids_on_cpu)
        };
        for world in &cornell_and_two_rooms() {
            for (start_level, bins) in [(1, false), (0, false), (1, true)] {
                let mut s = RenderSettings {
                    width: 48,
                    height: 27,
                    vpls: 3000,
                    component: lgh_render::Component::Indirect,
                    ..RenderSettings::default()
                };
                s.lgh.normal_bins = bins;
                s.lgh.start_level = start_level;
                s.lgh.alpha = 1.5;
                s.tiling.interleave = Some(4);
                s.shadows.samples = Some(4);
                let made = FrameInputs::new(world, &s);
                let read = |s: &RenderSettings| {
                    let set = crate::vpls::method_vpls(world, s, (true, false))
                        .expect("gpu")
                        .expect("vpls");
                    assert!(set.kept == 0 && !set.vpls.is_empty());
                    let inputs = MethodInputs {
                        vpls: &set.vpls,
                        vpl_count: set.vpls.len(),
                        ..made.inputs(world, s)
                    };
                    (render(&inputs), set.vpls.len(), set.paths)
                };
                let kept = |s: &RenderSettings, records: bool| {
                    let set = crate::vpls::method_vpls(world, s, (true, true))
                        .expect("gpu")
                        .expect("vpls");
                    assert!(set.vpls.is_empty() && set.kept > 0);
                    assert_eq!(set.kept_bins.is_some(), s.lgh.normal_bins);
                    if !records {
                        crate::vpls::resident::clear(ctx);
                    }
                    let inputs = MethodInputs {
                        vpls: &none,
                        vpl_count: set.kept,
                        vpl_bins: set.kept_bins,
                        ..made.inputs(world, s)
                    };
                    (render(&inputs), set.kept, set.paths)
                };
                let (a, n, paths) = read(&s);
                let (b, kept_n, kept_paths) = kept(&s, true);
                assert_eq!((kept_n, kept_paths), (n, paths));
                assert!(a.0.iter().any(|p| p.max_element() > 0.0));
                assert!(
                    a.0 == b.0,
                    "start level {start_level}: kept VPLs, another image"
                );
                assert!(!b.1, "the grids stayed on the GPU");
                // Not read back: the light-path records are still kept.
                assert!(crate::vpls::resident::take_records(ctx, n).is_some());
                // Ended after its builds: made again with its grids and VPLs on the CPU.
                AGAIN.with(|a| a.set(true));
                let (again, _, _) = kept(&s, true);
                AGAIN.with(|a| a.set(false));
                assert!(
                    a.0 == again.0,
                    "start level {start_level}: made again, another image"
                );
                assert!(again.1, "made again with the grids on the CPU");
                // Made again with the grids on the CPU: the kept VPLs are read back.
                s.lgh.only_level = Some(2);
                let (a, _, _) = read(&s);
                for records in [true, false] {
                    let (b, _, _) = kept(&s, records);
                    assert!(a.0 == b.0, "one level, records {records}: another image");
                    assert!(b.1, "grids on the CPU");
                }
            }
        }
    }

    /// A frame prepared from grids kept on the GPU holds no shaded light on the CPU where
    /// every later step runs on the GPU (the unbiased estimate's shadow samples), and is
    /// refused where a step needs them on the CPU (no shadow samples: the CPU packs the
    /// lights; one level shown alone), which the GPU frame answers by building again with
    /// the grids read back.
    #[test]
    #[cfg_attr(
        not(gpu_adapter),
        ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
    )]
    fn grids_stay_on_the_gpu_only_for_frames_that_run_there() {
        let world = cornell();
        for (shadowed, only_level, resident) in [
            (true, None, true),
            (false, None, false),
            (true, Some(2), false),
        ] {
            let mut s = RenderSettings {
                width: 32,
                height: 18,
                vpls: 2000,
                ..RenderSettings::default()
            };
            s.lgh.only_level = only_level;
            let made = FrameInputs::new(&world, &s);
            let inputs = made.inputs(&world, &s);
            let ctx = GpuContext::shared().expect("an adapter");
            let mut builder = GpuGridBuilder::new(ctx);
            builder.keep_representatives(true);
            builder.keep_grid(true);
            let mut memory = FrameMemory::default();
            let prepared =
                LghFrame::prepare_with(&inputs, shadowed, &mut memory, true, Some(&mut builder));
            match prepared {
                Ok(Prepared::Frame(frame)) => {
                    assert!(resident, "{shadowed} {only_level:?}: prepared");
                    assert!(!frame.lights_on_cpu());
                    let t = frame.tables(s.width, s.height).expect("tables");
                    assert!(t.lights.is_empty() && t.light_count > 1000);
                    assert!(t.hierarchies.iter().all(|h| h.grid.lookups_on_device));
                }
                Err(e) => {
                    assert!(!resident, "{shadowed} {only_level:?}: {e}");
                    assert_eq!(e, GridError::KeptOnDevice);
                }
                Ok(Prepared::Dark(_)) => panic!("a dark frame"),
            }
        }
    }
}
