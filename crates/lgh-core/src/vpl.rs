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
    /// The VPLs as the input lights of a lighting grid hierarchy (oriented, intensity =
    /// flux).
    #[must_use]
    pub fn as_input(&self) -> crate::lighting_grid::InputLights<'_> {
        crate::lighting_grid::InputLights {
            positions: &self.positions,
            intensity: &self.flux,
            normals: Some(&self.normals),
        }
    }

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

    /// Appends the first `n` VPLs of `other` (all of them if it has fewer).
    pub fn extend_prefix(&mut self, other: &Vpls, n: usize) {
        let n = n.min(other.len());
        self.positions.extend_from_slice(&other.positions[..n]);
        self.normals.extend_from_slice(&other.normals[..n]);
        self.flux.extend_from_slice(&other.flux[..n]);
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
/// The `eps` clamp of 1/d^2 is the authors' code's (eps = 0.01 x scene radius; docs/design.md,
/// "Clamps"). Returns zero when either cosine is not positive (back-facing early-out).
#[inline]
#[must_use]
pub fn vpl_irradiance(x: Vec3, n_x: Vec3, p: Vec3, n_v: Vec3, flux: Vec3, eps2: f32) -> Vec3 {
    light_irradiance(x, n_x, p, n_v, 0.0, flux, eps2)
}

/// How the emission of a grid light, which stands for many oriented VPLs, depends on the
/// direction. The paper is silent; the authors' demo code uses
/// [`GridEmission::MeanNormal`], which loses light in a closed room, so this project's
/// default is [`GridEmission::EnergyConserving`] (docs/design.md, "Grid-light emission").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum GridEmission {
    /// `max(0, m . w)` with m the weighted mean normal, not renormalised (the demo code): a
    /// cluster whose normals disagree (a room's corner) has |m| < 1 and loses that share of
    /// its light.
    MeanNormal,
    /// `max(0, m . w) + (1 - |m|) / 4`: the lost share is emitted uniformly over the sphere
    /// instead. Both terms integrate to pi per unit |m| over the sphere, so a cluster emits the
    /// total flux of its VPLs whatever its normals (the 1/4 is the mean of a clamped cosine
    /// over the sphere, its zeroth spherical-harmonic band). Exact for one VPL (|m| = 1). An
    /// extension of this project, not in the paper; the default.
    #[default]
    #[cfg_attr(feature = "clap", value(name = "energy"))]
    #[serde(rename = "energy")]
    EnergyConserving,
}

impl GridEmission {
    /// The direction-independent part of the emission cosine for mean normal `m`:
    /// 0 for [`GridEmission::MeanNormal`], `(1 - |m|) / 4` for
    /// [`GridEmission::EnergyConserving`].
    #[inline]
    #[must_use]
    pub fn isotropic(self, m: Vec3) -> f32 {
        match self {
            Self::MeanNormal => 0.0,
            Self::EnergyConserving => 0.25 * (1.0 - m.length()).clamp(0.0, 1.0),
        }
    }
}

/// [`vpl_irradiance`] for a light with mean normal `m` (|m| <= 1) and an isotropic emission
/// share `iso` ([`GridEmission::isotropic`]): the emission cosine is `max(0, m . w_v) + iso`.
#[inline]
#[must_use]
pub fn light_irradiance(
    x: Vec3,
    n_x: Vec3,
    p: Vec3,
    m: Vec3,
    iso: f32,
    flux: Vec3,
    eps2: f32,
) -> Vec3 {
    let d = p - x;
    let d2 = d.length_squared();
    light_irradiance_along(d, d2, d2.sqrt().recip(), n_x, m, iso, flux, eps2)
}

/// [`light_irradiance`] with the offset d = p - x, d^2 and 1 / |d| already at hand (the LGH
/// lighting loop needs them for the blending weight first).
#[inline]
#[must_use]
#[allow(clippy::too_many_arguments)]
pub fn light_irradiance_along(
    d: Vec3,
    d2: f32,
    inv_d: f32,
    n_x: Vec3,
    m: Vec3,
    iso: f32,
    flux: Vec3,
    eps2: f32,
) -> Vec3 {
    flux * (light_geometry(d, d2, inv_d, n_x, m, iso, eps2) * std::f32::consts::FRAC_1_PI)
}

/// The geometry term G = cos_x cos_v / (d^2 + eps^2) of a light with emission normal `m` and
/// isotropic share `iso` at offset d = p - x (with d^2 and 1 / |d| at hand) from a receiver
/// with normal `n_x`, cos_v = max(0, -m . w) + iso; zero where either cosine is not positive
/// or d is zero. [`light_irradiance_along`] is flux G / pi.
#[inline]
#[must_use]
pub fn light_geometry(
    d: Vec3,
    d2: f32,
    inv_d: f32,
    n_x: Vec3,
    m: Vec3,
    iso: f32,
    eps2: f32,
) -> f32 {
    let cos_x = n_x.dot(d) * inv_d;
    let cos_v = (-m.dot(d) * inv_d).max(0.0) + iso;
    if cos_x <= 0.0 || cos_v <= 0.0 || !inv_d.is_finite() {
        return 0.0;
    }
    cos_x * cos_v / (d2 + eps2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Integral over the sphere of the emission cosine, by a fine midpoint rule in
    /// (cos theta, phi) around the z axis.
    fn emitted(m: Vec3, iso: f32) -> f64 {
        let (nt, np) = (400, 400);
        let mut sum = 0.0f64;
        for i in 0..nt {
            let z = -1.0 + (i as f32 + 0.5) * 2.0 / nt as f32;
            let r = (1.0 - z * z).sqrt();
            for j in 0..np {
                let phi = (j as f32 + 0.5) * std::f32::consts::TAU / np as f32;
                let w = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                sum += f64::from(m.dot(w).max(0.0) + iso);
            }
        }
        sum * 4.0 * std::f64::consts::PI / f64::from(nt * np)
    }

    #[test]
    fn energy_conserving_emission_integrates_to_pi_for_any_mean_normal() {
        let pi = std::f64::consts::PI;
        // Two VPLs at a right-angle corner, opposite walls, a single VPL, a mixed cluster.
        let corner = (Vec3::Y + Vec3::X) * 0.5;
        let opposite = (Vec3::Y - Vec3::Y) * 0.5;
        let mixed = (Vec3::Y * 3.0 + Vec3::X - Vec3::Z * 2.0).normalize() * 0.37;
        for m in [corner, opposite, Vec3::Y, mixed] {
            let e = emitted(m, GridEmission::EnergyConserving.isotropic(m));
            assert!((e - pi).abs() < 1e-3 * pi, "{m}: {e}");
            let lost = emitted(m, GridEmission::MeanNormal.isotropic(m));
            assert!(
                (lost - pi * f64::from(m.length())).abs() < 1e-3 * pi,
                "{m}: {lost}"
            );
        }
    }

    #[test]
    fn a_single_vpl_is_the_same_under_both_models() {
        let (x, nx) = (Vec3::ZERO, Vec3::Y);
        let (p, n) = (Vec3::new(0.3, 1.0, -0.2), -Vec3::Y);
        let flux = Vec3::new(1.0, 2.0, 3.0);
        let iso = GridEmission::EnergyConserving.isotropic(n);
        assert_eq!(iso, 0.0);
        assert_eq!(
            light_irradiance(x, nx, p, n, iso, flux, 1e-4),
            vpl_irradiance(x, nx, p, n, flux, 1e-4)
        );
    }
}
