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
/// split into an integer power set in the exponent bits and a polynomial for the fraction; 0
/// beyond e = 80.
#[inline]
fn exp_neg(e: f32) -> f32 {
    if e.is_nan() || e >= 80.0 {
        return 0.0;
    }
    let t = -e * std::f32::consts::LOG2_E;
    // round(t) for t <= 0 without a libm call: truncation of a positive number is its floor.
    let i = -(((0.5 - t) as i32) as f32);
    let f = t - i; // in (-0.5, 0.5]
    // 2^f = e^(f ln 2) by its Taylor series to degree 5 (relative error below 1e-6 here).
    let p = 1.0
        + f * (std::f32::consts::LN_2
            + f * (0.240_226_5 + f * (0.055_504_1 + f * (0.009_618_1 + f * 0.001_333_4))));
    // Clamp the exponent so that 2^i stays a normal float.
    let bits = (((i as i32).max(-126) + 127) as u32) << 23;
    f32::from_bits(bits) * p
}

/// What one tap reads, packed so that a tap touches one cache line instead of six arrays.
#[derive(Clone, Copy, Debug, Default)]
struct Tap {
    position: Vec3,
    normal: Vec3,
    s: Vec3,
    u: Vec3,
    guide: f32,
    hit: bool,
}

/// Filters S and U with identical edge-stopping weights (see the module docs). Pixels that
/// see nothing are left as they are and never used as taps.
#[must_use]
pub fn filter_ratio_pair(
    s: &[Vec3],
    u: &[Vec3],
    g: &GBuffer,
    params: &AtrousParams,
) -> (Vec<Vec3>, Vec<Vec3>) {
    let (w, h) = (g.width as i64, g.height as i64);
    let mut taps: Vec<Tap> = (0..s.len())
        .into_par_iter()
        .map(|p| Tap {
            position: g.position[p],
            normal: g.normal[p],
            s: s[p],
            u: u[p],
            guide: ratio(s[p], u[p]),
            hit: g.is_hit(p),
        })
        .collect();
    let (inv_n, inv_p) = (1.0 / params.n_phi, 1.0 / params.p_phi);
    // Two buffers, ping-ponged: fresh pages cost as much as the filtering on this VM.
    let mut next = taps.clone();
    for pass in 0..params.passes {
        let step = 1i64 << pass;
        let inv_c = 4f32.powi(pass as i32) / params.c_phi;
        let src = &taps;
        next.par_iter_mut().enumerate().for_each(|(p, out)| {
            let c = src[p];
            if !c.hit {
                *out = c;
                return;
            }
            let (y, x) = (p as i64 / w, p as i64 % w);
            let (mut acc_s, mut acc_u, mut acc_w) = (Vec3::ZERO, Vec3::ZERO, 0.0f32);
            for (j, hy) in H1.iter().enumerate() {
                let qy = y + (j as i64 - 2) * step;
                if qy < 0 || qy >= h {
                    continue;
                }
                for (i, hx) in H1.iter().enumerate() {
                    let qx = x + (i as i64 - 2) * step;
                    if qx < 0 || qx >= w {
                        continue;
                    }
                    let q = &src[(qy * w + qx) as usize];
                    if !q.hit {
                        continue;
                    }
                    let dc = c.guide - q.guide;
                    // w_c w_n w_x as one exponential (each exponent is <= 0, so the
                    // clamps to 1 of the separate weights are implied).
                    let e = dc * dc * inv_c
                        + (c.normal - q.normal).length_squared() * inv_n
                        + (c.position - q.position).length_squared() * inv_p;
                    let wgt = hx * hy * exp_neg(e);
                    acc_s += q.s * wgt;
                    acc_u += q.u * wgt;
                    acc_w += wgt;
                }
            }
            // The centre tap has weight h(0) > 0, so acc_w > 0.
            let (s, u) = (acc_s / acc_w, acc_u / acc_w);
            *out = Tap {
                s,
                u,
                guide: ratio(s, u),
                ..c
            };
        });
        std::mem::swap(&mut taps, &mut next);
    }
    taps.into_iter().map(|t| (t.s, t.u)).unzip()
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
        assert_eq!(super::exp_neg(100.0), 0.0);
        assert_eq!(super::exp_neg(f32::NAN), 0.0);
    }
}
