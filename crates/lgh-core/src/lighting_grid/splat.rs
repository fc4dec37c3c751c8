//! The trilinear splat of one level (LGH 2019 section 3.1), parallel and deterministic.
//!
//! Each source light adds its trilinear weights w to the 8 vertices of its cell: weight W,
//! position, squared position, intensity and normal sums (design notes 3.1). On a GPU this is a
//! scatter with atomics; here it is organised so that no two tasks ever write the same memory,
//! without atomics or locks:
//!
//! 1. every source gets its cell and in-cell fraction f, and the sources are sorted by cell
//!    row (z, then y) with a stable two-pass counting sort (input order is kept within a
//!    row); their attributes are then packed in that order;
//! 2. vertex row (v_y, v_z) receives from the sources of the four cell rows
//!    (v_y - 1 or v_y, v_z - 1 or v_z). Each vertex layer is cut into bands of consecutive
//!    vertex rows holding about [`BAND_SOURCES`] sources; a band task reads its cell rows in
//!    order and sums their contributions in a rolling pair of dense vertex rows (kept in the
//!    L2 cache), emitting each vertex row in x order once it is complete;
//! 3. bands are concatenated in (z, y) order, so the level comes out in vertex order.
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

    fn push(&mut self, v: UVec3, a: &Accum, geom: &GridGeometry, level: u32) {
        let h = f64::from(geom.cell_size(level));
        let mean = a.p() / a.w();
        self.vertex.push(v);
        self.position
            .push((geom.origin.as_dvec3() + (v.as_dvec3() + mean) * h).as_vec3());
        self.intensity.push(a.i().as_vec3());
        self.variance
            .push(((a.q() / a.w() - mean * mean).max(DVec3::ZERO) * (h * h)).as_vec3());
        self.normal.push((a.n() / a.w()).as_vec3());
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

    /// The moments of prepared source `ps` for a vertex at offset 0 from its cell: W = m,
    /// P = m g, Q = m (g^2 + var), intensity, m n. A contribution is these times the
    /// trilinear weight ([`Accum::add_scaled`]); [`Accum::shifted`] moves them to another
    /// corner. Computed once per source and layer instead of once per corner.
    #[inline(always)]
    fn moments(ps: &PSource) -> Self {
        let m = f64::from(ps.mass);
        let g = ps.g.as_dvec3();
        Self::from_parts(
            m,
            m * g,
            m * (g * g + ps.variance.as_dvec3()),
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

/// Sources per chunk of the parallel counting sort.
const SORT_CHUNK: usize = 1 << 16;

/// One source, prepared for a level: its cell x, in-cell fraction and attributes, packed so
/// that the hot loop reads memory sequentially (variance in cell units). Its cell row (y, z)
/// is where it is stored.
#[derive(Clone, Copy, Debug, Default)]
struct PSource {
    /// In-cell fraction that gives the trilinear weights.
    f: Vec3,
    /// In-cell position of the moments (P, Q): `f`, except for a restriction, where `f` is
    /// the fine vertex's fraction and `g` that of the fine grid light's mean position.
    g: Vec3,
    cell_x: u32,
    intensity: Vec3,
    normal: Vec3,
    mass: f32,
    variance: Vec3,
}

/// Reusable working memory of the splat: a renderer that rebuilds its hierarchy every frame
/// keeps one, so that no step pays for fresh memory (page faults cost about as much as the
/// arithmetic here). After [`Workspace::prepare`], the sources of cell row (y, z) are
/// `src[row_start[z r + y]..row_start[z r + y + 1]]`, in input order.
#[derive(Debug, Default)]
pub struct Workspace {
    by_row: Vec<Located>,
    src: Vec<PSource>,
    z_start: Vec<usize>,
    row_start: Vec<usize>,
    /// The grid, level and source count of the last sort.
    sorted: Option<(GridGeometry, u32, usize)>,
    bands: Vec<Band>,
    r: u32,
}

/// A located source as the sorts move it: its cell, in-cell fraction and input index, so
/// that the passes after a sort read memory in order.
#[derive(Clone, Copy, Debug, Default)]
struct Located {
    cell: UVec3,
    f: Vec3,
    index: u32,
}

/// Vertex rows `y0..y1` of vertex layer `z`: one task of the splat.
#[derive(Clone, Copy, Debug)]
struct Band {
    z: u32,
    y0: u32,
    y1: u32,
}

impl Workspace {
    /// Locates the sources, sorts them by cell row (stable: input order within a row), packs
    /// their attributes in that order, and cuts the vertex layers into bands.
    fn prepare(&mut self, src: &Sources, geom: &GridGeometry, level: u32) {
        self.sort_by_row(src, geom, level);
        self.pack(src, geom, level);
    }

    /// Packs the attributes of the sources in the order of the last sort (which must have
    /// been of `src` at `level` of `geom`), then cuts the vertex layers into bands.
    fn pack(&mut self, src: &Sources, geom: &GridGeometry, level: u32) {
        let h = geom.cell_size(level);
        let inv_h2 = 1.0 / (h * h).max(f32::MIN_POSITIVE);
        let restriction = src.finer_vertices.is_some();
        self.by_row
            .par_iter()
            .map(|&Located { cell, f, index }| {
                let i = index as usize;
                let g = if restriction {
                    (src.positions[i] - geom.origin) / h - cell.as_vec3()
                } else {
                    f
                };
                PSource {
                    f,
                    g,
                    cell_x: cell.x,
                    intensity: src.intensity[i],
                    normal: src.normals.map_or(Vec3::ZERO, |n| n[i]),
                    mass: src.mass.map_or(1.0, |m| m[i]),
                    variance: src.variance.map_or(Vec3::ZERO, |v| v[i] * inv_h2),
                }
            })
            .collect_into_vec(&mut self.src);
        self.cut_bands();
    }

    /// Stable counting sort of the sources by cell row (z, then y) at `level`, in parallel,
    /// locating each source on the way (its cell and in-cell fraction). Every chunk of
    /// sources locates itself and buckets itself by z (keeping input order); then every z
    /// bucket counts its chunks' pieces by y and scatters them, in chunk order, to its rows.
    /// Fills `by_row`, `z_start` and `row_start`.
    fn sort_by_row(&mut self, src: &Sources, geom: &GridGeometry, level: u32) {
        let h = geom.cell_size(level);
        let r = geom.cells_per_axis(level);
        self.r = r;
        let n = src.positions.len();
        self.sorted = Some((*geom, level, n));
        let locate_one = |i: usize| match src.finer_vertices {
            None => locate(src.positions[i], geom.origin, h, r),
            Some(v) => locate_finer_vertex(v[i], r),
        };
        let r = r as usize;
        let local: Vec<(Vec<Located>, Vec<usize>)> = (0..n.div_ceil(SORT_CHUNK))
            .into_par_iter()
            .map(|ci| {
                let range = ci * SORT_CHUNK..((ci + 1) * SORT_CHUNK).min(n);
                let located: Vec<Located> = range
                    .map(|i| {
                        let (cell, f) = locate_one(i);
                        Located {
                            cell,
                            f,
                            index: i as u32,
                        }
                    })
                    .collect();
                let mut start = vec![0usize; r + 1];
                for l in &located {
                    start[l.cell.z as usize + 1] += 1;
                }
                for z in 0..r {
                    start[z + 1] += start[z];
                }
                let mut next = start.clone();
                let mut bucketed = vec![Located::default(); located.len()];
                for l in located {
                    let z = l.cell.z as usize;
                    bucketed[next[z]] = l;
                    next[z] += 1;
                }
                (bucketed, start)
            })
            .collect();
        self.z_start.clear();
        self.z_start.resize(r + 1, 0);
        for z in 0..r {
            let count: usize = local.iter().map(|(_, st)| st[z + 1] - st[z]).sum();
            self.z_start[z + 1] = self.z_start[z] + count;
        }
        self.by_row.clear();
        self.by_row.resize(n, Located::default());
        self.row_start.clear();
        self.row_start.resize(r * r + 1, 0);
        self.row_start[r * r] = n;
        let z_start = &self.z_start;
        split_buckets(&mut self.by_row, z_start)
            .into_par_iter()
            .zip(self.row_start[..r * r].par_chunks_mut(r))
            .enumerate()
            .for_each(|(z, (sorted, rows))| {
                let pieces = || local.iter().flat_map(|(b, st)| &b[st[z]..st[z + 1]]);
                let mut next = vec![0usize; r + 1];
                for l in pieces() {
                    next[l.cell.y as usize + 1] += 1;
                }
                for y in 0..r {
                    next[y + 1] += next[y];
                }
                for (y, row) in rows.iter_mut().enumerate() {
                    *row = z_start[z] + next[y];
                }
                for l in pieces() {
                    let y = l.cell.y as usize;
                    sorted[next[y]] = *l;
                    next[y] += 1;
                }
            });
    }
}

/// `v` cut into the consecutive buckets `z_start[z]..z_start[z + 1]`.
fn split_buckets<'a, T>(mut rest: &'a mut [T], z_start: &[usize]) -> Vec<&'a mut [T]> {
    let mut out = Vec::with_capacity(z_start.len() - 1);
    for w in z_start.windows(2) {
        let (head, tail) = rest.split_at_mut(w[1] - w[0]);
        out.push(head);
        rest = tail;
    }
    out
}

impl Workspace {
    /// The prepared sources of cell row (`y`, `z`); empty outside the grid.
    fn cell_row(&self, y: u32, z: u32) -> &[PSource] {
        if y >= self.r || z >= self.r {
            return &[];
        }
        let k = (z * self.r + y) as usize;
        &self.src[self.row_start[k]..self.row_start[k + 1]]
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
    /// handed to `emit` (touched vertices in x order) once complete. A vertex receives its
    /// contributions in a fixed order (cell row y - 1 before y, layer z - 1 before z, input
    /// order within a row), so the sums do not depend on the thread that runs the band.
    #[inline(always)]
    fn sweep(&self, b: Band, rows: &mut RowPair, mut emit: impl FnMut(u32, &mut Row)) {
        let side = self.r as usize + 1;
        rows.fit(side);
        let layers = [(b.z.wrapping_sub(1), 1.0f32), (b.z, 0.0f32)];
        for cy in b.y0.saturating_sub(1)..b.y1.min(self.r) {
            let (low, high) = rows.split();
            for (cz, dz) in layers {
                for ps in self.cell_row(cy, cz) {
                    let wz = if dz == 1.0 { ps.f.z } else { 1.0 - ps.f.z };
                    if wz <= 0.0 {
                        continue;
                    }
                    let m = Accum::moments(ps);
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
                emit(cy, low);
                low.clear();
            }
            rows.swap();
        }
        // The last vertex row of the grid (y = r) is complete after cell row r - 1.
        if b.y1 == self.r + 1 {
            let (low, _) = rows.split();
            emit(self.r, low);
            low.clear();
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
    let x = ps.cell_x as usize;
    let w0 = (1.0 - ps.f.x) * wyz;
    if w0 > 0.0 {
        row.at(x).add_scaled(f64::from(w0), m);
    }
    let w1 = ps.f.x * wyz;
    if w1 > 0.0 {
        row.at(x + 1).add_scaled(f64::from(w1), &m.shifted(0));
    }
}

/// One vertex row of sums, dense in x, with the list of vertices touched so that clearing
/// costs what was touched. At most 513 entries (about 53 KB): it stays in the L2 cache,
/// where a dense 2-D layer would not.
#[derive(Default)]
struct Row {
    acc: Vec<Accum>,
    hit: Vec<bool>,
    touched: Vec<u32>,
}

impl Row {
    #[inline(always)]
    fn at(&mut self, x: usize) -> &mut Accum {
        if !self.hit[x] {
            self.hit[x] = true;
            self.touched.push(x as u32);
        }
        &mut self.acc[x]
    }

    /// The touched vertices in x order with their sums.
    fn sorted(&mut self) -> impl Iterator<Item = (u32, &Accum)> {
        self.touched.sort_unstable();
        self.touched.iter().map(|&x| (x, &self.acc[x as usize]))
    }

    fn clear(&mut self) {
        for &x in &self.touched {
            self.acc[x as usize] = Accum::default();
            self.hit[x as usize] = false;
        }
        self.touched.clear();
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
                row.hit.resize(side, false);
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

/// Builds the grid lights of `level` from `src` into `out` (see the module docs), using
/// (and growing) the working memory `ws`.
pub fn splat_into(
    ws: &mut Workspace,
    src: &Sources,
    geom: &GridGeometry,
    level: u32,
    out: &mut Level,
) {
    ws.prepare(src, geom, level);
    sweep_into(ws, geom, level, out);
}

/// [`splat_into`] right after [`count_vertices`] of the same `src` at the same `level` of the
/// same `geom`: the count's sort is reused, only the attributes are packed. (The number of
/// levels is chosen by counting; the level kept is then built without sorting again.)
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
    ws.pack(src, geom, level);
    sweep_into(ws, geom, level, out);
}

/// Sweeps the bands of a prepared workspace into `out`.
fn sweep_into(ws: &Workspace, geom: &GridGeometry, level: u32, out: &mut Level) {
    let parts: Vec<Level> = ws
        .bands
        .par_iter()
        .map(|&b| {
            let mut part = Level::default();
            with_rows(|rows| sweep_band(ws, b, rows, geom, level, &mut part));
            part
        })
        .collect();
    out.clear();
    for p in parts {
        out.append(p);
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
    ws.sweep(b, rows, |y, row| {
        for (x, a) in row.sorted() {
            part.push(UVec3::new(x, y, b.z), a, geom, level);
        }
    });
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
pub fn count_vertices(ws: &mut Workspace, src: &Sources, geom: &GridGeometry, level: u32) -> usize {
    ws.sort_by_row(src, geom, level);
    let ws = &*ws;
    let r = ws.r;
    (0..=r)
        .into_par_iter()
        .map(|vz| {
            let from = ws.z_start[vz.saturating_sub(1) as usize];
            let to = ws.z_start[(vz + 1).min(r) as usize];
            count_layer(r + 1, |layer| {
                for &Located { cell: c, f, .. } in &ws.by_row[from..to] {
                    let wz = if c.z == vz { 1.0 - f.z } else { f.z };
                    layer.mark(c, f, wz);
                }
            })
        })
        .sum()
}

/// [`count_vertices`] of the same sources at the same `level` of the next finer geometry
/// (l_max + 1: twice the cells per axis), from the sort that the last count or build at
/// `level` of `geom` left in `ws`, without sorting again: `None` if `ws` holds another sort,
/// or the sources are a restriction's.
///
/// A source in cell c with fraction f lies in the finer cell 2c + b with fraction 2f - b, b =
/// [2f >= 1], per axis. Both are exact in floating point and equal to locating it on the
/// finer grid directly (whose spacing is exactly half), so the same weights are zero. One
/// task per coarse cell layer m marks the finer vertex layers 2m (from the sources of
/// coarse layers m - 1 and m) and 2m + 1 (from layer m): each source is read twice, as in
/// [`count_vertices`], and marks without branching on its finer z, which is a coin toss.
#[must_use]
pub fn count_vertices_finer(
    ws: &Workspace,
    src: &Sources,
    geom: &GridGeometry,
    level: u32,
) -> Option<usize> {
    if ws.sorted != Some((*geom, level, src.positions.len())) || src.finer_vertices.is_some() {
        return None;
    }
    let r = ws.r;
    let side = 2 * r + 1;
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
    let slab = |m: u32| &ws.by_row[ws.z_start[m as usize]..ws.z_start[m as usize + 1]];
    Some(
        (0..=r)
            .into_par_iter()
            .map(|m| {
                count_layers(side, |[even, odd]: &mut [LayerBits; 2]| {
                    // With t = 2 f_z, a source of coarse layer m lies in the finer cell layer
                    // 2m (t < 1, fraction t) or 2m + 1 (t >= 1, fraction t - 1), and its z
                    // weights follow without asking which: max(0, t - 1) in finer vertex
                    // layer 2m + 2, min(t, 2 - t) in 2m + 1, max(0, 1 - t) in 2m (the same
                    // values as 1 - fraction and fraction, exactly).
                    if m > 0 {
                        for &Located { cell, f, .. } in slab(m - 1) {
                            let (c, fxy) = finer_xy(cell, f);
                            even.mark(c, fxy, (2.0 * f.z - 1.0).max(0.0));
                        }
                    }
                    if m < r {
                        for &Located { cell, f, .. } in slab(m) {
                            let (c, fxy) = finer_xy(cell, f);
                            let t = 2.0 * f.z;
                            even.mark(c, fxy, (1.0 - t).max(0.0));
                            odd.mark(c, fxy, t.min(2.0 - t));
                        }
                    }
                })
            })
            .sum(),
    )
}

/// Vertices of one layer (`side` x `side` vertices) marked by `visit` (see
/// [`LayerBits::mark`]).
fn count_layer(side: u32, visit: impl FnOnce(&mut LayerBits)) -> usize {
    count_layers(side, |[layer]: &mut [LayerBits; 1]| visit(layer))
}

/// Vertices of `N` layers (`side` x `side` vertices each) marked by `visit`.
fn count_layers<const N: usize>(side: u32, visit: impl FnOnce(&mut [LayerBits; N])) -> usize {
    with_bits(|bits| {
        let side = side as usize;
        let words = (side * side).div_ceil(64);
        bits.clear();
        bits.resize(N * words, 0);
        let mut rest: &mut [u64] = bits;
        let mut layers: [LayerBits; N] = std::array::from_fn(|_| {
            let (layer, tail) = std::mem::take(&mut rest).split_at_mut(words);
            rest = tail;
            LayerBits { bits: layer, side }
        });
        visit(&mut layers);
        bits.iter().map(|b| b.count_ones() as usize).sum()
    })
}

/// The vertices of one layer touched so far, one bit each.
struct LayerBits<'a> {
    bits: &'a mut [u64],
    side: usize,
}

impl LayerBits<'_> {
    /// Marks the layer's vertices of cell `c` (x, y) that a source with fraction `f` (x, y)
    /// and z weight `wz` gives a non-zero weight: the same products as the sweep's, so that
    /// the same weights are zero. Without branches: every corner's word is written.
    #[inline]
    fn mark(&mut self, c: UVec3, f: Vec3, wz: f32) {
        for (dy, wy) in [1.0 - f.y, f.y].into_iter().enumerate() {
            let wyz = wz * wy;
            for (dx, wx) in [1.0 - f.x, f.x].into_iter().enumerate() {
                let hit = (wyz > 0.0) & (wx * wyz > 0.0);
                let k = (c.y as usize + dy) * self.side + c.x as usize + dx;
                self.bits[k / 64] |= u64::from(hit) << (k % 64);
            }
        }
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
    for (v, a) in sums {
        out.push(v, &a, geom, level);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
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
            let src = Sources {
                positions: &positions,
                intensity: &intensity,
                normals: None,
                mass: None,
                variance: None,
                finer_vertices: None,
            };
            let restriction = Sources {
                finer_vertices: Some(&vertices),
                ..src
            };
            for s in [src, restriction] {
                let n = count_vertices(&mut ws, &s, &geom, 1);
                assert_eq!(n, splat(&s, &geom, 1).len(), "l_max {l_max}");
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
                count_vertices(&mut ws, &s, &geom, 1);
                assert_eq!(count_vertices_finer(&ws, &s, &geom, 1), Some(expected));
                assert_eq!(count_vertices_finer(&ws, &s, &finer, 1), None);
            }
        }
    }
}
