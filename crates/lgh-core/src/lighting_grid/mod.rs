//! The lighting grid hierarchy (Yuksel & Yuksel 2017), built in parallel as in Lin & Yuksel
//! 2019 section 3.1.
//!
//! Level 0 is the input lights S_0. Level 1 (S_1, the finest grid, spacing h_1) is built by a
//! trilinear splat of the input lights onto its vertices; every coarser level l >= 2 is built
//! from the grid lights of S_1 ("gather from S_1", the paper's method), or, for comparison,
//! from the input lights again ("all-scatter", the paper's Table 1 baseline). A grid light has
//! intensity = the weighted intensity sum (so every level keeps the total), position = the
//! weighted mean, deviation pi sigma per axis, and the weighted mean normal (not renormalised).
//! Vertices whose grid light has zero intensity are removed (stream compaction) and all levels
//! are merged into one struct-of-arrays buffer with per-level offsets.
//!
//! Decisions where the paper is silent are those of `shared/design/lgh-method.md`: h_top =
//! 1.1 x the longest edge, trilinear splatting at every level, piecewise-linear blending
//! ([`crate::blending`]). One deliberate difference from the authors' demo: when a level is
//! gathered from S_1, each S_1 light counts with its mass W_j and carries its own variance
//! (the demo treats S_1 lights as unit-mass points and drops their spread). With masses, every
//! level's weighted centroid equals the input centroid exactly, and the deviations include the
//! spread inside each S_1 cluster.
//!
//! Number of levels: the paper's rule (section 4.3), the largest l_max such that |S_1| < N/2,
//! or a fixed count.

pub mod geometry;
pub mod reference;
pub mod splat;
pub mod synthetic;

use std::time::Instant;

use glam::{UVec3, Vec3};
use rayon::prelude::*;

pub use geometry::{GridGeometry, MAX_LEVELS};
pub use splat::{Level, Sources};

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

/// Which lights the levels l >= 2 are built from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Construction {
    /// From the grid lights of S_1 (the paper's method; Table 1, right column).
    GatherFromS1,
    /// Every level from the input lights (Table 1, left column).
    ScatterAll,
}

impl Construction {
    /// Short name used in reports (`gather` or `scatter`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::GatherFromS1 => "gather",
            Self::ScatterAll => "scatter",
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
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BuildTimings(pub Vec<(String, f64)>);

impl BuildTimings {
    fn time<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let t = Instant::now();
        let out = f();
        self.0
            .push((name.to_string(), t.elapsed().as_secs_f64() * 1e3));
        out
    }

    /// Sum of all steps.
    #[must_use]
    pub fn total(&self) -> f64 {
        self.0.iter().map(|(_, t)| t).sum()
    }
}

impl LightingGrid {
    /// The top level l_max.
    #[must_use]
    pub fn l_max(&self) -> u32 {
        self.geometry.l_max
    }

    /// Index range of the lights of level `l` (1..=l_max).
    #[must_use]
    pub fn level_range(&self, l: u32) -> std::ops::Range<usize> {
        self.level_start[l as usize - 1] as usize..self.level_start[l as usize] as usize
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

    /// Builds the hierarchy (parallel; deterministic whatever the thread count).
    ///
    /// # Errors
    /// No lights, arrays of different lengths, or a non-finite or negative value.
    pub fn build(
        lights: &InputLights,
        levels: LevelCount,
        construction: Construction,
    ) -> Result<(Self, BuildTimings), GridError> {
        let mut t = BuildTimings::default();
        let (lo, hi) = t.time("bounds", || bounds(lights))?;
        let src = lights.sources();
        let (geometry, s1) = match levels {
            LevelCount::Fixed(l) => {
                let g = GridGeometry::new(lo, hi, l);
                (g, t.time("S1", || splat::splat(&src, &g, 1)))
            }
            LevelCount::Auto => {
                let g = t.time("level_count", || auto_geometry(lights, lo, hi));
                (g, t.time("S1", || splat::splat(&src, &g, 1)))
            }
        };
        let mut levels_out = vec![s1];
        for l in 2..=geometry.l_max {
            let level = t.time(&format!("S{l}"), || match construction {
                Construction::GatherFromS1 => {
                    let s1 = &levels_out[0];
                    let from = Sources {
                        positions: &s1.position,
                        intensity: &s1.intensity,
                        normals: lights.normals.map(|_| &s1.normal[..]),
                        mass: Some(&s1.mass),
                        variance: Some(&s1.variance),
                    };
                    splat::splat(&from, &geometry, l)
                }
                Construction::ScatterAll => splat::splat(&src, &geometry, l),
            });
            levels_out.push(level);
        }
        let levels_out = t.time("compaction", || compact(levels_out));
        let grid = t.time("merge", || merge(geometry, levels_out));
        Ok((grid, t))
    }
}

/// Validates the input and returns its bounds (parallel reduction; min and max are exact, so
/// the result does not depend on the split).
fn bounds(lights: &InputLights) -> Result<(Vec3, Vec3), GridError> {
    let n = lights.positions.len();
    let nn = lights.normals.map_or(n, <[Vec3]>::len);
    if n != lights.intensity.len() || nn != n {
        return Err(GridError::LengthMismatch(n, lights.intensity.len(), nn));
    }
    if n == 0 {
        return Err(GridError::Empty);
    }
    if let Some(index) = (0..n).into_par_iter().find_first(|&i| {
        let (p, c) = (lights.positions[i], lights.intensity[i]);
        !p.is_finite() || !c.is_finite() || c.min_element() < 0.0
    }) {
        return Err(GridError::InvalidLight { index });
    }
    Ok(lights
        .positions
        .par_iter()
        .fold(
            || (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        )
        .reduce(
            || (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        ))
}

/// The paper's rule: the largest l_max with |S_1| < N/2 (at least 1). |S_1| for a given
/// l_max is the number of occupied vertices at spacing h_top / 2^(l_max - 1), which grows with
/// l_max; the search counts them ([`splat::count_vertices`]) walking from a first guess (for
/// lights on surfaces |S_1| grows about 4x per level).
fn auto_geometry(lights: &InputLights, lo: Vec3, hi: Vec3) -> GridGeometry {
    let n = lights.positions.len();
    if n < 2 || (hi - lo).max_element() <= 0.0 {
        return GridGeometry::new(lo, hi, 1);
    }
    let src = lights.sources();
    let fits = |l: u32| {
        let g = GridGeometry::new(lo, hi, l);
        l == 1 || 2 * splat::count_vertices(&src, &g, 1) < n
    };
    let guess = (1.0 + ((n as f64 / 8.0).max(1.0).log(4.0)).round()) as u32;
    let mut l = guess.clamp(1, MAX_LEVELS);
    if fits(l) {
        while l < MAX_LEVELS && fits(l + 1) {
            l += 1;
        }
    } else {
        while l > 1 && !fits(l) {
            l -= 1;
        }
    }
    GridGeometry::new(lo, hi, l)
}

/// Removes grid lights of zero intensity (all channels zero): they light nothing.
pub(crate) fn compact(levels: Vec<Level>) -> Vec<Level> {
    levels
        .into_par_iter()
        .map(|level| {
            let keep: Vec<usize> = (0..level.len())
                .filter(|&i| level.intensity[i].max_element() > 0.0)
                .collect();
            if keep.len() == level.len() {
                return level;
            }
            Level {
                vertex: keep.iter().map(|&i| level.vertex[i]).collect(),
                position: keep.iter().map(|&i| level.position[i]).collect(),
                intensity: keep.iter().map(|&i| level.intensity[i]).collect(),
                variance: keep.iter().map(|&i| level.variance[i]).collect(),
                normal: keep.iter().map(|&i| level.normal[i]).collect(),
                mass: keep.iter().map(|&i| level.mass[i]).collect(),
            }
        })
        .collect()
}

/// Concatenates the levels into one buffer with per-level offsets; variances become
/// deviations pi sigma.
pub(crate) fn merge(geometry: GridGeometry, levels: Vec<Level>) -> LightingGrid {
    let total: usize = levels.iter().map(Level::len).sum();
    let mut g = LightingGrid {
        geometry,
        level_start: Vec::with_capacity(levels.len() + 1),
        vertex: Vec::with_capacity(total),
        position: Vec::with_capacity(total),
        intensity: Vec::with_capacity(total),
        deviation: Vec::with_capacity(total),
        normal: Vec::with_capacity(total),
        mass: Vec::with_capacity(total),
    };
    g.level_start.push(0);
    for level in levels {
        g.vertex.extend(level.vertex);
        g.position.extend(level.position);
        g.intensity.extend(level.intensity);
        g.deviation.extend(
            level
                .variance
                .iter()
                .map(|v| v.max(Vec3::ZERO).powf(0.5) * std::f32::consts::PI),
        );
        g.normal.extend(level.normal);
        g.mass.extend(level.mass);
        g.level_start.push(g.position.len() as u32);
    }
    g
}
