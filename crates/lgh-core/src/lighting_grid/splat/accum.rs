//! The sums of one vertex of a level, in double precision, and the moments of a source that
//! contributions scale and shift.

use glam::{DVec3, Vec3};

use super::Sources;
use super::sort::{Cluster, PSource};

/// Sums of one vertex: W, P (local, cell units), Q (local, squared), intensity, normal.
/// Double precision: a coarse vertex sums millions of contributions, which f32 would round
/// to a relative error near 1e-4. Stored as one padded array `[W, P, Q, I, N, 0, 0, 0]` so
/// that adding a weighted contribution is a plain loop the compiler vectorises.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Accum {
    s: [f64; 16],
}

impl Accum {
    pub(super) fn from_parts(w: f64, p: DVec3, q: DVec3, i: DVec3, n: DVec3) -> Self {
        let mut s = [0.0; 16];
        s[0] = w;
        for (k, v) in [p, q, i, n].into_iter().enumerate() {
            s[1 + 3 * k..4 + 3 * k].copy_from_slice(&v.to_array());
        }
        Self { s }
    }

    pub(super) fn part(&self, k: usize) -> DVec3 {
        DVec3::new(self.s[1 + 3 * k], self.s[2 + 3 * k], self.s[3 + 3 * k])
    }

    /// Total weight W.
    pub fn w(&self) -> f64 {
        self.s[0]
    }

    /// Weighted local position sum P.
    pub fn p(&self) -> DVec3 {
        self.part(0)
    }

    /// Weighted local squared position (plus variance) sum Q.
    pub fn q(&self) -> DVec3 {
        self.part(1)
    }

    /// Weighted intensity sum.
    pub fn i(&self) -> DVec3 {
        self.part(2)
    }

    /// Weighted normal sum.
    pub fn n(&self) -> DVec3 {
        self.part(3)
    }

    /// The moments of prepared source `ps` (with its cluster attributes `c`, if any) for a
    /// vertex at offset 0 from its cell: W = m, P = m g, Q = m (g^2 + var), intensity, m n,
    /// where a point source has m = 1, g = f and var = 0. A contribution is these times the
    /// trilinear weight ([`Accum::add_scaled`]); [`Accum::shifted`] moves them to another
    /// corner. Computed once per source and layer instead of once per corner.
    #[inline(always)]
    pub(super) fn moments(ps: &PSource, c: Option<&Cluster>) -> Self {
        let (m, g, var) = c.map_or((1.0, ps.f, Vec3::ZERO), |c| (c.mass, c.g, c.variance));
        let (m, g) = (f64::from(m), g.as_dvec3());
        Self::from_parts(
            m,
            m * g,
            m * (g * g + var.as_dvec3()),
            ps.intensity.as_dvec3(),
            m * ps.normal.as_dvec3(),
        )
    }

    /// These moments seen from a vertex one cell further along `axis`: the local position g
    /// becomes g - 1 there, so P - W and Q - (2 P - W) (exact algebra:
    /// (g - 1)^2 = g^2 - 2 g + 1).
    #[inline(always)]
    pub(super) fn shifted(&self, axis: usize) -> Self {
        let mut s = self.s;
        let (w, p) = (s[0], s[1 + axis]);
        s[1 + axis] = p - w;
        s[4 + axis] -= 2.0 * p - w;
        Self { s }
    }

    /// Adds moments `m` with trilinear weight `w`.
    #[inline(always)]
    pub(super) fn add_scaled(&mut self, w: f64, m: &Self) {
        for (a, b) in self.s.iter_mut().zip(&m.s) {
            *a += w * b;
        }
    }

    /// Adds source `s` of `src` (unprepared) with weight `w` at local offset `local`;
    /// `inv_h2` converts the source's variance to cell units. For the reference builder.
    pub(crate) fn add_source(&mut self, src: &Sources, s: usize, w: f32, local: Vec3, inv_h2: f32) {
        let m = src.mass.map_or(1.0, |m| m[s]);
        let var = src
            .variance
            .map_or(Vec3::ZERO, |v| v[s] * inv_h2)
            .as_dvec3();
        let wm = f64::from(w * m);
        let local = local.as_dvec3();
        let n = src.normals.map_or(DVec3::ZERO, |n| wm * n[s].as_dvec3());
        self.add_scaled(
            1.0,
            &Self::from_parts(
                wm,
                wm * local,
                wm * (local * local + var),
                f64::from(w) * src.intensity[s].as_dvec3(),
                n,
            ),
        );
    }
}
