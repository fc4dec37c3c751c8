//! The representative VPLs of a light as the CPU's unbiased estimate weighs them (Lin &
//! Yuksel 2019 section 3.3 with docs/design.md, "Shadow targets"): [`RepSet`], the weight of
//! one representative at a pixel, and the colours its gain compares.

use glam::Vec3;
use lgh_core::color::luminance;
use lgh_core::lighting_grid::representative::{NONE, SLOTS};
use lgh_core::vpl::Vpls;

/// The [`SLOTS`] representative VPLs of one light, structure of arrays (positions, normals
/// and flux colours per axis), so that weighing all of them for a pixel is a few vector
/// operations on adjacent cache lines. A zero normal marks an empty slot. The colour of
/// each VPL's flux ([`chroma`]) is kept here so that the unbiased estimate's gain needs no
/// read of the VPL itself: a pass that draws targets for pixel after pixel waits on memory
/// for each such read, and those lines sit next to the ones the weights have just read.
#[derive(Clone, Copy, Debug, Default)]
#[repr(align(64))]
pub(super) struct RepSet {
    position: [[f32; SLOTS]; 3],
    normal: [[f32; SLOTS]; 3],
    colour: [[f32; SLOTS]; 3],
}

impl RepSet {
    /// Slot `s`: position and normal.
    pub(super) fn get(&self, s: usize) -> (Vec3, Vec3) {
        let [px, py, pz] = self.position;
        let [nx, ny, nz] = self.normal;
        (
            Vec3::new(px[s], py[s], pz[s]),
            Vec3::new(nx[s], ny[s], nz[s]),
        )
    }

    /// The flux colour of slot `s`.
    pub(super) fn colour(&self, s: usize) -> Vec3 {
        let [r, g, b] = &self.colour;
        Vec3::new(r[s], g[s], b[s])
    }

    /// Sets slot `s` to a VPL at `p` with normal `n` and flux `flux`.
    pub(super) fn set(&mut self, s: usize, p: Vec3, n: Vec3, flux: Vec3) {
        let colour = chroma(flux);
        for a in 0..3 {
            self.position[a][s] = p[a];
            self.normal[a][s] = n[a];
            self.colour[a][s] = colour[a];
        }
    }

    /// A sum of one value of each of its cache lines: reading it ahead of the weights
    /// brings the lines in.
    pub(super) fn touch(&self) -> f32 {
        (0..3)
            .map(|a| self.position[a][0] + self.normal[a][0] + self.colour[a][0])
            .sum()
    }

    /// The representatives `slots` (VPL indices, [`NONE`] for an empty slot) of `vpls`.
    pub(super) fn of(slots: &[u32], vpls: &Vpls) -> Self {
        let mut set = Self::default();
        for (s, &r) in slots.iter().enumerate() {
            if r != NONE {
                let r = r as usize;
                set.set(s, vpls.positions[r], vpls.normals[r], vpls.flux[r]);
            }
        }
        set
    }

    /// [`representative_weight`] of every slot for the pixel at `x` with normal `n_x`.
    #[inline]
    pub(super) fn weights(&self, x: Vec3, n_x: Vec3, eps2: f32) -> [f32; SLOTS] {
        let [px, py, pz] = &self.position;
        let [nx, ny, nz] = &self.normal;
        // A plain loop over the lanes, not `array::from_fn`: in some builds its closure was
        // compiled as an out-of-line call (docs/performance.md, "Shadow targets").
        let mut w = [0.0; SLOTS];
        for (s, w) in w.iter_mut().enumerate() {
            *w = representative_weight(
                x,
                n_x,
                Vec3::new(px[s], py[s], pz[s]),
                Vec3::new(nx[s], ny[s], nz[s]),
                eps2,
            );
        }
        w
    }
}

/// An RGB value divided by its luminance (its colour at unit luminance); zero for a value
/// without luminance.
pub(super) fn chroma(c: Vec3) -> Vec3 {
    let lum = luminance(c);
    if lum > 0.0 { c / lum } else { Vec3::ZERO }
}

/// The colour `c` relative to the colour `of` channel by channel, zero in a channel where
/// `of` has none: a light with no flux in a channel has no VPL with flux in it either.
pub(super) fn relative_colour(c: Vec3, of: Vec3) -> Vec3 {
    Vec3::select(of.cmpgt(Vec3::ZERO), c / of, Vec3::ZERO)
}

/// The contribution at x (normal n_x) of a representative VPL at q (normal n_q) as a VPL
/// of its light's intensity I, up to the factor luminance(I) / pi that a light's
/// representatives share: cos_x cos_q / (d^2 + eps^2) = max(0, n_x . d) max(0, -n_q . d) /
/// (d^2 (d^2 + eps^2)), d = q - x, without a branch or a square root (the shadow targets
/// weigh 8 of them per selected sample). Zero where d = 0.
#[inline]
pub(super) fn representative_weight(x: Vec3, n_x: Vec3, q: Vec3, n_q: Vec3, eps2: f32) -> f32 {
    let d = q - x;
    let d2 = d.length_squared();
    let w = n_x.dot(d).max(0.0) * (-n_q.dot(d)).max(0.0) / (d2 * (d2 + eps2));
    if w.is_finite() { w } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lgh_core::rng::Rng;
    use lgh_core::vpl::light_irradiance;

    /// A light or VPL with no flux in a channel (a pure-red wall's VPLs) gives a finite
    /// colour, zero in that channel, and a VPL without flux no colour: divided channel by
    /// channel, 0 / 0 would put NaN in the sample's gain.
    #[test]
    fn colours_of_lights_without_some_channel_stay_finite() {
        let red = Vec3::new(0.8, 0.0, 0.0);
        let vpl = Vec3::new(0.3, 0.0, 0.0);
        let c = relative_colour(chroma(vpl), chroma(red));
        assert_eq!(c, Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(chroma(Vec3::ZERO), Vec3::ZERO);
        let mixed = relative_colour(chroma(Vec3::new(0.1, 0.2, 0.0)), chroma(Vec3::ONE));
        assert!(mixed.is_finite() && mixed.z == 0.0 && mixed.y > mixed.x);
    }

    /// The representatives' weight is their VPL contribution divided by luminance(I) / pi,
    /// for random positions and normals (both sides of both surfaces), and zero at d = 0.
    #[test]
    fn representative_weight_is_the_vpl_contribution() {
        let mut rng = Rng::new(&[17, 3]);
        let mut v = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
        let intensity = Vec3::new(0.7, 1.3, 0.4);
        let eps2 = 1e-4;
        let mut lit = 0;
        for _ in 0..2000 {
            let (x, q) = (v(), v());
            let (n_x, n_q) = (v().normalize(), v().normalize());
            let exact = luminance(light_irradiance(x, n_x, q, n_q, 0.0, intensity, eps2));
            let w = representative_weight(x, n_x, q, n_q, eps2) * luminance(intensity)
                / std::f32::consts::PI;
            assert!(
                (w - exact).abs() <= 1e-4 * exact.max(1e-3),
                "{w} vs {exact}"
            );
            lit += usize::from(exact > 0.0);
        }
        assert!(lit > 300, "{lit}");
        assert_eq!(
            representative_weight(Vec3::ONE, Vec3::Y, Vec3::ONE, -Vec3::Y, eps2),
            0.0
        );
    }
}
