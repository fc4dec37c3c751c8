//! One hierarchy build on the GPU: its passes recorded and submitted, and what comes back
//! (the grid, or where it stays on the GPU its level ranges) unpacked (the module docs of
//! [`super`] list the passes).

use std::time::Instant;

use glam::Vec3;
use lgh_core::lighting_grid::{
    self, BuildTimings, GridBuilder, GridGeometry, GridShape, InputLights, LevelCount, MAX_LEVELS,
};

use super::transfer::{unpack, upload_lights};
use super::{
    ACC_WORDS, GridParams, GridState, Held, MAX_INVOCATIONS, RECORD_WORDS, SUM_FLOATS, draw, marks,
    number, pipeline,
};
use crate::batch::{Batch, PassTimes, Words, add_passes};
use crate::context::{GpuContext, GpuError};
use crate::pool::Lease;

/// What a build is asked for.
#[derive(Clone, Copy)]
pub(super) struct Request {
    pub(super) levels: LevelCount,
    /// The box the grid is fitted to.
    pub(super) bounds: (Vec3, Vec3),
    /// The seed of the representatives' draw, if they are to be drawn.
    pub(super) seed: Option<u64>,
    /// Whether drawn representatives and the records stay on the GPU (not read back).
    pub(super) keep_slots: bool,
    /// Whether the grid is not read back (its level ranges are).
    pub(super) keep_grid: bool,
}

/// The lights of one build: on the CPU, and the same on the GPU if they are there already
/// (`resident`); or only there (`lights` `None`: the frame's VPLs, not read back).
pub(super) struct Run<'a, 'c> {
    pub(super) lights: Option<&'a InputLights<'a>>,
    pub(super) resident: Option<Lease<'c>>,
    /// How many lights.
    pub(super) count: usize,
    /// Whether they have normals.
    pub(super) normals: bool,
    pub(super) request: &'a Request,
}

impl<'a, 'c> Run<'a, 'c> {
    /// The build of `count` lights the GPU holds already (`lights`, with normals: the
    /// frame's VPLs, not read back).
    pub(super) fn held(lights: Lease<'c>, count: usize, request: &'a Request) -> Self {
        Self {
            lights: None,
            resident: Some(lights),
            count,
            normals: true,
            request,
        }
    }
}

/// Builds the hierarchy of `lights` on the GPU into `state` (its grid, and the S_1
/// representatives where asked), with its timings in `t` and the GPU's pass times in
/// `passes`; returns what the GPU holds of it: the lights, and the representatives where
/// they are kept there. Two waits: the marks' counts, then the grid ([`record_marks`],
/// [`Marking::marked`], [`Marked::record`], [`Building::built`]).
pub(super) fn build_on<'c>(
    ctx: &'c GpuContext,
    run: Run<'_, 'c>,
    state: &mut GridState,
    t: &mut BuildTimings,
    passes: &mut PassTimes,
) -> Result<Held<'c>, GpuError> {
    state.kept_shape = None;
    state.drawn = false;
    let mut batch = Batch::new(ctx);
    let marking = record_marks(ctx, &mut batch, run, t)?;
    let (reads, gpu) = batch.finish()?;
    add_passes(passes, gpu);
    let marked = marking.marked(ctx, &reads, passes, t)?;
    let mut batch = Batch::new(ctx);
    let building = marked.record(ctx, &mut batch)?;
    let (reads, gpu) = batch.finish()?;
    add_passes(passes, gpu);
    Ok(building.built(&reads, Some(state), t))
}

/// A build whose first step is recorded ([`record_marks`]).
pub(super) struct Marking<'c> {
    up: Lease<'c>,
    n: usize,
    normals: bool,
    request: Request,
    base: GridParams,
    pending: marks::Pending<'c>,
    start: Instant,
}

/// Step 1, recorded into `batch`: the lights up (where they are not on the GPU already),
/// the marks, their numbering and the counts. The level rule's walk usually stays within
/// two levels of its guess: those are marked first, and all ten only if the walk reaches
/// the last marked ([`Marking::marked`]).
///
/// # Errors
/// The lights could not be uploaded, or a buffer leased.
pub(super) fn record_marks<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    run: Run<'_, 'c>,
    t: &mut BuildTimings,
) -> Result<Marking<'c>, GpuError> {
    let Run {
        lights,
        resident,
        count: n,
        normals,
        request,
    } = run;
    let (lo, hi) = request.bounds;
    let top = GridGeometry::new(lo, hi, MAX_LEVELS);
    let degenerate = n < 2 || (hi - lo).max_element() <= 0.0;
    let first_marks = match request.levels {
        LevelCount::Fixed(l) => l.clamp(1, MAX_LEVELS),
        LevelCount::Auto if degenerate => 1,
        LevelCount::Auto => (lighting_grid::level_guess(n) + 2).min(MAX_LEVELS),
    };
    let base = GridParams {
        origin: top.origin.to_array(),
        h_top: top.h_top,
        ..GridParams::default()
    };
    // (No upload where the frame's VPLs are on the GPU already: no `gpu_upload` time.)
    let up = match (resident, lights) {
        (Some(lease), _) => lease,
        (None, Some(lights)) => {
            let start = Instant::now();
            let up = upload_lights(ctx, lights)?;
            t.push("gpu_upload", start.elapsed().as_secs_f64() * 1e3);
            up
        }
        (None, None) => return Err(GpuError::Failed("the build's lights are missing".into())),
    };
    let start = Instant::now();
    let pending = marks::record(ctx, batch, &up, &base, n, first_marks)?;
    Ok(Marking {
        up,
        n,
        normals,
        request: *request,
        base,
        pending,
        start,
    })
}

/// A build whose marks are counted ([`Marking::marked`]): step 2 can be sized.
pub(super) struct Marked<'c> {
    up: Lease<'c>,
    n: usize,
    normals: bool,
    request: Request,
    base: GridParams,
    marks: marks::Marks<'c>,
    l_max: u32,
}

impl<'c> Marking<'c> {
    /// The marks counted, from the read-backs `reads` of the batch step 1 was recorded in,
    /// and l_max by the level rule (marking all ten resolutions, in a batch of its own, if
    /// the walk reached the last marked).
    ///
    /// # Errors
    /// The GPU failed.
    pub(super) fn marked(
        self,
        ctx: &'c GpuContext,
        reads: &[Vec<Words>],
        passes: &mut PassTimes,
        t: &mut BuildTimings,
    ) -> Result<Marked<'c>, GpuError> {
        let Self {
            up,
            n,
            normals,
            request,
            base,
            pending,
            start,
        } = self;
        let (lo, hi) = request.bounds;
        let mut m = pending.finish(reads);
        let l_max = match request.levels {
            LevelCount::Fixed(l) => l.clamp(1, MAX_LEVELS),
            LevelCount::Auto => {
                // A level not marked counts as not fitting (n: 2n < n is false).
                let rule = |m: &marks::Marks<'_>| {
                    lighting_grid::level_rule(n, lo, hi, |l| m.count(l - 1).unwrap_or(n))
                };
                let mut l = rule(&m);
                if l == m.resolutions() && l < MAX_LEVELS {
                    m = marks::mark(ctx, &up, &base, n, MAX_LEVELS, passes)?;
                    l = rule(&m);
                }
                l
            }
        };
        t.push("level_count", start.elapsed().as_secs_f64() * 1e3);
        Ok(Marked {
            up,
            n,
            normals,
            request,
            base,
            marks: m,
            l_max,
        })
    }
}

/// A build whose step 2 is recorded ([`Marked::record`]).
pub(super) struct Building<'c> {
    up: Lease<'c>,
    normals: bool,
    request: Request,
    l_max: u32,
    counts: Vec<usize>,
    level_records: Vec<u32>,
    records: Lease<'c>,
    drawn: Option<draw::Drawn<'c>>,
    numbered: Option<number::Numbered<'c>>,
    /// The batch's read-back of the grid (or its level ranges), then those of the draw.
    read: usize,
    start: Instant,
}

impl<'c> Marked<'c> {
    /// Step 2, recorded into `batch`: S_1's sums, the coarser levels, the grid lights, the
    /// representatives where asked, the records numbered where kept, and the read-backs.
    ///
    /// # Errors
    /// A buffer could not be leased.
    pub(super) fn record(
        self,
        ctx: &'c GpuContext,
        batch: &mut Batch<'c>,
    ) -> Result<Building<'c>, GpuError> {
        let Self {
            up,
            n,
            normals,
            request,
            base,
            marks: m,
            l_max,
        } = self;
        let Request {
            seed,
            keep_slots,
            keep_grid,
            ..
        } = request;
        let start = Instant::now();
        let imax = m.imax;
        let count_at = |k: u32| m.count(k).unwrap_or(0);
        let marks::Marks {
            word_start,
            bits,
            prefix,
            starts,
            ..
        } = &m;
        let used = l_max as usize;
        let mut vert_start = vec![0u32; used + 1];
        for k in 0..used {
            vert_start[k + 1] = vert_start[k] + count_at(k as u32) as u32;
        }
        // Records level by level, S_1 (the finest resolution in use) first.
        let mut out_start = vec![0u32; used];
        let mut at = 0u32;
        for k in (0..used).rev() {
            out_start[k] = at;
            at += count_at(k as u32) as u32;
        }
        let vertices = vert_start[used] as usize;
        let s1 = count_at(l_max - 1);
        let mut layout = vert_start.clone();
        layout.extend_from_slice(&out_start);
        let layout_buf = ctx.upload("grid layout", &layout)?;
        let keys = ctx.output("grid keys", 4 * vertices as u64)?;
        let acc = ctx.output("grid fixed sums", 4 * ACC_WORDS * s1 as u64)?;
        let sums = ctx.output("grid sums", 4 * SUM_FLOATS * vertices as u64)?;
        let records = ctx.output("grid lights", 4 * (RECORD_WORDS * vertices) as u64)?;
        let base = GridParams {
            count: l_max,
            imax,
            inv_imax: if imax > 0.0 { 1.0 / imax } else { 0.0 },
            ..base
        };
        batch.clear_lease(&acc);
        let dispatch = |batch: &mut Batch<'_>,
                        name: &'static str,
                        kernel: &'static str,
                        p: GridParams,
                        buffers: Vec<wgpu::BindingResource<'_>>| {
            record(ctx, batch, name, kernel, &p, buffers)
        };
        dispatch(
            batch,
            "grid_list",
            "grid list",
            GridParams {
                n: starts[used],
                ..base
            },
            vec![
                word_start.binding(),
                bits.binding(),
                prefix.binding(),
                keys.binding(),
            ],
        )?;
        let k1 = l_max - 1;
        dispatch(
            batch,
            "grid_splat",
            "grid splat",
            GridParams {
                n: n as u32,
                k: k1,
                word0: starts[k1 as usize],
                vert0: vert_start[k1 as usize],
                ..base
            },
            vec![
                up.binding(),
                bits.binding(),
                prefix.binding(),
                acc.binding(),
            ],
        )?;
        dispatch(
            batch,
            "grid_s1",
            "grid s1 sums",
            GridParams {
                n: s1 as u32,
                vert0: vert_start[k1 as usize],
                ..base
            },
            vec![acc.binding(), sums.binding()],
        )?;
        for k in (0..k1).rev() {
            dispatch(
                batch,
                "grid_restrict",
                "grid restrict",
                GridParams {
                    n: count_at(k) as u32,
                    k,
                    fine_word0: starts[k as usize + 1],
                    vert0: vert_start[k as usize],
                    ..base
                },
                vec![
                    keys.binding(),
                    bits.binding(),
                    prefix.binding(),
                    sums.binding(),
                ],
            )?;
        }
        dispatch(
            batch,
            "grid_emit",
            "grid emit",
            GridParams {
                n: vertices as u32,
                ..base
            },
            vec![
                layout_buf.binding(),
                keys.binding(),
                sums.binding(),
                records.binding(),
            ],
        )?;
        let drawn = match seed {
            Some(seed) => Some(draw::record_draw(
                ctx,
                batch,
                &draw::Inputs {
                    base: GridParams {
                        k: k1,
                        vert0: vert_start[k1 as usize],
                        seed_lo: seed as u32,
                        seed_hi: (seed >> 32) as u32,
                        ..base
                    },
                    lights: &up,
                    n,
                    s1,
                    keys: &keys,
                    sums: &sums,
                },
            )?),
            None => None,
        };
        let counts: Vec<usize> = (1..=l_max).map(|l| count_at(l_max - l)).collect();
        let level_records: Vec<u32> = counts.iter().map(|&c| c as u32).collect();
        let numbered = match vertices {
            0 => None,
            v if keep_slots => Some(number::number(ctx, batch, &records, v as u32)?),
            _ => None,
        };
        let read = batch.reads();
        match &numbered {
            Some(numbered) if keep_grid => {
                let starts = number::level_starts(ctx, batch, numbered, &level_records)?;
                batch.read(starts.buffer(), starts.bytes())?;
                batch.keep(starts);
            }
            _ if keep_grid => {
                // No records: every level is empty.
                let zeros =
                    ctx.upload("grid level starts", &vec![0u32; level_records.len() + 1])?;
                batch.read(zeros.buffer(), zeros.bytes())?;
                batch.keep(zeros);
            }
            _ => batch.read(records.buffer(), records.bytes())?,
        }
        if let Some(d) = &drawn {
            if !keep_slots {
                batch.read(d.slots.buffer(), d.slots.bytes())?;
            }
            batch.read(d.flag.buffer(), d.flag.bytes())?;
        }
        // The marks' buffers are read by the passes recorded: kept until they have run.
        let marks::Marks {
            word_start,
            bits,
            prefix,
            ..
        } = m;
        for lease in [word_start, bits, prefix, layout_buf, keys, acc, sums] {
            batch.keep(lease);
        }
        Ok(Building {
            up,
            normals,
            request,
            l_max,
            counts,
            level_records,
            records,
            drawn,
            numbered,
            read,
            start,
        })
    }
}

impl<'c> Building<'c> {
    /// The build finished from the read-backs `reads` of the batch step 2 was recorded in:
    /// what the GPU holds of it. The grid goes into `state` (read back and unpacked, or its
    /// level ranges where it stays on the GPU); without a state (builds made together,
    /// which keep their grids on the GPU) the level ranges are in [`Held::shape`].
    pub(super) fn built(
        self,
        reads: &[Vec<Words>],
        state: Option<&mut GridState>,
        t: &mut BuildTimings,
    ) -> Held<'c> {
        let Self {
            up,
            normals,
            request,
            l_max,
            counts,
            level_records,
            records,
            drawn,
            numbered,
            read,
            start,
        } = self;
        let Request {
            bounds: (lo, hi),
            keep_slots,
            keep_grid,
            ..
        } = request;
        t.push("gpu_build", start.elapsed().as_secs_f64() * 1e3);
        let start = Instant::now();
        let words: &[u32] = reads.get(read).map_or(&[], |r| bytemuck::cast_slice(r));
        let geometry = GridGeometry::new(lo, hi, l_max);
        let mut shape = None;
        let mut state = state;
        if keep_grid {
            let mut level_start = vec![0u32];
            level_start.extend(words.iter().skip(1).take(level_records.len()));
            shape = Some(GridShape {
                geometry,
                level_start,
            });
        } else if let Some(state) = state.as_deref_mut() {
            let grid = state
                .grid
                .get_or_insert_with(|| GridBuilder::default().into_grid());
            unpack(geometry, &counts, words, normals, grid);
        }
        let mut slots = None;
        // The draw's read-backs follow the grid's: the flag, after the slots where these
        // come back (other builds' may follow in the same batch).
        let draws = if keep_slots { 1 } else { 2 };
        let draw_reads = reads.get(read + 1..read + 1 + draws).unwrap_or(&[]);
        match drawn {
            Some(d) if keep_slots && draw_reads.len() == 1 => {
                slots = draw::drew(&draw_reads[0]).then_some(d.slots);
            }
            Some(_) if draw_reads.len() == 2 => {
                if let Some(state) = state.as_deref_mut() {
                    let kept = state.grid.as_ref().map_or(0, |g| g.level_range(1).len());
                    state.drawn =
                        draw::unpack_draw(&draw_reads[0], &draw_reads[1], kept, &mut state.reps);
                }
            }
            _ => {}
        }
        if let Some(state) = state {
            state.kept_shape = shape.take();
        }
        t.push("unpack", start.elapsed().as_secs_f64() * 1e3);
        Held {
            lights: up,
            slots,
            records: keep_slots.then_some(records),
            level_records: if keep_slots {
                level_records
            } else {
                Vec::new()
            },
            numbered,
            shape,
        }
    }
}

/// Records a dispatch of kernel `kernel` (of [`sources`]) under `name`, one invocation per
/// item of `p.n` up to what one dispatch holds (the kernels loop with its stride), with
/// `buffers` at bindings 1, 2, ... after the parameters.
pub(super) fn record(
    ctx: &GpuContext,
    batch: &mut Batch<'_>,
    name: &'static str,
    kernel: &'static str,
    p: &GridParams,
    buffers: Vec<wgpu::BindingResource<'_>>,
) -> Result<(), GpuError> {
    let pipe = pipeline(ctx, kernel);
    let uniform = batch.uniform(p)?;
    let mut resources = vec![uniform.as_entire_binding()];
    resources.extend(buffers);
    let bind = ctx.bind_group(&pipe, resources);
    batch.dispatch(name, &pipe, &bind, (p.n as usize).min(MAX_INVOCATIONS))
}
