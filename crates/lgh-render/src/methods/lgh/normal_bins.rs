//! The split of the VPLs by the dominant direction of their normal (`--normal-bins`, an
//! extension of Lin & Yuksel 2019 section 3.1; docs/design.md, "Normal bins"): one
//! hierarchy per bin, so that a grid light only averages normals that roughly agree.

use glam::Vec3;
use lgh_core::vpl::Vpls;

/// The number of normal bins: +x, -x, +y, -y, +z, -z.
pub const NORMAL_BINS: usize = 6;

/// The bin of normal `n`: twice the axis of its largest component (the first of equal
/// ones), plus one where that component is negative. A backend that splits VPLs itself
/// (lgh-gpu's `shaders/normal_bin.wgsl`) decides as this does.
#[must_use]
pub fn normal_bin(n: Vec3) -> usize {
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    2 * axis + usize::from(n[axis] < 0.0)
}

/// Splits VPLs into the [`NORMAL_BINS`] groups of [`normal_bin`], each in the VPLs' order.
pub(super) fn split_by_normal(vpls: &Vpls) -> Vec<Vpls> {
    let mut groups = vec![Vpls::default(); NORMAL_BINS];
    for i in 0..vpls.len() {
        let n = vpls.normals[i];
        groups[normal_bin(n)].push(vpls.positions[i], n, vpls.flux[i]);
    }
    groups
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each axis direction lands in its own bin, ties go to the first axis, and the split
    /// keeps every VPL in order.
    #[test]
    fn bins_by_dominant_axis_and_sign() {
        let dirs = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        for (b, d) in dirs.iter().enumerate() {
            assert_eq!(normal_bin(*d), b);
            assert_eq!(normal_bin(*d + 0.3 * Vec3::ONE.normalize()), b);
        }
        assert_eq!(normal_bin(Vec3::new(0.5, 0.5, 0.5)), 0);
        assert_eq!(normal_bin(Vec3::new(0.1, -0.6, 0.6)), 3);
        let mut v = Vpls::default();
        for (i, d) in dirs.iter().cycle().take(20).enumerate() {
            v.push(Vec3::splat(i as f32), *d, Vec3::ONE);
        }
        let groups = split_by_normal(&v);
        assert_eq!(groups.iter().map(Vpls::len).sum::<usize>(), 20);
        for (b, g) in groups.iter().enumerate() {
            assert!(g.normals.iter().all(|&n| normal_bin(n) == b));
            assert!(g.positions.windows(2).all(|w| w[0].x < w[1].x));
        }
    }
}
