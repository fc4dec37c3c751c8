//! VPL generation by light tracing on the GPU (Keller 1997, "Instant Radiosity"; LGH 2019
//! section 4): lgh-render's `generate_vpls` with its Sobol path numbers
//! ([`lgh_render::passes::vpl_gen::PathNumbers::Sobol`]), one invocation per light path
//! (`shaders/vpl_paths.wgsl`: the emission choice of `shaders/emission.wgsl`, the numbers of
//! `shaders/sobol.wgsl`, closest hits and surfaces as the G-buffer's).
//!
//! The same VPL set as the CPU's: path k draws the CPU's numbers bit for bit, and the set
//! is the paths in order of k up to the first that brings the VPLs to the target. Paths go
//! in batches; each batch's counts are prefix-summed ([`crate::scan`]) and its kept paths'
//! VPLs written in order (`shaders/vpl_compact.wgsl`), so the result does not depend on
//! scheduling. The warps' `cos`, `sin` and `sqrt` are the GPU's, so a position may differ
//! from the CPU's in its last bits, and a path that grazes an edge may take another turn.

#[cfg(test)]
mod batching;
pub(crate) mod plan;
pub(crate) mod resident;
pub mod tables;

use glam::Vec4;
use lgh_core::vpl::Vpls;
use lgh_render::World;
use lgh_render::methods::lgh::NORMAL_BINS;
use lgh_render::passes::vpl_gen::{PathNumbers, VplSet, max_paths, path_seed};

use rayon::prelude::*;

use crate::batch::Batch;
use crate::context::{GpuContext, GpuError};
use crate::pool::Lease;

/// Bytes of a VPL on the GPU (three `vec4`s).
const VPL_BYTES: u64 = 48;

/// `Params` of `shaders/vpl_paths.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PathParams {
    centre: [f32; 3],
    radius: f32,
    first: u32,
    paths: u32,
    bounces: u32,
    lights: u32,
    ray_eps: f32,
    block0: u32,
    groups: u32,
    pad: u32,
    seeds: [[u32; 4]; tables::MAX_SEEDS / 4],
}

/// `Params` of `shaders/vpl_compact.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CompactParams {
    paths: u32,
    bounces: u32,
    done: u32,
    target: u32,
    first: u32,
    pad: [u32; 3],
}

/// `Params` of `shaders/vpl_grid.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GridInParams {
    capacity: u32,
    bins: u32,
    words: u32,
    pad: u32,
}

/// The WGSL sources of the light-path kernel, the compaction, the conversion to the
/// hierarchy build's layout and the split by normal bin.
#[must_use]
pub fn sources() -> [String; 4] {
    [
        crate::kernel(&[
            include_str!("../shaders/vpl_paths.wgsl"),
            include_str!("../shaders/emission.wgsl"),
            include_str!("../shaders/sobol.wgsl"),
            include_str!("../shaders/surface.wgsl"),
            include_str!("../shaders/bvh.wgsl"),
        ]),
        crate::kernel(&[include_str!("../shaders/vpl_compact.wgsl")]),
        crate::kernel(&[
            include_str!("../shaders/vpl_grid.wgsl"),
            include_str!("../shaders/normal_bin.wgsl"),
            include_str!("../shaders/recip.wgsl"),
        ]),
        crate::kernel(&[
            include_str!("../shaders/vpl_bins.wgsl"),
            include_str!("../shaders/normal_bin.wgsl"),
        ]),
    ]
}

/// lgh-render's `generate_vpls(world, target, bounces, seed, PathNumbers::Sobol)` on the
/// GPU: at least `target` VPLs (whole paths), fluxes divided by the number of paths.
///
/// # Errors
/// The scene or the VPLs do not fit the adapter's buffers, or the GPU failed.
pub fn generate_vpls(
    ctx: &GpuContext,
    world: &World,
    target: usize,
    bounces: u32,
    seed: u64,
) -> Result<VplSet, GpuError> {
    generate(ctx, world, (target, bounces, seed), Want::Cpu).map(|(set, _)| set)
}

/// Where a frame wants its VPLs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Want {
    /// Read back.
    Cpu,
    /// Read back, and also in the hierarchy build's layout on the GPU.
    CpuAndGrid,
    /// Only on the GPU in the build's layout, with their bounds
    /// ([`resident::keep_held`]); the set comes back empty, its [`VplSet::kept`] their
    /// number.
    Grid,
    /// As [`Want::Grid`], sorted by normal bin, each bin's number in
    /// [`VplSet::kept_bins`].
    GridBins,
}

/// [`generate_vpls`] for `(target, bounces, seed)`, with the VPLs where `want` says: with
/// [`Want::CpuAndGrid`] the VPLs in the build's layout are returned beside the set; with
/// [`Want::Grid`] they are kept ([`resident::keep_held`]) and none is read back.
///
/// The batches are planned by [`plan::next_batch`]; what follows the paths (the build's
/// layout, the bounds or the VPLs read back) goes into the submission of the batch
/// expected to be the last, so that a frame whose yield is known waits once.
fn generate<'c>(
    ctx: &'c GpuContext,
    world: &World,
    (target, bounces, seed): (usize, u32, u64),
    want: Want,
) -> Result<(VplSet, Option<Lease<'c>>), GpuError> {
    let Some(table) = tables::tables(world).filter(|_| target > 0 && bounces > 0) else {
        return Ok((VplSet::default(), None));
    };
    let too_large = || GpuError::TooLarge(format!("{target} VPLs"));
    let target32 = u32::try_from(target).map_err(|_| too_large())?;
    let scene = ctx.scene(world)?;
    let surfaces = scene.surfaces(ctx, world)?;
    let lights = ctx.upload("light tables", &table)?;
    let limit = ctx.limits.max_storage_buffer_binding_size;
    let b = u64::from(bounces);
    let groups = tables::groups(bounces);
    let max_batch = plan::MAX_BATCH
        .min(tables::max_batch_for_seeds(groups))
        .min(limit / (b * VPL_BYTES))
        .max(1);
    // The last path kept may leave up to `bounces` VPLs past the target.
    let capacity = target as u64 + b;
    if capacity * VPL_BYTES > limit {
        return Err(too_large());
    }
    let out = ctx.output("vpls", capacity * VPL_BYTES)?;
    let status = ctx.output("vpl status", 16)?;
    let [paths_src, compact_src, grid_src, bins_src] = sources();
    let kernels = Kernels {
        grid: &grid_src,
        bins: &bins_src,
    };
    let paths_kernel = ctx.pipeline("vpl paths", || paths_src);
    let compact_kernel = ctx.pipeline("vpl compact", || compact_src);
    let set_seed = path_seed(seed);
    let cap = max_paths(target);
    let key = (world.geometry_id(), world.lights.len(), bounces);
    let known = ctx.vpl_yields().get(key);
    let (mut paths, mut done) = (0u64, 0u64);
    // The last batch's read-backs, and what follows the paths if it was recorded there.
    let mut last = None;
    while paths < cap && done < target as u64 {
        let planned = plan::next_batch(
            (paths, done, target as u64 - done),
            known,
            bounces,
            (max_batch, cap - paths),
        );
        let n = planned.paths;
        let mut seeds = [[0u32; 4]; tables::MAX_SEEDS / 4];
        for (i, s) in tables::seeds(set_seed, paths, n, groups)
            .into_iter()
            .enumerate()
        {
            seeds[i / 4][i % 4] = s;
        }
        let mut batch = Batch::new(ctx);
        let params = batch.uniform(&PathParams {
            centre: world.centre.into(),
            radius: world.radius,
            first: paths as u32,
            paths: n as u32,
            bounces,
            lights: world.lights.len() as u32,
            ray_eps: world.ray_epsilon,
            block0: (paths / lgh_core::qmc::BLOCK) as u32,
            groups,
            pad: 0,
            seeds,
        })?;
        let compact = batch.uniform(&CompactParams {
            paths: n as u32,
            bounces,
            done: done as u32,
            target: target32,
            first: paths as u32,
            pad: [0; 3],
        })?;
        let slots = ctx.output("vpl slots", n * b * VPL_BYTES)?;
        let counts = ctx.output("vpl counts", 4 * n)?;
        let prefix = ctx.output("vpl prefix", 4 * n)?;
        let total = ctx.output("vpl total", 16)?;
        let mut resources = surfaces.bindings(params.as_entire_binding(), &scene);
        resources.extend([lights.binding(), slots.binding(), counts.binding()]);
        let bind = ctx.bind_group(&paths_kernel, resources);
        batch.dispatch("vpl paths", &paths_kernel, &bind, n as usize)?;
        crate::scan::record(ctx, &mut batch, &counts, &prefix, &total, n as usize, false)?;
        let bind = ctx.bind_group(
            &compact_kernel,
            vec![
                compact.as_entire_binding(),
                slots.binding(),
                counts.binding(),
                prefix.binding(),
                out.binding(),
                status.binding(),
            ],
        );
        batch.dispatch("vpl compact", &compact_kernel, &bind, n as usize)?;
        batch.read(status.buffer(), 16)?;
        let after = if planned.last {
            Some(record_after(
                ctx,
                &mut batch,
                (&out, &status, capacity),
                want,
                kernels,
            )?)
        } else {
            None
        };
        let (reads, _) = batch.finish()?;
        let words: &[u32] = reads.first().map_or(&[], |r| bytemuck::cast_slice(r));
        let [kept, count, ..] = *words else {
            return Err(GpuError::Failed(
                "the VPL count's read-back is missing".into(),
            ));
        };
        paths += u64::from(kept);
        done = u64::from(count);
        last = Some((reads, after));
    }
    let Some((reads, after)) = last else {
        return Ok((VplSet::default(), None));
    };
    ctx.vpl_yields().set(key, paths, done);
    // What follows the paths, where the last batch did not record it (the status it reads
    // is the last batch's).
    let (reads, after) = match after {
        Some(after) => (reads, after),
        None => {
            let mut batch = Batch::new(ctx);
            let after = record_after(ctx, &mut batch, (&out, &status, capacity), want, kernels)?;
            (batch.finish()?.0, after)
        }
    };
    let read = |i: Option<usize>| -> &[u32] {
        i.and_then(|i| reads.get(i))
            .map_or(&[], |r| bytemuck::cast_slice(r))
    };
    let scale = 1.0 / paths.max(1) as f32;
    let grid_in = after.grid.filter(|_| done > 0);
    if matches!(want, Want::Grid | Want::GridBins) {
        let Some(lights) = grid_in else {
            // No VPL.
            let set = VplSet {
                paths,
                ..VplSet::default()
            };
            return Ok((set, None));
        };
        let bins = want == Want::GridBins;
        let parts = held_parts(read(after.bounds), if bins { NORMAL_BINS } else { 1 });
        let kept_bins = bins.then(|| std::array::from_fn(|b| parts[b].count));
        let held = resident::Held::new(done as usize, parts, scale);
        resident::keep_held(ctx, lights, out, held);
        let set = VplSet {
            vpls: Vpls::default(),
            paths,
            kept: done as usize,
            kept_bins,
        };
        return Ok((set, None));
    }
    let vpls = unpack(bytemuck::cast_slice(read(after.vpls)), done as usize, scale);
    Ok((
        VplSet {
            vpls,
            paths,
            ..VplSet::default()
        },
        grid_in,
    ))
}

/// The WGSL sources of the kernels that follow the light paths ([`sources`]).
#[derive(Clone, Copy)]
struct Kernels<'a> {
    grid: &'a str,
    bins: &'a str,
}

/// What follows the light paths, recorded in a batch ([`record_after`]): the VPLs in the
/// build's layout, and which of the batch's read-backs hold their bounds or the VPLs.
struct After<'c> {
    grid: Option<Lease<'c>>,
    bounds: Option<usize>,
    vpls: Option<usize>,
}

/// Records into `batch` what a frame that wants its VPLs where `want` says does after the
/// light paths that wrote `out` and `status` (`capacity` VPLs at most): the conversion into
/// the build's layout (its bounds read back where the VPLs are not) and the VPLs' read-back.
/// The kernels read the number of VPLs and of paths from `status`, so that this can go
/// into the submission of the last batch of paths, before those numbers are known.
///
/// # Errors
/// A buffer could not be leased, or the VPLs exceed a dispatch or the scan.
fn record_after<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    (out, status, capacity): (&Lease<'c>, &Lease<'c>, u64),
    want: Want,
    kernels: Kernels<'_>,
) -> Result<After<'c>, GpuError> {
    let mut after = After {
        grid: None,
        bounds: None,
        vpls: None,
    };
    if want != Want::Cpu {
        let bins = (want == Want::GridBins).then_some(kernels.bins);
        let (lights, bounds) =
            to_grid_layout(ctx, batch, (out, status, capacity), (kernels.grid, bins))?;
        if want != Want::CpuAndGrid {
            after.bounds = Some(batch.reads());
            batch.read(bounds.buffer(), bounds.bytes())?;
        }
        batch.keep(bounds);
        after.grid = Some(lights);
    }
    if matches!(want, Want::Cpu | Want::CpuAndGrid) {
        after.vpls = Some(batch.reads());
        batch.read(out.buffer(), capacity * VPL_BYTES)?;
    }
    Ok(after)
}

/// Words per bin of `shaders/vpl_grid.wgsl`'s bounds: lo, hi (as order-preserving bits),
/// the first invalid index, the count.
const BIN_WORDS: usize = 8;

/// The bounds (lo, hi) of one bin's words of `shaders/vpl_grid.wgsl`'s bounds (as
/// order-preserving bits, then the first invalid index), or the index of the first invalid
/// VPL.
fn held_bounds(words: &[u32]) -> resident::Bounds {
    let float = |b: u32| {
        f32::from_bits(if b & 0x8000_0000 != 0 {
            b & 0x7fff_ffff
        } else {
            !b
        })
    };
    match *words {
        [a, b, c, d, e, f, bad, ..] if bad == u32::MAX => Ok((
            glam::Vec3::new(float(a), float(b), float(c)),
            glam::Vec3::new(float(d), float(e), float(f)),
        )),
        [_, _, _, _, _, _, bad, ..] => Err(bad as usize),
        _ => Err(0),
    }
}

/// The `bins` parts of `shaders/vpl_grid.wgsl`'s bounds: each bin's first VPL, number and
/// bounds (a missing word reads as an empty bin).
fn held_parts(words: &[u32], bins: usize) -> Vec<resident::Part> {
    let mut first = 0;
    (0..bins)
        .map(|b| {
            let w = words.get(BIN_WORDS * b..BIN_WORDS * (b + 1)).unwrap_or(&[]);
            let count = w.get(7).map_or(0, |&c| c as usize);
            let part = resident::Part {
                first,
                count,
                bounds: held_bounds(w),
            };
            first += count;
            part
        })
        .collect()
}

/// Records into `batch` the conversion of the light-path records in `records` (at most
/// `capacity`; their number and the flux scale, one over the paths, read from the paths'
/// `status`) into the hierarchy build's layout (`shaders/vpl_grid.wgsl`), sorted by normal
/// bin where the split's kernel is given (`shaders/vpl_bins.wgsl`, then [`crate::scan`];
/// the kernels' sources are [`sources`]'s, made once a frame); returns the lights and their
/// bounds' words ([`BIN_WORDS`] per bin, six bins).
///
/// # Errors
/// A buffer could not be leased, or the VPLs exceed a dispatch or the scan.
fn to_grid_layout<'c>(
    ctx: &'c GpuContext,
    batch: &mut Batch<'c>,
    (records, status, capacity): (&Lease<'c>, &Lease<'c>, u64),
    (grid_src, bins_src): (&str, Option<&str>),
) -> Result<(Lease<'c>, Lease<'c>), GpuError> {
    let lights = ctx.lease(
        crate::grid::LIGHTS_IN,
        capacity * crate::grid::LIGHT_BYTES,
        GpuContext::STORAGE,
    )?;
    // Per bin: lo, hi (as order-preserving bits), the first invalid index, the count.
    let max = u32::MAX;
    let empty: Vec<u32> = [max, max, max, 0, 0, 0, max, 0].repeat(NORMAL_BINS);
    let bounds = ctx.upload("vpl bounds", &empty)?;
    let words = capacity.div_ceil(32);
    let bins = bins_src.is_some();
    let (bits, prefix) = if let Some(bins_src) = bins_src {
        let n = NORMAL_BINS as u64 * words;
        let (bits, prefix) = (
            ctx.output("vpl bins", 4 * n)?,
            ctx.output("vpl bin places", 4 * n)?,
        );
        let total = ctx.output("vpl bin total", 16)?;
        batch.clear_lease(&bits);
        let params = batch.uniform(&[capacity as u32, words as u32, 0, 0])?;
        let kernel = ctx.pipeline("vpl bins", || bins_src.to_owned());
        let bind = ctx.bind_group(
            &kernel,
            vec![
                params.as_entire_binding(),
                records.binding(),
                bits.binding(),
                status.binding(),
            ],
        );
        batch.dispatch("vpl bins", &kernel, &bind, capacity as usize)?;
        crate::scan::record(ctx, batch, &bits, &prefix, &total, n as usize, true)?;
        batch.keep(total);
        (bits, prefix)
    } else {
        (
            ctx.output("vpl bins", 16)?,
            ctx.output("vpl bin places", 16)?,
        )
    };
    let params = batch.uniform(&GridInParams {
        capacity: capacity as u32,
        bins: u32::from(bins),
        words: words as u32,
        pad: 0,
    })?;
    let kernel = ctx.pipeline("vpl grid", || grid_src.to_owned());
    let bind = ctx.bind_group(
        &kernel,
        vec![
            params.as_entire_binding(),
            records.binding(),
            lights.binding(),
            bounds.binding(),
            bits.binding(),
            prefix.binding(),
            status.binding(),
        ],
    );
    batch.dispatch("vpl grid", &kernel, &bind, capacity as usize)?;
    batch.keep(bits);
    batch.keep(prefix);
    Ok((lights, bounds))
}

/// `count` VPLs as the light-path kernel writes them (three `vec4`s each), the flux scaled
/// by `scale` as `Vpls::scale_flux` does, into planes (in parallel: a million VPLs).
fn unpack(records: &[[Vec4; 3]], count: usize, scale: f32) -> Vpls {
    let records = &records[..count.min(records.len())];
    let plane = |f: &(dyn Fn(&[Vec4; 3]) -> glam::Vec3 + Sync)| records.par_iter().map(f).collect();
    Vpls {
        positions: plane(&|r| r[0].truncate()),
        normals: plane(&|r| r[1].truncate()),
        flux: plane(&|r| {
            let mut f = r[2].truncate();
            f *= scale;
            f
        }),
    }
}

/// The VPLs of a frame that kept them on the GPU without reading them back
/// ([`VplSet::kept`], `count` of them), read back after all, for a frame that has to be
/// made with them on the CPU: from the light-path kernel's records where this thread's
/// are still kept, else traced again (the same set: the light paths are deterministic).
///
/// # Errors
/// The GPU failed.
pub(crate) fn read_back_kept(
    ctx: &GpuContext,
    world: &World,
    s: &lgh_render::RenderSettings,
    count: usize,
) -> Result<Vpls, GpuError> {
    if let Some((records, scale)) = resident::take_records(ctx, count) {
        let mut batch = Batch::new(ctx);
        batch.read(records.buffer(), (count.max(1) as u64) * VPL_BYTES)?;
        let (reads, _) = batch.finish()?;
        return Ok(unpack(
            reads.first().map_or(&[], |r| bytemuck::cast_slice(r)),
            count,
            scale,
        ));
    }
    let (set, _) = generate(ctx, world, (s.vpls, s.bounces, s.seed), Want::Cpu)?;
    Ok(set.vpls)
}

/// [`generate_vpls`] for a GPU method's
/// [`lgh_render::methods::IndirectMethod::generate_vpls`] on the process's context:
/// `Ok(None)` (the CPU traces them) for independent random path numbers
/// ([`PathNumbers::Random`]), or where the scene or the VPLs do not fit the adapter's
/// buffers. With `for_grid` (a method that builds a hierarchy over them) the VPLs are also
/// kept on the GPU for the build (the module `resident`); with `only_grid` as well (a frame
/// whose every pass after the VPLs runs on the GPU) they are not read back
/// ([`lgh_render::passes::vpl_gen::VplSet::kept`]).
///
/// # Errors
/// No adapter, or the GPU failed.
pub fn method_vpls(
    world: &World,
    s: &lgh_render::RenderSettings,
    (for_grid, only_grid): (bool, bool),
) -> Result<Option<VplSet>, lgh_render::settings::RenderError> {
    let fail = |e: GpuError| lgh_render::settings::RenderError::Backend(e.to_string());
    let ctx = GpuContext::shared().map_err(fail)?;
    resident::clear(ctx);
    if s.path_numbers != PathNumbers::Sobol {
        return Ok(None);
    }
    let want = match (for_grid, only_grid) {
        (true, true) if s.lgh.normal_bins => Want::GridBins,
        (true, true) => Want::Grid,
        (true, false) => Want::CpuAndGrid,
        _ => Want::Cpu,
    };
    match generate(ctx, world, (s.vpls, s.bounces, s.seed), want) {
        Ok((set, lights)) => {
            if let Some(lights) = lights {
                resident::keep(ctx, resident::Key::of(&set.vpls.as_input()), lights);
            }
            Ok(Some(set))
        }
        Err(GpuError::TooLarge(_)) => Ok(None),
        Err(e) => Err(fail(e)),
    }
}

#[cfg(test)]
mod tests {
    use super::held_bounds;
    use glam::Vec3;

    /// `shaders/vpl_grid.wgsl`'s `ordered`: the float's bits as an unsigned number of the
    /// same order.
    fn ordered(x: f32) -> u32 {
        let b = x.to_bits();
        if b & 0x8000_0000 != 0 {
            !b
        } else {
            b | 0x8000_0000
        }
    }

    /// The order-preserving bits decode to the floats, their order is the floats' (so that
    /// atomic min and max of the bits are those of the floats), and an invalid index is
    /// reported as such.
    #[test]
    fn the_bounds_decode_from_order_preserving_bits() {
        let xs = [-3.5e7f32, -2.0, -1e-30, -0.0, 0.0, 1e-30, 0.75, 4.0e9];
        for w in xs.windows(2) {
            assert!(ordered(w[0]) <= ordered(w[1]), "{w:?}");
        }
        let (lo, hi) = (Vec3::new(-2.0, -0.0, 1e-30), Vec3::new(0.75, 4.0e9, 3.0));
        let words = [
            ordered(lo.x),
            ordered(lo.y),
            ordered(lo.z),
            ordered(hi.x),
            ordered(hi.y),
            ordered(hi.z),
            u32::MAX,
            0,
        ];
        let (a, b) = held_bounds(&words).expect("valid");
        assert_eq!(
            a.to_array().map(f32::to_bits),
            lo.to_array().map(f32::to_bits)
        );
        assert_eq!(b, hi);
        let mut bad = words;
        bad[6] = 17;
        assert_eq!(held_bounds(&bad), Err(17));
        assert_eq!(held_bounds(&[]), Err(0));
    }
}
