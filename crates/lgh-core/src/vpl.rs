//! Virtual point lights (VPLs), stored structure-of-arrays.
//!
//! A VPL stands for light that arrived at a diffuse surface point and is reflected from there
//! (Keller 1997, "Instant Radiosity"; LGH 2019 section 3 uses them as the input S_0 of the
//! hierarchy). It is oriented: it emits with a cosine around its normal, so its radiant
//! intensity towards direction w is `flux * max(0, n . w) / pi`.

use glam::Vec3;

/// A set of VPLs: `positions[i]`, `normals[i]` and `flux[i]` describe VPL i.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Vpls {
    /// World-space positions p_i.
    pub positions: Vec<Vec3>,
    /// Unit normals n_i of the surfaces the VPLs lie on, on the side the light arrived from.
    pub normals: Vec<Vec3>,
    /// Reflected RGB flux Phi_i (arriving flux times albedo), in watts.
    pub flux: Vec<Vec3>,
}

impl Vpls {
    /// An empty set with room for `n` VPLs.
    #[must_use]
    pub fn with_capacity(n: usize) -> Self {
        Self {
            positions: Vec::with_capacity(n),
            normals: Vec::with_capacity(n),
            flux: Vec::with_capacity(n),
        }
    }

    /// Number of VPLs.
    #[must_use]
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True if there is no VPL.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Appends one VPL.
    pub fn push(&mut self, position: Vec3, normal: Vec3, flux: Vec3) {
        self.positions.push(position);
        self.normals.push(normal);
        self.flux.push(flux);
    }

    /// Appends all VPLs of `other`.
    pub fn extend(&mut self, other: &Vpls) {
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.flux.extend_from_slice(&other.flux);
    }

    /// Multiplies every flux by `s`.
    pub fn scale_flux(&mut self, s: f32) {
        for f in &mut self.flux {
            *f *= s;
        }
    }

    /// Sum of all fluxes.
    #[must_use]
    pub fn total_flux(&self) -> Vec3 {
        self.flux.iter().copied().sum()
    }
}

/// Unshadowed irradiance-like term of one oriented VPL at a receiver, without the receiver's
/// BRDF: `Phi * max(0, n_v . w_v) * max(0, n_x . w_x) / (pi * (d^2 + eps^2))`, where w_x points
/// from the receiver x to the VPL and w_v = -w_x.
///
/// The `eps` clamp of 1/d^2 is the LGH design notes' choice (section 4.3, eps = 0.01 x scene
/// radius). Returns zero when either cosine is not positive (back-facing early-out).
#[inline]
#[must_use]
pub fn vpl_irradiance(x: Vec3, n_x: Vec3, p: Vec3, n_v: Vec3, flux: Vec3, eps2: f32) -> Vec3 {
    let d = p - x;
    let d2 = d.length_squared();
    let inv_d = d2.sqrt().recip();
    let cos_x = n_x.dot(d) * inv_d;
    let cos_v = -n_v.dot(d) * inv_d;
    if cos_x <= 0.0 || cos_v <= 0.0 || !inv_d.is_finite() {
        return Vec3::ZERO;
    }
    flux * (cos_x * cos_v / (std::f32::consts::PI * (d2 + eps2)))
}
