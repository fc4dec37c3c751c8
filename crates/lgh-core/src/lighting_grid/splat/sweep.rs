//! Step 2 of the splat: each vertex layer is cut into bands of vertex rows; a band task reads
//! its cell rows in order and sums every source's trilinear contributions into a rolling pair
//! of dense vertex rows, emitting each vertex row in x order once complete.

use glam::UVec3;

use super::super::geometry::GridGeometry;
use super::sort::{PSource, Workspace};
use super::{Accum, Level};

/// Source visits per task: consecutive vertex rows of one layer are grouped into a band
/// until the cell rows they read hold about this many sources. A single crowded row (the
/// coarsest levels of the all-scatter construction) is one band whatever its size.
pub const BAND_SOURCES: usize = 1 << 15;

/// Vertex rows `y0..y1` of vertex layer `z`: one task of the splat.
#[derive(Clone, Copy, Debug)]
pub(super) struct Band {
    pub(super) z: u32,
    pub(super) y0: u32,
    pub(super) y1: u32,
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
    pub(super) fn cut_bands(&mut self) {
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
pub(super) struct RowPair {
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

pub(super) fn with_rows<T>(f: impl FnOnce(&mut RowPair) -> T) -> T {
    ROWS.with(|s| f(&mut s.borrow_mut()))
}

/// [`Workspace::sweep`] of band `b` into the grid lights `part`, compiled also for AVX2 with
/// FMA (chosen at run time): a contribution adds 16 weighted doubles to a vertex, which is
/// eight SSE2 multiply-adds without them and four FMAs with them.
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub(super) fn sweep_band(
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
