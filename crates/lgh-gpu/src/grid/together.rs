//! Hierarchies built together ([`HierarchyBuilder::prepare_held`]): a frame with one
//! hierarchy per normal bin builds up to six, and each build waits twice (for the marks'
//! counts, which size its buffers, and for its level ranges). Built one after another they
//! wait twelve times, each a round trip in which the GPU drains its queue; built together,
//! the first steps of all go into one submission and the second steps into another: two
//! waits. Each build's passes and results are those it has alone (the same kernels on the
//! same buffers' contents), so the grids are the same.

use std::collections::VecDeque;

use lgh_core::lighting_grid::{BuildTimings, Construction, GridError, LevelCount};

use super::build::{Request, Run, record_marks};
use super::{GpuGridBuilder, Held};
use crate::batch::{Batch, PassTimes, add_passes};
use crate::context::{GpuContext, GpuError};
use crate::pool::Lease;

/// A build made ahead, waiting for its [`HierarchyBuilder::build_held`] call.
///
/// [`HierarchyBuilder::build_held`]: lgh_core::lighting_grid::HierarchyBuilder::build_held
pub(super) struct Ahead<'c> {
    pub(super) part: usize,
    pub(super) count: usize,
    pub(super) result: Result<(BuildTimings, Held<'c>), GridError>,
    /// The GPU's pass times of the builds made together (with the first of them).
    pub(super) passes: PassTimes,
    /// Why the builds failed on the GPU, if they did.
    pub(super) fallback: Option<String>,
}

/// The builds made ahead, in the order their calls come.
pub(super) type Aheads<'c> = VecDeque<Ahead<'c>>;

impl<'c> GpuGridBuilder<'c> {
    /// [`HierarchyBuilder::prepare_held`]: builds `parts` of the held lights together where
    /// there are several and their grids stay on the GPU (their shapes all the CPU gets).
    ///
    /// [`HierarchyBuilder::prepare_held`]: lgh_core::lighting_grid::HierarchyBuilder::prepare_held
    pub(super) fn build_ahead(
        &mut self,
        parts: &[(usize, usize)],
        levels: LevelCount,
        construction: Construction,
    ) {
        self.ahead.clear();
        if parts.len() < 2 || !self.keep_grid || construction == Construction::GatherFromS1 {
            return;
        }
        let ctx = self.ctx;
        let ahead = |part, count, result| Ahead {
            part,
            count,
            result,
            passes: PassTimes::new(),
            fallback: None,
        };
        // Each part's lights and request; a part that cannot be built gets its error.
        let mut runs = Vec::new();
        let mut taken = true;
        for &(part, count) in parts {
            let held = taken
                .then(|| crate::vpls::resident::take_held(ctx, part, count))
                .flatten();
            taken = held.is_some();
            let result = match held {
                None => Err(GridError::KeptOnDevice),
                Some((_, Err(index))) => Err(GridError::InvalidLight { index }),
                Some(_) if count == 0 => Err(GridError::Empty),
                Some((lights, Ok(bounds))) => {
                    runs.push((
                        self.ahead.len(),
                        lights,
                        self.request(bounds, levels),
                        count,
                    ));
                    // Until its build below succeeds (a failed one leaves the frame to be
                    // made again, as a failed build alone does).
                    Err(GridError::KeptOnDevice)
                }
            };
            self.ahead.push_back(ahead(part, count, result));
        }
        let mut passes = PassTimes::new();
        match build_together(ctx, runs, &mut passes) {
            Ok(built) => {
                for (at, t, held) in built {
                    self.ahead[at].result = Ok((t, held));
                }
            }
            Err(e) => {
                if let Some(first) = self.ahead.front_mut() {
                    first.fallback = Some(e.to_string());
                }
            }
        }
        if let Some(first) = self.ahead.front_mut() {
            first.passes = passes;
        }
    }
}

/// The builds of `runs` (each: its place among the builds made ahead, its lights, request
/// and count), their first steps in one submission, their second in another.
fn build_together<'c>(
    ctx: &'c GpuContext,
    runs: Vec<(usize, Lease<'c>, Request, usize)>,
    passes: &mut PassTimes,
) -> Result<Vec<(usize, BuildTimings, Held<'c>)>, GpuError> {
    let mut batch = Batch::new(ctx);
    let mut marking = Vec::with_capacity(runs.len());
    for (at, lights, request, count) in runs {
        let mut t = BuildTimings::default();
        let run = Run::held(lights, count, &request);
        marking.push((at, record_marks(ctx, &mut batch, run, &mut t)?, t));
    }
    let (reads, gpu) = batch.finish()?;
    add_passes(passes, gpu);
    let mut batch = Batch::new(ctx);
    let mut building = Vec::with_capacity(marking.len());
    for (at, m, mut t) in marking {
        let marked = m.marked(ctx, &reads, passes, &mut t)?;
        building.push((at, marked.record(ctx, &mut batch)?, t));
    }
    let (reads, gpu) = batch.finish()?;
    add_passes(passes, gpu);
    Ok(building
        .into_iter()
        .map(|(at, b, mut t)| {
            let held = b.built(&reads, None, &mut t);
            (at, t, held)
        })
        .collect())
}
