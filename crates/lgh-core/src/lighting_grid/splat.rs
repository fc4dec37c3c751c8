//! The trilinear splat of one level (LGH 2019 section 3.1), parallel and deterministic.
//!
//! Each source light adds its trilinear weights w to the 8 vertices of its cell: weight W,
//! position, squared position, intensity and normal sums (design notes 3.1). On a GPU this is a
//! scatter with atomics; here it is organised so that no two tasks ever write the same memory,
//! without atomics or locks:
//!
//! 1. every source gets its cell and in-cell fraction f, and is packed with its attributes
//!    into 40 bytes (plus 28 for the mass, variance and mean of a source that stands for
//!    several lights); the packed sources are sorted by cell row (z, then y) with a stable
//!    two-pass counting sort (input order is kept within a row). The sort is bound by memory
//!    bandwidth, so each pass buckets into a per-thread buffer that stays in the L2 cache
//!    and then copies it out in one stream (a restriction needs no sort at all; see
//!    `Workspace::gather_rows`);
//! 2. vertex row (v_y, v_z) receives from the sources of the four cell rows
//!    (v_y - 1 or v_y, v_z - 1 or v_z). Each vertex layer is cut into bands of consecutive
//!    vertex rows holding about [`BAND_SOURCES`] sources; a band task reads its cell rows in
//!    order and sums their contributions in a rolling pair of dense vertex rows (kept in the
//!    L2 cache), emitting each vertex row in x order once it is complete;
//! 3. bands are concatenated in (z, y) order, in parallel, so the level comes out in vertex
//!    order.
//!
//! A vertex's contributions arrive in an order fixed by the data (cell row y - 1 before y,
//! layer z - 1 before z, input order within a row), and the bands are cut by the data, not by
//! the thread pool, so the result does not depend on the number of threads. Each source's
//! moments are computed once per layer and shifted exactly to each corner. Positions are
//! accumulated relative to the receiving
//! vertex, in cell units and in double precision, which keeps the variance Q/W - (P/W)^2
//! free of cancellation far from the origin and the sums of coarse levels exact to ~1e-12.

use glam::{DVec3, UVec3, Vec3, Vec4};
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

    /// Appends the grid light of vertex `v` with sums `a` at a level of cell size `h` of a
    /// grid with origin `origin`.
    #[inline]
    fn push(&mut self, v: UVec3, a: &Accum, origin: DVec3, h: f64) {
        let inv_w = 1.0 / a.w();
        let mean = a.p() * inv_w;
        self.vertex.push(v);
        self.position
            .push((origin + (v.as_dvec3() + mean) * h).as_vec3());
        self.intensity.push(a.i().as_vec3());
        self.variance
            .push(((a.q() * inv_w - mean * mean).max(DVec3::ZERO) * (h * h)).as_vec3());
        self.normal.push((a.n() * inv_w).as_vec3());
        self.mass.push(a.w() as f32);
    }

    /// This level's grid lights as sources for a coarser level (the gather from S_1): each
    /// counts with its mass and its variance. `normals` says
    /// whether the input lights had normals.
    #[must_use]
    pub fn as_sources(&self, normals: bool) -> Sources<'_> {
        Sources {
            positions: &self.position,
            intensity: &self.intensity,
            normals: normals.then_some(&self.normal[..]),
            mass: Some(&self.mass),
            variance: Some(&self.variance),
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
}

/// Sums of one vertex: W, P (local, cell units), Q (local, squared), intensity, normal.
/// Double precision: a coarse vertex sums millions of contributions, which f32 would round
/// to a relative error near 1e-4. Stored as one padded array `[W, P, Q, I, N, 0, 0, 0]` so
/// that adding a weighted contribution is a plain loop the compiler vectorises.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Accum {
    s: [f64; 16],
}

impl Accum {
    fn from_parts(w: f64, p: DVec3, q: DVec3, i: DVec3, n: DVec3) -> Self {
        let mut s = [0.0; 16];
        s[0] = w;
        for (k, v) in [p, q, i, n].into_iter().enumerate() {
            s[1 + 3 * k..4 + 3 * k].copy_from_slice(&v.to_array());
        }
        Self { s }
    }

    fn part(&self, k: usize) -> DVec3 {
        DVec3::new(self.s[1 + 3 * k], self.s[2 + 3 * k], self.s[3 + 3 * k])
    }

    /// Total weight W.
    pub fn w(&self) -> f64 {
        self.s[0]
    }

    /// Weighted local position sum P.
    pub fn p(&self) -> DVec3 {
        self.part(0)
    }

    /// Weighted local squared position (plus variance) sum Q.
    pub fn q(&self) -> DVec3 {
        self.part(1)
    }

    /// Weighted intensity sum.
    pub fn i(&self) -> DVec3 {
        self.part(2)
    }

    /// Weighted normal sum.
    pub fn n(&self) -> DVec3 {
        self.part(3)
    }

    /// The moments of prepared source `ps` (with its cluster attributes `c`, if any) for a
    /// vertex at offset 0 from its cell: W = m, P = m g, Q = m (g^2 + var), intensity, m n,
    /// where a point source has m = 1, g = f and var = 0. A contribution is these times the
    /// trilinear weight ([`Accum::add_scaled`]); [`Accum::shifted`] moves them to another
    /// corner. Computed once per source and layer instead of once per corner.
    #[inline(always)]
    fn moments(ps: &PSource, c: Option<&Cluster>) -> Self {
        let (m, g, var) = c.map_or((1.0, ps.f, Vec3::ZERO), |c| (c.mass, c.g, c.variance));
        let (m, g) = (f64::from(m), g.as_dvec3());
        Self::from_parts(
            m,
            m * g,
            m * (g * g + var.as_dvec3()),
            ps.intensity.as_dvec3(),
            m * ps.normal.as_dvec3(),
        )
    }

    /// These moments seen from a vertex one cell further along `axis`: the local position g
    /// becomes g - 1 there, so P - W and Q - (2 P - W) (exact algebra:
    /// (g - 1)^2 = g^2 - 2 g + 1).
    #[inline(always)]
    fn shifted(&self, axis: usize) -> Self {
        let mut s = self.s;
        let (w, p) = (s[0], s[1 + axis]);
        s[1 + axis] = p - w;
        s[4 + axis] -= 2.0 * p - w;
        Self { s }
    }

    /// Adds moments `m` with trilinear weight `w`.
    #[inline(always)]
    fn add_scaled(&mut self, w: f64, m: &Self) {
        for (a, b) in self.s.iter_mut().zip(&m.s) {
            *a += w * b;
        }
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
        let n = src.normals.map_or(DVec3::ZERO, |n| wm * n[s].as_dvec3());
        self.add_scaled(
            1.0,
            &Self::from_parts(
                wm,
                wm * local,
                wm * (local * local + var),
                f64::from(w) * src.intensity[s].as_dvec3(),
                n,
            ),
        );
    }
}

/// Cell and in-cell fraction of a point at level spacing `h` with `r` cells per axis.
#[inline]
pub(crate) fn locate(p: Vec3, origin: Vec3, h: f32, r: u32) -> (UVec3, Vec3) {
    let u = (p - origin) / h;
    // Truncation after the clamp is the floor (the clamped value is not negative), without
    // the libm call that `floor` costs on baseline x86-64.
    let c = u.clamp(Vec3::ZERO, Vec3::splat((r - 1) as f32)).as_uvec3();
    (c, (u - c.as_vec3()).clamp(Vec3::ZERO, Vec3::ONE))
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

/// Source visits per task: consecutive vertex rows of one layer are grouped into a band
/// until the cell rows they read hold about this many sources. A single crowded row (the
/// coarsest levels of the all-scatter construction) is one band whatever its size.
pub const BAND_SOURCES: usize = 1 << 15;

/// Sources per task, at least, of the passes that go layer by layer: below this, a task
/// costs rayon more than it saves.
const LAYER_TASK_SOURCES: usize = 1 << 13;

/// Layers per task of a pass over `layers` layers of `n` sources in all (see
/// [`LAYER_TASK_SOURCES`]).
fn layers_per_task(n: usize, layers: usize) -> usize {
    (LAYER_TASK_SOURCES * layers / n.max(1)).max(1)
}

/// Sources per chunk of the parallel counting sort: a chunk's bucketed sources (320 KB, 544
/// KB with their cluster attributes) stay in the L2 cache.
const SORT_CHUNK: usize = 1 << 13;

/// One source, prepared for a level: its cell, in-cell fraction and attributes, packed so
/// that the hot loops read memory sequentially. Its cell layer z is the bucket it is stored
/// in. 40 bytes: the sort moves every source twice, and memory traffic is its cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct PSource {
    /// In-cell fraction that gives the trilinear weights.
    f: Vec3,
    /// Cell x and y (at most 2^([`MAX_LEVELS`] - 1) cells per axis).
    cell: [u16; 2],
    intensity: Vec3,
    normal: Vec3,
}

impl PSource {
    /// The cell's x and y (z is the layer the source is stored in).
    #[inline]
    fn cell_xy(&self) -> UVec3 {
        UVec3::new(u32::from(self.cell[0]), u32::from(self.cell[1]), 0)
    }
}

/// The attributes of a source that stands for several input lights (a grid light of a
/// finer level), kept apart from [`PSource`] so that the input lights of S_1, which have
/// none, do not carry them through the sort.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Cluster {
    /// In-cell position of the moments (P, Q): for a restriction, `PSource::f` is the fine
    /// vertex's fraction and `g` that of the fine grid light's mean position.
    g: Vec3,
    mass: f32,
    /// Positional variance in cell units.
    variance: Vec3,
}

/// Reusable working memory of the splat: a renderer that rebuilds its hierarchy every frame
/// keeps one, so that no step pays for fresh memory (page faults cost about as much as the
/// arithmetic here). After its sort by cell row, the sources of cell row (y, z) are
/// `src[row_start[z r + y]..row_start[z r + y + 1]]`, in input order.
#[derive(Debug, Default)]
pub struct Workspace {
    /// The sources bucketed by cell layer within each chunk of the input (first pass).
    staged: Vec<PSource>,
    staged_clusters: Vec<Cluster>,
    src: Vec<PSource>,
    /// Row starts of the fine level of a restriction ([`Workspace::gather_rows`]).
    fine_rows: Vec<usize>,
    /// The cluster attributes of `src` (same order), if the sources have any.
    clusters: Vec<Cluster>,
    has_clusters: bool,
    z_start: Vec<usize>,
    row_start: Vec<usize>,
    /// The grid, level and source count of the last sort.
    sorted: Option<(GridGeometry, u32, usize)>,
    bands: Vec<Band>,
    /// The grid lights of each band (kept for their memory).
    parts: Vec<Level>,
    r: u32,
}

/// Vertex rows `y0..y1` of vertex layer `z`: one task of the splat.
#[derive(Clone, Copy, Debug)]
struct Band {
    z: u32,
    y0: u32,
    y1: u32,
}

impl Workspace {
    /// Stable counting sort of the sources by cell row (z, then y) at `level`, in parallel,
    /// locating and packing each source on the way (its cell, in-cell fraction and
    /// attributes), then cuts the vertex layers into bands. Every chunk of the input
    /// counts its sources per cell layer, then packs them into its own range of `staged`,
    /// bucketed by layer (input order kept); then every layer counts its chunks' pieces by
    /// row and moves them, in chunk order, to its rows of `src`. The input is read in order
    /// and every move is of whole packed sources, so no pass gathers from random places.
    fn sort_by_row(&mut self, src: &Sources, geom: &GridGeometry, level: u32) {
        self.sort_by_row_with(src, geom, level, true);
    }

    /// [`Workspace::sort_by_row`], with the shortcut of [`Workspace::gather_rows`] for
    /// restrictions if `gather`.
    fn sort_by_row_with(&mut self, src: &Sources, geom: &GridGeometry, level: u32, gather: bool) {
        let h = geom.cell_size(level);
        let r = geom.cells_per_axis(level);
        self.r = r;
        let n = src.positions.len();
        self.sorted = Some((*geom, level, n));
        let locate_one = |i: usize| match src.finer_vertices {
            None => locate(src.positions[i], geom.origin, h, r),
            Some(v) => locate_finer_vertex(v[i], r),
        };
        // The cell layer alone, as `locate_one` finds it, for the count by layer.
        let top = (r - 1) as f32;
        let locate_z = |i: usize| match src.finer_vertices {
            None => ((src.positions[i].z - geom.origin.z) / h).clamp(0.0, top) as usize,
            Some(v) => (v[i].z / 2).min(r - 1) as usize,
        };
        let inv_h2 = 1.0 / (h * h).max(f32::MIN_POSITIVE);
        let has_clusters =
            src.finer_vertices.is_some() || src.mass.is_some() || src.variance.is_some();
        self.has_clusters = has_clusters;
        let pack_one = |i: usize| {
            let (cell, f) = locate_one(i);
            let ps = PSource {
                f,
                // Cells per axis are at most 2^(MAX_LEVELS - 1): the casts are exact.
                cell: [cell.x as u16, cell.y as u16],
                intensity: src.intensity[i],
                normal: src.normals.map_or(Vec3::ZERO, |n| n[i]),
            };
            let cluster = has_clusters.then(|| Cluster {
                g: if src.finer_vertices.is_some() {
                    (src.positions[i] - geom.origin) / h - cell.as_vec3()
                } else {
                    f
                },
                mass: src.mass.map_or(1.0, |m| m[i]),
                variance: src.variance.map_or(Vec3::ZERO, |v| v[i] * inv_h2),
            });
            (cell.z as usize, ps, cluster)
        };
        let r = r as usize;
        if gather
            && let Some(v) = src.finer_vertices
            && self.gather_rows(v, r, pack_one)
        {
            self.cut_bands();
            return;
        }
        self.staged.resize(n, PSource::default());
        self.staged_clusters
            .resize(if has_clusters { n } else { 0 }, Cluster::default());
        let cluster_chunks: Vec<Option<&mut [Cluster]>> = if has_clusters {
            self.staged_clusters
                .chunks_mut(SORT_CHUNK)
                .map(Some)
                .collect()
        } else {
            (0..n.div_ceil(SORT_CHUNK)).map(|_| None).collect()
        };
        let chunk_starts: Vec<Vec<usize>> = self
            .staged
            .par_chunks_mut(SORT_CHUNK)
            .zip(cluster_chunks)
            .enumerate()
            .map(|(ci, (out, mut out_clusters))| {
                let range = ci * SORT_CHUNK..ci * SORT_CHUNK + out.len();
                let mut start = vec![0usize; r + 1];
                for i in range.clone() {
                    start[locate_z(i) + 1] += 1;
                }
                for z in 0..r {
                    start[z + 1] += start[z];
                }
                // Bucketed in a per-thread scratch that stays in the L2 cache, then copied
                // out in one stream: written straight to `out`, the r interleaved streams
                // of the buckets each missed the cache line by line.
                let mut next = start.clone();
                with_scratch(|scratch, scratch_clusters| {
                    scratch.resize(out.len(), PSource::default());
                    if out_clusters.is_some() {
                        scratch_clusters.resize(out.len(), Cluster::default());
                    }
                    for i in range {
                        let (z, ps, cluster) = pack_one(i);
                        scratch[next[z]] = ps;
                        if let Some(c) = cluster {
                            scratch_clusters[next[z]] = c;
                        }
                        next[z] += 1;
                    }
                    out.copy_from_slice(&scratch[..out.len()]);
                    if let Some(oc) = out_clusters.as_deref_mut() {
                        oc.copy_from_slice(&scratch_clusters[..oc.len()]);
                    }
                });
                start
            })
            .collect();
        self.z_start.clear();
        self.z_start.resize(r + 1, 0);
        for z in 0..r {
            let count: usize = chunk_starts.iter().map(|st| st[z + 1] - st[z]).sum();
            self.z_start[z + 1] = self.z_start[z] + count;
        }
        self.src.resize(n, PSource::default());
        self.clusters
            .resize(if has_clusters { n } else { 0 }, Cluster::default());
        self.row_start.clear();
        self.row_start.resize(r * r + 1, 0);
        self.row_start[r * r] = n;
        let (z_start, staged, staged_clusters) =
            (&self.z_start, &self.staged, &self.staged_clusters);
        // Piece k of layer z: the staged indices of chunk k's sources in that layer.
        let pieces = |z: usize| {
            chunk_starts
                .iter()
                .enumerate()
                .map(move |(ci, st)| ci * SORT_CHUNK + st[z]..ci * SORT_CHUNK + st[z + 1])
        };
        let cluster_layers: Vec<Option<&mut [Cluster]>> = if has_clusters {
            split_buckets(&mut self.clusters, z_start)
                .into_iter()
                .map(Some)
                .collect()
        } else {
            (0..r).map(|_| None).collect()
        };
        split_buckets(&mut self.src, z_start)
            .into_par_iter()
            .zip(cluster_layers)
            .zip(self.row_start[..r * r].par_chunks_mut(r))
            .enumerate()
            .with_min_len(layers_per_task(n, r))
            .for_each(|(z, ((sorted, mut sorted_clusters), rows))| {
                let mut next = vec![0usize; r + 1];
                for piece in pieces(z) {
                    for ps in &staged[piece] {
                        next[usize::from(ps.cell[1]) + 1] += 1;
                    }
                }
                for y in 0..r {
                    next[y + 1] += next[y];
                }
                for (y, row) in rows.iter_mut().enumerate() {
                    *row = z_start[z] + next[y];
                }
                for piece in pieces(z) {
                    if let Some(sc) = sorted_clusters.as_deref_mut() {
                        for (ps, c) in staged[piece.clone()].iter().zip(&staged_clusters[piece]) {
                            let y = usize::from(ps.cell[1]);
                            sorted[next[y]] = *ps;
                            sc[next[y]] = *c;
                            next[y] += 1;
                        }
                    } else {
                        for ps in &staged[piece] {
                            let y = usize::from(ps.cell[1]);
                            sorted[next[y]] = *ps;
                            next[y] += 1;
                        }
                    }
                }
            });
        self.cut_bands();
    }

    /// The sort of [`Workspace::sort_by_row`] for the sources of a restriction whose fine
    /// vertices `v` are in vertex order (z, then y), as a [`Level`] keeps them: it is then a
    /// concatenation of row ranges of the input, so the sources are packed in one pass
    /// instead of the two of the counting sort. Cell row (Y, Z) holds the fine vertex rows
    /// (2Y + a, 2Z + b) for a, b in {0, 1}, and 2 on the last row or layer (the clamp puts
    /// the grid's last vertex in cell r - 1), in input order: b, then a. Returns false,
    /// doing nothing, if `v` is not in vertex order.
    fn gather_rows(
        &mut self,
        v: &[UVec3],
        r: usize,
        pack_one: impl Fn(usize) -> (usize, PSource, Option<Cluster>) + Sync,
    ) -> bool {
        let key = |u: &UVec3| (u.z, u.y);
        let in_grid = |u: &UVec3| u.max_element() as usize <= 2 * r;
        let in_order = v
            .par_windows(2)
            .with_min_len(LAYER_TASK_SOURCES)
            .all(|w| key(&w[0]) <= key(&w[1]));
        if !in_order || !v.par_iter().with_min_len(LAYER_TASK_SOURCES).all(in_grid) {
            return false;
        }
        // Fine vertex row (y, z) is v[fine_rows[z side + y]..fine_rows[z side + y + 1]].
        let side = 2 * r + 1;
        self.fine_rows.resize(side * side + 1, 0);
        self.fine_rows[side * side] = v.len();
        self.fine_rows[..side * side]
            .par_chunks_mut(side)
            .enumerate()
            .with_min_len(layers_per_task(v.len(), side))
            .for_each(|(z, rows)| {
                let lo = v.partition_point(|u| (u.z as usize) < z);
                let hi = v.partition_point(|u| (u.z as usize) <= z);
                rows.fill(0);
                for u in &v[lo..hi] {
                    rows[u.y as usize] += 1;
                }
                let mut start = lo;
                for row in rows {
                    (*row, start) = (start, start + *row);
                }
            });
        let fine_rows = &self.fine_rows;
        // The fine rows (or layers) of cell row (or layer) c.
        let fine = |c: usize| 2 * c..if c + 1 == r { 2 * c + 3 } else { 2 * c + 2 };
        let ranges = |y: usize, z: usize| {
            fine(z).flat_map(move |fz| {
                fine(y).map(move |fy| fine_rows[fz * side + fy]..fine_rows[fz * side + fy + 1])
            })
        };
        self.row_start.clear();
        self.row_start.resize(r * r + 1, 0);
        self.z_start.clear();
        self.z_start.resize(r + 1, 0);
        let mut start = 0;
        for z in 0..r {
            self.z_start[z] = start;
            for y in 0..r {
                self.row_start[z * r + y] = start;
                start += ranges(y, z).map(|range| range.len()).sum::<usize>();
            }
        }
        self.z_start[r] = start;
        self.row_start[r * r] = start;
        let n = v.len();
        self.src.resize(n, PSource::default());
        self.clusters.resize(n, Cluster::default());
        split_buckets(&mut self.src, &self.z_start)
            .into_par_iter()
            .zip(split_buckets(&mut self.clusters, &self.z_start))
            .enumerate()
            .with_min_len(layers_per_task(n, r))
            .for_each(|(z, (out, out_clusters))| {
                let sources = (0..r).flat_map(|y| ranges(y, z)).flatten();
                for (k, i) in sources.enumerate() {
                    let (_, ps, cluster) = pack_one(i);
                    out[k] = ps;
                    out_clusters[k] = cluster.unwrap_or_default();
                }
            });
        true
    }

    /// The packed sources of cell layer `z`, in row order.
    fn layer(&self, z: u32) -> &[PSource] {
        &self.src[self.z_start[z as usize]..self.z_start[z as usize + 1]]
    }
}

/// `v` cut into the consecutive buckets `z_start[z]..z_start[z + 1]`.
fn split_buckets<'a, T>(v: &'a mut [T], z_start: &[usize]) -> Vec<&'a mut [T]> {
    split_lengths(v, z_start.windows(2).map(|w| w[1] - w[0]))
}

/// `v` cut into consecutive pieces of the given lengths.
fn split_lengths<T>(mut rest: &mut [T], lengths: impl Iterator<Item = usize>) -> Vec<&mut [T]> {
    let mut out = Vec::with_capacity(lengths.size_hint().0);
    for len in lengths {
        let (head, tail) = std::mem::take(&mut rest).split_at_mut(len);
        out.push(head);
        rest = tail;
    }
    out
}

impl Workspace {
    /// The indices in `src` of the sources of cell row (`y`, `z`); empty outside the grid.
    fn cell_row(&self, y: u32, z: u32) -> std::ops::Range<usize> {
        if y >= self.r || z >= self.r {
            return 0..0;
        }
        let k = (z * self.r + y) as usize;
        self.row_start[k]..self.row_start[k + 1]
    }

    /// Number of sources that can reach vertex row (`y`, `z`) through cell row `y` (the
    /// rows y - 1 are counted with the vertex row before).
    fn row_load(&self, y: u32, z: u32) -> usize {
        self.cell_row(y, z).len() + z.checked_sub(1).map_or(0, |zm| self.cell_row(y, zm).len())
    }

    /// Cuts every vertex layer into bands of consecutive vertex rows of about
    /// [`BAND_SOURCES`] source visits. The cut depends only on the data, never on the thread
    /// pool.
    fn cut_bands(&mut self) {
        let mut bands = std::mem::take(&mut self.bands);
        bands.clear();
        for z in 0..=self.r {
            let mut y0 = 0;
            let mut load = 0;
            for y in 0..=self.r {
                let l = self.row_load(y, z);
                if y > y0 && load + l > BAND_SOURCES {
                    bands.push(Band { z, y0, y1: y });
                    y0 = y;
                    load = 0;
                }
                load += l;
            }
            bands.push(Band {
                z,
                y0,
                y1: self.r + 1,
            });
        }
        self.bands = bands;
    }

    /// Sweeps band `b`: every source of the cell rows that reach its vertex rows adds its
    /// non-zero trilinear contributions to a two-row rolling buffer, and every vertex row is
    /// handed to `emit` (its touched vertices in x order) once complete. A vertex receives its
    /// contributions in a fixed order (cell row y - 1 before y, layer z - 1 before z, input
    /// order within a row), so the sums do not depend on the thread that runs the band.
    /// `CLUSTERS` must be `has_clusters` (a constant, so that point sources compile to a loop
    /// that does not look for cluster attributes).
    #[inline(always)]
    fn sweep<const CLUSTERS: bool>(
        &self,
        b: Band,
        rows: &mut RowPair,
        mut emit: impl FnMut(UVec3, &Accum),
    ) {
        let side = self.r as usize + 1;
        rows.fit(side);
        let layers = [(b.z.wrapping_sub(1), 1.0f32), (b.z, 0.0f32)];
        for cy in b.y0.saturating_sub(1)..b.y1.min(self.r) {
            let (low, high) = rows.split();
            for (cz, dz) in layers {
                for k in self.cell_row(cy, cz) {
                    let ps = &self.src[k];
                    let wz = if dz == 1.0 { ps.f.z } else { 1.0 - ps.f.z };
                    if wz <= 0.0 {
                        continue;
                    }
                    let m = Accum::moments(ps, CLUSTERS.then(|| &self.clusters[k]));
                    let m = if dz == 1.0 { m.shifted(2) } else { m };
                    // Vertex row cy (dy = 0) if it is in the band, cy + 1 (dy = 1) if it is.
                    if cy >= b.y0 {
                        add_row(low, ps, wz * (1.0 - ps.f.y), &m);
                    }
                    if cy + 1 < b.y1 {
                        add_row(high, ps, wz * ps.f.y, &m.shifted(1));
                    }
                }
            }
            if cy >= b.y0 {
                low.drain(|x, a| emit(UVec3::new(x, cy, b.z), a));
            }
            rows.swap();
        }
        // The last vertex row of the grid (y = r) is complete after cell row r - 1.
        if b.y1 == self.r + 1 {
            let (low, _) = rows.split();
            low.drain(|x, a| emit(UVec3::new(x, self.r, b.z), a));
        }
    }
}

/// Adds source `ps` (moments `m` at the row's x = cell x vertex) to a vertex row with its
/// y-z weight `wyz`, at both x corners.
#[inline(always)]
fn add_row(row: &mut Row, ps: &PSource, wyz: f32, m: &Accum) {
    if wyz <= 0.0 {
        return;
    }
    let x = usize::from(ps.cell[0]);
    let w0 = (1.0 - ps.f.x) * wyz;
    if w0 > 0.0 {
        row.at(x).add_scaled(f64::from(w0), m);
    }
    let w1 = ps.f.x * wyz;
    if w1 > 0.0 {
        row.at(x + 1).add_scaled(f64::from(w1), &m.shifted(0));
    }
}

/// One vertex row of sums, dense in x, with one bit per vertex that says whether it was
/// touched, so that reading the row out in x order and clearing it cost what was touched.
/// At most 513 entries (about 66 KB): it stays in the L2 cache, where a dense 2-D layer
/// would not.
#[derive(Default)]
struct Row {
    acc: Vec<Accum>,
    hit: Vec<u64>,
}

impl Row {
    #[inline(always)]
    fn at(&mut self, x: usize) -> &mut Accum {
        self.hit[x / 64] |= 1 << (x % 64);
        &mut self.acc[x]
    }

    /// Hands the touched vertices to `f` in x order with their sums, and clears them.
    #[inline(always)]
    fn drain(&mut self, mut f: impl FnMut(u32, &Accum)) {
        for (w, word) in self.hit.iter_mut().enumerate() {
            let mut bits = std::mem::take(word);
            while bits != 0 {
                let x = w * 64 + bits.trailing_zeros() as usize;
                f(x as u32, &self.acc[x]);
                self.acc[x] = Accum::default();
                bits &= bits - 1;
            }
        }
    }
}

/// The rolling buffer of [`Workspace::sweep`]: the vertex rows cy and cy + 1 of the cell
/// row being read. One per worker thread, kept between builds; it is left clear after every
/// band, so which thread runs a band cannot change the result.
#[derive(Default)]
struct RowPair {
    rows: [Row; 2],
    low: usize,
}

impl RowPair {
    fn fit(&mut self, side: usize) {
        for row in &mut self.rows {
            if row.acc.len() < side {
                row.acc.resize(side, Accum::default());
                row.hit.resize(side.div_ceil(64), 0);
            }
        }
    }

    fn split(&mut self) -> (&mut Row, &mut Row) {
        let [a, b] = &mut self.rows;
        if self.low == 0 { (a, b) } else { (b, a) }
    }

    fn swap(&mut self) {
        self.low ^= 1;
    }
}

thread_local! {
    static ROWS: std::cell::RefCell<RowPair> = std::cell::RefCell::new(RowPair::default());
}

fn with_rows<T>(f: impl FnOnce(&mut RowPair) -> T) -> T {
    ROWS.with(|s| f(&mut s.borrow_mut()))
}

thread_local! {
    static SCRATCH: std::cell::RefCell<(Vec<PSource>, Vec<Cluster>)> =
        const { std::cell::RefCell::new((Vec::new(), Vec::new())) };
}

/// The per-thread buffers a chunk of the sort is bucketed in.
fn with_scratch<T>(f: impl FnOnce(&mut Vec<PSource>, &mut Vec<Cluster>) -> T) -> T {
    SCRATCH.with(|s| {
        let (a, b) = &mut *s.borrow_mut();
        f(a, b)
    })
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
    ws.sort_by_row(src, geom, level);
    sweep_into(ws, geom, level, out);
}

/// [`splat_into`] right after [`count_vertices`] of the same `src` at the same `level` of the
/// same `geom`: the count's sort (which packed the sources) is reused. (The number of levels
/// is chosen by counting; the level kept is then built without sorting again.)
pub(crate) fn splat_counted_into(
    ws: &mut Workspace,
    src: &Sources,
    geom: &GridGeometry,
    level: u32,
    out: &mut Level,
) {
    if ws.sorted != Some((*geom, level, src.positions.len())) {
        ws.sort_by_row(src, geom, level);
    }
    sweep_into(ws, geom, level, out);
}

/// Sweeps the bands of a prepared workspace into `out`.
/// Each band writes its own part (kept in `ws` between builds), and the parts are then
/// copied to their places in `out` in parallel.
fn sweep_into(ws: &mut Workspace, geom: &GridGeometry, level: u32, out: &mut Level) {
    let mut parts = std::mem::take(&mut ws.parts);
    parts.resize_with(ws.bands.len(), Level::default);
    let w = &*ws;
    parts
        .par_iter_mut()
        .zip(w.bands.par_iter())
        .for_each(|(part, &b)| {
            part.clear();
            with_rows(|rows| sweep_band(w, b, rows, geom, level, part));
        });
    let used = &parts[..ws.bands.len()];
    let n = used.iter().map(Level::len).sum();
    concat_into(used, n, &mut out.vertex, |p| &p.vertex);
    concat_into(used, n, &mut out.position, |p| &p.position);
    concat_into(used, n, &mut out.intensity, |p| &p.intensity);
    concat_into(used, n, &mut out.variance, |p| &p.variance);
    concat_into(used, n, &mut out.normal, |p| &p.normal);
    concat_into(used, n, &mut out.mass, |p| &p.mass);
    ws.parts = parts;
}

/// Writes field `get` of the `parts` (`n` elements in all) one after the other into `out`,
/// in parallel.
fn concat_into<T: Copy + Default + Send + Sync>(
    parts: &[Level],
    n: usize,
    out: &mut Vec<T>,
    get: impl Fn(&Level) -> &[T] + Sync,
) {
    out.resize(n, T::default());
    let places = split_lengths(out, parts.iter().map(|p| get(p).len()));
    let copy = |(dst, p): (&mut [T], &Level)| dst.copy_from_slice(get(p));
    // Below this, a parallel loop costs more than it saves.
    if n < 1 << 15 {
        places.into_iter().zip(parts).for_each(copy);
    } else {
        places.into_par_iter().zip(parts).for_each(copy);
    }
}

/// [`Workspace::sweep`] of band `b` into the grid lights `part`, compiled also for AVX2 with
/// FMA (chosen at run time): a contribution adds 16 weighted doubles to a vertex, which is
/// eight SSE2 multiply-adds without them and four FMAs with them.
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
fn sweep_band(
    ws: &Workspace,
    b: Band,
    rows: &mut RowPair,
    geom: &GridGeometry,
    level: u32,
    part: &mut Level,
) {
    let (origin, h) = (geom.origin.as_dvec3(), f64::from(geom.cell_size(level)));
    let emit = |v, a: &Accum| part.push(v, a, origin, h);
    if ws.has_clusters {
        ws.sweep::<true>(b, rows, emit);
    } else {
        ws.sweep::<false>(b, rows, emit);
    }
}

/// Builds the grid lights of `level` from `src` with fresh working memory.
#[must_use]
pub fn splat(src: &Sources, geom: &GridGeometry, level: u32) -> Level {
    let mut out = Level::default();
    splat_into(&mut Workspace::default(), src, geom, level, &mut out);
    out
}

/// Number of vertices of `level` that receive a non-zero weight from `src` (the length of
/// [`splat`]'s result, before compaction), without computing their grid lights: after the
/// same sort, one task per vertex layer marks the vertices it touches in a bit set of the
/// layer (33 KB at 512 cells per axis: it stays in the L1 cache), with the same weight
/// products as the splat, so the same weights are zero. Used to choose the number of levels.
/// The sort stays in `ws`, so that building the level next does not sort again.
pub fn count_vertices(ws: &mut Workspace, src: &Sources, geom: &GridGeometry, level: u32) -> usize {
    ws.sort_by_row(src, geom, level);
    count_sorted::<false>(ws).0
}

/// [`count_vertices`], and the same count at the same `level` of the next finer geometry
/// (l_max + 1: twice the cells per axis) from the same sort and in the same pass over the
/// sources (`None` for a restriction's sources, whose fine vertices have no finer cell).
///
/// A source in cell c with fraction f lies in the finer cell 2c + b with fraction 2f - b, b =
/// [2f >= 1], per axis. Both are exact in floating point and equal to locating it on the
/// finer grid directly (whose spacing is exactly half), so the same weights are zero.
pub fn count_vertices_and_finer(
    ws: &mut Workspace,
    src: &Sources,
    geom: &GridGeometry,
    level: u32,
) -> (usize, Option<usize>) {
    ws.sort_by_row(src, geom, level);
    if src.finer_vertices.is_some() {
        return (count_sorted::<false>(ws).0, None);
    }
    let (n, finer) = count_sorted::<true>(ws);
    (n, Some(finer))
}

/// The vertex counts of the sort in `ws` (and, if `FINER`, of the grid twice as fine). One
/// task per layer m counts vertex layer m from the sources of cell layers m - 1 and m, and
/// the finer vertex layers 2m (from the same sources) and 2m + 1 (from layer m): each source
/// is read twice.
///
/// A source strictly inside its cell (see [`interior`]) gives all 8 corners a non-zero
/// weight, so it only marks its cell; the layer's marked cells are then dilated to their
/// corners row by row ([`LayerBits::count_with_corners`]). Only the other sources (on a
/// cell face) mark their corners one by one, with the sweep's weight products.
fn count_sorted<const FINER: bool>(ws: &Workspace) -> (usize, usize) {
    let r = ws.r as usize;
    let fine_side = if FINER { 2 * r + 1 } else { 0 };
    // Finer cell and fraction of x and y: t = 2f, b = [t >= 1], cell 2c + b, fraction t - b,
    // in SSE lanes (a scalar comparison becomes a branch, mispredicted half the time).
    let finer_xy = |c: UVec3, f: Vec3| {
        let t = Vec4::new(f.x, f.y, 0.0, 0.0) * 2.0;
        let upper = t.cmpge(Vec4::ONE);
        let b = upper.bitmask();
        let fine = t - Vec4::select(upper, Vec4::ONE, Vec4::ZERO);
        (
            UVec3::new(2 * c.x + (b & 1), 2 * c.y + ((b >> 1) & 1), 0),
            Vec3::new(fine.x, fine.y, 0.0),
        )
    };
    (0..ws.r + 1)
        .into_par_iter()
        .with_min_len(layers_per_task(ws.src.len(), r))
        .map(|m| {
            let sides = [r + 1, r + 1, fine_side, fine_side, fine_side, fine_side];
            count_layers(
                sides,
                |[
                    mut cells,
                    mut corners,
                    mut even_cells,
                    mut even,
                    mut odd_cells,
                    mut odd,
                ]| {
                    // With t = 2 f_z, a source of cell layer m lies in the finer cell layer 2m
                    // (t < 1, fraction t) or 2m + 1 (t >= 1, fraction t - 1), and its z weights
                    // follow without asking which: max(0, t - 1) in finer vertex layer 2m + 2,
                    // min(t, 2 - t) in 2m + 1, max(0, 1 - t) in 2m (the same values as
                    // 1 - fraction and fraction, exactly).
                    if m > 0 {
                        for ps in ws.layer(m - 1) {
                            let c = ps.cell_xy();
                            if interior(ps.f) {
                                cells.set(c, true);
                            } else {
                                corners.mark(c, ps.f, ps.f.z);
                            }
                            if FINER {
                                let (c, fxy) = finer_xy(c, ps.f);
                                let t = 2.0 * ps.f.z;
                                let upper = t >= 1.0;
                                if interior(fxy.with_z(t - f32::from(upper))) {
                                    even_cells.set(c, upper);
                                } else {
                                    even.mark(c, fxy, (t - 1.0).max(0.0));
                                }
                            }
                        }
                    }
                    if m < ws.r {
                        for ps in ws.layer(m) {
                            let c = ps.cell_xy();
                            if interior(ps.f) {
                                cells.set(c, true);
                            } else {
                                corners.mark(c, ps.f, 1.0 - ps.f.z);
                            }
                            if FINER {
                                let (c, fxy) = finer_xy(c, ps.f);
                                let t = 2.0 * ps.f.z;
                                let upper = t >= 1.0;
                                if interior(fxy.with_z(t - f32::from(upper))) {
                                    even_cells.set(c, !upper);
                                    odd_cells.set(c, true);
                                } else {
                                    even.mark(c, fxy, (1.0 - t).max(0.0));
                                    odd.mark(c, fxy, t.min(2.0 - t));
                                }
                            }
                        }
                    }
                    let n = corners.count_with_corners(&cells);
                    let n_finer = if FINER {
                        even.count_with_corners(&even_cells) + odd.count_with_corners(&odd_cells)
                    } else {
                        0
                    };
                    (n, n_finer)
                },
            )
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// True if every trilinear weight of a source with in-cell fraction `f` is non-zero: each
/// factor f or 1 - f is at least 2^-40 (1 - f is at least 2^-24 once f < 1 in f32), so a
/// product of three is at least 2^-120, above the smallest normal f32 (2^-126).
#[inline]
fn interior(f: Vec3) -> bool {
    const MIN: f32 = 1.0 / (1u64 << 40) as f32;
    f.min_element() >= MIN && f.max_element() < 1.0
}

/// `N` bit sets of `sides[k]` rows of `sides[k]` bits (see [`LayerBits`]), cleared, handed
/// to `visit`.
fn count_layers<const N: usize, T>(
    sides: [usize; N],
    visit: impl FnOnce([LayerBits; N]) -> T,
) -> T {
    with_bits(|bits| {
        let row_words = sides.map(|side| side.div_ceil(64));
        let words: [usize; N] = std::array::from_fn(|k| sides[k] * row_words[k]);
        bits.clear();
        bits.resize(words.iter().sum(), 0);
        let mut rest: &mut [u64] = bits;
        let mut k = 0;
        let layers: [LayerBits; N] = std::array::from_fn(|_| {
            let (layer, tail) = std::mem::take(&mut rest).split_at_mut(words[k]);
            rest = tail;
            k += 1;
            LayerBits {
                bits: layer,
                row_words: row_words[k - 1],
            }
        });
        visit(layers)
    })
}

/// The vertices (or cells) of one layer marked so far, one bit each, row by row: bit x of
/// row y is bit x % 64 of word y * row_words + x / 64.
struct LayerBits<'a> {
    bits: &'a mut [u64],
    row_words: usize,
}

impl LayerBits<'_> {
    /// Sets the bit of (`c.x`, `c.y`) if `on`, without a branch.
    #[inline]
    fn set(&mut self, c: UVec3, on: bool) {
        let (x, y) = (c.x as usize, c.y as usize);
        self.bits[y * self.row_words + x / 64] |= u64::from(on) << (x % 64);
    }

    /// Marks the layer's vertices of cell `c` (x, y) that a source with fraction `f` (x, y)
    /// and z weight `wz` gives a non-zero weight: the same products as the sweep's, so that
    /// the same weights are zero. Without branches: every corner's word is written.
    #[inline]
    fn mark(&mut self, c: UVec3, f: Vec3, wz: f32) {
        for (dy, wy) in [1.0 - f.y, f.y].into_iter().enumerate() {
            let wyz = wz * wy;
            for (dx, wx) in [1.0 - f.x, f.x].into_iter().enumerate() {
                let hit = (wyz > 0.0) & (wx * wyz > 0.0);
                self.set(c + UVec3::new(dx as u32, dy as u32, 0), hit);
            }
        }
    }

    /// Number of vertices marked here or a corner of a cell marked in `cells`: vertex
    /// (x, y) is a corner of cells x - 1 and x of rows y - 1 and y.
    fn count_with_corners(&self, cells: &LayerBits) -> usize {
        let w = self.row_words;
        let rows = self.bits.len() / w.max(1);
        let cell_row = |y: usize| &cells.bits[y * w..(y + 1) * w];
        let mut n = 0;
        for y in 0..rows {
            let mut carry = 0;
            for k in 0..w {
                let c = if y > 0 { cell_row(y - 1)[k] } else { 0 } | cell_row(y)[k];
                let corners = c | c << 1 | carry;
                carry = c >> 63;
                n += (corners | self.bits[y * w + k]).count_ones() as usize;
            }
        }
        n
    }
}

thread_local! {
    static BITS: std::cell::RefCell<Vec<u64>> = const { std::cell::RefCell::new(Vec::new()) };
}

fn with_bits<T>(f: impl FnOnce(&mut Vec<u64>) -> T) -> T {
    BITS.with(|s| f(&mut s.borrow_mut()))
}

/// Finishes accumulated sums into a level (shared with the reference builder).
pub(crate) fn level_from_sums(
    sums: impl IntoIterator<Item = (UVec3, Accum)>,
    geom: &GridGeometry,
    level: u32,
) -> Level {
    let mut out = Level::default();
    let (origin, h) = (geom.origin.as_dvec3(), f64::from(geom.cell_size(level)));
    for (v, a) in sums {
        out.push(v, &a, origin, h);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unit-mass point sources without normals.
    fn point_sources<'a>(positions: &'a [Vec3], intensity: &'a [Vec3]) -> Sources<'a> {
        Sources {
            positions,
            intensity,
            normals: None,
            mass: None,
            variance: None,
            finer_vertices: None,
        }
    }

    /// The restriction's shortcut ([`Workspace::gather_rows`]) sorts exactly as the counting
    /// sort does, and is not taken for vertices out of vertex order.
    #[test]
    fn restriction_rows_match_the_counting_sort() {
        let mut rng = Rng::new(&[3, 5]);
        let positions: Vec<Vec3> = (0..5000)
            .map(|_| Vec3::new(rng.next_f32(), rng.next_f32() * 0.3, rng.next_f32()) * 4.0)
            .collect();
        let intensity = vec![Vec3::ONE; positions.len()];
        let src = point_sources(&positions, &intensity);
        for l_max in 2..=6 {
            let geom = GridGeometry::new(Vec3::ZERO, Vec3::splat(4.0), l_max);
            let fine = splat(&src, &geom, 1);
            let restriction = fine.as_restriction_sources(false);
            let (mut gathered, mut sorted) = (Workspace::default(), Workspace::default());
            gathered.sort_by_row_with(&restriction, &geom, 2, true);
            sorted.sort_by_row_with(&restriction, &geom, 2, false);
            assert!(gathered.staged.is_empty(), "the shortcut was not taken");
            assert_eq!(gathered.row_start, sorted.row_start, "l_max {l_max}");
            assert_eq!(gathered.z_start, sorted.z_start);
            assert_eq!(gathered.src, sorted.src);
            assert_eq!(gathered.clusters, sorted.clusters);
            // Out of order: the counting sort.
            let mut reversed = fine.vertex.clone();
            reversed.reverse();
            let shuffled = Sources {
                finer_vertices: Some(&reversed),
                ..restriction
            };
            let mut ws = Workspace::default();
            ws.sort_by_row_with(&shuffled, &geom, 2, true);
            assert_eq!(ws.staged.len(), fine.len());
        }
    }
    use crate::lighting_grid::geometry::MAX_LEVELS;
    use crate::rng::Rng;

    /// The vertex count agrees with the splat, for positions and for the vertices of a
    /// finer grid (restriction), whose fractions are exactly 0, 1/2 or 1: the zero weights
    /// must not count.
    #[test]
    fn count_vertices_matches_the_splat() {
        let mut rng = Rng::new(&[7, 11]);
        let (lo, hi) = (Vec3::ZERO, Vec3::splat(4.0));
        let mut ws = Workspace::default();
        let positions: Vec<Vec3> = (0..3000)
            .map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0)
            .collect();
        let intensity = vec![Vec3::ONE; positions.len()];
        for l_max in 1..=6 {
            let geom = GridGeometry::new(lo, hi, l_max);
            let fine = 2 * geom.cells_per_axis(1);
            let vertices: Vec<UVec3> = (0..positions.len())
                .map(|_| {
                    UVec3::new(
                        rng.next_u32() % (fine + 1),
                        rng.next_u32() % (fine + 1),
                        rng.next_u32() % 3,
                    )
                })
                .collect();
            let src = point_sources(&positions, &intensity);
            let restriction = Sources {
                finer_vertices: Some(&vertices),
                ..src
            };
            for s in [src, restriction] {
                let n = count_vertices(&mut ws, &s, &geom, 1);
                assert_eq!(n, splat(&s, &geom, 1).len(), "l_max {l_max}");
                let (both, finer) = count_vertices_and_finer(&mut ws, &s, &geom, 1);
                assert_eq!(both, n, "l_max {l_max}");
                assert_eq!(finer.is_none(), s.finer_vertices.is_some());
            }
            // The count at l_max + 1 from this sort, against a sort at l_max + 1. Some
            // positions on the cell boundaries of the finer grid (fractions 0 and 1/2).
            if l_max < MAX_LEVELS {
                let mut on_edges = positions.clone();
                for (i, p) in on_edges.iter_mut().enumerate().take(500) {
                    let h = geom.cell_size(1) / 2.0;
                    let snapped = ((*p - geom.origin) / h).floor() * h + geom.origin;
                    *p = if i % 2 == 0 {
                        snapped
                    } else {
                        Vec3::new(snapped.x, p.y, snapped.z)
                    };
                }
                let s = Sources {
                    positions: &on_edges,
                    ..src
                };
                let finer = GridGeometry {
                    l_max: l_max + 1,
                    ..geom
                };
                let expected = splat(&s, &finer, 1).len();
                let (n, n_finer) = count_vertices_and_finer(&mut ws, &s, &geom, 1);
                assert_eq!(n, splat(&s, &geom, 1).len(), "l_max {l_max}");
                assert_eq!(n_finer, Some(expected), "l_max {l_max}");
            }
        }
    }
}
