//! Edge-avoiding a-trous wavelet filter (Dammertz, Sewtz, Hanika & Lensch 2010), used on the
//! shadow estimates of the ratio estimator (LGH 2019 section 3.3).
//!
//! Pass i (i = 0..n-1) convolves with the 5 x 5 B3-spline kernel h = h1 x h1,
//! h1 = (1/16, 1/4, 3/8, 1/4, 1/16), whose taps are 2^i pixels apart, and weights each tap by
//! edge-stopping functions w = w_c w_n w_x:
//! w_c = exp(-|c_p - c_q|^2 / c_phi_i) on the guide image, with c_phi halved in standard
//! deviation (quartered) at every pass; w_n = exp(-|N_p - N_q|^2 / n_phi) on the shading
//! normals; w_x = exp(-|X_p - X_q|^2 / p_phi) on the world positions. Defaults are the LGH
//! demo's (design notes section 8): 5 passes, c_phi = 0.5, n_phi = 0.1, p_phi = 0.66 x scene
//! radius.
//!
//! [`filter_ratio_pair`] filters the two images of the ratio estimator, S and U, with one and
//! the same set of weights (the guide is the current ratio lum(S)/lum(U)), so that
//! D(S) <= D(U) channel by channel and the filtered ratio stays in [0, 1]. (The demo weighs S
//! and U with separate colour weights, a quirk the design notes say not to copy.)

use glam::Vec3;
use lgh_core::color::luminance;
use rayon::prelude::*;

use crate::gbuffer::GBuffer;

/// Parameters of the filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtrousParams {
    /// Number of passes (step widths 1, 2, 4, ...).
    pub passes: u32,
    /// Colour (guide) weight parameter c_phi = sigma_c^2 of the first pass.
    pub c_phi: f32,
    /// Normal weight parameter n_phi.
    pub n_phi: f32,
    /// Position weight parameter p_phi (squared world distance scale).
    pub p_phi: f32,
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
        }
    }
}

const H1: [f32; 5] = [1.0 / 16.0, 1.0 / 4.0, 3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0];

fn ratio(s: Vec3, u: Vec3) -> f32 {
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

/// Number of per-pixel planes of [`Planes`]: position, normal, S, U (3 each), guide, hit.
const PLANES: usize = 14;
/// First of the planes a pass writes (S r, g, b, U r, g, b, guide).
const OUT: usize = 6;
const GUIDE: usize = 12;
const HIT: usize = 13;

/// Pixels processed together in the inner loop: fixed-size blocks vectorise reliably.
const LANES: usize = 8;

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

/// The planes a pass reads: position x, y, z, normal x, y, z and hit (1 or 0), which never
/// change (`fixed`, planes 0..6 and 6), and S r, g, b, U r, g, b and guide, which every pass
/// rewrites (`dynamic`, ping-ponged between two buffers).
struct Planes<'a> {
    layout: Layout,
    fixed: &'a [f32],
    dynamic: &'a [f32],
}

impl Planes<'_> {
    /// Row `y` of plane `k` (numbered as [`PLANES`] lists them), padding included.
    fn row(&self, k: usize, y: usize) -> &[f32] {
        let (buf, k) = match k {
            OUT..HIT => (self.dynamic, k - OUT),
            HIT => (self.fixed, 6),
            _ => (self.fixed, k),
        };
        let at = k * self.layout.plane() + y * self.layout.stride;
        &buf[at..at + self.layout.stride]
    }
}

/// Filters S and U with identical edge-stopping weights (see the module docs). Pixels that
/// see nothing are left as they are and never used as taps.
///
/// Layout for speed: structure-of-arrays planes with padded rows; for every output row the
/// 25 taps are the outer loop and blocks of [`LANES`] pixels the inner one, so that the
/// inner loop reads contiguous memory and vectorises (measured 4x faster than a loop over
/// taps per pixel). Only the 7 planes a pass rewrites are double-buffered.
#[must_use]
pub fn filter_ratio_pair(
    s: &[Vec3],
    u: &[Vec3],
    g: &GBuffer,
    params: &AtrousParams,
) -> (Vec<Vec3>, Vec<Vec3>) {
    let (w, h) = (g.width as usize, g.height as usize);
    let passes = params.passes.min(12);
    let pad = 2 << passes.saturating_sub(1);
    let layout = Layout {
        stride: pad + w.div_ceil(LANES) * LANES + pad,
        pad,
        height: h,
    };
    // Plane k, row y: the image's pixels from `pad` on.
    let fill = |buf: &mut [f32], value: &(dyn Fn(usize) -> f32 + Sync)| {
        buf.par_chunks_mut(layout.stride)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, v) in row[pad..pad + w].iter_mut().enumerate() {
                    let p = y * w + x;
                    *v = if g.is_hit(p) { value(p) } else { 0.0 };
                }
            });
    };
    let plane = layout.plane();
    let mut fixed = vec![0.0f32; 7 * plane];
    let mut cur = vec![0.0f32; 7 * plane];
    for (c, buf) in fixed.chunks_mut(plane).enumerate() {
        match c {
            0..3 => fill(buf, &|p| g.position[p][c]),
            3..6 => fill(buf, &|p| g.normal[p][c - 3]),
            _ => fill(buf, &|_| 1.0),
        }
    }
    for (c, buf) in cur.chunks_mut(plane).enumerate() {
        match c {
            0..3 => fill(buf, &|p| s[p][c]),
            3..6 => fill(buf, &|p| u[p][c - 3]),
            _ => fill(buf, &|p| ratio(s[p], u[p])),
        }
    }
    let (inv_n, inv_p) = (1.0 / params.n_phi, 1.0 / params.p_phi);
    // Non-hit pixels and padding stay zero in both buffers: passes write only hit pixels.
    let mut next = vec![0.0f32; 7 * plane];
    for pass in 0..passes {
        let step = 1usize << pass;
        let inv_c = 4f32.powi(pass as i32) / params.c_phi;
        let src = Planes {
            layout,
            fixed: &fixed,
            dynamic: &cur,
        };
        // Output rows in parallel; each task writes its row of the 7 output planes.
        let mut rows: Vec<Vec<&mut [f32]>> = (0..h).map(|_| Vec::with_capacity(7)).collect();
        for (r, chunk) in next.chunks_mut(layout.stride).enumerate() {
            rows[r % h].push(chunk);
        }
        rows.into_par_iter().enumerate().for_each(|(y, mut row)| {
            filter_row(&src, &mut row, w, y, step, [inv_c, inv_n, inv_p]);
        });
        std::mem::swap(&mut cur, &mut next);
    }
    let pixel = |c: usize, p: usize| {
        let at = |k: usize| cur[(c + k) * plane + (p / w) * layout.stride + pad + p % w];
        Vec3::new(at(0), at(1), at(2))
    };
    (0..s.len())
        .into_par_iter()
        .map(|p| {
            if g.is_hit(p) {
                (pixel(0, p), pixel(3, p))
            } else {
                // Pixels that see nothing keep their input values.
                (s[p], u[p])
            }
        })
        .unzip()
}

/// `LANES` values of `s` from `b` on.
#[inline(always)]
fn block(s: &[f32], b: usize) -> [f32; LANES] {
    let mut out = [0.0; LANES];
    out.copy_from_slice(&s[b..b + LANES]);
    out
}

/// One output row `y` of one pass: `out` holds the row's S r, g, b, U r, g, b and guide
/// (padded like the planes). Compiled for AVX2 as well, chosen at run time (the blocks then
/// run 8 lanes wide instead of 4).
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
fn filter_row(
    src: &Planes,
    out: &mut [&mut [f32]],
    w: usize,
    y: usize,
    step: usize,
    [inv_c, inv_n, inv_p]: [f32; 3],
) {
    let (pad, h) = (src.layout.pad, src.layout.height);
    let wp = w.div_ceil(LANES) * LANES;
    // Accumulators: S r, g, b, U r, g, b, weight.
    let mut acc = vec![[0.0f32; LANES]; 7 * (wp / LANES)];
    let centre: [&[f32]; 7] = [0, 1, 2, 3, 4, 5, GUIDE].map(|k| &src.row(k, y)[pad..pad + wp]);
    for (j, hy) in H1.iter().enumerate() {
        let qy = y as i64 + (j as i64 - 2) * step as i64;
        if qy < 0 || qy >= h as i64 {
            continue;
        }
        let tap: [&[f32]; PLANES] = std::array::from_fn(|k| src.row(k, qy as usize));
        for (i, hx) in H1.iter().enumerate() {
            // The tap row shifted by dx = (i - 2) step, within the padding.
            let from = (pad as i64 + (i as i64 - 2) * step as i64) as usize;
            let q: [&[f32]; PLANES] = tap.map(|t| &t[from..from + wp]);
            let hxy = hx * hy;
            for (bi, b) in (0..wp).step_by(LANES).enumerate() {
                let c = |k: usize| block(centre[k], b);
                let t = |k: usize| block(q[k], b);
                let (cpx, cpy, cpz, cnx, cny, cnz, cg) = (c(0), c(1), c(2), c(3), c(4), c(5), c(6));
                let (qpx, qpy, qpz, qnx, qny, qnz) = (t(0), t(1), t(2), t(3), t(4), t(5));
                let (qg, qhit) = (t(GUIDE), t(HIT));
                let mut wgt = [0.0f32; LANES];
                for m in 0..LANES {
                    let dc = cg[m] - qg[m];
                    let (dnx, dny, dnz) = (cnx[m] - qnx[m], cny[m] - qny[m], cnz[m] - qnz[m]);
                    let (dpx, dpy, dpz) = (cpx[m] - qpx[m], cpy[m] - qpy[m], cpz[m] - qpz[m]);
                    // w_c w_n w_x as one exponential (each exponent is <= 0, so the clamps
                    // to 1 of the separate weights are implied).
                    let e = dc * dc * inv_c
                        + (dnx * dnx + dny * dny + dnz * dnz) * inv_n
                        + (dpx * dpx + dpy * dpy + dpz * dpz) * inv_p;
                    wgt[m] = hxy * qhit[m] * exp_neg(e);
                }
                for c in 0..6 {
                    let v = t(OUT + c);
                    let a = &mut acc[7 * bi + c];
                    for m in 0..LANES {
                        a[m] += wgt[m] * v[m];
                    }
                }
                let a = &mut acc[7 * bi + 6];
                for m in 0..LANES {
                    a[m] += wgt[m];
                }
            }
        }
    }
    let hit = &src.row(HIT, y)[pad..pad + w];
    for x in (0..w).filter(|&x| hit[x] != 0.0) {
        let a = |c: usize| acc[7 * (x / LANES) + c][x % LANES];
        // The centre tap has weight h(0) > 0, so the weight sum is positive.
        let inv = 1.0 / a(6);
        let sv = Vec3::new(a(0), a(1), a(2)) * inv;
        let uv = Vec3::new(a(3), a(4), a(5)) * inv;
        for (k, v) in sv.to_array().into_iter().chain(uv.to_array()).enumerate() {
            out[k][pad + x] = v;
        }
        out[6][pad + x] = ratio(sv, uv);
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn exp_neg_is_close_to_exp() {
        let mut e = 0.0f32;
        while e < 60.0 {
            let (a, b) = (super::exp_neg(e), (-e).exp());
            assert!((a - b).abs() <= 2e-4 * b + 1e-30, "{e}: {a} vs {b}");
            e += 0.013;
        }
        assert!(super::exp_neg(100.0) < 1e-30);
        assert!(super::exp_neg(f32::NAN) < 1e-30);
        assert!(super::exp_neg(f32::INFINITY) < 1e-30);
    }
}
