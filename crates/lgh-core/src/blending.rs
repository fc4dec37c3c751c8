//! Blending functions B_l(d) of the lighting grid hierarchy (Yuksel & Yuksel 2017; Lin &
//! Yuksel 2019 section 2.2 and Fig. 2).
//!
//! The light of level l with radius r_l = alpha h_l is weighted by B_l(d), where d is the
//! distance from the shading point to that light's own position. The functions are piecewise
//! linear (both reference codes agree; docs/design.md, "Blending functions"), with R = r_l:
//!
//! | level | d <= R/2 | R/2 < d <= R | R < d < 2R | d >= 2R |
//! | --- | --- | --- | --- | --- |
//! | lowest used | 1 | 1 | 2 - d/R | 0 |
//! | middle | 0 | 2d/R - 1 | 2 - d/R | 0 |
//! | top | 0 | 2d/R - 1 | 1 | 1 |
//!
//! Since r_{l+1} = 2 r_l, on [r_l, 2 r_l] = [r_{l+1}/2, r_{l+1}] the falling edge of level l
//! and the rising edge of level l+1 sum to 1: the functions form a partition of unity for any
//! d, and at most two consecutive levels are non-zero. A hierarchy with a single level uses
//! B = 1.

/// The role of a level in the blend, which fixes the shape of its function.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LevelRole {
    /// The only level shaded: B = 1 everywhere.
    Only,
    /// The lowest level shaded (S_0 or S_1): 1 up to r, falling to 0 at 2r.
    Lowest,
    /// A middle level: rising from r/2 to r, falling from r to 2r.
    Middle,
    /// The top level: rising from r/2 to r, then 1 with no cut-off.
    Top,
}

impl LevelRole {
    /// The role of level `l` when levels `lowest..=top` are shaded.
    #[must_use]
    pub fn of(l: u32, lowest: u32, top: u32) -> Self {
        if lowest == top {
            Self::Only
        } else if l == lowest {
            Self::Lowest
        } else if l == top {
            Self::Top
        } else {
            Self::Middle
        }
    }

    /// The largest distance with a non-zero weight, for radius `r` (infinite for the top).
    #[must_use]
    pub fn reach(self, r: f32) -> f32 {
        match self {
            Self::Only | Self::Top => f32::INFINITY,
            Self::Lowest | Self::Middle => 2.0 * r,
        }
    }

    /// The floors (rising, falling) under the two ramps of B_l: B_l(d) = min(max(clamp(2t -
    /// 1, 0, 1), rising), max(clamp(2 - t, 0, 1), falling)), t = d / r. A floor of 1 turns
    /// its ramp off (the lowest level does not rise, the top does not fall). The form of
    /// [`blend`] without a branch on the role, as the batched and GPU loops evaluate it.
    #[must_use]
    pub fn floors(self) -> (f32, f32) {
        match self {
            Self::Only => (1.0, 1.0),
            Self::Lowest => (1.0, 0.0),
            Self::Middle => (0.0, 0.0),
            Self::Top => (0.0, 1.0),
        }
    }

    /// The distance below which B_l is zero for a level of radius `r` = r_l: r / 2 where
    /// the role has a rising edge (middle and top levels), else 0 (B_l = 1 near the light).
    #[must_use]
    pub fn hole(self, r: f32) -> f32 {
        match self {
            Self::Middle | Self::Top => 0.5 * r,
            Self::Only | Self::Lowest => 0.0,
        }
    }
}

/// B_l(d) for a level of radius `r` = r_l and the given role.
#[inline]
#[must_use]
pub fn blend(role: LevelRole, d: f32, r: f32) -> f32 {
    let x = d / r;
    let rising = || (2.0 * x - 1.0).clamp(0.0, 1.0);
    let falling = || (2.0 - x).clamp(0.0, 1.0);
    match role {
        LevelRole::Only => 1.0,
        LevelRole::Lowest => falling(),
        LevelRole::Middle => rising().min(falling()),
        LevelRole::Top => rising(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// For any number of levels and any distance, the weights of the levels (each with its own
    /// r_l = r_0 2^l) sum to 1.
    #[test]
    fn partition_of_unity() {
        let mut rng = Rng::new(&[1]);
        for lowest in 0..2u32 {
            for top in lowest..lowest + 8 {
                for _ in 0..2000 {
                    let r0 = 0.01 + rng.next_f32();
                    let d = rng.next_f32() * r0 * 2f32.powi(top as i32 + 3);
                    let sum: f32 = (lowest..=top)
                        .map(|l| blend(LevelRole::of(l, lowest, top), d, r0 * 2f32.powi(l as i32)))
                        .sum();
                    assert!(
                        (sum - 1.0).abs() < 1e-5,
                        "sum {sum} at d {d}, levels {lowest}..={top}"
                    );
                }
            }
        }
    }

    #[test]
    fn zero_where_the_paper_says() {
        let r = 2.0;
        for role in [LevelRole::Lowest, LevelRole::Middle] {
            for d in [4.0, 4.5, 100.0] {
                assert_eq!(blend(role, d, r), 0.0);
            }
        }
        for role in [LevelRole::Middle, LevelRole::Top] {
            for d in [0.0, 0.5, 1.0] {
                assert_eq!(blend(role, d, r), 0.0);
            }
        }
        assert_eq!(blend(LevelRole::Top, 1e9, r), 1.0);
        assert_eq!(blend(LevelRole::Lowest, 0.0, r), 1.0);
        assert_eq!(blend(LevelRole::Lowest, 2.0, r), 1.0);
        assert!((blend(LevelRole::Middle, 1.5, r) - 0.5).abs() < 1e-6);
        assert!((blend(LevelRole::Middle, 3.0, r) - 0.5).abs() < 1e-6);
        assert_eq!(LevelRole::of(3, 3, 3), LevelRole::Only);
    }
}
