//! The lighting grid hierarchy built on the GPU (Lin & Yuksel 2019 section 3.1), with its
//! S_1 lights' representatives where asked (`grid/draw.rs`): S_1 by a
//! trilinear splat of the lights, every coarser level by exact restriction from the one
//! below (`lgh_core`'s [`Construction::Restrict`], which equals the all-scatter
//! hierarchy), the number of levels by the paper's rule (section 4.3,
//! [`lighting_grid::level_rule`]). The result is read back as a [`LightingGrid`], or where
//! the frame's later steps all run on the GPU ([`GpuGridBuilder::keep_grid`]) kept there
//! with only its level ranges read back ([`HierarchyBuilder::shape`]).
//!
//! The passes (`shaders/grid/`), with the grid placed as the CPU places it
//! ([`lighting_grid::bounds`], [`lighting_grid::shifted_bounds`]):
//!
//! 1. `mark`: every light sets, in a bit set per resolution (2^k cells per axis), the bits of
//!    the vertices it gives a non-zero weight; a [`scan`](crate::scan) of the words'
//!    population counts numbers the marked vertices, and `counts` gives each resolution's
//!    count, read back with the largest intensity (one wait): the level rule needs |S_1| at
//!    several level counts, and the next passes' buffers their sizes;
//! 2. `list` writes each marked vertex's key; `splat` adds every light's trilinear
//!    contributions to S_1's sums in 96-bit fixed point with integer atomics (exact, so the
//!    result does not depend on the order of the adds); `s1_sums` turns them into floats;
//!    `restrict` gathers each coarser level from its 27 finer neighbours in a fixed order;
//!    `emit` writes every vertex's grid light, level by level, read back in one copy (the
//!    second wait); the CPU drops zero-intensity lights as it unpacks them;
//! 3. where the records are kept on the GPU, `kept` flags the records the CPU keeps and a
//!    scan numbers them (`grid/number.rs`: each record's grid index, from which the frame's
//!    tables are made on the GPU); with [`GpuGridBuilder::keep_grid`] the index at each
//!    level's first record is read back in the records' place (the grid's level ranges).
//!
//! Memory: a bit per vertex of every resolution in use (17 MB at the finest, 512 cells per
//! axis), 156 bytes per S_1 vertex of sums and 68 per vertex of every level. The gather
//! construction, and inputs the adapter's buffers cannot hold, are built by the CPU's
//! builder instead (the same contract, [`HierarchyBuilder`]).

use std::sync::{Mutex, PoisonError};

use glam::Vec3;
use lgh_core::lighting_grid::representative::SLOTS;
use lgh_core::lighting_grid::{
    self, BuildTimings, Construction, GridBuilder, GridError, GridShape, HierarchyBuilder,
    InputLights, LevelCount, LightingGrid,
};

use crate::batch::PassTimes;
use crate::context::{GpuContext, GpuError};
use crate::pool::Lease;

mod build;
mod draw;
mod marks;
mod number;
mod together;
mod transfer;

pub use number::Numbered;

use build::{Request, Run, build_on, record};

/// Floats per light in the uploaded lights: position, intensity, normal.
pub(crate) const LIGHT_FLOATS: usize = 9;
/// Bytes per light in the uploaded lights.
pub(crate) const LIGHT_BYTES: u64 = 4 * LIGHT_FLOATS as u64;
/// The pool's label of the uploaded lights (the frame's VPLs kept on the GPU are leased
/// under it too, [`crate::vpls`]).
pub(crate) const LIGHTS_IN: &str = "grid lights in";
/// Words per grid light read back (vertex and mass, position, intensity, normal; the
/// deviation in the fourth word of the last three).
pub(crate) const RECORD_WORDS: usize = 16;
/// Words of the fixed-point sums per S_1 vertex (13 sums of three words).
const ACC_WORDS: u64 = 39;
/// Floats per vertex of the sums of every level (13 used).
const SUM_FLOATS: u64 = 16;

/// The invocations of one dispatch at most (65,535 workgroups of 64); the kernels loop over
/// their items with the dispatch's stride.
const MAX_INVOCATIONS: usize = 64 * 65_535;

/// The parameters of one dispatch (`GridParams` in `shaders/grid/common.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct GridParams {
    origin: [f32; 3],
    h_top: f32,
    n: u32,
    k: u32,
    count: u32,
    word0: u32,
    fine_word0: u32,
    vert0: u32,
    imax: f32,
    inv_imax: f32,
    step: u32,
    seed_lo: u32,
    seed_hi: u32,
    pad: u32,
}

/// The WGSL sources of the build's kernels, by name.
#[must_use]
pub fn sources() -> Vec<(&'static str, String)> {
    let common = include_str!("../shaders/grid/common.wgsl");
    let lookup = include_str!("../shaders/grid/lookup.wgsl");
    let with = |parts: &[&str]| {
        let mut all = vec![common];
        all.extend_from_slice(parts);
        crate::kernel(&all)
    };
    vec![
        (
            "grid mark",
            with(&[include_str!("../shaders/grid/mark.wgsl")]),
        ),
        (
            "grid counts",
            with(&[include_str!("../shaders/grid/counts.wgsl")]),
        ),
        (
            "grid list",
            with(&[include_str!("../shaders/grid/list.wgsl")]),
        ),
        (
            "grid splat",
            with(&[include_str!("../shaders/grid/splat.wgsl"), lookup]),
        ),
        (
            "grid s1 sums",
            with(&[include_str!("../shaders/grid/s1_sums.wgsl")]),
        ),
        (
            "grid restrict",
            with(&[include_str!("../shaders/grid/restrict.wgsl"), lookup]),
        ),
        (
            "grid emit",
            with(&[include_str!("../shaders/grid/emit.wgsl")]),
        ),
        (
            "grid cells",
            with(&[include_str!("../shaders/grid/cells.wgsl")]),
        ),
        (
            "grid cell sort",
            with(&[include_str!("../shaders/grid/cell_sort.wgsl")]),
        ),
        (
            "grid s1 keep",
            with(&[include_str!("../shaders/grid/s1_keep.wgsl")]),
        ),
        (
            "grid kept",
            with(&[include_str!("../shaders/grid/kept.wgsl")]),
        ),
        (
            "grid draw",
            with(&[include_str!("../shaders/grid/draw.wgsl")]),
        ),
    ]
}

/// The compiled pipeline of kernel `name` of [`sources`].
fn pipeline(ctx: &GpuContext, name: &'static str) -> std::sync::Arc<wgpu::ComputePipeline> {
    ctx.pipeline(name, || {
        sources()
            .into_iter()
            .find(|(n, _)| *n == name)
            .map(|(_, s)| s)
            .unwrap_or_default()
    })
}

/// What a GPU builder keeps between frames: the grid's buffers, and the CPU builder it
/// hands what it does not build.
#[derive(Debug, Default)]
pub struct GridState {
    grid: Option<LightingGrid>,
    cpu: GridBuilder,
    /// Whether the last build was the CPU's.
    on_cpu: bool,
    /// The seed of the representatives' draw, if the builds draw them.
    seed: Option<u64>,
    /// The S_1 lights' representatives of the last build (valid with `drawn`).
    reps: Vec<[u32; SLOTS]>,
    drawn: bool,
    /// Whether this builder has built (a recycled state's grids are an earlier builder's).
    built: bool,
    /// The last build's shape where its grid stays on the GPU (not read back; `grid` is
    /// then an earlier build's).
    kept_shape: Option<GridShape>,
}

impl GridState {
    /// This state with its memory and without its settings: a builder that takes it from
    /// the pool starts as a new one (no grid shift, no draw), whatever the builder that
    /// dropped it was set to.
    fn recycled(mut self) -> Self {
        self.cpu.set_shift(None);
        self.seed = None;
        self.drawn = false;
        self.on_cpu = false;
        self.built = false;
        self.kept_shape = None;
        self
    }
}

/// Builds hierarchies on the GPU of `ctx` ([`HierarchyBuilder`]); the working memory comes
/// from the context's pools and goes back when the builder is dropped.
pub struct GpuGridBuilder<'c> {
    ctx: &'c GpuContext,
    state: Option<GridState>,
    /// Why the last build ran on the CPU, if it did because of the GPU.
    pub fallback: Option<String>,
    /// The GPU's pass times of the last build (timestamps, where the adapter has them),
    /// apart from its timings, whose `level_count` and `gpu_build` hold them.
    pub passes: PassTimes,
    /// Per build since the last [`GpuGridBuilder::take_held`], what the GPU holds of it
    /// (`None` where the CPU built it).
    kept: Vec<Option<Held<'c>>>,
    /// Whether the builds keep their representatives on the GPU instead of reading them
    /// back ([`GpuGridBuilder::keep_representatives`]).
    keep_slots: bool,
    /// Whether the builds keep their grid on the GPU instead of reading it back
    /// ([`GpuGridBuilder::keep_grid`]).
    keep_grid: bool,
    /// The builds made ahead ([`HierarchyBuilder::prepare_held`]).
    ahead: together::Aheads<'c>,
}

/// What the GPU holds of one build for the frame's later passes.
pub struct Held<'c> {
    /// The build's input lights (36 bytes a light: position, intensity, normal).
    pub lights: Lease<'c>,
    /// The S_1 lights' [`SLOTS`] representatives each (indices into the lights), in grid
    /// order, where the build drew them and keeps them
    /// ([`GpuGridBuilder::keep_representatives`]).
    pub slots: Option<Lease<'c>>,
    /// The grid lights as the build emitted them (16 words each: vertex and
    /// mass, position, intensity, normal, the deviation in the fourth word of the last
    /// three), level by level from S_1, the zero-intensity ones still among them (the CPU
    /// drops them as it unpacks), where the build keeps them
    /// ([`GpuGridBuilder::keep_representatives`]).
    pub records: Option<Lease<'c>>,
    /// The records of each level l = 1..=l_max (index l - 1), zero-intensity ones included.
    pub level_records: Vec<u32>,
    /// The records numbered as the CPU keeps them, where they are kept (`None` also
    /// without records).
    pub numbered: Option<Numbered<'c>>,
    /// The grid's shape where it stays on the GPU and the build was made together with
    /// others ([`HierarchyBuilder::prepare_held`]); else in the builder's state.
    shape: Option<GridShape>,
}

/// States kept per context: one per frame building at once.
#[derive(Debug, Default)]
pub(crate) struct GridStates(Mutex<Vec<GridState>>);

impl<'c> GpuGridBuilder<'c> {
    /// A builder on `ctx`, with the buffers of an earlier builder where one was dropped.
    #[must_use]
    pub fn new(ctx: &'c GpuContext) -> Self {
        let state = ctx
            .grid_states()
            .0
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .pop()
            .unwrap_or_default();
        Self {
            ctx,
            state: Some(state),
            fallback: None,
            passes: PassTimes::new(),
            kept: Vec::new(),
            keep_slots: false,
            keep_grid: false,
            ahead: together::Aheads::new(),
        }
    }

    fn state(&mut self) -> &mut GridState {
        self.state.get_or_insert_with(GridState::default)
    }

    /// What the GPU holds of each build since the last call, in build order (`None` where
    /// the CPU built it): its input lights, where the lighting loop reads the representative
    /// VPLs ([`HierarchyBuilder::keeps_lights`]), and its representatives where it keeps
    /// them ([`HierarchyBuilder::keeps_representatives`]).
    pub fn take_held(&mut self) -> Vec<Option<Held<'c>>> {
        std::mem::take(&mut self.kept)
    }

    /// Makes the next builds keep on the GPU, for a lighting loop that runs there, their
    /// grid lights as emitted ([`Held::records`]) and, where they draw them, their
    /// representatives instead of reading these back ([`Held::slots`]), where `keep`: such a
    /// frame needs no copy of the representatives on the CPU.
    pub fn keep_representatives(&mut self, keep: bool) {
        self.keep_slots = keep;
    }

    /// Makes the next builds keep their grid on the GPU, where `keep`, as
    /// [`GpuGridBuilder::keep_representatives`] does and without reading the grid back:
    /// [`HierarchyBuilder::grid`] is then `None`, and [`HierarchyBuilder::shape`] (the level
    /// ranges, read back instead) all the CPU gets of it. For a frame whose passes after the
    /// build all run on the GPU, from what it holds ([`Held`]).
    pub fn keep_grid(&mut self, keep: bool) {
        self.keep_grid = keep;
    }
}

impl<'c> GpuGridBuilder<'c> {
    /// What a build on the GPU fitted to `(lo, hi)` with `levels` is asked for.
    fn request(&mut self, (lo, hi): (Vec3, Vec3), levels: LevelCount) -> Request {
        let (keep_slots, keep_grid) = (self.keep_slots || self.keep_grid, self.keep_grid);
        let state = self.state();
        Request {
            levels,
            bounds: lighting_grid::shifted_bounds(lo, hi, state.cpu.shift()),
            seed: state.seed,
            keep_slots,
            keep_grid,
        }
    }

    /// Builds `run` on the GPU; what it holds is kept for [`GpuGridBuilder::take_held`].
    fn build_gpu(&mut self, run: Run<'_, 'c>, t: &mut BuildTimings) -> Result<(), GpuError> {
        let ctx = self.ctx;
        let state = self.state.get_or_insert_with(GridState::default);
        let held = build_on(ctx, run, state, t, &mut self.passes)?;
        state.on_cpu = false;
        state.built = true;
        self.kept.push(Some(held));
        Ok(())
    }
}

impl Drop for GpuGridBuilder<'_> {
    fn drop(&mut self) {
        if let Some(s) = self.state.take() {
            let mut kept = self
                .ctx
                .grid_states()
                .0
                .lock()
                .unwrap_or_else(PoisonError::into_inner);
            if kept.len() < 2 {
                kept.push(s.recycled());
            }
        }
    }
}

impl HierarchyBuilder for GpuGridBuilder<'_> {
    fn set_shift(&mut self, shift: Option<Vec3>) {
        // The CPU builder keeps the offset for both (it builds what the GPU does not).
        self.state().cpu.set_shift(shift);
    }

    fn build(
        &mut self,
        lights: &InputLights,
        levels: LevelCount,
        construction: Construction,
    ) -> Result<BuildTimings, GridError> {
        self.fallback = None;
        self.passes.clear();
        // The frame's VPLs, if they are still on the GPU in the build's layout.
        let resident = crate::vpls::resident::take(self.ctx, lights);
        if construction != Construction::GatherFromS1 {
            let mut t = BuildTimings::default();
            let bounds = t.time("bounds", || lighting_grid::bounds(lights))?;
            let request = self.request(bounds, levels);
            let run = Run {
                lights: Some(lights),
                resident,
                count: lights.positions.len(),
                normals: lights.normals.is_some(),
                request: &request,
            };
            match self.build_gpu(run, &mut t) {
                Ok(()) => return Ok(t),
                Err(e) => self.fallback = Some(e.to_string()),
            }
        }
        self.kept.push(None);
        let state = self.state();
        state.on_cpu = true;
        state.built = true;
        state.cpu.build(lights, levels, construction)
    }

    fn build_held(
        &mut self,
        part: usize,
        count: usize,
        levels: LevelCount,
        construction: Construction,
    ) -> Result<BuildTimings, GridError> {
        self.fallback = None;
        self.passes.clear();
        // Made ahead with others.
        if let Some(a) = self.ahead.pop_front() {
            if (a.part, a.count) == (part, count) {
                (self.fallback, self.passes) = (a.fallback, a.passes);
                let state = self.state();
                state.drawn = false;
                return match a.result {
                    Ok((t, mut held)) => {
                        state.kept_shape = held.shape.take();
                        state.on_cpu = false;
                        state.built = true;
                        self.kept.push(Some(held));
                        Ok(t)
                    }
                    Err(e) => {
                        state.built = false;
                        Err(e)
                    }
                };
            }
            self.ahead.clear();
        }
        let held = crate::vpls::resident::take_held(self.ctx, part, count);
        let Some((lights, bounds)) = held.filter(|_| construction != Construction::GatherFromS1)
        else {
            return Err(GridError::KeptOnDevice);
        };
        let bounds = bounds.map_err(|index| GridError::InvalidLight { index })?;
        if count == 0 {
            return Err(GridError::Empty);
        }
        let mut t = BuildTimings::default();
        let request = self.request(bounds, levels);
        match self.build_gpu(Run::held(lights, count, &request), &mut t) {
            Ok(()) => Ok(t),
            Err(e) => {
                // The CPU has no copy to build from: the frame is made again with one.
                self.fallback = Some(e.to_string());
                self.state().built = false;
                Err(GridError::KeptOnDevice)
            }
        }
    }

    fn prepare_held(
        &mut self,
        parts: &[(usize, usize)],
        levels: LevelCount,
        construction: Construction,
    ) {
        self.build_ahead(parts, levels, construction);
    }

    fn device(&self) -> &'static str {
        match &self.state {
            Some(s) if !s.on_cpu => "gpu",
            _ => "cpu",
        }
    }

    fn draw_representatives(&mut self, seed: Option<u64>) {
        self.state().seed = seed;
    }

    fn representatives(&self) -> Option<&[[u32; SLOTS]]> {
        let s = self.state.as_ref().filter(|s| s.built)?;
        (!s.on_cpu && s.drawn).then_some(&s.reps[..])
    }

    fn keeps_lights(&self) -> bool {
        matches!(self.kept.last(), Some(Some(_)))
    }

    fn keeps_representatives(&self) -> bool {
        matches!(self.kept.last(), Some(Some(h)) if h.slots.is_some())
    }

    fn makes_lookups(&self) -> bool {
        matches!(self.kept.last(), Some(Some(h)) if h.records.is_some())
    }

    fn grid(&self) -> Option<&LightingGrid> {
        let s = self.state.as_ref().filter(|s| s.built)?;
        if s.on_cpu {
            s.cpu.grid()
        } else if s.kept_shape.is_some() {
            None
        } else {
            s.grid.as_ref()
        }
    }

    fn shape(&self) -> Option<GridShape> {
        let s = self.state.as_ref().filter(|s| s.built)?;
        match &s.kept_shape {
            Some(shape) if !s.on_cpu => Some(shape.clone()),
            _ => self.grid().map(LightingGrid::shape),
        }
    }
}
