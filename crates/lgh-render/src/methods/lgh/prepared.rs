//! An `lgh` frame in its three steps (Lin & Yuksel 2019 sections 3.1-3.3): what comes before
//! the lighting loop (hierarchies, shaded lights, tile bins; [`LghFrame::prepare`]), the
//! lighting loop with its shadow rays ([`LghFrame::shade`] on the CPU), and what comes after
//! it (ratio estimator, filters; [`LghFrame::finish`]). A backend that runs the loop
//! elsewhere (lgh-gpu) takes the same first and last steps, so that both backends shade the
//! same lights with the same filters.

use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;
use lgh_core::lighting_grid::partition::ShadedLevels;
use lgh_core::lighting_grid::{GridError, HierarchyBuilder};
use lgh_core::rng::Rng;
use lgh_core::timing::Timings;
use lgh_core::vpl::Vpls;
use rayon::prelude::*;

use super::LghStats;
use super::lights::{LghTargets, ShadeLights};
use super::normal_bins::{NORMAL_BINS, split_by_normal};
use super::settings::{DEFAULT_INTERLEAVE, DEFAULT_SHADOW_SAMPLES, Estimator, JitterAt};
use super::settings::{Selection, ShadowTarget, auto_tile};
use super::shade::{RowContext, RowScratch, Shaded, shade_rows};
use super::tables::DeviceKeeps;
use crate::memory::FrameMemory;
use crate::methods::lgh::light_batch::PackedLight;
use crate::methods::{MethodInputs, MethodOutput};
use crate::passes::par_filled;
use crate::shading::interleave::missed_sub_images;
use crate::shading::ratio::{
    AtrousBackend, RATIO_CORRECTION, RATIO_VISIBILITY, RatioFilter, Shadowed, Unshadowed,
    WindowFill, discontinuities, shadowed_indirect_with,
};
use crate::shading::reservoirs::ReservoirLayout;
use crate::shading::shadow_pass::{ShadowEstimates, ShadowPass, Targets};
use crate::shading::strata::ScreenStrata;
use crate::shading::tiles::{AllBounds, BinLights, InterleavedBins};

/// Random-stream tag of the grid offset of `--grid-jitter`.
const STREAM_GRID_SHIFT: u64 = 0x6a1d;

/// What [`LghFrame::prepare`] gives: a frame ready for its lighting loop, or the finished
/// output of a frame without VPLs.
pub enum Prepared {
    /// The frame before its lighting loop.
    Frame(Box<LghFrame>),
    /// No VPLs: a black frame, already finished.
    Dark(MethodOutput),
}

/// An `lgh` frame before its lighting loop: its shaded lights (the grid lights of the shaded
/// levels of every hierarchy, and the VPLs as S_0), their tile bins, and what the loop and
/// the ratio estimator need.
pub struct LghFrame {
    pub(super) lights: ShadeLights,
    /// The tile bins: made by [`LghFrame::prepare`] for the CPU's loop; for a backend's
    /// (`tables`), by that backend or by [`LghFrame::bin_on_cpu`].
    pub(super) bins: Option<InterleavedBins>,
    /// The tile edge in sub-image pixels.
    tile: u32,
    /// Per pixel, the sub-images its recombination window misses and it shades itself
    /// (the CPU's loop; a backend that shades makes its own; `lgh.fill_below`).
    missed: Option<Vec<u64>>,
    pub(super) packed: Vec<PackedLight>,
    pub(super) stats: LghStats,
    timings: Timings,
    /// Milliseconds of the lighting pass spent before the loop (the shaded lights).
    lighting_ms: f64,
    /// Shadow samples per pixel (0: unshadowed).
    pub(super) k: usize,
    /// Interleaving n.
    pub(super) n: u32,
    pub(super) eps2: f32,
}

/// The shaded lights as the tile binning reads them ([`LghFrame::spheres`]).
#[derive(Clone, Debug)]
pub struct LightSpheres<'a> {
    /// The number of lights: the arrays' length, or where a builder's device holds the
    /// lights and makes their spheres there, theirs (the arrays are then empty).
    pub count: usize,
    /// Centres.
    pub centres: &'a [Vec3],
    /// Radii of influence.
    pub radii: &'a [f32],
    /// Sub-image of each light.
    pub sub: &'a [u16],
    /// Per light, the normal of the plane behind which it gives nothing, or zero
    /// ([`BinLights::facing`]).
    pub facing: Vec<Vec3>,
    /// Per light, the distance within which it gives nothing ([`BinLights::holes`]).
    pub holes: Vec<f32>,
    /// Interleaving n.
    pub n: u32,
    /// Tile edge in sub-image pixels.
    pub tile: u32,
}

/// The lights of `lights` binned into tiles of `tile` sub-image pixels over the frame of
/// `inputs` under `n` x `n` interleaving, with the tile bounds kept in `memory` while the
/// view stands still.
fn bin(
    lights: &ShadeLights,
    inputs: &MethodInputs,
    memory: &mut FrameMemory,
    (n, tile): (u32, u32),
    guests: Option<(&[u64], f32)>,
) -> InterleavedBins {
    let g = inputs.gbuffer;
    let key = [n, tile, guests.map_or(0, |(_, below)| below.to_bits()), 0];
    let bounds = memory.tile_bounds.get_or_insert_with(g, key, || {
        AllBounds::with_guests(g, n, tile * n, guests.map(|(m, _)| m))
    });
    let (facing, holes) = lights.bin_extras();
    InterleavedBins::from_bounds(
        g,
        inputs.camera,
        bounds,
        BinLights {
            centres: &lights.position,
            radii: &lights.reach,
            facing: &facing,
            holes: &holes,
        },
        &lights.sub,
    )
}

/// The sub-images each pixel's recombination window misses where it reaches fewer than
/// `lgh.fill_below` n^2 of them ([`missed_sub_images`]), under the frame's blur; `None`
/// without interleaving or where no pixel misses any. Kept in `memory` while the view
/// stands still.
fn missed(inputs: &MethodInputs, memory: &mut FrameMemory, n: u32) -> Option<Vec<u64>> {
    let all = inputs.settings;
    let p = all.ratio_filter(n).interleave_blur?;
    let g = inputs.gbuffer;
    let below = all.lgh.fill_below;
    let key = [
        p.z_diff.to_bits(),
        p.crease_n_diff().to_bits(),
        n,
        below.to_bits(),
    ];
    if let Some(kept) = memory.missed_sub_images.kept(g, key) {
        return kept.clone();
    }
    let missed = missed_sub_images(g, discontinuities(g, &p, memory), &p.recombination(), below);
    if g.view.is_some() {
        memory.missed_sub_images.insert(g, key, missed.clone());
    }
    missed
}

/// What a lighting loop gives for every pixel ([`LghFrame::shade`] on the CPU): the
/// unshadowed sum A, the overdraw (lights whose sphere covers the pixel), the shadow
/// estimates S and U, and its pass timings in milliseconds.
#[derive(Clone, Debug, Default)]
pub struct LoopResult {
    /// A per pixel.
    pub a: Vec<Vec3>,
    /// Overdraw per pixel.
    pub overdraw: Vec<u32>,
    /// S, U and the rays traced.
    pub estimates: ShadowEstimates,
    /// Per pixel, what it shaded as a guest of the sub-images its recombination window
    /// misses (the CPU's loop, where any pixel fills its window).
    pub filled: Option<Vec<Vec3>>,
    /// Timings of the loop's passes ("lighting", "shadow_targets", "shadow_rays").
    pub timings: Timings,
}

impl LghFrame {
    /// The steps before the lighting loop (sections 3.1 and 3.2): the hierarchies (one per
    /// dominant normal direction with `normal_bins`), the shaded lights with their radii and
    /// roles, what the shadow targets need (representatives, or the unbiased estimate's
    /// walks), and the lights binned into screen tiles. With `tables`, each hierarchy's
    /// lookup tables are kept for [`LghFrame::tables`] (a backend that runs the loop
    /// elsewhere), the CPU's copies of the representatives are not made (such a frame is
    /// not for [`LghFrame::shade`]), and the lights are not binned: the backend bins them
    /// ([`LghFrame::spheres`]) or asks the CPU to ([`LghFrame::bin_on_cpu`]).
    ///
    /// # Errors
    /// The VPLs cannot form a hierarchy (non-finite values).
    pub fn prepare(
        inputs: &MethodInputs,
        shadowed: bool,
        memory: &mut FrameMemory,
        tables: bool,
    ) -> Result<Prepared, GridError> {
        Self::prepare_with(inputs, shadowed, memory, tables, None)
    }

    /// [`LghFrame::prepare`] with the hierarchies built by `builder` (a backend's, e.g. a
    /// GPU's) instead of the CPU's in `memory`.
    ///
    /// # Errors
    /// The VPLs cannot form a hierarchy (non-finite values); or the builder kept a grid on
    /// its device ([`HierarchyBuilder::shape`]) where the frame needs it on the CPU (without
    /// `tables`, without the unbiased estimate's shadow samples, with one level shown
    /// alone, or with some grids on the CPU and some not), or the VPLs are kept on the
    /// builder's device ([`MethodInputs::vpls`] empty, [`MethodInputs::vpl_count`] not) where
    /// the frame needs them here (normal bins the device did not split them into,
    /// [`MethodInputs::vpl_bins`], or a grid read back):
    /// [`GridError::KeptOnDevice`].
    pub fn prepare_with(
        inputs: &MethodInputs,
        shadowed: bool,
        memory: &mut FrameMemory,
        tables: bool,
        builder: Option<&mut dyn HierarchyBuilder>,
    ) -> Result<Prepared, GridError> {
        let MethodInputs {
            gbuffer: g,
            vpls,
            settings: all,
            ..
        } = *inputs;
        let (settings, seed) = (&all.lgh, all.seed);
        let builder: &mut dyn HierarchyBuilder = match builder {
            Some(b) => b,
            None => &mut memory.grid,
        };
        builder.set_shift(settings.grid_jitter.then(|| {
            let mut rng = Rng::new(&[seed, STREAM_GRID_SHIFT]);
            Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32())
        }));
        let mut t = Timings::default();
        let n_px = g.len();
        let k = all.shadows.k(shadowed, DEFAULT_SHADOW_SAMPLES);
        let n = all.tiling.interleave.unwrap_or(DEFAULT_INTERLEAVE).max(1);
        let mut stats = LghStats {
            alpha: settings.alpha,
            shadow_samples: k as u32,
            interleave: n,
            hierarchy_device: "none",
            ..LghStats::default()
        };
        if inputs.vpl_count == 0 {
            return Ok(Prepared::Dark(MethodOutput {
                radiance: par_filled(n_px, Vec3::ZERO),
                lights_per_pixel: Some(par_filled(n_px, 0)),
                stats: Some(Arc::new(stats)),
                ..MethodOutput::default()
            }));
        }
        // One hierarchy, or one per dominant normal direction (--normal-bins); where the
        // builder's device keeps the VPLs (none here), built there, of the parts it keeps
        // them in: all of them, or the bins it split them into. Each group: its VPLs here
        // (none where held), their number, its part on the device.
        let held = vpls.is_empty();
        let split;
        let groups: Vec<(&Vpls, usize, usize)> = match (held, settings.normal_bins) {
            (false, true) => {
                split = split_by_normal(vpls);
                split.iter().map(|g| (g, g.len(), 0)).collect()
            }
            (false, false) => vec![(vpls, vpls.len(), 0)],
            (true, false) => vec![(vpls, inputs.vpl_count, 0)],
            (true, true) => {
                let bins = inputs.vpl_bins.ok_or(GridError::KeptOnDevice)?;
                (0..NORMAL_BINS).map(|b| (vpls, bins[b], b)).collect()
            }
        };
        let lowest = settings.start_level.min(1);
        let unbiased = settings.estimator == Estimator::Unbiased;
        let n2 = (n * n) as usize;
        let mut lights = ShadeLights::default();
        let (mut build_ms, mut lighting_ms, mut reps_ms) = (0.0, 0.0, 0.0);
        // A builder that can draw the S_1 representatives with the build (a GPU's) does.
        let draw = k > 0 && unbiased && settings.shadow_target == ShadowTarget::Representative;
        builder.draw_representatives(draw.then_some(seed));
        if held {
            // A device that holds the parts may build them together (fewer waits).
            let start = Instant::now();
            let parts: Vec<(usize, usize)> = groups
                .iter()
                .filter(|g| g.1 > 0)
                .map(|g| (g.2, g.1))
                .collect();
            builder.prepare_held(&parts, settings.levels, settings.construction);
            build_ms += start.elapsed().as_secs_f64() * 1e3;
        }
        for &(group, count, part) in groups.iter().filter(|g| g.1 > 0) {
            let start = Instant::now();
            if held {
                builder.build_held(part, count, settings.levels, settings.construction)?;
            } else {
                builder.build(&group.as_input(), settings.levels, settings.construction)?;
            }
            build_ms += start.elapsed().as_secs_f64() * 1e3;
            let Some(shape) = builder.shape() else {
                continue;
            };
            stats.hierarchy_device = builder.device();
            let start = Instant::now();
            stats.grid_lights += shape.len();
            stats.levels = stats.levels.max(shape.l_max());
            let keeps = DeviceKeeps {
                lights: tables && builder.keeps_lights(),
                representatives: tables && builder.keeps_representatives(),
                lookups: tables && builder.makes_lookups(),
            };
            // A grid its builder keeps on its device serves a frame whose every later step
            // runs there: the unbiased estimate's tables, from what the device keeps.
            let grid = builder.grid();
            stats.grids_on_cpu = grid.is_some();
            let on_device = keeps.lights && keeps.representatives && keeps.lookups;
            if grid.is_none() && !(on_device && draw && settings.only_level.is_none()) {
                return Err(GridError::KeptOnDevice);
            }
            // A grid on the CPU needs its VPLs here too (S_0, its representatives).
            if held && grid.is_some() {
                return Err(GridError::KeptOnDevice);
            }
            let first = lights.len();
            match grid {
                Some(grid) => {
                    let (alpha, emission) = (settings.alpha, settings.emission);
                    lights.add_hierarchy(grid, group, lowest, alpha, emission, n2)?;
                }
                None => lights.add_on_device(&shape, count, lowest)?,
            }
            lighting_ms += start.elapsed().as_secs_f64() * 1e3;
            if k > 0 && settings.shadow_target == ShadowTarget::Representative {
                let start = Instant::now();
                if unbiased {
                    let levels = ShadedLevels {
                        lowest,
                        alpha: settings.alpha,
                    };
                    let drawn = builder.representatives();
                    let reps = (seed, drawn);
                    lights.add_unbiased(
                        (grid, &shape),
                        (group, count),
                        levels,
                        reps,
                        first,
                        (tables, keeps),
                    );
                } else if let Some(grid) = grid {
                    lights.add_representatives(
                        grid,
                        group,
                        lowest,
                        settings.shadow_from_level,
                        settings.construction,
                        seed,
                    );
                }
                reps_ms += start.elapsed().as_secs_f64() * 1e3;
            }
        }
        t.push("lgh_build", build_ms);
        if reps_ms > 0.0 {
            t.push("representatives", reps_ms);
        }
        let start = Instant::now();
        stats.shaded_lights = lights.len();
        if let Some(level) = settings.only_level {
            lights.show_only_level(level);
        }
        let tile = all.tiling.tile.unwrap_or_else(|| auto_tile(n)).max(1);
        // The CPU's loop fills cut recombination windows with these masks (a backend that
        // shades makes its own: lgh-gpu's `fill`).
        let missed = if tables {
            None
        } else {
            missed(inputs, memory, n)
        };
        let guests = missed.as_deref().map(|m| (m, settings.fill_below));
        let bins = (!tables).then(|| bin(&lights, inputs, memory, (n, tile), guests));
        let packed = lights.packed(n2 as f32);
        lighting_ms += start.elapsed().as_secs_f64() * 1e3;
        Ok(Prepared::Frame(Box::new(Self {
            lights,
            bins,
            missed,
            tile,
            packed,
            stats,
            timings: t,
            lighting_ms,
            k,
            n,
            eps2: inputs.eps() * inputs.eps(),
        })))
    }

    /// Whether the shaded lights are on the CPU: not where the hierarchies' builder keeps
    /// them on its device ([`HierarchyBuilder::shape`]), which then makes their rows and
    /// spheres itself; such a frame cannot be binned nor shaded on the CPU.
    #[must_use]
    pub fn lights_on_cpu(&self) -> bool {
        self.lights.len() == self.lights.position.len()
    }

    /// Bins the shaded lights into screen tiles on the CPU, for a frame prepared with
    /// `tables` whose backend does not bin them itself; nothing if they are binned (or
    /// not on the CPU, [`LghFrame::lights_on_cpu`]).
    pub fn bin_on_cpu(&mut self, inputs: &MethodInputs, memory: &mut FrameMemory) {
        if self.bins.is_none() && self.lights_on_cpu() {
            let start = Instant::now();
            self.bins = Some(bin(&self.lights, inputs, memory, (self.n, self.tile), None));
            self.lighting_ms += start.elapsed().as_secs_f64() * 1e3;
        }
    }

    /// What the tile binning reads, for a backend that bins the lights itself: light i is a
    /// sphere (`centres[i]`, `radii[i]`; infinite radius: everywhere, negative or NaN:
    /// nowhere) of sub-image `sub[i]`, giving nothing behind the plane of normal
    /// `facing[i]` nor within `holes[i]` of its centre, binned into tiles of `tile`
    /// sub-image pixels under `n` x `n` interleaving ([`InterleavedBins::build`]).
    #[must_use]
    pub fn spheres(&self) -> LightSpheres<'_> {
        let (facing, holes) = self.lights.bin_extras();
        LightSpheres {
            count: self.lights.len(),
            centres: &self.lights.position,
            radii: &self.lights.reach,
            sub: &self.lights.sub,
            facing,
            holes,
            n: self.n,
            tile: self.tile,
        }
    }

    /// The lighting loop on the CPU (section 3.2 and Appendix A) and the shadow rays (3.3):
    /// per pixel A, the overdraw, and the shadow estimates S and U, in bands of rows
    /// ([`ShadowPass::shade_in_bands`]).
    #[must_use]
    pub fn shade(&self, inputs: &MethodInputs) -> LoopResult {
        let MethodInputs {
            world,
            gbuffer: g,
            settings: all,
            ..
        } = *inputs;
        let (settings, seed, k) = (&all.lgh, all.seed, self.k);
        let start = Instant::now();
        let representative = settings.shadow_target == ShadowTarget::Representative;
        // Per pixel: A and overdraw; and k reservoirs.
        let mut shaded: Vec<Shaded> = par_filled(g.len(), (Vec3::ZERO, 0, Vec3::ZERO));
        let binned;
        let bins = match &self.bins {
            Some(b) => b,
            None => {
                binned = bin(
                    &self.lights,
                    inputs,
                    &mut FrameMemory::default(),
                    (self.n, self.tile),
                    self.missed.as_deref().map(|m| (m, settings.fill_below)),
                );
                &binned
            }
        };
        let ctx = RowContext {
            g,
            bins,
            packed: &self.packed,
            lights: &self.lights,
            settings,
            layout: ReservoirLayout::new(k),
            k,
            representative,
            eps2: self.eps2,
            seed,
            phases: self.n as usize,
            strata: (settings.selection == Selection::Dithered)
                .then(|| ScreenStrata::new(seed, self.n)),
            missed: self.missed.as_deref(),
        };
        let targets = LghTargets {
            lights: &self.lights,
            g,
            seed,
            eps2: self.eps2,
        };
        // One row of tiles per call, so that a tile's light batch serves all its rows.
        let pass = ShadowPass::new(world, g, k, seed).with_group_rows(bins.tile_pixels() as usize);
        let (estimates, times) = pass.shade_in_bands(
            &mut shaded,
            RowScratch::default,
            |scratch, y0, rows, res| shade_rows(&ctx, y0, rows, res, scratch),
            (representative && settings.jitter == JitterAt::Ray)
                .then_some(&targets as &dyn Targets),
        );
        let mut timings = Timings::default();
        timings.push(
            "lighting",
            start.elapsed().as_secs_f64() * 1e3 - times.resolve_ms - times.rays_ms,
        );
        if times.resolve_ms > 0.0 {
            timings.push("shadow_targets", times.resolve_ms);
        }
        if k > 0 {
            timings.push("shadow_rays", times.rays_ms);
        }
        LoopResult {
            a: shaded.par_iter().map(|p| p.0).collect(),
            overdraw: shaded.par_iter().map(|p| p.1).collect(),
            filled: self
                .missed
                .is_some()
                .then(|| shaded.par_iter().map(|p| p.2).collect()),
            estimates,
            timings,
        }
    }

    /// The steps after the lighting loop (3.3): the interleaving blur, the ratio estimator
    /// with its a-trous filter and the composite, from the loop's `shaded` result. The
    /// frame's timings are the preparation's, the loop's and the filters'.
    #[must_use]
    pub fn finish(
        self,
        inputs: &MethodInputs,
        shaded: LoopResult,
        memory: &mut FrameMemory,
    ) -> MethodOutput {
        self.finish_with(inputs, shaded, memory, None)
    }

    /// [`LghFrame::finish`] with the a-trous filter of `atrous` where given (the GPU's).
    #[must_use]
    pub fn finish_with(
        mut self,
        inputs: &MethodInputs,
        shaded: LoopResult,
        memory: &mut FrameMemory,
        atrous: Option<AtrousBackend>,
    ) -> MethodOutput {
        let filter = self.ratio_filter(inputs);
        let LoopResult {
            a,
            overdraw,
            estimates,
            filled,
            timings,
        } = shaded;
        let mut t = timings;
        let (world, g) = (inputs.world, inputs.gbuffer);
        let fill = match (self.missed.take(), filled) {
            (Some(missed), Some(filled)) => Some(WindowFill { missed, filled }),
            _ => None,
        };
        let a = Unshadowed { a, fill };
        let shadowed =
            shadowed_indirect_with(world, g, a, estimates, &filter, &mut t, memory, atrous);
        self.finish_shadowed(inputs, shadowed, overdraw, t)
    }

    /// The ratio estimator's settings for this frame: the blur of its interleaving, the
    /// a-trous passes, and the largest ratio (lgh's unbiased estimate corrects A, so its
    /// ratio may exceed 1).
    #[must_use]
    pub fn ratio_filter(&self, inputs: &MethodInputs) -> RatioFilter {
        let all = inputs.settings;
        RatioFilter {
            max_ratio: if all.lgh.estimator == Estimator::Unbiased {
                RATIO_CORRECTION
            } else {
                RATIO_VISIBILITY
            },
            ..all.ratio_filter(self.n)
        }
    }

    /// The frame's output from the ratio estimator's result `shadowed` (computed elsewhere,
    /// e.g. on the GPU, with [`LghFrame::ratio_filter`]), the lights per pixel and the times
    /// of the steps after the preparation (`lighting` gets the preparation's share added).
    #[must_use]
    pub fn finish_shadowed(
        self,
        inputs: &MethodInputs,
        shadowed: Shadowed,
        overdraw: Vec<u32>,
        timings: Timings,
    ) -> MethodOutput {
        let stats = |stats: &mut LghStats| {
            stats.avg_overdraw = inputs.gbuffer.mean_over_hits(&overdraw);
            stats.shadow_rays = shadowed.rays;
        };
        let out = self.output(timings, stats);
        MethodOutput {
            radiance: shadowed.indirect,
            unshadowed: Some(shadowed.unshadowed),
            shadow_ratio: Some(shadowed.ratio),
            lights_per_pixel: Some(overdraw),
            shadow_rays: shadowed.rays,
            ..out
        }
    }

    /// The output of a frame shown where its images were computed (on the GPU:
    /// `lgh_render::display`), which brings none of them back: its statistics, without the
    /// lights per pixel and the rays, and the times of the steps after the preparation
    /// (`lighting` gets the preparation's share added).
    #[must_use]
    pub fn finish_shown(self, timings: Timings) -> MethodOutput {
        self.output(timings, |_| {})
    }

    /// The output without images: the statistics (`fill` adds what the images say) and
    /// the times.
    fn output(self, timings: Timings, fill: impl FnOnce(&mut LghStats)) -> MethodOutput {
        let Self {
            mut stats,
            timings: mut t,
            lighting_ms,
            ..
        } = self;
        for (name, ms) in timings.0 {
            let ms = if name == "lighting" {
                ms + lighting_ms
            } else {
                ms
            };
            t.push(&name, ms);
        }
        fill(&mut stats);
        MethodOutput {
            timings: t,
            stats: Some(Arc::new(stats)),
            ..MethodOutput::default()
        }
    }
}
