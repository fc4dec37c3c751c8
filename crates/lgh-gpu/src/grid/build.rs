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
use crate::batch::{Batch, PassTimes};
use crate::context::{GpuContext, GpuError};
use crate::pool::Lease;

/// What a build is asked for.
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

/// Builds the hierarchy of `lights` on the GPU into `state` (its grid, and the S_1
/// representatives where asked), with its timings in `t` and the GPU's pass times in
/// `passes`; returns what the GPU holds of it: the lights, and the representatives where
/// they are kept there.
pub(super) fn build_on<'c>(
    ctx: &'c GpuContext,
    run: Run<'_, 'c>,
    state: &mut GridState,
    t: &mut BuildTimings,
    passes: &mut PassTimes,
) -> Result<Held<'c>, GpuError> {
    let Run {
        lights,
        resident,
        count: n,
        normals,
        request,
    } = run;
    let Request {
        levels,
        bounds: (lo, hi),
        seed,
        keep_slots,
        keep_grid,
    } = *request;
    state.kept_shape = None;
    state.drawn = false;
    let top = GridGeometry::new(lo, hi, MAX_LEVELS);
    let degenerate = n < 2 || (hi - lo).max_element() <= 0.0;
    let first_marks = match levels {
        LevelCount::Fixed(l) => l.clamp(1, MAX_LEVELS),
        LevelCount::Auto if degenerate => 1,
        LevelCount::Auto => (lighting_grid::level_guess(n) + 2).min(MAX_LEVELS),
    };
    let base = GridParams {
        origin: top.origin.to_array(),
        h_top: top.h_top,
        ..GridParams::default()
    };

    // Step 1: the lights up, the marks, their numbering and the counts. The level rule's
    // walk usually stays within two levels of its guess: those are marked first, and all
    // ten only if the walk reaches the last marked.
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
    let mut m = marks::mark(ctx, &up, &base, n, first_marks, passes)?;
    let l_max = match levels {
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
    let imax = m.imax;
    let count_at = |k: u32| m.count(k).unwrap_or(0);
    let marks::Marks {
        word_start,
        bits,
        prefix,
        starts,
        ..
    } = &m;
    t.push("level_count", start.elapsed().as_secs_f64() * 1e3);

    // Step 2: S_1's sums, the coarser levels, the grid lights.
    let start = Instant::now();
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
    let mut batch = Batch::new(ctx);
    batch.clear_lease(&acc);
    let dispatch = |batch: &mut Batch<'_>,
                    name: &'static str,
                    kernel: &'static str,
                    p: GridParams,
                    buffers: Vec<wgpu::BindingResource<'_>>| {
        record(ctx, batch, name, kernel, &p, buffers)
    };
    dispatch(
        &mut batch,
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
        &mut batch,
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
        &mut batch,
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
            &mut batch,
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
        &mut batch,
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
            &mut batch,
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
        v if keep_slots => Some(number::number(ctx, &mut batch, &records, v as u32)?),
        _ => None,
    };
    match &numbered {
        Some(numbered) if keep_grid => {
            let starts = number::level_starts(ctx, &mut batch, numbered, &level_records)?;
            batch.read(starts.buffer(), starts.bytes())?;
            batch.keep(starts);
        }
        _ if keep_grid => {
            // No records: every level is empty.
            let zeros = ctx.upload("grid level starts", &vec![0u32; level_records.len() + 1])?;
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
    let (reads, gpu) = batch.finish()?;
    for (name, ms) in gpu {
        match passes.iter_mut().find(|(n, _)| *n == name) {
            Some((_, sum)) => *sum += ms,
            None => passes.push((name, ms)),
        }
    }
    t.push("gpu_build", start.elapsed().as_secs_f64() * 1e3);
    let start = Instant::now();
    let words: &[u32] = reads.first().map_or(&[], |r| bytemuck::cast_slice(r));
    let geometry = GridGeometry::new(lo, hi, l_max);
    if keep_grid {
        let mut level_start = vec![0u32];
        level_start.extend(words.iter().skip(1).take(level_records.len()));
        state.kept_shape = Some(GridShape {
            geometry,
            level_start,
        });
    } else {
        let grid = state
            .grid
            .get_or_insert_with(|| GridBuilder::default().into_grid());
        unpack(geometry, &counts, words, normals, grid);
    }
    let mut slots = None;
    match drawn {
        Some(d) if keep_slots && reads.len() == 2 => {
            slots = draw::drew(&reads[1]).then_some(d.slots);
        }
        Some(_) if reads.len() == 3 => {
            let kept = state.grid.as_ref().map_or(0, |g| g.level_range(1).len());
            state.drawn = draw::unpack_draw(&reads[1], &reads[2], kept, &mut state.reps);
        }
        _ => {}
    }
    t.push("unpack", start.elapsed().as_secs_f64() * 1e3);
    Ok(Held {
        lights: up,
        slots,
        records: keep_slots.then_some(records),
        level_records: if keep_slots {
            level_records
        } else {
            Vec::new()
        },
        numbered,
    })
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
    let uniform = ctx.uniform("grid params", p);
    let mut resources = vec![uniform.as_entire_binding()];
    resources.extend(buffers);
    let bind = ctx.bind_group(&pipe, resources);
    batch.dispatch(name, &pipe, &bind, (p.n as usize).min(MAX_INVOCATIONS))
}
