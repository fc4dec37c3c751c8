//! Representative input lights of grid lights: shadow-ray targets that lie where the light
//! really is (an extension; the paper and the authors' demo trace to the grid light's
//! centroid jittered by its deviation, LGH 2019 section 3.3).
//!
//! A grid light stands for the input lights around its vertex. Its centroid may lie where no
//! input light is, for example inside a box whose top and surrounding floor carry VPLs, or
//! inside a wall lit from both sides; a shadow ray towards it then reports the whole light as
//! occluded, and the ratio estimator darkens the image (docs/design.md, "Shadow targets"). A representative is one input light i drawn with probability
//! proportional to its share of the grid light, w_v(p_i) lum(I_i), where w_v is the trilinear
//! weight of vertex v at spacing h_l; the visibility of a representative then estimates the
//! share-weighted visibility of the lights the grid light stands for, as brute force sums it.
//!
//! S_1 lights draw their [`SLOTS`] slots by inverse transform over the input lights of the 8
//! cells around their vertex, stratified (one uniform per light, a random rotation of the
//! strata over the slots, so that each slot alone is an exact draw). The cells' lights are
//! visited in a fixed order, so the result is the same for every thread count; this costs
//! two passes over the (light, vertex) pairs instead of an update of every slot per pair.
//! Coarser levels chain: they use the weighted reservoir of Efraimidis and Spirakis, every
//! (source, vertex) pair drawing the key E / w with E exponential from a hash and each slot
//! keeping the smallest key, a minimum that does not depend on the order of the updates.

use std::sync::atomic::{AtomicU64, Ordering};

use glam::{UVec3, Vec3};
use rayon::prelude::*;

use super::lookup::VertexLookup as Lookup;
use super::splat::{corner_weight, locate_finer_vertex};
use super::{Construction, InputLights, LightingGrid};
use crate::color::luminance;
use crate::rng::hash;

/// Representatives drawn per grid light (stratified at S_1, independent above; a power of
/// two). The set is fixed for a frame, so its randomness is correlated over the image; more
/// slots spread it, at the cost of evaluating each of them per shadow sample
/// (docs/design.md, "Shadow targets").
pub const SLOTS: usize = 16;

/// No representative (a slot that no input light reached).
pub const NONE: u32 = u32::MAX;

/// Draws [`SLOTS`] representatives for every grid light of levels 1 and
/// `from_level..=l_max` of `grid`, which was built from `lights` by `construction`. Entry
/// `SLOTS * j + s` is slot s of grid light j: an index into `lights`, or [`NONE`] for lights
/// of zero intensity (and, for the gather, for the levels between 1 and `from_level`).
///
/// The draw follows the construction: an S_1 light picks input light i in proportion to
/// w_1(p_i) lum(I_i). For the gather of section 3.1, a light of level l >= 2 picks an S_1
/// light u in proportion to w_l(p_u) lum(I_u) and takes u's representative of the same slot.
/// For the restriction (and the all-scatter hierarchy, which it equals), a light at vertex V
/// of level l picks a light u of level l - 1 in proportion to its stencil weight
/// w_l(v_u) lum(I_u) and takes u's representative; since w_l(p - V) = sum over u of
/// w_l(v_u - V) w_(l-1)(p - v_u), the chance of input light i is then exactly
/// w_l(p_i) lum(I_i) / lum(I_V). So every grid light with non-zero intensity has a
/// representative, drawn with its share of the light.
#[must_use]
pub fn representatives(
    grid: &LightingGrid,
    lights: &InputLights,
    from_level: u32,
    construction: Construction,
    seed: u64,
) -> Vec<u32> {
    let mut reps = vec![NONE; grid.len() * SLOTS];
    let rows = super::lookup::VertexRows::new(grid);
    let grid = Lookup::new(grid, &rows);
    let s1 = grid.grid.level_range(1);
    let cells = CellRuns::new(&grid, lights);
    reps[SLOTS * s1.start..SLOTS * s1.end]
        .par_chunks_mut(SLOTS)
        .enumerate()
        .for_each_init(Vec::new, |scratch, (k, slots)| {
            cells.draw_s1(&grid, s1.start + k, seed, scratch, slots);
        });
    // Levels above S_1 only if some are asked for (the chain of the restriction needs every
    // level below the ones it draws).
    let top = if from_level > grid.grid.l_max() {
        1
    } else {
        grid.grid.l_max()
    };
    let keys: Vec<AtomicU64> = if top > 1 {
        (0..grid.grid.len() * SLOTS)
            .map(|_| AtomicU64::new(u64::MAX))
            .collect()
    } else {
        Vec::new()
    };
    for l in 2..=top {
        // Light u of level `from` (its slots final in `reps`) offered to level l's vertices.
        let chain = |from: u32, located: &(dyn Fn(usize) -> (UVec3, Vec3) + Sync)| {
            let range = grid.grid.level_range(from);
            range.into_par_iter().for_each(|u| {
                let slots = &reps[SLOTS * u..SLOTS * (u + 1)];
                let lum = luminance(grid.grid.intensity[u]);
                offer(&grid, &keys, l, located(u), lum, seed, u as u64, |s| {
                    slots[s]
                });
            });
        };
        match construction {
            Construction::GatherFromS1 if l >= from_level => {
                chain(1, &|u| grid.locate(l, grid.grid.position[u]));
            }
            Construction::GatherFromS1 => {}
            Construction::Restrict | Construction::ScatterAll => {
                let r = grid.grid.geometry.cells_per_axis(l);
                chain(l - 1, &|u| locate_finer_vertex(grid.grid.vertex[u], r));
            }
        }
        let range = grid.grid.level_range(l);
        reps[SLOTS * range.start..SLOTS * range.end]
            .par_iter_mut()
            .zip(&keys[SLOTS * range.start..SLOTS * range.end])
            .for_each(|(r, k)| *r = unpack(k.load(Ordering::Relaxed)));
    }
    reps
}

/// The S_1 lights' representatives alone, drawn as [`representatives`] draws them (same
/// seed, same slots), each light's [`SLOTS`] handed to `make` as soon as they are drawn, in
/// parallel; the results in grid order of the S_1 lights. No table of every level's slots
/// is filled and read back.
pub fn s1_representatives<T: Send>(
    grid: &LightingGrid,
    lights: &InputLights,
    seed: u64,
    make: impl Fn(&[u32; SLOTS]) -> T + Sync,
) -> Vec<T> {
    let rows = super::lookup::VertexRows::new(grid);
    let grid = Lookup::new(grid, &rows);
    let cells = CellRuns::new(&grid, lights);
    grid.grid
        .level_range(1)
        .into_par_iter()
        .map_init(Vec::new, |scratch, j| {
            let mut slots = [NONE; SLOTS];
            cells.draw_s1(&grid, j, seed, scratch, &mut slots);
            make(&slots)
        })
        .collect()
}

/// The input lights sorted by their level-1 cell, in runs of one cell each, with a table of
/// where each cell row (y, z) starts among the runs: the lights around a vertex are then
/// found by one table read and a search within a row, as [`Lookup::find`] finds vertices.
struct CellRuns {
    /// Per light in cell order: its index, in-cell fraction and luminance.
    lights: Vec<(u32, Vec3, f32)>,
    /// Per run: its cell's x, and where it starts in `lights` (one more entry at the end).
    run_x: Vec<u32>,
    run_start: Vec<u32>,
    /// Per cell row z r + y (r cells per axis), where its runs start (one more at the end).
    row_start: Vec<u32>,
    /// Cells per axis at level 1.
    r: u32,
}

impl CellRuns {
    fn new(grid: &Lookup, lights: &InputLights) -> Self {
        let r = grid.grid.geometry.cells_per_axis(1);
        // Cells per axis at level 1 are a power of two: the key packs (z, y, x) in `b` bits
        // each, so that key >> b is the row.
        let b = r.trailing_zeros();
        // One u64 per light, cell key above the light's index (at most 3 x 9 + 32 bits): a
        // sort of plain integers, several times faster than of the lights' records, gives
        // the order by (cell, index); the records are gathered after it.
        let (mut order, located): (Vec<u64>, Vec<(Vec3, f32)>) = lights
            .positions
            .par_iter()
            .zip(lights.intensity.par_iter())
            .enumerate()
            .map(|(i, (&p, &intensity))| {
                let (c, f) = grid.locate(1, p);
                let cell = (u64::from(c.z) << (2 * b)) | (u64::from(c.y) << b) | u64::from(c.x);
                ((cell << 32) | i as u64, (f, luminance(intensity)))
            })
            .unzip();
        order.par_sort_unstable();
        let cell = |k: usize| order[k] >> 32;
        let starts: Vec<u32> = (0..order.len())
            .into_par_iter()
            .filter(|&k| k == 0 || cell(k) != cell(k - 1))
            .map(|k| k as u32)
            .collect();
        let mask = (1u64 << b) - 1;
        let run_x = starts
            .iter()
            .map(|&k| (cell(k as usize) & mask) as u32)
            .collect();
        let rows = r as usize * r as usize;
        let mut row_start = vec![0u32; rows + 1];
        for &k in &starts {
            row_start[(cell(k as usize) >> b) as usize + 1] += 1;
        }
        for k in 1..=rows {
            row_start[k] += row_start[k - 1];
        }
        let mut run_start = starts;
        run_start.push(order.len() as u32);
        let lights = order
            .par_iter()
            .map(|&key| {
                let i = key as u32;
                let (f, lum) = located[i as usize];
                (i, f, lum)
            })
            .collect();
        Self {
            lights,
            run_x,
            run_start,
            row_start,
            r,
        }
    }

    /// The lights of cell `c`, if any.
    fn cell(&self, c: UVec3) -> &[(u32, Vec3, f32)] {
        let row = (c.z * self.r + c.y) as usize;
        let (a, b) = (
            self.row_start[row] as usize,
            self.row_start[row + 1] as usize,
        );
        match self.run_x[a..b].binary_search(&c.x) {
            Ok(k) => {
                let run = a + k;
                &self.lights[self.run_start[run] as usize..self.run_start[run + 1] as usize]
            }
            Err(_) => &[],
        }
    }

    /// Fills the [`SLOTS`] slots of S_1 light `j` with input lights drawn in proportion to
    /// w_1(p_i) lum(I_i), stratified: one uniform u, slot (s + o) mod [`SLOTS`] takes the
    /// light where the cumulative share crosses (s + u) / [`SLOTS`] of the total. The offset o
    /// is uniform too, so every slot alone has exactly the share distribution (and the
    /// chain of the coarser levels, which reads one slot, stays exact), while the slots
    /// together cover the light's VPLs more evenly than independent draws.
    fn draw_s1(
        &self,
        grid: &Lookup,
        j: usize,
        seed: u64,
        scratch: &mut Vec<(f32, u32)>,
        slots: &mut [u32],
    ) {
        scratch.clear();
        let v = grid.grid.vertex[j];
        let mut total = 0.0f32;
        for corner in 0..8u32 {
            let d = UVec3::new(corner & 1, (corner >> 1) & 1, corner >> 2);
            // The cell whose corner d is vertex v.
            if v.cmplt(d).any() || (v - d).cmpge(UVec3::splat(self.r)).any() {
                continue;
            }
            for &(i, f, lum) in self.cell(v - d) {
                let w = corner_weight(f, d) * lum;
                if w > 0.0 {
                    total += w;
                    scratch.push((total, i));
                }
            }
        }
        let Some(&(_, last)) = scratch.last() else {
            return;
        };
        let bits = hash(&[seed, 1, j as u64]);
        // As many bits as leave s + u exact in f32's 24-bit significand for every s.
        let u = (bits >> (64 - U_BITS)) as f32 * (1.0 / (1u64 << U_BITS) as f32);
        let o = (bits & (SLOTS as u64 - 1)) as usize;
        let mut at = 0;
        for s in 0..SLOTS {
            let target = (s as f32 + u) * (1.0 / SLOTS as f32) * total;
            while at < scratch.len() && scratch[at].0 <= target {
                at += 1;
            }
            slots[(s + o) % SLOTS] = scratch.get(at).map_or(last, |e| e.1);
        }
    }
}

/// Bits of the stratified draw's uniform: s + u, s < [`SLOTS`], is then exact in f32.
const U_BITS: u32 = 24 - SLOTS.trailing_zeros();

/// The representative packed in a key (its low 32 bits), or [`NONE`].
fn unpack(key: u64) -> u32 {
    if key == u64::MAX { NONE } else { key as u32 }
}

/// Offers source `id` (at cell `c` and in-cell fraction `f` of level `l`, luminance `lum`)
/// to the slots of the 8 level-`l` vertices around it, with weight w_l lum; slot s carries
/// the input light `rep(s)`.
#[allow(clippy::too_many_arguments)]
fn offer(
    lookup: &Lookup,
    keys: &[AtomicU64],
    l: u32,
    (c, f): (UVec3, Vec3),
    lum: f32,
    seed: u64,
    id: u64,
    rep: impl Fn(usize) -> u32,
) {
    if lum <= 0.0 {
        return;
    }
    for corner in 0..8u32 {
        let d = UVec3::new(corner & 1, (corner >> 1) & 1, corner >> 2);
        let w = corner_weight(f, d) * lum;
        if w <= 0.0 {
            continue;
        }
        let Some(j) = lookup.find(l, c + d) else {
            continue;
        };
        // One hash per (source, vertex) and 4 slots: 16 random bits for each.
        let base = hash(&[seed, u64::from(l), id, u64::from(corner)]);
        let mut bits = base;
        for (s, slot) in keys[SLOTS * j..SLOTS * (j + 1)].iter().enumerate() {
            let r = rep(s);
            if r == NONE {
                continue;
            }
            // Key E / w with E = -ln(u) exponential, u uniform in (0, 1].
            if s % 4 == 0 && s > 0 {
                bits = hash(&[base, s as u64]);
            }
            let u = (((bits >> (16 * (s % 4))) & 0xffff) as f32 + 1.0) * (1.0 / 65_536.0);
            // Most offers lose: read before the (costlier) atomic update, and skip the
            // logarithm when a lower bound of the key already loses: -`ln`(u) >= 1 - u -
            // LN_MARGIN for every u drawn here (tested), so the computed key is above the
            // bound below, strictly; a skipped offer would have lost to the current key, and
            // keys only decrease, so the minimum stays order-independent.
            let current = slot.load(Ordering::Relaxed);
            let current_key = f32::from_bits((current >> 32) as u32);
            if current != u64::MAX && (1.0 - u - LN_MARGIN) / w * 0.999_9 >= current_key {
                continue;
            }
            let key = (u64::from((-ln(u) / w).to_bits()) << 32) | u64::from(r);
            if key < current {
                slot.fetch_min(key, Ordering::Relaxed);
            }
        }
    }
}

/// Margin of the lower bound -ln(u) >= 1 - u that [`offer`] uses with the approximate
/// [`ln`].
const LN_MARGIN: f32 = 1e-3;

/// ln(u) for u in (0, 1], to about 3e-4 absolute: the exponent bits plus a polynomial for the
/// mantissa (keys need no more, and libm's ln dominated the cost of the draw).
#[inline]
fn ln(u: f32) -> f32 {
    let bits = u.to_bits();
    let e = ((bits >> 23) & 0xff) as f32 - 127.0;
    // m in [1, 2); log2(m) by a degree-5 fit of (m - 1).
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000) - 1.0;
    let log2_m = m
        * (1.442_686_8
            + m * (-0.720_871_5 + m * (0.469_209_6 + m * (-0.276_168_1 + m * 0.085_142_8))));
    (e + log2_m) * std::f32::consts::LN_2
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::lighting_grid::{Construction, LevelCount};

    /// Six lights of different powers, spread over a few cells, two levels.
    fn lights() -> (Vec<Vec3>, Vec<Vec3>) {
        let p = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.3, 0.1, 0.2),
            Vec3::new(0.9, 0.4, 0.1),
            Vec3::new(0.5, 0.8, 0.6),
            Vec3::new(0.2, 0.7, 0.9),
            Vec3::new(1.0, 1.0, 1.0),
        ];
        let i = [1.0, 2.0, 0.5, 3.0, 1.5, 2.5].map(Vec3::splat).to_vec();
        (p, i)
    }

    /// The trilinear weight of position `p` at vertex `v` of level `l`.
    fn tent(grid: &LightingGrid, l: u32, v: glam::UVec3, p: Vec3) -> f64 {
        let geom = grid.geometry;
        let d = (p - geom.vertex_position(l, v)) / geom.cell_size(l);
        let t = (Vec3::ONE - d.abs()).max(Vec3::ZERO);
        f64::from(t.x * t.y * t.z)
    }

    /// The S_1-only draw hands out exactly the slots of the full draw, light by light, for
    /// several seeds (the unbiased estimate uses the former, the paper's the latter).
    #[test]
    fn s1_draw_equals_the_full_draws_s1_slots() {
        let (p, i) = lights();
        let input = InputLights {
            positions: &p,
            intensity: &i,
            normals: None,
        };
        let (grid, _) =
            LightingGrid::build(&input, LevelCount::Fixed(3), Construction::Restrict).unwrap();
        let s1 = grid.level_range(1);
        assert!(!s1.is_empty());
        for seed in 0..8 {
            let full = representatives(&grid, &input, 1, Construction::Restrict, seed);
            let alone = s1_representatives(&grid, &input, seed, |s| *s);
            assert_eq!(alone.len(), s1.len());
            for (k, slots) in alone.iter().enumerate() {
                let j = s1.start + k;
                assert_eq!(
                    &full[SLOTS * j..SLOTS * (j + 1)],
                    slots,
                    "light {j}, seed {seed}"
                );
            }
        }
    }

    /// Each slot of a grid light picks input light i with probability equal to its share of
    /// the light: w_l(p_i) lum(I_i) at S_1 and, for the restriction, at every level; for the
    /// gather, sum over S_1 lights u of w_l(p_u) w_1,u(p_i) lum(I_i) at level l >= 2.
    /// Chi-square over 4000 seeds for every light of the three levels (p = 0.001).
    #[test]
    fn representatives_follow_the_shares() {
        for construction in [Construction::GatherFromS1, Construction::Restrict] {
            shares_match(construction);
        }
    }

    fn shares_match(construction: Construction) {
        let (p, i) = lights();
        let input = InputLights {
            positions: &p,
            intensity: &i,
            normals: None,
        };
        let (grid, _) = LightingGrid::build(&input, LevelCount::Fixed(3), construction).unwrap();
        let trials = 4000;
        let mut counts = vec![[0u32; 6]; grid.len()];
        for seed in 0..trials {
            let reps = representatives(&grid, &input, 2, construction, seed);
            for (j, c) in counts.iter_mut().enumerate() {
                c[reps[SLOTS * j + (seed as usize % SLOTS)] as usize] += 1;
            }
        }
        let s1 = grid.level_range(1);
        let share =
            |l: u32, j: usize, k: usize| tent(&grid, l, grid.vertex[j], p[k]) * f64::from(i[k].x);
        for (j, count) in counts.iter().enumerate() {
            let l = (1..=3).find(|&l| grid.level_range(l).contains(&j)).unwrap();
            let w: Vec<f64> = (0..6)
                .map(|k| {
                    if l == 1 || construction == Construction::Restrict {
                        share(l, j, k)
                    } else {
                        s1.clone()
                            .map(|u| {
                                tent(&grid, l, grid.vertex[j], grid.position[u]) * share(1, u, k)
                            })
                            .sum()
                    }
                })
                .collect();
            let total: f64 = w.iter().sum();
            let mut chi2 = 0.0;
            let mut df = 0;
            for k in 0..6 {
                let expected = w[k] / total * trials as f64;
                if expected > 0.0 {
                    chi2 += (f64::from(count[k]) - expected).powi(2) / expected;
                    df += 1;
                } else {
                    assert_eq!(count[k], 0, "light {k} has no share in grid light {j}");
                }
            }
            // 0.999 quantiles of chi-square with 1..=5 degrees of freedom (0 when one light).
            let limit = [1e-9, 10.83, 13.82, 16.27, 18.47, 20.52][df - 1];
            assert!(
                chi2 <= limit,
                "{construction:?}, grid light {j} (level {l}): chi2 {chi2} (df {})",
                df - 1
            );
        }
    }

    #[test]
    fn fast_ln_is_close_to_ln() {
        let mut u = 1.0f32 / 65_536.0;
        while u <= 1.0 {
            assert!(
                (ln(u) - u.ln()).abs() < 5e-4,
                "{u}: {} vs {}",
                ln(u),
                u.ln()
            );
            u += 1.0 / 4096.0;
        }
    }

    /// The bound that lets `offer` skip the logarithm holds for every u it draws.
    #[test]
    fn the_key_bound_holds_for_every_draw() {
        for k in 0..65_536u32 {
            let u = (k as f32 + 1.0) * (1.0 / 65_536.0);
            assert!(
                -ln(u) >= 1.0 - u - super::LN_MARGIN + 1e-5,
                "{u}: {}",
                -ln(u)
            );
        }
    }

    /// The minimum keys make the result independent of the thread count.
    #[test]
    fn representatives_do_not_depend_on_threads() {
        let p: Vec<Vec3> = (0..20_000)
            .map(|k| {
                let t = k as f32;
                Vec3::new((t * 0.37).sin(), (t * 0.11).cos(), (t * 0.05).sin())
            })
            .collect();
        let i = vec![Vec3::ONE; p.len()];
        let input = InputLights {
            positions: &p,
            intensity: &i,
            normals: None,
        };
        let (grid, _) =
            LightingGrid::build(&input, LevelCount::Auto, Construction::Restrict).unwrap();
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| representatives(&grid, &input, 2, Construction::Restrict, 7))
        };
        let one = run(1);
        assert_eq!(one, run(2));
        assert!(grid.level_range(2).all(|j| one[SLOTS * j] != NONE));
    }
}
