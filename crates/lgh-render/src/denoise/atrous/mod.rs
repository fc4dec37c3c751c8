//! Edge-avoiding a-trous wavelet filter (Dammertz, Sewtz, Hanika & Lensch 2010), used on the
//! shadow estimates of the ratio estimator (LGH 2019 section 3.3).
//!
//! Pass i (i = 0..n-1) convolves with the 5 x 5 B3-spline kernel h = h1 x h1,
//! h1 = (1/16, 1/4, 3/8, 1/4, 1/16), whose taps are 2^i pixels apart, and weights each tap by
//! edge-stopping functions w = w_c w_n w_x:
//! w_c = exp(-|c_p - c_q|^2 / c_phi_i) on the guide image, with c_phi halved in standard
//! deviation (quartered) at every pass; w_n = exp(-|N_p - N_q|^2 / n_phi) on the shading
//! normals; w_x = exp(-|X_p - X_q|^2 / p_phi) on the world positions. Defaults are the LGH
//! demo's (docs/design.md, "A-trous filter"): 5 passes, c_phi = 0.5, n_phi = 0.1, p_phi = 0.66 x scene
//! radius.
//!
//! A fourth weight w_a = exp(-(a_p - a_q)^2 / a_phi), a_p = ln lum(A_p), compares the
//! unshadowed sums A of the two pixels ([`AtrousParams::a_phi`], off at 0). A changes fast
//! where the ratio does near the corners of a room (a VPL a few centimetres away on the
//! other wall), and D(S) / D(U) weighs a tap by its U: without w_a the filter carried the
//! ratio of the open wall into the corner, which came out too bright (docs/design.md,
//! "A-trous filter").
//!
//! [`filter_ratio_pair`] filters the two images of the ratio estimator, S and U, with one and
//! the same set of weights (the guide is the current ratio lum(S)/lum(U)), so that
//! D(S) <= D(U) channel by channel and the filtered ratio stays in [0, 1]. (The demo weighs S
//! and U with separate colour weights, a quirk not copied; docs/design.md,
//! "Quirks of the reference code".)

use std::sync::{Mutex, PoisonError};

use glam::Vec3;
use lgh_core::color::luminance;
use rayon::prelude::*;

use crate::passes::gbuffer::GBuffer;

/// The most passes the filter runs (a step of 2^11 pixels: wider than any image lgh
/// renders); `--filter-passes` refuses more.
pub const MAX_PASSES: u32 = 12;

/// Parameters of the filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtrousParams {
    /// Number of passes (step widths 1, 2, 4, ...), at most [`MAX_PASSES`].
    pub passes: u32,
    /// Colour (guide) weight parameter c_phi = sigma_c^2 of the first pass.
    pub c_phi: f32,
    /// Normal weight parameter n_phi.
    pub n_phi: f32,
    /// Position weight parameter p_phi (squared world distance scale).
    pub p_phi: f32,
    /// The unshadowed sum's weight parameter a_phi, on ln lum(A) (0: no such weight, and
    /// none without A).
    pub a_phi: f32,
}

impl AtrousParams {
    /// The LGH demo's defaults for a scene of bounding-sphere radius `radius`.
    #[must_use]
    pub fn lgh_defaults(radius: f32) -> Self {
        Self {
            passes: 5,
            c_phi: 0.5,
            n_phi: 0.1,
            p_phi: 0.66 * radius,
            a_phi: 0.0,
        }
    }
}

/// The key of the unshadowed sum A that w_a compares: ln lum(A), lum(A) at least 1e-20
/// (a pixel that no light reaches is far from every lit one).
#[must_use]
pub fn unshadowed_key(a: Vec3) -> f32 {
    luminance(a).max(1e-20).ln()
}

const H1: [f32; 5] = [1.0 / 16.0, 1.0 / 4.0, 3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0];

/// The filter's guide of a pixel with estimates S and U: lum(S) / lum(U) clamped to [0, 1],
/// 1 where U has no luminance.
#[must_use]
pub fn filter_guide(s: Vec3, u: Vec3) -> f32 {
    let lu = luminance(u);
    if lu > 1e-12 {
        (luminance(s) / lu).clamp(0.0, 1.0)
    } else {
        1.0
    }
}

/// exp(-e) for e >= 0, to about 1e-4 relative (filter weights need no more): 2^(-e log2 e)
/// split into an integer power set in the exponent bits and a polynomial for the fraction.
/// Branch-free, so that the filter's inner loop vectorises: e is clamped to 80 (NaN and
/// infinity included), where the result, 2^-115, is negligible against the centre tap.
#[inline(always)]
fn exp_neg(e: f32) -> f32 {
    let t = -e.min(80.0) * std::f32::consts::LOG2_E;
    // round(t) by the 1.5 x 2^23 trick: adding it leaves the rounded integer in the low
    // mantissa bits, with no float-to-int conversion (Rust's saturating `as` would keep the
    // loop scalar).
    const MAGIC: f32 = 12_582_912.0;
    let r = t + MAGIC;
    let i = r - MAGIC;
    let f = t - i; // in [-0.5, 0.5]
    // 2^f = e^(f ln 2) by its Taylor series to degree 5 (relative error below 1e-6 here).
    let p = 1.0
        + f * (std::f32::consts::LN_2
            + f * (0.240_226_5 + f * (0.055_504_1 + f * (0.009_618_1 + f * 0.001_333_4))));
    let int = (r.to_bits() as i32).wrapping_sub(MAGIC.to_bits() as i32);
    let bits = (int.wrapping_add(127) as u32) << 23;
    f32::from_bits(bits) * p
}

// The 15 per-pixel planes of [`Planes`], numbered: position (0..3), normal (3..6), S and U
// (6..12), guide, hit and the key of A.
/// First of the planes a pass writes (S r, g, b, U r, g, b, guide).
const OUT: usize = 6;
/// The guide plane.
const GUIDE: usize = 12;
/// The hit plane (1 where the pixel sees a surface, else 0).
const HIT: usize = 13;
/// The plane of A's key ([`unshadowed_key`]; 0 without A).
const KEY_A: usize = 14;
/// Planes that never change: position, normal, hit and A's key.
const FIXED: usize = 8;
/// Planes a pass rewrites: S, U and guide.
const DYNAMIC: usize = 7;

/// Exponent of the edge-stopping weight beyond which a tap counts as zero ([`weight_row`]).
const NEGLIGIBLE: f32 = 40.0;

/// Pixels processed together in the inner loop: fixed-size blocks vectorise reliably.
const LANES: usize = 16;

/// Layout of the filter's structure-of-arrays planes: every row is stored with `pad` zero
/// pixels on each side and rounded up to whole [`LANES`] blocks, so that a tap shifted by up
/// to `pad` pixels reads a plain slice (zeros, hit 0, outside the image) and no tap ever reads
/// a NaN.
#[derive(Clone, Copy)]
struct Layout {
    /// Pixels per stored row: pad + width rounded up to LANES + pad.
    stride: usize,
    pad: usize,
    height: usize,
}

impl Layout {
    /// Floats per plane.
    fn plane(&self) -> usize {
        self.stride * self.height
    }
}

/// The planes a pass reads: position x, y, z, normal x, y, z, hit (1 or 0) and A's key,
/// which never change (`fixed`, planes 0..6, 6 and 7), and S r, g, b, U r, g, b and guide,
/// which every pass rewrites (`dynamic`, ping-ponged between two buffers).
struct Planes<'a> {
    layout: Layout,
    fixed: &'a [f32],
    dynamic: &'a [f32],
}

impl Planes<'_> {
    /// Row `y` of plane `k` (numbered as listed above [`OUT`]), padding included.
    fn row(&self, k: usize, y: usize) -> &[f32] {
        let (buf, k) = match k {
            OUT..HIT => (self.dynamic, k - OUT),
            HIT => (self.fixed, 6),
            KEY_A => (self.fixed, 7),
            _ => (self.fixed, k),
        };
        let at = k * self.layout.plane() + y * self.layout.stride;
        &buf[at..at + self.layout.stride]
    }
}

/// Filters S and U with identical edge-stopping weights (see the module docs), w_a on the
/// unshadowed sums `a` where given. Pixels that see nothing are left as they are and never
/// used as taps.
///
/// Layout for speed: structure-of-arrays planes with padded rows, read in blocks of
/// `LANES` pixels so that the loops vectorise; only the 7 planes a pass rewrites are
/// double-buffered. The edge-stopping weight of a pair of pixels is symmetric, so each pair's
/// exponential is computed once and serves both pixels (`FORWARD`): 12 instead of 24 per
/// pixel and pass.
#[must_use]
pub fn filter_ratio_pair(
    s: &[Vec3],
    u: &[Vec3],
    a: Option<&[Vec3]>,
    g: &GBuffer,
    params: &AtrousParams,
) -> (Vec<Vec3>, Vec<Vec3>) {
    filter_ratio_pair_with(s, u, a, g, params, &mut AtrousBuffers::default())
}

/// The working memory of [`filter_ratio_pair_with`]: 22 image-sized planes (about 95 MB at
/// 1280x720). A renderer that filters every frame keeps one, so that the planes are not
/// paged in afresh each frame.
#[derive(Debug, Default)]
pub struct AtrousBuffers {
    fixed: Vec<f32>,
    cur: Vec<f32>,
    next: Vec<f32>,
    /// The weight ring ([`filter_chain`]) of each worker thread.
    rings: Vec<Mutex<Vec<f32>>>,
    /// The layout (stride, padding, width, height) the buffers were last laid out for:
    /// their padding and the pixels beyond the width are zero.
    layout: Option<(usize, usize, usize, usize)>,
}

/// [`filter_ratio_pair`] in the working memory `buffers`, reused from call to call.
#[must_use]
pub fn filter_ratio_pair_with(
    s: &[Vec3],
    u: &[Vec3],
    a: Option<&[Vec3]>,
    g: &GBuffer,
    params: &AtrousParams,
    buffers: &mut AtrousBuffers,
) -> (Vec<Vec3>, Vec<Vec3>) {
    let (mut s, mut u) = (s.to_vec(), u.to_vec());
    filter_ratio_pair_in_place(&mut s, &mut u, a, g, params, buffers);
    (s, u)
}

/// [`filter_ratio_pair_with`] in place: `s` and `u` become the filtered images (a renderer
/// that no longer needs the unfiltered ones saves two image-sized buffers).
pub fn filter_ratio_pair_in_place(
    s: &mut [Vec3],
    u: &mut [Vec3],
    a: Option<&[Vec3]>,
    g: &GBuffer,
    params: &AtrousParams,
    buffers: &mut AtrousBuffers,
) {
    let (w, h) = (g.width as usize, g.height as usize);
    let passes = params.passes.min(MAX_PASSES);
    let pad = 2 << passes.saturating_sub(1);
    let layout = Layout {
        stride: pad + w.div_ceil(LANES) * LANES + pad,
        pad,
        height: h,
    };
    let plane = layout.plane();
    let AtrousBuffers {
        fixed,
        cur,
        next,
        rings,
        layout: laid_out,
    } = buffers;
    if *laid_out != Some((layout.stride, pad, w, h)) {
        // A new layout: zero everything, padding included (nothing writes the padding).
        // Fresh zeroed allocations, not a resize: the system gives zero pages, which the
        // parallel fill below then touches, instead of one thread writing 90 MB of zeros.
        *fixed = vec![0.0; FIXED * plane];
        for buf in [&mut *cur, &mut *next] {
            *buf = vec![0.0; DYNAMIC * plane];
        }
        // The rings' padding moves with the stride.
        rings.clear();
        *laid_out = Some((layout.stride, pad, w, h));
    }
    // One pass over the image writes all 15 input planes, row by row in parallel: plane k,
    // row y holds the image's pixels from `pad` on, zero where the pixel sees nothing. The
    // passes write only pixels that see something; elsewhere the output planes may hold an
    // earlier image's values, which are finite and weigh 0 (their hit flag is 0).
    let mut rows: Vec<Vec<&mut [f32]>> = (0..h).map(|_| Vec::with_capacity(15)).collect();
    for buf in [&mut *fixed, &mut *cur] {
        for plane_rows in buf.chunks_mut(plane) {
            for (y, row) in plane_rows.chunks_mut(layout.stride).enumerate() {
                rows[y].push(row);
            }
        }
    }
    rows.into_par_iter().enumerate().for_each(|(y, mut row)| {
        for x in 0..w {
            let p = y * w + x;
            if !g.is_hit(p) {
                for plane_row in &mut row {
                    plane_row[pad + x] = 0.0;
                }
                continue;
            }
            let key = a.map_or(0.0, |a| unshadowed_key(a[p]));
            let values = [
                g.position[p].to_array(),
                g.normal[p].to_array(),
                [1.0, key, s[p].x],
                [s[p].y, s[p].z, u[p].x],
                [u[p].y, u[p].z, filter_guide(s[p], u[p])],
            ];
            // Planes in order: position, normal, hit, A's key (fixed), then S, U, guide.
            for (k, &v) in values.as_flattened().iter().enumerate() {
                row[k][pad + x] = v;
            }
        }
    });
    let (fixed, mut cur, mut next) = (&*fixed, cur, next);
    let (inv_n, inv_p) = (1.0 / params.n_phi, 1.0 / params.p_phi);
    // No A, or no weight on it: the keys are all 0 and the term vanishes.
    let inv_a = if a.is_some() && params.a_phi > 0.0 {
        1.0 / params.a_phi
    } else {
        0.0
    };
    for pass in 0..passes {
        let step = 1usize << pass;
        let inv_c = 4f32.powi(pass as i32) / params.c_phi;
        let src = Planes {
            layout,
            fixed,
            dynamic: cur,
        };
        // The taps of a pass join only rows of the same residue y mod step (a chain of rows
        // `step` apart). Each task filters a stretch of one chain: its rows of the 7 output
        // planes, one slice per plane and row, and recomputes the weights of the 2 chain rows
        // above its first (its halo).
        let chains = Chains::new(h, step);
        let stretches: Vec<_> = chains.stretches().collect();
        let mut tasks: Vec<Vec<Vec<&mut [f32]>>> = stretches
            .iter()
            .map(|(_, rows)| (0..rows.len()).map(|_| Vec::with_capacity(7)).collect())
            .collect();
        for plane_rows in next.chunks_mut(plane) {
            for (y, row) in plane_rows.chunks_mut(layout.stride).enumerate() {
                let (task, local) = chains.task_of(y);
                tasks[task][local].push(row);
            }
        }
        let threads = rayon::current_num_threads();
        if rings.len() < threads {
            rings.resize_with(threads, Mutex::default);
        }
        let rings = &*rings;
        tasks
            .into_par_iter()
            .zip(stretches)
            .for_each(|(mut out, (residue, rows))| {
                // This thread's ring: never contended (the task spawns no work of its own).
                let me = rayon::current_thread_index().unwrap_or(0) % rings.len();
                let mut ring = rings[me].lock().unwrap_or_else(PoisonError::into_inner);
                filter_chain(
                    &src,
                    &mut out,
                    w,
                    Chain {
                        residue,
                        rows,
                        step,
                    },
                    [inv_c, inv_n, inv_p, inv_a],
                    &mut ring,
                );
            });
        std::mem::swap(&mut cur, &mut next);
    }
    // Pixels that see nothing keep their input values.
    s.par_chunks_mut(w)
        .zip(u.par_chunks_mut(w))
        .enumerate()
        .for_each(|(y, (s_row, u_row))| {
            let at = |c: usize, x: usize| cur[c * plane + y * layout.stride + pad + x];
            for x in (0..w).filter(|&x| g.is_hit(y * w + x)) {
                s_row[x] = Vec3::new(at(0, x), at(1, x), at(2, x));
                u_row[x] = Vec3::new(at(3, x), at(4, x), at(5, x));
            }
        });
}

/// `LANES` values of `s` from `b` on.
#[inline(always)]
fn block(s: &[f32], b: usize) -> [f32; LANES] {
    let mut out = [0.0; LANES];
    out.copy_from_slice(&s[b..b + LANES]);
    out
}

/// The 12 tap offsets (dx, dy), in steps, whose weights a row computes: one of each mirror
/// pair (dx, dy), (-dx, -dy) of the 24 taps around the centre. The edge-stopping weight of a
/// pair of pixels is symmetric (every term is a squared difference, and the B3 kernel is
/// even), so the weight of tap -o at pixel p is the weight of tap o at pixel p - o.
const FORWARD: [(isize, isize); 12] = [
    (1, 0),
    (2, 0),
    (-2, 1),
    (-1, 1),
    (0, 1),
    (1, 1),
    (2, 1),
    (-2, 2),
    (-1, 2),
    (0, 2),
    (1, 2),
    (2, 2),
];

/// Chain rows of a pass filtered together, at most this many (a task's halo is 2 of them).
const STRETCH: usize = 32;

/// The rows of an image of `height` rows as the chains of a pass of step `step`: chain
/// `residue` holds rows residue, residue + step, ..., numbered 0, 1, ... along the chain, and
/// is cut into stretches of [`STRETCH`] chain rows, one task each.
struct Chains {
    height: usize,
    step: usize,
    /// Task index of each chain's first stretch.
    first: Vec<usize>,
}

impl Chains {
    fn new(height: usize, step: usize) -> Self {
        let mut first = Vec::with_capacity(step + 1);
        let mut tasks = 0;
        for residue in 0..step {
            first.push(tasks);
            tasks += Self::len(height, step, residue).div_ceil(STRETCH);
        }
        first.push(tasks);
        Self {
            height,
            step,
            first,
        }
    }

    /// Rows in chain `residue`.
    fn len(height: usize, step: usize, residue: usize) -> usize {
        height.saturating_sub(residue).div_ceil(step)
    }

    /// Every task in order: its chain and its chain rows.
    fn stretches(&self) -> impl Iterator<Item = (usize, std::ops::Range<usize>)> + '_ {
        (0..self.step).flat_map(move |residue| {
            let len = Self::len(self.height, self.step, residue);
            (0..len.div_ceil(STRETCH))
                .map(move |k| (residue, k * STRETCH..((k + 1) * STRETCH).min(len)))
        })
    }

    /// The task of image row `y` and the row's place in the task.
    fn task_of(&self, y: usize) -> (usize, usize) {
        let (residue, m) = (y % self.step, y / self.step);
        (self.first[residue] + m / STRETCH, m % STRETCH)
    }
}

/// A stretch of one chain of a pass: chain rows `rows` of chain `residue` (image rows
/// residue + m step).
struct Chain {
    residue: usize,
    rows: std::ops::Range<usize>,
    step: usize,
}

/// The chain rows `chain.rows` of one pass: `out[m]` holds the 7 output planes' row (S r, g,
/// b, U r, g, b and guide, padded like the planes) of the stretch's m-th row. Row by row
/// along the chain, the weights of the [`FORWARD`] taps are computed once into `ring` (which
/// keeps the last 3 chain rows' weights) and serve both the row itself and, mirrored, the
/// 2 chain rows below it; the stretch starts 2 chain rows early so that its first rows find
/// their mirrored weights. Then every block of [`LANES`] output pixels sums its 25 taps in
/// registers. Along a chain the taps of a row span 5 rows at any step, so the working set
/// stays in the cache even for the widest steps. Compiled for AVX-512 and AVX2 as well,
/// chosen at run time (the blocks then run 16 or 8 lanes wide instead of 4).
#[multiversion::multiversion(targets("x86_64+avx512f+avx512vl+avx2+fma", "x86_64+avx2+fma"))]
fn filter_chain(
    src: &Planes,
    out: &mut [Vec<&mut [f32]>],
    w: usize,
    chain: Chain,
    inv: [f32; 4],
    ring: &mut Vec<f32>,
) {
    let Layout { stride, height, .. } = src.layout;
    let Chain {
        residue,
        rows,
        step,
    } = chain;
    const SLOTS: usize = 3;
    let per_row = FORWARD.len() * stride;
    if ring.len() != SLOTS * per_row {
        // Zeroed: the padding of the weight rows is never written and reads as 0 (every
        // row's interior is written before it is read).
        *ring = vec![0.0; SLOTS * per_row];
    }
    for m in rows.start.saturating_sub(2)..rows.end {
        let r = residue + m * step;
        let slot = (m % SLOTS) * per_row;
        weight_row(src, &mut ring[slot..slot + per_row], r, step, inv);
        if m >= rows.start {
            let weights = |row: usize, o: usize| {
                let at = ((row / step) % SLOTS) * per_row + o * stride;
                &ring[at..at + stride]
            };
            sum_row(src, &mut out[m - rows.start], w, r, step, height, &weights);
        }
    }
}

/// The weights of the [`FORWARD`] taps of every pixel of row `r`, tap o at
/// `ring_row[o * stride + pad + x]`: h(dx) h(dy) w_c w_n w_x w_a, times 0 where either pixel sees
/// nothing or the tap lies below the image.
#[inline(always)]
fn weight_row(
    src: &Planes,
    ring_row: &mut [f32],
    r: usize,
    step: usize,
    [inv_c, inv_n, inv_p, inv_a]: [f32; 4],
) {
    let Layout {
        stride,
        pad,
        height,
    } = src.layout;
    let wp = stride - 2 * pad;
    const KEYS: [usize; 9] = [0, 1, 2, 3, 4, 5, GUIDE, HIT, KEY_A];
    let centre: [&[f32]; 9] = KEYS.map(|k| &src.row(k, r)[pad..pad + wp]);
    // Per tap: its 8 planes shifted, or None below the image.
    let taps: [Option<[&[f32]; 9]>; 12] = FORWARD.map(|(dx, dy)| {
        let qy = r + dy as usize * step;
        (qy < height).then(|| {
            let from = (pad as isize + dx * step as isize) as usize;
            KEYS.map(|k| &src.row(k, qy)[from..from + wp])
        })
    });
    let hxy: [f32; 12] = FORWARD.map(|(dx, dy)| H1[(dx + 2) as usize] * H1[(dy + 2) as usize]);
    for b in (0..wp).step_by(LANES) {
        let c = |k: usize| block(centre[k], b);
        let (cpx, cpy, cpz, cnx, cny, cnz, cg, ch, ca) =
            (c(0), c(1), c(2), c(3), c(4), c(5), c(6), c(7), c(8));
        for (o, tap) in taps.iter().enumerate() {
            let dst = &mut ring_row[o * stride + pad + b..o * stride + pad + b + LANES];
            let Some(q) = tap else {
                dst.fill(0.0);
                continue;
            };
            let t = |k: usize| block(q[k], b);
            let (qpx, qpy, qpz, qnx, qny, qnz, qg, qh, qa) =
                (t(0), t(1), t(2), t(3), t(4), t(5), t(6), t(7), t(8));
            for m in 0..LANES {
                let dc = cg[m] - qg[m];
                let (dnx, dny, dnz) = (cnx[m] - qnx[m], cny[m] - qny[m], cnz[m] - qnz[m]);
                let (dpx, dpy, dpz) = (cpx[m] - qpx[m], cpy[m] - qpy[m], cpz[m] - qpz[m]);
                let da = ca[m] - qa[m];
                // w_c w_n w_x w_a as one exponential (each exponent is <= 0, so the clamps to 1
                // of the separate weights are implied).
                let e = dc * dc * inv_c
                    + (dnx * dnx + dny * dny + dnz * dnz) * inv_n
                    + (dpx * dpx + dpy * dpy + dpz * dpz) * inv_p
                    + da * da * inv_a;
                // Weights below e^-40 (1e-18 of the centre's) are set to zero: their products
                // with the pixel values would be subnormal floats, which cost the vector units
                // a hundred times a normal multiply (the wide passes, whose colour weight
                // grows fourfold per pass, made most of their weights so small).
                let wt = hxy[o] * ch[m] * qh[m] * exp_neg(e);
                dst[m] = if e < NEGLIGIBLE { wt } else { 0.0 };
            }
        }
    }
}

/// Output row `r` (`out`: its 7 planes' rows): every pixel's 25 taps, the 12 [`FORWARD`] ones
/// with this row's weights and the 12 mirrored ones with the weights of the rows above
/// (`weights(row, o)`, a padded row), summed in registers block by block; hit pixels get
/// the normalised sums and their new guide.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn sum_row<'a>(
    src: &Planes,
    out: &mut [&mut [f32]],
    w: usize,
    r: usize,
    step: usize,
    height: usize,
    weights: &impl Fn(usize, usize) -> &'a [f32],
) {
    let Layout { stride, pad, .. } = src.layout;
    let wp = stride - 2 * pad;
    let values = |row: usize, dx: isize| -> [&[f32]; 6] {
        let from = (pad as isize + dx * step as isize) as usize;
        std::array::from_fn(|c| &src.row(OUT + c, row)[from..from + wp])
    };
    // (weights, values) of every tap but the centre.
    let mut taps: Vec<(&[f32], [&[f32]; 6])> = Vec::with_capacity(24);
    for (o, &(dx, dy)) in FORWARD.iter().enumerate() {
        let below = r + dy as usize * step;
        if below < height {
            taps.push((&weights(r, o)[pad..pad + wp], values(below, dx)));
        }
        if let Some(above) = r.checked_sub(dy as usize * step) {
            // Tap -o of pixel x is tap o of pixel x - o: its weight row shifted by -dx.
            let from = (pad as isize - dx * step as isize) as usize;
            taps.push((&weights(above, o)[from..from + wp], values(above, -dx)));
        }
    }
    let centre = values(r, 0);
    let h00 = H1[2] * H1[2];
    let hit = &src.row(HIT, r)[pad..pad + w];
    let at = pad;
    for b in (0..wp).step_by(LANES) {
        // Accumulators: S r, g, b, U r, g, b, weight; the centre tap has weight h(0) > 0.
        let mut acc = [[0.0f32; LANES]; 7];
        for c in 0..6 {
            let v = block(centre[c], b);
            for m in 0..LANES {
                acc[c][m] = h00 * v[m];
            }
        }
        acc[6] = [h00; LANES];
        for (wt, vals) in &taps {
            let wt = block(wt, b);
            for c in 0..6 {
                let v = block(vals[c], b);
                for m in 0..LANES {
                    acc[c][m] += wt[m] * v[m];
                }
            }
            for m in 0..LANES {
                acc[6][m] += wt[m];
            }
        }
        // The block's pixels inside the image, with their hit flags.
        let inside = b..(b + LANES).min(w);
        for (m, _) in hit[inside].iter().enumerate().filter(|(_, h)| **h != 0.0) {
            let x = b + m;
            let inv = 1.0 / acc[6][m];
            let sv = Vec3::new(acc[0][m], acc[1][m], acc[2][m]) * inv;
            let uv = Vec3::new(acc[3][m], acc[4][m], acc[5][m]) * inv;
            for (k, v) in sv.to_array().into_iter().chain(uv.to_array()).enumerate() {
                out[k][at + x] = v;
            }
            out[6][at + x] = filter_guide(sv, uv);
        }
    }
}

#[cfg(test)]
mod tests;
