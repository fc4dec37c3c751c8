//! The trilinear splat of one level (LGH 2019 section 3.1), parallel and deterministic.
//!
//! Each source light adds its trilinear weights w to the 8 vertices of its cell: weight W,
//! position, squared position, intensity and normal sums (design notes 3.1). On a GPU this is a
//! scatter with atomics; here it is organised so that no two tasks ever write the same memory,
//! without atomics or locks:
//!
//! 1. every source gets its cell and in-cell fraction f (parallel map);
//! 2. sources are bucketed by cell z with a stable counting sort; unordered inputs (S_0) are
//!    also sorted by (cell y, cell x) inside each bucket for memory locality (S_1 lights come
//!    out of their own build in vertex order already), and their attributes are packed in
//!    that order;
//! 3. vertex layer v_z receives from the sources of cell layers v_z - 1 and v_z, which are one
//!    contiguous range; the range is cut into chunks of [`CHUNK`] sources, and each
//!    (layer, chunk) task sums its contributions in a private dense 2-D scratch grid;
//! 4. each layer adds its chunks' partial sums in chunk order, and layers are concatenated in
//!    z order, each in (y, x) order.
//!
//! The chunk boundaries are fixed by the data, not by the thread pool, so the result does not
//! depend on the number of threads. Positions are accumulated relative to the receiving
//! vertex, in cell units and in double precision, which keeps the variance Q/W - (P/W)^2
//! free of cancellation far from the origin and the sums of coarse levels exact to ~1e-12.

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
    /// True if the sources are already in vertex order of a finer grid (the lights of S_1):
    /// the locality sort is skipped.
    pub ordered: bool,
    /// For the restriction from the next finer level: the sources' integer vertex
    /// coordinates there. The trilinear weights then come from the vertex (fractions 0, 1/2
    /// or 1, exactly), while the moments use the source's position; see
    /// [`Level::as_restriction_sources`].
    pub finer_vertices: Option<&'a [UVec3]>,
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

    /// This level's grid lights as sources for a coarser level (the gather from S_1): each
    /// counts with its mass and its variance, and is already in vertex order. `normals` says
    /// whether the input lights had normals.
    #[must_use]
    pub fn as_sources(&self, normals: bool) -> Sources<'_> {
        Sources {
            positions: &self.position,
            intensity: &self.intensity,
            normals: normals.then_some(&self.normal[..]),
            mass: Some(&self.mass),
            variance: Some(&self.variance),
            ordered: true,
            finer_vertices: None,
        }
    }

    /// This level's grid lights as the sources of the next coarser level by exact
    /// restriction. A hat function of spacing 2h is a sum of hats of spacing h with weights
    /// (1/2, 1, 1/2) at the fine vertices, so a coarse vertex's sums (W, P, Q, intensity,
    /// normal) are the fine vertices' sums weighted by the trilinear weights *of the fine
    /// vertices* (the 3x3x3 stencil (1/2, 1, 1/2)^3). The result equals splatting the input
    /// lights at the coarse level (the all-scatter hierarchy) up to rounding, at the cost of
    /// splatting |S_(l-1)| sources instead of |S_0|. Must be taken before compaction: a
    /// zero-intensity vertex still carries mass.
    #[must_use]
    pub fn as_restriction_sources(&self, normals: bool) -> Sources<'_> {
        Sources {
            finer_vertices: Some(&self.vertex),
            ..self.as_sources(normals)
        }
    }

    pub(crate) fn truncate(&mut self, n: usize) {
        self.vertex.truncate(n);
        self.position.truncate(n);
        self.intensity.truncate(n);
        self.variance.truncate(n);
        self.normal.truncate(n);
        self.mass.truncate(n);
    }

    fn clear(&mut self) {
        self.vertex.clear();
        self.position.clear();
        self.intensity.clear();
        self.variance.clear();
        self.normal.clear();
        self.mass.clear();
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
    /// Adds prepared source `ps` with trilinear weight `w`, whose moment position is at
    /// local offset `local` (cell units) from the vertex.
    #[inline(always)]
    fn add(&mut self, ps: &PSource, w: f32, local: Vec3) {
        let wm = f64::from(w * ps.mass);
        let local = local.as_dvec3();
        self.w += wm;
        self.p += wm * local;
        self.q += wm * (local * local + ps.variance.as_dvec3());
        self.i += f64::from(w) * ps.intensity.as_dvec3();
        self.n += wm * ps.normal.as_dvec3();
    }

    /// Adds another partial sum.
    #[inline]
    fn merge(&mut self, o: &Accum) {
        self.w += o.w;
        self.p += o.p;
        self.q += o.q;
        self.i += o.i;
        self.n += o.n;
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

/// Cell and in-cell fraction (0, 1/2 or 1 per axis, exactly) of vertex `v` of the next finer
/// grid (2r cells per axis) in a grid of `r` cells per axis.
#[inline]
pub(crate) fn locate_finer_vertex(v: UVec3, r: u32) -> (UVec3, Vec3) {
    let c = (v / 2).min(UVec3::splat(r - 1));
    (c, (v - 2 * c).as_vec3() * 0.5)
}

/// The 8 trilinear weights: for corner (dx, dy, dz), w = prod over axes of (d ? f : 1 - f).
#[inline]
pub(crate) fn corner_weight(f: Vec3, d: UVec3) -> f32 {
    let pick = |fa: f32, da: u32| if da == 1 { fa } else { 1.0 - fa };
    pick(f.x, d.x) * pick(f.y, d.y) * pick(f.z, d.z)
}

/// Sources per task: a layer with more sources is split into chunks whose partial sums are
/// added in chunk order.
pub const CHUNK: usize = 1 << 15;

/// Sources per chunk of the parallel counting sort.
const SORT_CHUNK: usize = 1 << 16;

/// One source, prepared for a level: its cell, in-cell fraction and attributes, packed so
/// that the hot loop reads memory sequentially (variance in cell units).
#[derive(Clone, Copy, Debug, Default)]
struct PSource {
    /// In-cell fraction that gives the trilinear weights.
    f: Vec3,
    /// In-cell position of the moments (P, Q): `f`, except for a restriction, where `f` is
    /// the fine vertex's fraction and `g` that of the fine grid light's mean position.
    g: Vec3,
    cell: UVec3,
    intensity: Vec3,
    normal: Vec3,
    mass: f32,
    variance: Vec3,
}

/// Reusable working memory of the splat: a renderer that rebuilds its hierarchy every frame
/// keeps one, so that no step pays for fresh memory (page faults cost about as much as the
/// arithmetic here). After [`Workspace::prepare`], bucket z of the prepared sources is
/// `src[start[z]..start[z + 1]]`.
#[derive(Debug, Default)]
pub struct Workspace {
    located: Vec<(UVec3, Vec3)>,
    order: Vec<u64>,
    src: Vec<PSource>,
    start: Vec<usize>,
    r: u32,
}

impl Workspace {
    /// Locates and buckets the sources; with `pack`, also sorts the buckets (unordered
    /// sources) and packs the attributes (not needed to count vertices).
    fn prepare(&mut self, src: &Sources, geom: &GridGeometry, level: u32, pack: bool) {
        let h = geom.cell_size(level);
        let r = geom.cells_per_axis(level);
        self.r = r;
        match src.finer_vertices {
            None => src
                .positions
                .par_iter()
                .map(|&p| locate(p, geom.origin, h, r))
                .collect_into_vec(&mut self.located),
            Some(v) => v
                .par_iter()
                .map(|&v| locate_finer_vertex(v, r))
                .collect_into_vec(&mut self.located),
        }
        // Stable counting sort by cell z, in parallel: every chunk of sources buckets itself
        // (keeping input order), then every z bucket concatenates the chunks' pieces in chunk
        // order. The packed key (y, x, index) lets a later sort order a bucket by row, column
        // and input order.
        let nz = r as usize;
        let local: Vec<(Vec<u64>, Vec<usize>)> = self
            .located
            .par_chunks(SORT_CHUNK)
            .enumerate()
            .map(|(ci, chunk)| {
                let mut start = vec![0usize; nz + 1];
                for (c, _) in chunk {
                    start[c.z as usize + 1] += 1;
                }
                for z in 0..nz {
                    start[z + 1] += start[z];
                }
                let mut next = start.clone();
                let mut keys = vec![0u64; chunk.len()];
                for (k, (c, _)) in chunk.iter().enumerate() {
                    let i = (ci * SORT_CHUNK + k) as u64;
                    let z = c.z as usize;
                    keys[next[z]] = (u64::from(c.y) << 54) | (u64::from(c.x) << 44) | i;
                    next[z] += 1;
                }
                (keys, start)
            })
            .collect();
        self.start.clear();
        self.start.resize(nz + 1, 0);
        for z in 0..nz {
            let count: usize = local.iter().map(|(_, st)| st[z + 1] - st[z]).sum();
            self.start[z + 1] = self.start[z] + count;
        }
        self.order.clear();
        self.order.resize(self.located.len(), 0);
        let mut buckets: Vec<&mut [u64]> = Vec::with_capacity(nz);
        let mut rest = &mut self.order[..];
        for z in 0..nz {
            let (head, tail) = rest.split_at_mut(self.start[z + 1] - self.start[z]);
            buckets.push(head);
            rest = tail;
        }
        let sort = pack && !src.ordered;
        buckets.into_par_iter().enumerate().for_each(|(z, bucket)| {
            let mut at = 0;
            for (keys, st) in &local {
                let piece = &keys[st[z]..st[z + 1]];
                bucket[at..at + piece.len()].copy_from_slice(piece);
                at += piece.len();
            }
            if sort {
                bucket.sort_unstable();
            }
        });
        if !pack {
            return;
        }
        let inv_h2 = 1.0 / (h * h).max(f32::MIN_POSITIVE);
        let located = &self.located;
        let restriction = src.finer_vertices.is_some();
        self.order
            .par_iter()
            .map(|&k| {
                let i = (k & ((1 << 44) - 1)) as usize;
                let (cell, f) = located[i];
                let g = if restriction {
                    (src.positions[i] - geom.origin) / h - cell.as_vec3()
                } else {
                    f
                };
                PSource {
                    f,
                    g,
                    cell,
                    intensity: src.intensity[i],
                    normal: src.normals.map_or(Vec3::ZERO, |n| n[i]),
                    mass: src.mass.map_or(1.0, |m| m[i]),
                    variance: src.variance.map_or(Vec3::ZERO, |v| v[i] * inv_h2),
                }
            })
            .collect_into_vec(&mut self.src);
    }

    /// The contiguous range of prepared sources that can reach vertex layer `vz`.
    fn layer_sources(&self, vz: u32) -> std::ops::Range<usize> {
        self.start[vz.saturating_sub(1) as usize]..self.start[(vz + 1).min(self.r) as usize]
    }
}

/// Calls `visit(index_in_layer, weight, local_offset)` for each non-zero contribution of
/// prepared source `ps` to vertex layer `vz` (at most 4: the source's cell layer is vz - 1 or
/// vz).
#[inline(always)]
fn contributions(ps: &PSource, vz: u32, side: usize, mut visit: impl FnMut(usize, f32, Vec3)) {
    let dz = vz.wrapping_sub(ps.cell.z);
    if dz > 1 {
        return;
    }
    let f = ps.f;
    let g = ps.g;
    let wz = if dz == 1 { f.z } else { 1.0 - f.z };
    if wz <= 0.0 {
        return;
    }
    let row = ps.cell.y as usize * side + ps.cell.x as usize;
    let wy = [1.0 - f.y, f.y];
    let wx = [1.0 - f.x, f.x];
    for (dy, wy) in wy.into_iter().enumerate() {
        for (dx, wx) in wx.into_iter().enumerate() {
            let w = wx * wy * wz;
            if w > 0.0 {
                let local = g - Vec3::new(dx as f32, dy as f32, dz as f32);
                visit(row + dy * side + dx, w, local);
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
    fn mark(&mut self, idx: usize) {
        if self.stamp[idx] != self.generation {
            self.stamp[idx] = self.generation;
            self.touched.push(idx as u32);
        }
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

/// Builds the grid lights of `level` from `src` into `out` (see the module docs), using
/// (and growing) the working memory `ws`.
pub fn splat_into(
    ws: &mut Workspace,
    src: &Sources,
    geom: &GridGeometry,
    level: u32,
    out: &mut Level,
) {
    ws.prepare(src, geom, level, true);
    let ws = &*ws;
    let side = ws.r as usize + 1;
    let layers: Vec<Level> = (0..=ws.r)
        .into_par_iter()
        .map(|vz| {
            let range = ws.layer_sources(vz);
            let mut part = Level::default();
            if range.len() <= CHUNK {
                with_scratch(|scratch| {
                    accumulate(scratch, &ws.src[range], vz, side);
                    for &idx in &scratch.touched {
                        part.push(
                            vertex_of(idx, side, vz),
                            &scratch.acc[idx as usize],
                            geom,
                            level,
                        );
                    }
                });
                return part;
            }
            // A crowded layer (coarse levels): chunks in parallel, partial sums added in chunk
            // order (stable sort keeps equal vertices in chunk order).
            let mut sums: Vec<(u32, Accum)> = ws.src[range]
                .par_chunks(CHUNK)
                .map(|chunk| {
                    with_scratch(|scratch| {
                        accumulate(scratch, chunk, vz, side);
                        scratch
                            .touched
                            .iter()
                            .map(|&i| (i, scratch.acc[i as usize]))
                            .collect::<Vec<_>>()
                    })
                })
                .flatten_iter()
                .collect();
            sums.sort_by_key(|(idx, _)| *idx);
            let mut i = 0;
            while i < sums.len() {
                let (idx, mut sum) = sums[i];
                let mut j = i + 1;
                while j < sums.len() && sums[j].0 == idx {
                    sum.merge(&sums[j].1);
                    j += 1;
                }
                part.push(vertex_of(idx, side, vz), &sum, geom, level);
                i = j;
            }
            part
        })
        .collect();
    out.clear();
    for l in layers {
        out.append(l);
    }
}

/// Adds the contributions of `sources` to vertex layer `vz` into a fresh scratch layer and
/// sorts its touched list.
fn accumulate(scratch: &mut Scratch, sources: &[PSource], vz: u32, side: usize) {
    scratch.begin(side * side);
    for ps in sources {
        contributions(ps, vz, side, |idx, w, local| {
            scratch.touch(idx).add(ps, w, local);
        });
    }
    scratch.touched.sort_unstable();
}

#[inline]
fn vertex_of(idx: u32, side: usize, vz: u32) -> UVec3 {
    UVec3::new(idx % side as u32, idx / side as u32, vz)
}

/// Builds the grid lights of `level` from `src` with fresh working memory.
#[must_use]
pub fn splat(src: &Sources, geom: &GridGeometry, level: u32) -> Level {
    let mut out = Level::default();
    splat_into(&mut Workspace::default(), src, geom, level, &mut out);
    out
}

/// Number of vertices of `level` that receive a non-zero weight from `src` (the length of
/// [`splat`]'s result, before compaction), without computing them: one task per vertex layer
/// marks the touched vertices in its scratch. Used to choose the number of levels.
pub fn count_vertices(ws: &mut Workspace, src: &Sources, geom: &GridGeometry, level: u32) -> usize {
    ws.prepare(src, geom, level, false);
    let ws = &*ws;
    let side = ws.r as usize + 1;
    (0..=ws.r)
        .into_par_iter()
        .map(|vz| {
            with_scratch(|scratch| {
                scratch.begin(side * side);
                for &k in &ws.order[ws.layer_sources(vz)] {
                    let (cell, f) = ws.located[(k & ((1 << 44) - 1)) as usize];
                    let ps = PSource {
                        f,
                        cell,
                        ..PSource::default()
                    };
                    contributions(&ps, vz, side, |idx, _, _| scratch.mark(idx));
                }
                scratch.touched.len()
            })
        })
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
