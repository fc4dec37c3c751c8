//! The trilinear splat of one level (LGH 2019 section 3.1), parallel and deterministic.
//!
//! Each source light adds its trilinear weights w to the 8 vertices of its cell: weight W,
//! position, squared position, intensity and normal sums (design notes 3.1). On a GPU this is a
//! scatter with atomics; here it is organised so that no two tasks ever write the same
//! vertex, without atomics or locks:
//!
//! 1. every source gets its cell (c_x, c_y, c_z) and in-cell fraction f (parallel map);
//! 2. sources are bucketed by c_z with a stable counting sort (so each bucket keeps the input
//!    order);
//! 3. each vertex z-layer v_z is one task: the sources of cell layers v_z - 1 and v_z add
//!    their weights into a dense 2-D scratch grid private to the task, then the touched
//!    vertices are emitted in (y, x) order;
//! 4. layers are concatenated in z order.
//!
//! Every vertex thus receives its contributions in one fixed order (cell layer, then input
//! order), so the result does not depend on the number of threads. Positions are accumulated
//! relative to the receiving vertex, in cell units, which keeps the variance
//! Q/W - (P/W)^2 free of cancellation far from the origin.

use glam::{DVec3, UVec3, Vec3};
use rayon::prelude::*;

use super::geometry::GridGeometry;

/// The lights a level is built from: the input lights (S_0), or the grid lights of S_1 for
/// the gather construction. Optional arrays default to: no normal (zero), unit mass, zero
/// variance.
#[derive(Clone, Copy, Debug)]
pub struct Sources<'a> {
    /// Positions.
    pub positions: &'a [Vec3],
    /// RGB intensities.
    pub intensity: &'a [Vec3],
    /// Normals (oriented lights such as VPLs).
    pub normals: Option<&'a [Vec3]>,
    /// Mass of each source (the W of a grid light standing for several inputs).
    pub mass: Option<&'a [f32]>,
    /// Per-axis positional variance of each source (the spread of the inputs it stands for).
    pub variance: Option<&'a [Vec3]>,
}

/// The grid lights of one level in vertex order (z, then y, then x), before compaction.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Level {
    /// Integer vertex coordinates.
    pub vertex: Vec<UVec3>,
    /// Weighted mean position P/W.
    pub position: Vec<Vec3>,
    /// Weighted intensity sum (not divided by W: every level keeps the total).
    pub intensity: Vec<Vec3>,
    /// Per-axis positional variance Q/W - (P/W)^2.
    pub variance: Vec<Vec3>,
    /// Weighted mean normal M/W (not renormalised).
    pub normal: Vec<Vec3>,
    /// Total weight W (mass) of the vertex.
    pub mass: Vec<f32>,
}

impl Level {
    /// Number of grid lights.
    #[must_use]
    pub fn len(&self) -> usize {
        self.vertex.len()
    }

    /// True if there is none.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.vertex.is_empty()
    }

    fn push(&mut self, v: UVec3, a: &Accum, geom: &GridGeometry, level: u32) {
        let h = f64::from(geom.cell_size(level));
        let mean = a.p / a.w;
        self.vertex.push(v);
        self.position
            .push((geom.origin.as_dvec3() + (v.as_dvec3() + mean) * h).as_vec3());
        self.intensity.push(a.i.as_vec3());
        self.variance
            .push(((a.q / a.w - mean * mean).max(DVec3::ZERO) * (h * h)).as_vec3());
        self.normal.push((a.n / a.w).as_vec3());
        self.mass.push(a.w as f32);
    }

    fn append(&mut self, other: Level) {
        self.vertex.extend(other.vertex);
        self.position.extend(other.position);
        self.intensity.extend(other.intensity);
        self.variance.extend(other.variance);
        self.normal.extend(other.normal);
        self.mass.extend(other.mass);
    }
}

/// Sums of one vertex: W, P (local, cell units), Q (local, squared), intensity, normal.
/// Double precision: a coarse vertex sums millions of contributions, which f32 would round
/// to a relative error near 1e-4.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Accum {
    pub w: f64,
    pub p: DVec3,
    pub q: DVec3,
    pub i: DVec3,
    pub n: DVec3,
}

impl Accum {
    /// Adds prepared source `s` with trilinear weight `w`, at local offset `local` (cell
    /// units) from the vertex.
    #[inline(always)]
    fn add(&mut self, prep: &Prepared, s: usize, w: f32, local: Vec3) {
        let wm = f64::from(w * prep.mass[s]);
        let local = local.as_dvec3();
        self.w += wm;
        self.p += wm * local;
        self.q += wm * (local * local + prep.variance[s].as_dvec3());
        self.i += f64::from(w) * prep.intensity[s].as_dvec3();
        self.n += wm * prep.normal[s].as_dvec3();
    }

    /// Adds source `s` of `src` (unprepared) with weight `w` at local offset `local`;
    /// `inv_h2` converts the source's variance to cell units. For the reference builder.
    pub(crate) fn add_source(&mut self, src: &Sources, s: usize, w: f32, local: Vec3, inv_h2: f32) {
        let m = src.mass.map_or(1.0, |m| m[s]);
        let var = src
            .variance
            .map_or(Vec3::ZERO, |v| v[s] * inv_h2)
            .as_dvec3();
        let wm = f64::from(w * m);
        let local = local.as_dvec3();
        self.w += wm;
        self.p += wm * local;
        self.q += wm * (local * local + var);
        self.i += f64::from(w) * src.intensity[s].as_dvec3();
        if let Some(n) = src.normals {
            self.n += wm * n[s].as_dvec3();
        }
    }
}

/// Cell and in-cell fraction of a point at level spacing `h` with `r` cells per axis.
#[inline]
pub(crate) fn locate(p: Vec3, origin: Vec3, h: f32, r: u32) -> (UVec3, Vec3) {
    let u = (p - origin) / h;
    let c = u.floor().clamp(Vec3::ZERO, Vec3::splat((r - 1) as f32));
    ((c.as_uvec3()), (u - c).clamp(Vec3::ZERO, Vec3::ONE))
}

/// The 8 trilinear weights: for corner (dx, dy, dz), w = prod over axes of (d ? f : 1 - f).
#[inline]
pub(crate) fn corner_weight(f: Vec3, d: UVec3) -> f32 {
    let pick = |fa: f32, da: u32| if da == 1 { fa } else { 1.0 - fa };
    pick(f.x, d.x) * pick(f.y, d.y) * pick(f.z, d.z)
}

/// The sources of a level in bucket order: grouped by cell z (a stable counting sort), and
/// inside each z bucket sorted by (cell y, cell x, input index), so that a layer task sweeps
/// its scratch rows in order. Attributes are copied into that order (variances converted to
/// cell units) so that the hot loop reads memory sequentially.
struct Prepared {
    cell: Vec<UVec3>,
    frac: Vec<Vec3>,
    intensity: Vec<Vec3>,
    normal: Vec<Vec3>,
    mass: Vec<f32>,
    variance: Vec<Vec3>,
    /// Start of each z bucket (r + 1 entries).
    start: Vec<usize>,
    r: u32,
}

fn prepare(src: &Sources, geom: &GridGeometry, level: u32) -> Prepared {
    let h = geom.cell_size(level);
    let r = geom.cells_per_axis(level);
    let located: Vec<(UVec3, Vec3)> = src
        .positions
        .par_iter()
        .map(|&p| locate(p, geom.origin, h, r))
        .collect();
    let mut start = vec![0usize; r as usize + 1];
    for (c, _) in &located {
        start[c.z as usize + 1] += 1;
    }
    for z in 0..r as usize {
        start[z + 1] += start[z];
    }
    let mut next = start.clone();
    let mut order = vec![0u64; located.len()];
    for (i, (c, _)) in located.iter().enumerate() {
        let z = c.z as usize;
        // (y, x, index) packed so that sorting a bucket orders it by row, column, input order.
        order[next[z]] = (u64::from(c.y) << 54) | (u64::from(c.x) << 44) | i as u64;
        next[z] += 1;
    }
    let mut buckets: Vec<&mut [u64]> = Vec::with_capacity(r as usize);
    let mut rest = &mut order[..];
    for z in 0..r as usize {
        let (head, tail) = rest.split_at_mut(start[z + 1] - start[z]);
        buckets.push(head);
        rest = tail;
    }
    buckets.into_par_iter().for_each(|b| b.sort_unstable());
    let index = |k: u64| (k & ((1 << 44) - 1)) as usize;
    let inv_h2 = 1.0 / (h * h).max(f32::MIN_POSITIVE);
    let gather = |f: &(dyn Fn(usize) -> Vec3 + Sync)| -> Vec<Vec3> {
        order.par_iter().map(|&k| f(index(k))).collect()
    };
    Prepared {
        cell: order.par_iter().map(|&k| located[index(k)].0).collect(),
        frac: order.par_iter().map(|&k| located[index(k)].1).collect(),
        intensity: gather(&|i| src.intensity[i]),
        normal: match src.normals {
            Some(n) => gather(&|i| n[i]),
            None => vec![Vec3::ZERO; order.len()],
        },
        variance: match src.variance {
            Some(v) => gather(&|i| v[i] * inv_h2),
            None => vec![Vec3::ZERO; order.len()],
        },
        mass: order
            .par_iter()
            .map(|&k| src.mass.map_or(1.0, |m| m[index(k)]))
            .collect(),
        start,
        r,
    }
}

/// Calls `visit(index_in_layer, source, weight, local_offset)` for every non-zero
/// contribution to vertex layer `vz`, in the fixed order described in the module docs
/// (`source` indexes the prepared, bucket-ordered arrays).
#[inline(always)]
fn for_each_contribution(prep: &Prepared, vz: u32, mut visit: impl FnMut(usize, usize, f32, Vec3)) {
    let side = prep.r as usize + 1;
    let lo = vz.saturating_sub(1);
    let hi = vz.min(prep.r - 1);
    for cz in lo..=hi {
        let dz = vz - cz;
        for s in prep.start[cz as usize]..prep.start[cz as usize + 1] {
            let (c, f) = (prep.cell[s], prep.frac[s]);
            let wz = if dz == 1 { f.z } else { 1.0 - f.z };
            if wz <= 0.0 {
                continue;
            }
            let row = c.y as usize * side + c.x as usize;
            let wy = [1.0 - f.y, f.y];
            let wx = [1.0 - f.x, f.x];
            for (dy, wy) in wy.into_iter().enumerate() {
                for (dx, wx) in wx.into_iter().enumerate() {
                    let w = wx * wy * wz;
                    if w > 0.0 {
                        let local = f - Vec3::new(dx as f32, dy as f32, dz as f32);
                        visit(row + dy * side + dx, s, w, local);
                    }
                }
            }
        }
    }
}

/// Task-private scratch: a dense 2-D layer of sums with generation stamps, so that a layer
/// is reset in time proportional to what it touched. One per worker thread, kept between
/// builds (at most 513^2 entries, about 14 MB); its contents never leak between layers, so
/// which thread runs a layer cannot change the result.
#[derive(Default)]
struct Scratch {
    generation: u32,
    stamp: Vec<u32>,
    acc: Vec<Accum>,
    touched: Vec<u32>,
}

impl Scratch {
    fn begin(&mut self, cells: usize) {
        if self.stamp.len() < cells {
            self.stamp = vec![0; cells];
            self.acc = vec![Accum::default(); cells];
            self.generation = 0;
        }
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.stamp.fill(0);
            self.generation = 1;
        }
        self.touched.clear();
    }

    #[inline]
    fn touch(&mut self, idx: usize) -> &mut Accum {
        if self.stamp[idx] != self.generation {
            self.stamp[idx] = self.generation;
            self.acc[idx] = Accum::default();
            self.touched.push(idx as u32);
        }
        &mut self.acc[idx]
    }
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch::default());
}

fn with_scratch<T>(f: impl FnOnce(&mut Scratch) -> T) -> T {
    SCRATCH.with(|s| f(&mut s.borrow_mut()))
}

/// Builds the grid lights of `level` from `src` (see the module docs).
#[must_use]
pub fn splat(src: &Sources, geom: &GridGeometry, level: u32) -> Level {
    let prep = prepare(src, geom, level);
    let side = prep.r as usize + 1;
    let layers: Vec<Level> = (0..=prep.r)
        .into_par_iter()
        .map(|vz| {
            with_scratch(|scratch| {
                scratch.begin(side * side);
                for_each_contribution(&prep, vz, |idx, s, w, local| {
                    scratch.touch(idx).add(&prep, s, w, local);
                });
                let mut touched = std::mem::take(&mut scratch.touched);
                touched.sort_unstable();
                let mut out = Level::default();
                for &idx in &touched {
                    let v = UVec3::new(idx % side as u32, idx / side as u32, vz);
                    out.push(v, &scratch.acc[idx as usize], geom, level);
                }
                scratch.touched = touched;
                out
            })
        })
        .collect();
    let mut level_out = Level::default();
    for l in layers {
        level_out.append(l);
    }
    level_out
}

/// Number of vertices of `level` that receive a non-zero weight from `src` (the length of
/// [`splat`]'s result), counted with a shared bitset over all vertices of the level (one
/// atomic OR per contribution; the count does not depend on the order). Used to choose the
/// number of levels without building the candidates.
#[must_use]
pub fn count_vertices(src: &Sources, geom: &GridGeometry, level: u32) -> usize {
    use std::sync::atomic::{AtomicU64, Ordering};
    let h = geom.cell_size(level);
    let r = geom.cells_per_axis(level);
    let side = r as usize + 1;
    let bits: Vec<AtomicU64> = (0..(side * side * side).div_ceil(64))
        .map(|_| AtomicU64::new(0))
        .collect();
    src.positions.par_iter().for_each(|&p| {
        let (c, f) = locate(p, geom.origin, h, r);
        for dz in 0..2u32 {
            for dy in 0..2u32 {
                for dx in 0..2u32 {
                    let d = UVec3::new(dx, dy, dz);
                    if corner_weight(f, d) > 0.0 {
                        let v = c + d;
                        let idx = (v.z as usize * side + v.y as usize) * side + v.x as usize;
                        bits[idx / 64].fetch_or(1 << (idx % 64), Ordering::Relaxed);
                    }
                }
            }
        }
    });
    bits.par_iter()
        .map(|w| w.load(Ordering::Relaxed).count_ones() as usize)
        .sum()
}

/// Finishes accumulated sums into a level (shared with the reference builder).
pub(crate) fn level_from_sums(
    sums: impl IntoIterator<Item = (UVec3, Accum)>,
    geom: &GridGeometry,
    level: u32,
) -> Level {
    let mut out = Level::default();
    for (v, a) in sums {
        out.push(v, &a, geom, level);
    }
    out
}
