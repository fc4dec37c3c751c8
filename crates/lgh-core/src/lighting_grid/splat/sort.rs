//! Step 1 of the splat: every source is located and packed into 40 bytes, and the packed
//! sources are sorted by cell row with a stable parallel two-pass counting sort (or, for a
//! restriction, gathered in row order without a sort).

use glam::{UVec3, Vec3};
use rayon::prelude::*;

use super::super::geometry::GridGeometry;
use super::sweep::Band;
use super::{LAYER_TASK_SOURCES, Level, Sources, layers_per_task, locate, locate_finer_vertex};

/// Sources per chunk of the parallel counting sort: a chunk's bucketed sources (320 KB, 544
/// KB with their cluster attributes) stay in the L2 cache.
const SORT_CHUNK: usize = 1 << 13;

/// One source, prepared for a level: its cell, in-cell fraction and attributes, packed so
/// that the hot loops read memory sequentially. Its cell layer z is the bucket it is stored
/// in. 40 bytes: the sort moves every source twice, and memory traffic is its cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct PSource {
    /// In-cell fraction that gives the trilinear weights.
    pub(super) f: Vec3,
    /// Cell x and y (at most 2^([`MAX_LEVELS`] - 1) cells per axis).
    pub(super) cell: [u16; 2],
    pub(super) intensity: Vec3,
    pub(super) normal: Vec3,
}

impl PSource {
    /// The cell's x and y (z is the layer the source is stored in).
    #[inline]
    pub(super) fn cell_xy(&self) -> UVec3 {
        UVec3::new(u32::from(self.cell[0]), u32::from(self.cell[1]), 0)
    }
}

/// The attributes of a source that stands for several input lights (a grid light of a
/// finer level), kept apart from [`PSource`] so that the input lights of S_1, which have
/// none, do not carry them through the sort.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Cluster {
    /// In-cell position of the moments (P, Q): for a restriction, `PSource::f` is the fine
    /// vertex's fraction and `g` that of the fine grid light's mean position.
    pub(super) g: Vec3,
    pub(super) mass: f32,
    /// Positional variance in cell units.
    pub(super) variance: Vec3,
}

/// Reusable working memory of the splat: a renderer that rebuilds its hierarchy every frame
/// keeps one, so that no step pays for fresh memory (page faults cost about as much as the
/// arithmetic here). After its sort by cell row, the sources of cell row (y, z) are
/// `src[row_start[z r + y]..row_start[z r + y + 1]]`, in input order.
#[derive(Debug, Default)]
pub struct Workspace {
    /// The sources bucketed by cell layer within each chunk of the input (first pass).
    pub(super) staged: Vec<PSource>,
    pub(super) staged_clusters: Vec<Cluster>,
    pub(super) src: Vec<PSource>,
    /// Row starts of the fine level of a restriction ([`Workspace::gather_rows`]).
    pub(super) fine_rows: Vec<usize>,
    /// The cluster attributes of `src` (same order), if the sources have any.
    pub(super) clusters: Vec<Cluster>,
    pub(super) has_clusters: bool,
    pub(super) z_start: Vec<usize>,
    pub(super) row_start: Vec<usize>,
    /// The grid, level and source count of the last sort.
    pub(super) sorted: Option<(GridGeometry, u32, usize)>,
    pub(super) bands: Vec<Band>,
    /// The grid lights of each band (kept for their memory).
    pub(super) parts: Vec<Level>,
    pub(super) r: u32,
}

impl Workspace {
    /// Stable counting sort of the sources by cell row (z, then y) at `level`, in parallel,
    /// locating and packing each source on the way (its cell, in-cell fraction and
    /// attributes), then cuts the vertex layers into bands. Every chunk of the input
    /// counts its sources per cell layer, then packs them into its own range of `staged`,
    /// bucketed by layer (input order kept); then every layer counts its chunks' pieces by
    /// row and moves them, in chunk order, to its rows of `src`. The input is read in order
    /// and every move is of whole packed sources, so no pass gathers from random places.
    pub(super) fn sort_by_row(&mut self, src: &Sources, geom: &GridGeometry, level: u32) {
        self.sort_by_row_with(src, geom, level, true);
    }

    /// [`Workspace::sort_by_row`], with the shortcut of [`Workspace::gather_rows`] for
    /// restrictions if `gather`.
    pub(super) fn sort_by_row_with(
        &mut self,
        src: &Sources,
        geom: &GridGeometry,
        level: u32,
        gather: bool,
    ) {
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
    pub(super) fn layer(&self, z: u32) -> &[PSource] {
        &self.src[self.z_start[z as usize]..self.z_start[z as usize + 1]]
    }
}

/// `v` cut into the consecutive buckets `z_start[z]..z_start[z + 1]`.
fn split_buckets<'a, T>(v: &'a mut [T], z_start: &[usize]) -> Vec<&'a mut [T]> {
    split_lengths(v, z_start.windows(2).map(|w| w[1] - w[0]))
}

/// `v` cut into consecutive pieces of the given lengths.
pub(super) fn split_lengths<T>(
    mut rest: &mut [T],
    lengths: impl Iterator<Item = usize>,
) -> Vec<&mut [T]> {
    let mut out = Vec::with_capacity(lengths.size_hint().0);
    for len in lengths {
        let (head, tail) = std::mem::take(&mut rest).split_at_mut(len);
        out.push(head);
        rest = tail;
    }
    out
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lighting_grid::splat::splat;
    use crate::lighting_grid::splat::tests::point_sources;
    use crate::rng::Rng;

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
}
