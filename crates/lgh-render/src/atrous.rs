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
    let mut cur_s = s.to_vec();
    let mut cur_u = u.to_vec();
    for pass in 0..params.passes {
        let step = 1i64 << pass;
        let c_phi = params.c_phi / 4f32.powi(pass as i32);
        let guide: Vec<f32> = cur_s
            .iter()
            .zip(&cur_u)
            .map(|(&a, &b)| ratio(a, b))
            .collect();
        let mut out_s = vec![Vec3::ZERO; s.len()];
        let mut out_u = vec![Vec3::ZERO; s.len()];
        out_s
            .par_chunks_mut(w as usize)
            .zip(out_u.par_chunks_mut(w as usize))
            .enumerate()
            .for_each(|(y, (row_s, row_u))| {
                let y = y as i64;
                for x in 0..w {
                    let p = (y * w + x) as usize;
                    if !g.is_hit(p) {
                        row_s[x as usize] = cur_s[p];
                        row_u[x as usize] = cur_u[p];
                        continue;
                    }
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
                            let q = (qy * w + qx) as usize;
                            if !g.is_hit(q) {
                                continue;
                            }
                            let dc = guide[p] - guide[q];
                            let dn = g.normal[p] - g.normal[q];
                            let dx = g.position[p] - g.position[q];
                            // w_c w_n w_x as one exponential (each exponent is <= 0, so
                            // the clamps to 1 of the separate weights are implied).
                            let wgt = hx
                                * hy
                                * (-(dc * dc) / c_phi
                                    - dn.length_squared() / params.n_phi
                                    - dx.length_squared() / params.p_phi)
                                    .exp();
                            acc_s += cur_s[q] * wgt;
                            acc_u += cur_u[q] * wgt;
                            acc_w += wgt;
                        }
                    }
                    // The centre tap has weight h(0) > 0, so acc_w > 0.
                    row_s[x as usize] = acc_s / acc_w;
                    row_u[x as usize] = acc_u / acc_w;
                }
            });
        cur_s = out_s;
        cur_u = out_u;
    }
    (cur_s, cur_u)
}
