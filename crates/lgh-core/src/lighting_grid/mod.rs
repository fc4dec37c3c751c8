//! The lighting grid hierarchy (Yuksel & Yuksel 2017), built in parallel as in Lin & Yuksel
//! 2019 section 3.1.
//!
//! Level 0 is the input lights S_0. Level 1 (S_1, the finest grid, spacing h_1) is built by a
//! trilinear splat of the input lights onto its vertices; every coarser level l >= 2 is built
//! from the grid lights of S_1 ("gather from S_1", the paper's method), from the input lights
//! again ("all-scatter", the paper's Table 1 baseline), or by exact restriction from the level
//! below (an extension, equal to the all-scatter result; see [`Construction::Restrict`]). A grid light has
//! intensity = the weighted intensity sum (so every level keeps the total), position = the
//! weighted mean, deviation pi sigma per axis, and the weighted mean normal (not renormalised).
//! Vertices whose grid light has zero intensity are removed (stream compaction) and all levels
//! are merged into one struct-of-arrays buffer with per-level offsets.
//!
//! Decisions where the paper is silent (docs/design.md, "Hierarchy"): h_top =
//! 1.1 x the longest edge, trilinear splatting at every level, piecewise-linear blending
//! ([`crate::blending`]). One deliberate difference from the authors' demo: when a level is
//! gathered from S_1, each S_1 light counts with its mass W_j and carries its own variance
//! (the demo treats S_1 lights as unit-mass points and drops their spread). With masses, every
//! level's weighted centroid equals the input centroid exactly, and the deviations include the
//! spread inside each S_1 cluster.
//!
//! Number of levels: the paper's rule (section 4.3), the largest l_max such that |S_1| < N/2,
//! or a fixed count.

pub mod descent;
pub mod geometry;
pub mod lookup;
pub mod partition;
pub mod reference;
pub mod representative;
pub mod shape;
pub mod splat;
pub mod synthetic;

use std::time::Instant;

use glam::{UVec3, Vec3};
use rayon::prelude::*;

pub use geometry::{GridGeometry, MAX_LEVELS};
pub use shape::GridShape;
pub use splat::{Level, Sources, Workspace};

/// The input lights of a hierarchy (S_0): positions, RGB intensities and optional normals.
#[derive(Clone, Copy, Debug)]
pub struct InputLights<'a> {
    /// Positions.
    pub positions: &'a [Vec3],
    /// RGB intensities (any non-negative linear quantity that lighting scales: for VPLs, the
    /// flux).
    pub intensity: &'a [Vec3],
    /// Unit normals of oriented lights (VPLs), or `None` for isotropic lights.
    pub normals: Option<&'a [Vec3]>,
}

impl<'a> InputLights<'a> {
    fn sources(&self) -> Sources<'a> {
        Sources {
            positions: self.positions,
            intensity: self.intensity,
            normals: self.normals,
            mass: None,
            variance: None,
            finer_vertices: None,
        }
    }
}

/// How many levels to build.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LevelCount {
    /// The largest l_max such that |S_1| < N/2 (LGH 2019 section 4.3), at least 1.
    Auto,
    /// Exactly this l_max (clamped to 1..=[`MAX_LEVELS`]).
    Fixed(u32),
}

impl serde::Serialize for LevelCount {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl std::fmt::Display for LevelCount {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Auto => f.write_str("auto"),
            Self::Fixed(l) => write!(f, "{l}"),
        }
    }
}

impl std::str::FromStr for LevelCount {
    type Err = String;

    /// `auto` or a number of levels from 1 to [`MAX_LEVELS`].
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "auto" => Ok(Self::Auto),
            s => match s.parse::<u32>() {
                Ok(l) if (1..=MAX_LEVELS).contains(&l) => Ok(Self::Fixed(l)),
                _ => Err(format!(
                    "'{s}': expected 'auto' or a number from 1 to {MAX_LEVELS}"
                )),
            },
        }
    }
}

/// Which lights the levels l >= 2 are built from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Construction {
    /// From the grid lights of S_1 (the paper's method, section 3.1; Table 1, right column).
    #[cfg_attr(feature = "clap", value(name = "gather"))]
    #[serde(rename = "gather")]
    GatherFromS1,
    /// Every level from the input lights (the paper's baseline; Table 1, left column).
    #[cfg_attr(feature = "clap", value(name = "scatter"))]
    #[serde(rename = "scatter")]
    ScatterAll,
    /// Each level l >= 2 from the grid lights of level l - 1 by exact restriction (an
    /// extension): the all-scatter hierarchy, to rounding, with each level costing about a
    /// quarter of the one before (`splat::Level::as_restriction_sources`).
    Restrict,
}

impl Construction {
    /// Short name used in reports (`gather`, `scatter` or `restrict`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::GatherFromS1 => "gather",
            Self::ScatterAll => "scatter",
            Self::Restrict => "restrict",
        }
    }
}

/// What is wrong with the input lights.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GridError {
    /// No light at all.
    #[error("no lights to build a lighting grid hierarchy from")]
    Empty,
    /// The arrays have different lengths.
    #[error("input arrays differ in length ({0} positions, {1} intensities, {2} normals)")]
    LengthMismatch(usize, usize, usize),
    /// A position or intensity is NaN or infinite, or an intensity is negative.
    #[error("light {index} has a non-finite position or a non-finite or negative intensity")]
    InvalidLight {
        /// Index of the first bad light.
        index: usize,
    },
    /// The builder kept a grid on its device ([`HierarchyBuilder::shape`]) for a frame
    /// that needs it on the CPU, or built some of a frame's grids there and some not; or
    /// the frame's VPLs are kept on a device whose builder cannot build from them
    /// ([`HierarchyBuilder::build_held`]) or where the frame needs them on the CPU.
    #[error(
        "the hierarchy builder's device keeps a grid or its lights, but this frame needs them on the CPU"
    )]
    KeptOnDevice,
}

/// A built hierarchy: levels 1..=l_max merged into one struct-of-arrays buffer.
///
/// Level l's lights are `level_range(l)`; within a level they are in vertex order.
#[derive(Clone, Debug, PartialEq)]
pub struct LightingGrid {
    /// Grid geometry (origin, h_top, l_max).
    pub geometry: GridGeometry,
    /// `level_start[l - 1]..level_start[l]` are the lights of level l (l_max + 1 entries).
    pub level_start: Vec<u32>,
    /// Integer vertex coordinates at the light's level.
    pub vertex: Vec<UVec3>,
    /// Illumination centre (weighted mean position).
    pub position: Vec<Vec3>,
    /// Intensity (weighted sum).
    pub intensity: Vec<Vec3>,
    /// Per-axis deviation pi sigma, used to jitter shadow-sample positions.
    pub deviation: Vec<Vec3>,
    /// Weighted mean normal (length below 1 where the normals disagree).
    pub normal: Vec<Vec3>,
    /// Total trilinear weight W of the vertex.
    pub mass: Vec<f32>,
}

/// Wall time of each construction step, in milliseconds, in order: `bounds`, `level_count`
/// (automatic mode only), `S1`, `S2`, ..., `compaction`, `merge`.
pub type BuildTimings = crate::timing::Timings;

impl LightingGrid {
    /// The top level l_max.
    #[must_use]
    pub fn l_max(&self) -> u32 {
        self.geometry.l_max
    }

    /// Index range of the lights of level `l` (1..=l_max).
    #[must_use]
    pub fn level_range(&self, l: u32) -> std::ops::Range<usize> {
        shape::level_range(&self.level_start, l)
    }

    /// Number of lights per level, from S_1 up.
    #[must_use]
    pub fn lights_per_level(&self) -> Vec<usize> {
        (1..=self.l_max())
            .map(|l| self.level_range(l).len())
            .collect()
    }

    /// Total number of grid lights.
    #[must_use]
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// True if there is no grid light.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Builds the hierarchy (parallel; deterministic whatever the thread count) with fresh
    /// working memory. To rebuild every frame, keep a [`GridBuilder`] instead.
    ///
    /// # Errors
    /// No lights, arrays of different lengths, or a non-finite or negative value.
    pub fn build(
        lights: &InputLights,
        levels: LevelCount,
        construction: Construction,
    ) -> Result<(Self, BuildTimings), GridError> {
        let mut b = GridBuilder::default();
        let t = b.build(lights, levels, construction)?;
        Ok((b.into_grid(), t))
    }
}

/// How far [`GridBuilder::set_shift`] enlarges the lights' bounds, as a fraction of their
/// longest edge.
const JITTER_SCALE: f32 = 0.125;

/// Builds lighting grid hierarchies frame after frame, keeping its working memory and the
/// output buffers between builds (as a GPU renderer keeps its buffers).
#[derive(Debug, Default)]
pub struct GridBuilder {
    ws: splat::Workspace,
    levels: Vec<Level>,
    grid: Option<LightingGrid>,
    shift: Option<Vec3>,
}

impl GridBuilder {
    /// Places the grids of the next builds at an offset: with `Some(u)`, u in [0, 1)^3, the
    /// lights' bounds are enlarged by an eighth of their longest edge on every axis, the enlarged box
    /// starting u x that much below them, so that every level's vertices move by a random
    /// fraction of their spacing. Averaging frames built with independent offsets turns the
    /// hierarchy's structured error (light clustered where the grid happens to fall) into
    /// noise that averages away (docs/design.md, "Accumulation"). `None` (the default): the
    /// grid centred on the bounds, as the paper builds it.
    pub fn set_shift(&mut self, shift: Option<Vec3>) {
        self.shift = shift.map(|u| u.clamp(Vec3::ZERO, Vec3::ONE));
    }

    /// The offset of the next builds ([`GridBuilder::set_shift`], clamped to [0, 1]^3).
    #[must_use]
    pub fn shift(&self) -> Option<Vec3> {
        self.shift
    }

    /// Builds the hierarchy of `lights`; the result is [`GridBuilder::grid`].
    ///
    /// # Errors
    /// No lights, arrays of different lengths, or a non-finite or negative value.
    pub fn build(
        &mut self,
        lights: &InputLights,
        levels: LevelCount,
        construction: Construction,
    ) -> Result<BuildTimings, GridError> {
        let mut t = BuildTimings::default();
        let (lo, hi) = t.time("bounds", || bounds(lights))?;
        let (lo, hi) = shifted_bounds(lo, hi, self.shift);
        let src = lights.sources();
        if self.levels.is_empty() {
            self.levels.push(Level::default());
        }
        let geometry = match levels {
            LevelCount::Fixed(l) => {
                let g = GridGeometry::new(lo, hi, l);
                let s1 = &mut self.levels[0];
                t.time("S1", || splat::splat_into(&mut self.ws, &src, &g, 1, s1));
                g
            }
            LevelCount::Auto => self.auto_levels(lights, lo, hi, &mut t),
        };
        self.levels
            .resize_with(geometry.l_max as usize, Level::default);
        let normals = lights.normals.is_some();
        for l in 2..=geometry.l_max {
            let (finer, rest) = self.levels.split_at_mut(l as usize - 1);
            let out = &mut rest[0];
            let ws = &mut self.ws;
            t.time(&format!("S{l}"), || match construction {
                Construction::GatherFromS1 => {
                    let from = finer[0].as_sources(normals);
                    splat::splat_into(ws, &from, &geometry, l, out);
                }
                Construction::ScatterAll => splat::splat_into(ws, &src, &geometry, l, out),
                Construction::Restrict => {
                    let from = finer[l as usize - 2].as_restriction_sources(normals);
                    splat::splat_into(ws, &from, &geometry, l, out);
                }
            });
        }
        let levels = &mut self.levels;
        t.time("compaction", || levels.par_iter_mut().for_each(compact));
        let grid = self
            .grid
            .get_or_insert_with(|| LightingGrid::empty(geometry));
        t.time("merge", || merge_into(geometry, levels, grid));
        Ok(t)
    }

    /// The paper's rule (section 4.3) by [`level_rule`], counting |S_1| without building it;
    /// the first count also counts the level above in the same pass
    /// ([`splat::count_vertices_and_finer`]: the walk usually asks for it next). Then it
    /// builds the S_1 of the level kept (into `levels[0]`), reusing the last count's sort
    /// when that count was of the level kept. The build of the final S_1 is reported as
    /// `S1`, everything else as `level_count`.
    fn auto_levels(
        &mut self,
        lights: &InputLights,
        lo: Vec3,
        hi: Vec3,
        t: &mut BuildTimings,
    ) -> GridGeometry {
        let src = lights.sources();
        let start = Instant::now();
        // The level whose sort the workspace holds, and a count made ahead.
        let mut sorted: Option<u32> = None;
        let mut ahead: Option<(u32, usize)> = None;
        let ws = &mut self.ws;
        let chosen = level_rule(lights.positions.len(), lo, hi, |l| {
            if let Some((at, len)) = ahead
                && at == l
            {
                return len;
            }
            let g = GridGeometry::new(lo, hi, l);
            let first = sorted.is_none();
            sorted = Some(l);
            if first {
                let (len, finer) = splat::count_vertices_and_finer(ws, &src, &g, 1);
                ahead = finer.map(|f| (l + 1, f));
                len
            } else {
                splat::count_vertices(ws, &src, &g, 1)
            }
        });
        let geometry = GridGeometry::new(lo, hi, chosen);
        let s1_ms = if sorted == Some(chosen) {
            self.build_counted_s1(&src, lo, hi, chosen)
        } else {
            let s = Instant::now();
            splat::splat_into(&mut self.ws, &src, &geometry, 1, &mut self.levels[0]);
            s.elapsed().as_secs_f64() * 1e3
        };
        let total = start.elapsed().as_secs_f64() * 1e3;
        t.push("level_count", (total - s1_ms).max(0.0));
        t.push("S1", s1_ms);
        geometry
    }

    /// Builds the S_1 of `l_max` levels into `levels[0]` right after counting it (reusing
    /// the count's sort); returns its time in ms.
    fn build_counted_s1(&mut self, src: &Sources, lo: Vec3, hi: Vec3, l_max: u32) -> f64 {
        let s = Instant::now();
        let g = GridGeometry::new(lo, hi, l_max);
        splat::splat_counted_into(&mut self.ws, src, &g, 1, &mut self.levels[0]);
        s.elapsed().as_secs_f64() * 1e3
    }

    /// The last hierarchy built (empty before the first build).
    #[must_use]
    pub fn grid(&self) -> Option<&LightingGrid> {
        self.grid.as_ref()
    }

    /// Takes the last hierarchy built.
    #[must_use]
    pub fn into_grid(self) -> LightingGrid {
        self.grid
            .unwrap_or_else(|| LightingGrid::empty(GridGeometry::new(Vec3::ZERO, Vec3::ZERO, 1)))
    }
}

/// What builds a frame's hierarchy, frame after frame: the CPU's [`GridBuilder`], or another
/// backend's (a GPU's) with the same contract: the grid placed by [`shifted_bounds`], the
/// levels chosen by [`level_rule`] or fixed, levels 1..=l_max in vertex order with
/// zero-intensity vertices removed, as [`LightingGrid`] documents.
pub trait HierarchyBuilder: Send {
    /// As [`GridBuilder::set_shift`].
    fn set_shift(&mut self, shift: Option<Vec3>);

    /// As [`GridBuilder::build`].
    ///
    /// # Errors
    /// No lights, arrays of different lengths, or a non-finite or negative value.
    fn build(
        &mut self,
        lights: &InputLights,
        levels: LevelCount,
        construction: Construction,
    ) -> Result<BuildTimings, GridError>;

    /// Builds the hierarchy of lights the builder's device already holds (a GPU's: the
    /// frame's VPLs, made there and not read back), as [`HierarchyBuilder::build`] builds
    /// it of the same lights: part `part` of them, of `count` lights, where the device split
    /// them (by dominant normal direction: one part per normal bin, in the bins' order), or
    /// part 0 for all of them.
    ///
    /// # Errors
    /// The builder holds no such lights (the default: none does),
    /// [`GridError::KeptOnDevice`]; or a light is invalid, as in `build`.
    fn build_held(
        &mut self,
        part: usize,
        count: usize,
        levels: LevelCount,
        construction: Construction,
    ) -> Result<BuildTimings, GridError> {
        let _ = (part, count, levels, construction);
        Err(GridError::KeptOnDevice)
    }

    /// Says that the next calls of [`HierarchyBuilder::build_held`] build `parts` (part,
    /// count) in this order with `levels` and `construction`, so that a builder whose
    /// device waits for each build's counts may build them together now (one wait per step
    /// for all parts instead of one per part) and answer those calls from what it built.
    /// By default nothing.
    fn prepare_held(&mut self, parts: &[(usize, usize)], levels: LevelCount, c: Construction) {
        let _ = (parts, levels, c);
    }

    /// The last hierarchy built; `None` also where the builder keeps it on its device
    /// ([`HierarchyBuilder::shape`] then describes it).
    fn grid(&self) -> Option<&LightingGrid>;

    /// The shape of the last hierarchy built: that of [`HierarchyBuilder::grid`], or where
    /// the builder keeps the grid on its device (for a frame whose later passes run there and
    /// read it there), all the caller gets of it.
    fn shape(&self) -> Option<GridShape> {
        self.grid().map(LightingGrid::shape)
    }

    /// Where the last hierarchy was built: `"cpu"`, or a backend's name (`"gpu"`).
    fn device(&self) -> &'static str {
        "cpu"
    }

    /// Asks the next builds to draw the S_1 lights' representatives too, with `seed`
    /// (`None`: not). A builder that does not draw them (the CPU's: the caller draws them
    /// with [`representative::s1_representatives`]) ignores it.
    fn draw_representatives(&mut self, seed: Option<u64>) {
        let _ = seed;
    }

    /// The S_1 lights' representatives of the last build, in grid order, drawn as
    /// [`representative::s1_representatives`] draws them with the seed given to
    /// [`HierarchyBuilder::draw_representatives`]; `None` if this build did not draw them.
    fn representatives(&self) -> Option<&[[u32; representative::SLOTS]]> {
        None
    }

    /// Whether the last build's input lights stay on the builder's device for the frame's
    /// later passes (a GPU's lighting loop reads the representative VPLs there), so that
    /// the caller need not keep a copy of them for those passes. The CPU's: false.
    fn keeps_lights(&self) -> bool {
        false
    }

    /// Whether the last build drew its S_1 lights' representatives and keeps them on the
    /// builder's device for the frame's later passes instead of handing them back
    /// ([`HierarchyBuilder::representatives`] is then `None`). The CPU's: false.
    fn keeps_representatives(&self) -> bool {
        false
    }

    /// Whether the last build's grid stays on the builder's device, which makes from it the
    /// unbiased estimate's lookup tables (where each vertex row of a level starts, and the
    /// children of every light of level >= 2 with the running sums of their weights,
    /// [`descent::Descent`]) for the frame's later passes, so that the caller need not make
    /// them. The CPU's: false.
    fn makes_lookups(&self) -> bool {
        false
    }
}

impl HierarchyBuilder for GridBuilder {
    fn set_shift(&mut self, shift: Option<Vec3>) {
        GridBuilder::set_shift(self, shift);
    }

    fn build(
        &mut self,
        lights: &InputLights,
        levels: LevelCount,
        construction: Construction,
    ) -> Result<BuildTimings, GridError> {
        GridBuilder::build(self, lights, levels, construction)
    }

    fn grid(&self) -> Option<&LightingGrid> {
        GridBuilder::grid(self)
    }
}

impl LightingGrid {
    pub(crate) fn empty(geometry: GridGeometry) -> Self {
        Self {
            geometry,
            level_start: vec![0],
            vertex: Vec::new(),
            position: Vec::new(),
            intensity: Vec::new(),
            deviation: Vec::new(),
            normal: Vec::new(),
            mass: Vec::new(),
        }
    }
}

/// The box a hierarchy's grid is fitted to: the lights' bounds `lo`, `hi`, enlarged by
/// [`GridBuilder::set_shift`]'s offset `shift` (u in [0, 1)^3) where there is one.
#[must_use]
pub fn shifted_bounds(lo: Vec3, hi: Vec3, shift: Option<Vec3>) -> (Vec3, Vec3) {
    match shift {
        Some(u) => {
            let d = Vec3::splat(JITTER_SCALE * (hi - lo).max_element());
            (lo - u * d, hi + (Vec3::ONE - u) * d)
        }
        None => (lo, hi),
    }
}

/// The paper's level rule (LGH 2019 section 4.3): the largest l_max in 1..=[`MAX_LEVELS`]
/// such that |S_1| < N/2, for `n` lights with bounds `lo`, `hi` (one level for fewer than two
/// lights or a box of no size). `count(l)` is |S_1| with l levels. |S_1| grows with l_max,
/// so the walk starts from a guess (for lights on surfaces |S_1| grows about 4x per level)
/// and counts there and at its neighbours: usually two or three counts. Every builder (the
/// CPU's, a GPU's) chooses by this one walk, so that they choose alike.
pub fn level_rule(n: usize, lo: Vec3, hi: Vec3, mut count: impl FnMut(u32) -> usize) -> u32 {
    if n < 2 || (hi - lo).max_element() <= 0.0 {
        return 1;
    }
    let fits = |len: usize| 2 * len < n;
    let guess = level_guess(n);
    let mut l = guess;
    if guess == 1 || fits(count(guess)) {
        while l < MAX_LEVELS && fits(count(l + 1)) {
            l += 1;
        }
    } else {
        while l > 1 {
            l -= 1;
            if fits(count(l)) {
                break;
            }
        }
    }
    l
}

/// Where [`level_rule`]'s walk starts for `n` lights: for lights on surfaces |S_1| grows
/// about 4x per level, so l_max = 1 + log4(n / 8). The walk then usually counts this level,
/// the next and sometimes one more or one less.
#[must_use]
pub fn level_guess(n: usize) -> u32 {
    ((1.0 + (n as f64 / 8.0).max(1.0).log(4.0).floor()) as u32).clamp(1, MAX_LEVELS)
}

/// Validates the input and returns its bounds (parallel reduction; min and max are exact, so
/// the result does not depend on the split).
///
/// # Errors
/// No lights, arrays of different lengths, or a non-finite or negative value.
pub fn bounds(lights: &InputLights) -> Result<(Vec3, Vec3), GridError> {
    let n = lights.positions.len();
    let nn = lights.normals.map_or(n, <[Vec3]>::len);
    if n != lights.intensity.len() || nn != n {
        return Err(GridError::LengthMismatch(n, lights.intensity.len(), nn));
    }
    if n == 0 {
        return Err(GridError::Empty);
    }
    // One pass over chunks: bounds and the first invalid index (min and max are exact, so
    // the split does not matter). Plain loops over chunk slices vectorise.
    const CHUNK: usize = 1 << 14;
    let empty = (
        Vec3::splat(f32::INFINITY),
        Vec3::splat(f32::NEG_INFINITY),
        usize::MAX,
    );
    let (lo, hi, bad) = lights
        .positions
        .par_chunks(CHUNK)
        .zip(lights.intensity.par_chunks(CHUNK))
        .enumerate()
        .map(|(ci, (ps, cs))| {
            let (mut lo, mut hi) = (empty.0, empty.1);
            let mut ok = true;
            for (&p, &c) in ps.iter().zip(cs) {
                lo = lo.min(p);
                hi = hi.max(p);
                ok &= p.is_finite() & c.is_finite() & (c.min_element() >= 0.0);
            }
            let bad = if ok {
                usize::MAX
            } else {
                let first = ps
                    .iter()
                    .zip(cs)
                    .position(|(p, c)| !(p.is_finite() && c.is_finite() && c.min_element() >= 0.0));
                first.map_or(usize::MAX, |k| ci * CHUNK + k)
            };
            (lo, hi, bad)
        })
        .reduce(|| empty, |a, b| (a.0.min(b.0), a.1.max(b.1), a.2.min(b.2)));
    if bad != usize::MAX {
        return Err(GridError::InvalidLight { index: bad });
    }
    Ok((lo, hi))
}

/// Removes grid lights of zero intensity (all channels zero) in place: they light nothing.
pub(crate) fn compact(level: &mut Level) {
    let mut k = 0;
    for i in 0..level.len() {
        if level.intensity[i].max_element() > 0.0 {
            level.vertex[k] = level.vertex[i];
            level.position[k] = level.position[i];
            level.intensity[k] = level.intensity[i];
            level.variance[k] = level.variance[i];
            level.normal[k] = level.normal[i];
            level.mass[k] = level.mass[i];
            k += 1;
        }
    }
    level.truncate(k);
}

/// Concatenates the levels into `g` (reusing its buffers) with per-level offsets; variances
/// become deviations pi sigma.
pub(crate) fn merge_into(geometry: GridGeometry, levels: &[Level], g: &mut LightingGrid) {
    g.geometry = geometry;
    g.level_start.clear();
    g.vertex.clear();
    g.position.clear();
    g.intensity.clear();
    g.deviation.clear();
    g.normal.clear();
    g.mass.clear();
    g.level_start.push(0);
    for level in levels {
        g.vertex.extend_from_slice(&level.vertex);
        g.position.extend_from_slice(&level.position);
        g.intensity.extend_from_slice(&level.intensity);
        g.deviation.extend(
            level
                .variance
                .iter()
                .map(|v| v.max(Vec3::ZERO).powf(0.5) * std::f32::consts::PI),
        );
        g.normal.extend_from_slice(&level.normal);
        g.mass.extend_from_slice(&level.mass);
        g.level_start.push(g.position.len() as u32);
    }
}
