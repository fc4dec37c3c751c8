//! The lights of one screen tile as a structure of arrays, evaluated eight at a time for one
//! pixel: B_l(d) times the unshadowed irradiance of each light (LGH 2019 section 3.2, the
//! sum A = sum over lights of B_l(d) f_j of the lighting pass).
//!
//! The lighting loop visits, for every pixel, the lights listed for its tile. Evaluated one
//! light at a time, the arithmetic stays scalar and branchy (about 10 ns per accepted
//! (pixel, light) pair). Here a row of pixels copies its tile's list once into
//! [`LightBatch`] (lane-padded arrays, amortised over the tile's width), and
//! [`LightBatch::eval`] computes [`LANES`] lights at once without branches, so that the
//! compiler vectorises it; the caller then visits only the lights that contribute, in list
//! order, so the per-pixel sequence of reservoir updates is the one of the scalar loop.
//!
//! The blending function is evaluated branch-free: with x = d / r_l, the rising edge
//! clamp(2x - 1, 0, 1) and the falling edge clamp(2 - x, 0, 1) are each replaced by 1 where
//! the level's role has no such edge (lowest: no rising edge, top: no falling edge), and
//! B_l = min(rising, falling); this is [`lgh_core::blending::blend`] for every role.

use glam::Vec3;
use lgh_core::blending::LevelRole;
use lgh_core::color::luminance;

/// Lights evaluated together.
pub const LANES: usize = 8;

/// What the lighting loop reads of a light, in one cache line (the loop visits the lights of
/// a tile by index; separate arrays would cost one cache miss each per light).
#[derive(Clone, Copy, Debug)]
#[repr(align(64))]
pub struct PackedLight {
    /// Position of the light (grid-light centroid or VPL).
    pub position: Vec3,
    /// Squared reach (infinite for the top level).
    pub reach2: f32,
    /// Emission normal m (weighted mean normal for grid lights).
    pub normal: Vec3,
    /// Isotropic share of the emission cosine.
    pub iso: f32,
    /// Intensity times the interleaving scale n^2.
    pub intensity: Vec3,
    /// Radius r_l of the light's level.
    pub radius: f32,
    /// Role of the light's level in the blend.
    pub role: LevelRole,
    /// Level l of the light (0 for VPLs).
    pub level: u8,
}

/// The lights of one tile, lane-padded structure of arrays.
#[derive(Clone, Debug, Default)]
pub struct LightBatch {
    /// Which list this batch holds (caller-defined), if any.
    pub key: Option<(usize, usize)>,
    /// Global light index of each entry.
    pub index: Vec<u32>,
    /// Level of each entry.
    pub level: Vec<u8>,
    pos: [Vec<f32>; 3],
    normal: [Vec<f32>; 3],
    intensity: [Vec<f32>; 3],
    /// Luminance of the intensity.
    lum: Vec<f32>,
    iso: Vec<f32>,
    inv_radius: Vec<f32>,
    reach2: Vec<f32>,
    /// 1 where the role has no rising edge, else 0.
    rise_off: Vec<f32>,
    /// 1 where the role has no falling edge, else 0.
    fall_off: Vec<f32>,
}

/// The result of one [`LightBatch::eval`]: per lane, whether the light reaches the pixel
/// (counts as overdraw) and B_l(d) f_j (zero if it does not contribute).
#[derive(Clone, Copy, Debug, Default)]
pub struct LaneResult {
    /// d^2 < reach^2.
    pub reached: [bool; LANES],
    /// B_l(d) times the irradiance, RGB.
    pub value: [[f32; LANES]; 3],
    /// The luminance of `value` (B_l(d) times the irradiance of the intensity's luminance):
    /// the light's selection weight.
    pub lum: [f32; LANES],
}

/// The sum of a chunk's lanes as a tree: lane l + lane l + 4, then + 2, then + 1, which the
/// compiler does in vector registers (halves, quarters, pairs). A sequential sum is seven
/// dependent scalar adds of values read back from memory, which the lighting loop waited on
/// once per chunk (a quarter of its time in a profile of Sponza at 80K VPLs).
#[inline(always)]
#[must_use]
pub fn lane_sum(v: &[f32; LANES]) -> f32 {
    let half = [v[0] + v[4], v[1] + v[5], v[2] + v[6], v[3] + v[7]];
    let quarter = [half[0] + half[2], half[1] + half[3]];
    quarter[0] + quarter[1]
}

impl LightBatch {
    /// Number of lights (without padding).
    #[must_use]
    pub fn len(&self) -> usize {
        self.index.len()
    }

    /// True if there is no light.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.index.is_empty()
    }

    /// Number of [`LANES`]-wide chunks.
    #[must_use]
    pub fn chunks(&self) -> usize {
        self.len().div_ceil(LANES)
    }

    /// Fills the batch with the lights `list` (global indices into `packed`), in order.
    ///
    /// The arrays are sized once and written through local slices: pushing to 17 vectors
    /// kept every length and capacity in memory (the compiler cannot keep them in registers
    /// across the other vectors' stores), which cost more than the light data's cache misses.
    pub fn fill(
        &mut self,
        key: (usize, usize),
        packed: &[PackedLight],
        list: impl Iterator<Item = usize>,
    ) {
        let Self {
            key: batch_key,
            index,
            level,
            pos,
            normal,
            intensity,
            lum,
            iso,
            inv_radius,
            reach2,
            rise_off,
            fall_off,
        } = self;
        *batch_key = Some(key);
        index.clear();
        index.extend(list.map(|j| j as u32));
        let n = index.len();
        // Padding lanes never reach a pixel (d^2 >= -1 always).
        let padded = n.div_ceil(LANES) * LANES;
        for v in pos
            .iter_mut()
            .chain(normal.iter_mut())
            .chain(intensity.iter_mut())
            .chain([
                &mut *lum,
                &mut *iso,
                &mut *inv_radius,
                &mut *rise_off,
                &mut *fall_off,
            ])
        {
            v.clear();
            v.resize(padded, 0.0);
        }
        reach2.clear();
        reach2.resize(padded, -1.0);
        level.clear();
        level.resize(n, 0);
        let [px, py, pz] = pos.each_mut().map(|v| &mut v[..]);
        let [mx, my, mz] = normal.each_mut().map(|v| &mut v[..]);
        let [ir, ig, ib] = intensity.each_mut().map(|v| &mut v[..]);
        let (lum, iso) = (&mut lum[..], &mut iso[..]);
        let (inv_radius, reach2) = (&mut inv_radius[..], &mut reach2[..]);
        let (rise_off, fall_off, level) = (&mut rise_off[..], &mut fall_off[..], &mut level[..]);
        for (e, &j) in index.iter().enumerate() {
            let pl = &packed[j as usize];
            (px[e], py[e], pz[e]) = pl.position.into();
            (mx[e], my[e], mz[e]) = pl.normal.into();
            (ir[e], ig[e], ib[e]) = pl.intensity.into();
            lum[e] = luminance(pl.intensity);
            iso[e] = pl.iso;
            inv_radius[e] = pl.radius.recip();
            reach2[e] = pl.reach2;
            (rise_off[e], fall_off[e]) = pl.role.floors();
            level[e] = pl.level;
        }
    }

    /// Evaluates lights `LANES * chunk ..` for the pixel at `x` with normal `n`: the reach
    /// test, B_l(d), and the irradiance f_j = I_j cos_x cos_v / (pi (d^2 + eps^2)) with
    /// cos_v = max(0, -m . w) + iso (as [`lgh_core::vpl::light_irradiance_along`]).
    #[inline(always)]
    #[must_use]
    pub fn eval(&self, chunk: usize, x: Vec3, n: Vec3, eps2: f32) -> LaneResult {
        let o = chunk * LANES;
        let lane = |v: &Vec<f32>| -> [f32; LANES] {
            let mut a = [0.0; LANES];
            a.copy_from_slice(&v[o..o + LANES]);
            a
        };
        let (px, py, pz) = (lane(&self.pos[0]), lane(&self.pos[1]), lane(&self.pos[2]));
        let (mx, my, mz) = (
            lane(&self.normal[0]),
            lane(&self.normal[1]),
            lane(&self.normal[2]),
        );
        let (iso, inv_r, reach2) = (lane(&self.iso), lane(&self.inv_radius), lane(&self.reach2));
        let (rise_off, fall_off) = (lane(&self.rise_off), lane(&self.fall_off));
        let mut out = LaneResult::default();
        let mut g = [0.0f32; LANES];
        for l in 0..LANES {
            let (dx, dy, dz) = (px[l] - x.x, py[l] - x.y, pz[l] - x.z);
            let d2 = dx * dx + dy * dy + dz * dz;
            let reached = d2 < reach2[l];
            // One division for 1 / d and 1 / (pi (d^2 + eps^2)): q = 1 / (d (d^2 + eps^2)).
            let d = d2.sqrt();
            let den = d2 + eps2;
            let q = 1.0 / (d * den);
            let inv_d = q * den;
            let t = d * inv_r[l];
            let rising = (2.0 * t - 1.0).clamp(0.0, 1.0).max(rise_off[l]);
            let falling = (2.0 - t).clamp(0.0, 1.0).max(fall_off[l]);
            let b = rising.min(falling);
            let cos_x = (n.x * dx + n.y * dy + n.z * dz) * inv_d;
            let cos_v = (-(mx[l] * dx + my[l] * dy + mz[l] * dz) * inv_d).max(0.0) + iso[l];
            let ok = reached && d2 > 0.0 && b > 0.0 && cos_x > 0.0 && cos_v > 0.0;
            let v = b * cos_x * cos_v * (q * d) * std::f32::consts::FRAC_1_PI;
            out.reached[l] = reached;
            g[l] = if ok { v } else { 0.0 };
        }
        let y = lane(&self.lum);
        for l in 0..LANES {
            out.lum[l] = g[l] * y[l];
        }
        for (a, ints) in self.intensity.iter().enumerate() {
            let i = lane(ints);
            for l in 0..LANES {
                out.value[a][l] = g[l] * i[l];
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lgh_core::blending::blend;
    use lgh_core::rng::Rng;
    use lgh_core::vpl::light_irradiance_along;

    /// The batch gives, light by light, what the scalar blend and irradiance give.
    #[test]
    fn batch_matches_the_scalar_evaluation() {
        let mut rng = Rng::new(&[5]);
        let mut u = || rng.next_f32();
        let roles = [
            LevelRole::Only,
            LevelRole::Lowest,
            LevelRole::Middle,
            LevelRole::Top,
        ];
        let packed: Vec<PackedLight> = (0..37)
            .map(|k| {
                let role = roles[k % 4];
                let radius = 0.1 + u();
                let reach = role.reach(radius);
                PackedLight {
                    position: Vec3::new(u(), u(), u()) * 3.0,
                    reach2: reach * reach,
                    normal: Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5) * 1.5,
                    iso: if k % 3 == 0 { 0.0 } else { 0.2 * u() },
                    intensity: Vec3::new(u(), u(), u()),
                    radius,
                    role,
                    level: (k % 5) as u8,
                }
            })
            .collect();
        let mut batch = LightBatch::default();
        let list: Vec<usize> = (0..37).rev().collect();
        batch.fill((0, 0), &packed, list.iter().copied());
        assert_eq!(batch.chunks(), 5);
        for _ in 0..50 {
            let x = Vec3::new(u(), u(), u()) * 3.0;
            let n = Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize();
            for c in 0..batch.chunks() {
                let r = batch.eval(c, x, n, 1e-4);
                for l in 0..LANES {
                    let Some(&j) = list.get(c * LANES + l) else {
                        assert!(!r.reached[l] && r.value[0][l] == 0.0, "padding lane");
                        continue;
                    };
                    let pl = &packed[j];
                    let dv = pl.position - x;
                    let d2 = dv.length_squared();
                    assert_eq!(r.reached[l], d2 < pl.reach2);
                    let inv_d = d2.sqrt().recip();
                    let b = blend(pl.role, d2 * inv_d, pl.radius);
                    let f = light_irradiance_along(
                        dv,
                        d2,
                        inv_d,
                        n,
                        pl.normal,
                        pl.iso,
                        pl.intensity,
                        1e-4,
                    );
                    let expected = if d2 < pl.reach2 { f * b } else { Vec3::ZERO };
                    let got = Vec3::new(r.value[0][l], r.value[1][l], r.value[2][l]);
                    assert!(
                        (got - expected).abs().max_element()
                            <= 1e-5 * expected.max_element().max(1e-3),
                        "light {j}: {got} vs {expected}"
                    );
                    let y = luminance(expected);
                    assert!(
                        (r.lum[l] - y).abs() <= 1e-5 * y.max(1e-3),
                        "light {j}: luminance {} vs {y}",
                        r.lum[l]
                    );
                }
            }
        }
    }
}
