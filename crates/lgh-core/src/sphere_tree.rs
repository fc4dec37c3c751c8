//! Bounding sphere tree of light influence regions (Tokuyoshi & Harada 2016, section 5.2).
//!
//! Shading points of a path tracer are scattered through the scene, so lights cannot be
//! binned into screen tiles. Instead a binary tree over the lights is built once (median split
//! of the light centres along the longest axis); every frame each leaf's sphere becomes the
//! light's influence region, centre c_i and radius rho_i + r_i (rho_i bounds the light's own
//! extent, r_i is the frame's random range of Eq. 3), and the inner spheres are refitted
//! bottom-up. A shading point x then visits exactly the leaves whose sphere contains x.

use glam::Vec3;

/// One node: a sphere, and either two children or one light.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Node {
    centre: Vec3,
    radius: f32,
    /// Leaf: light index; inner: index of the left child (the right one is `right`).
    first: u32,
    /// Inner: right child; leaf: `u32::MAX`.
    right: u32,
}

/// The tree. Nodes are stored parents before children, so a reverse sweep refits bottom-up.
#[derive(Clone, Debug, Default)]
pub struct SphereTree {
    nodes: Vec<Node>,
    /// rho_i: the radius of a sphere around c_i that holds light i.
    extent: Vec<f32>,
    centres: Vec<Vec3>,
}

/// The smallest sphere holding spheres (c1, r1) and (c2, r2).
#[must_use]
pub fn enclosing_sphere(c1: Vec3, r1: f32, c2: Vec3, r2: f32) -> (Vec3, f32) {
    let d = (c2 - c1).length();
    if d + r2 <= r1 {
        return (c1, r1);
    }
    if d + r1 <= r2 {
        return (c2, r2);
    }
    if !r1.is_finite() || !r2.is_finite() {
        return ((c1 + c2) * 0.5, f32::INFINITY);
    }
    let r = 0.5 * (d + r1 + r2);
    let c = c1 + (c2 - c1) * ((r - r1) / d.max(f32::MIN_POSITIVE));
    // Round outwards so that float error never leaves a child poking out.
    (c, r * (1.0 + 1e-6) + 1e-7)
}

impl SphereTree {
    /// Builds the tree over lights with centres `centres` and extents `extent` (rho_i).
    #[must_use]
    pub fn build(centres: &[Vec3], extent: &[f32]) -> Self {
        let mut tree = Self {
            nodes: Vec::with_capacity(2 * centres.len()),
            extent: extent.to_vec(),
            centres: centres.to_vec(),
        };
        if centres.is_empty() {
            return tree;
        }
        let mut ids: Vec<u32> = (0..centres.len() as u32).collect();
        tree.split(&mut ids);
        tree.refit(&vec![0.0; centres.len()]);
        tree
    }

    fn split(&mut self, ids: &mut [u32]) -> u32 {
        let at = self.nodes.len() as u32;
        self.nodes.push(Node {
            centre: Vec3::ZERO,
            radius: 0.0,
            first: 0,
            right: u32::MAX,
        });
        if ids.len() == 1 {
            self.nodes[at as usize].first = ids[0];
            return at;
        }
        let (lo, hi) = ids.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), &i| {
                let c = self.centres[i as usize];
                (lo.min(c), hi.max(c))
            },
        );
        let axis = (hi - lo).max_position();
        let mid = ids.len() / 2;
        let centres = &self.centres;
        ids.select_nth_unstable_by(mid, |&a, &b| {
            centres[a as usize][axis].total_cmp(&centres[b as usize][axis])
        });
        let (left, right) = ids.split_at_mut(mid);
        let l = self.split(left);
        let r = self.split(right);
        self.nodes[at as usize].first = l;
        self.nodes[at as usize].right = r;
        at
    }

    /// Number of lights.
    #[must_use]
    pub fn len(&self) -> usize {
        self.centres.len()
    }

    /// True if there is no light.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.centres.is_empty()
    }

    /// Sets every leaf's sphere to (c_i, rho_i + `ranges[i]`) and refits the inner spheres
    /// (once per frame, after new random ranges).
    pub fn refit(&mut self, ranges: &[f32]) {
        for k in (0..self.nodes.len()).rev() {
            let n = self.nodes[k];
            let (c, r) = if n.right == u32::MAX {
                let i = n.first as usize;
                (self.centres[i], self.extent[i] + ranges[i])
            } else {
                let (a, b) = (self.nodes[n.first as usize], self.nodes[n.right as usize]);
                enclosing_sphere(a.centre, a.radius, b.centre, b.radius)
            };
            self.nodes[k].centre = c;
            self.nodes[k].radius = r;
        }
    }

    /// Calls `f(i)` for every light whose leaf sphere contains `x`, in a fixed order.
    pub fn for_each_overlapping(&self, x: Vec3, mut f: impl FnMut(usize)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let n = self.nodes[stack[top] as usize];
            if (x - n.centre).length_squared() >= n.radius * n.radius {
                continue;
            }
            if n.right == u32::MAX {
                f(n.first as usize);
            } else if top + 2 <= stack.len() {
                stack[top] = n.right;
                stack[top + 1] = n.first;
                top += 2;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn the_tree_finds_exactly_the_overlapping_lights() {
        let mut rng = Rng::new(&[11]);
        let mut v = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        let n = 500;
        let centres: Vec<Vec3> = (0..n).map(|_| v() * 4.0).collect();
        let extent: Vec<f32> = (0..n).map(|_| v().x * 0.05).collect();
        let mut tree = SphereTree::build(&centres, &extent);
        for frame in 0..3 {
            let ranges: Vec<f32> = (0..n).map(|_| v().x * (0.2 + frame as f32 * 0.5)).collect();
            tree.refit(&ranges);
            for _ in 0..200 {
                let x = v() * 4.0;
                let mut found = Vec::new();
                tree.for_each_overlapping(x, |i| found.push(i));
                found.sort_unstable();
                let expected: Vec<usize> = (0..n)
                    .filter(|&i| (x - centres[i]).length() < extent[i] + ranges[i])
                    .collect();
                assert_eq!(found, expected);
            }
        }
    }

    #[test]
    fn enclosing_spheres_hold_both() {
        let cases = [
            (Vec3::ZERO, 1.0, Vec3::X * 3.0, 0.5),
            (Vec3::ZERO, 2.0, Vec3::X * 0.5, 0.5),
            (Vec3::ZERO, 0.1, Vec3::Y * 0.2, 3.0),
        ];
        for (c1, r1, c2, r2) in cases {
            let (c, r) = enclosing_sphere(c1, r1, c2, r2);
            assert!((c - c1).length() + r1 <= r + 1e-5);
            assert!((c - c2).length() + r2 <= r + 1e-5);
        }
    }
}
