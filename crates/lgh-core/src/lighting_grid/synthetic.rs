//! Synthetic light sets for benchmarks and tests: lights on surfaces, as VPLs are.
//!
//! The set: 60% of the lights on the six inner faces of a 10 x 4 x 8 room, 40% on the five
//! visible faces of 24 random boxes standing on its floor; each light has the normal of its
//! face (pointing into the room or out of the box) and a random positive RGB intensity in
//! [0.5, 1.5) per channel. So most grid cells stay empty, as with real VPLs.

use glam::Vec3;

use super::InputLights;
use crate::rng::Rng;

/// Positions, normals and intensities of a synthetic light set.
#[derive(Clone, Debug, Default)]
pub struct SyntheticLights {
    /// Positions.
    pub positions: Vec<Vec3>,
    /// Unit normals.
    pub normals: Vec<Vec3>,
    /// RGB intensities.
    pub intensity: Vec<Vec3>,
}

impl SyntheticLights {
    /// The set as a hierarchy's input lights (oriented).
    #[must_use]
    pub fn input(&self) -> InputLights<'_> {
        InputLights {
            positions: &self.positions,
            intensity: &self.intensity,
            normals: Some(&self.normals),
        }
    }
}

/// `n` lights without structure, from `seed`: uniform in the box `offset + scale x [0, 1)^3`
/// (a plane where a component of `scale` is 0), RGB intensities uniform in [0, 3) per
/// channel, normals within 45 degrees of +y.
#[must_use]
pub fn lights_in_box(n: usize, seed: u64, scale: Vec3, offset: Vec3) -> SyntheticLights {
    let mut r = Rng::new(&[seed, 99]);
    let mut out = SyntheticLights::default();
    for _ in 0..n {
        let p = offset + scale * Vec3::new(r.next_f32(), r.next_f32(), r.next_f32());
        out.positions.push(p);
        let c = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 3.0;
        out.intensity.push(c);
        let nrm = Vec3::new(r.next_f32() - 0.5, 1.0, r.next_f32() - 0.5).normalize();
        out.normals.push(nrm);
    }
    out
}

/// `n` lights on the surfaces of a room with boxes (see the module docs), from `seed`.
#[must_use]
pub fn lights_on_surfaces(n: usize, seed: u64) -> SyntheticLights {
    let room = Vec3::new(10.0, 4.0, 8.0);
    let mut boxes = Vec::new();
    let mut rng = Rng::new(&[seed, 0xb0c5]);
    for _ in 0..24 {
        let size = Vec3::new(
            0.3 + 1.2 * rng.next_f32(),
            0.3 + 2.0 * rng.next_f32(),
            0.3 + 1.2 * rng.next_f32(),
        );
        let min = Vec3::new(
            rng.next_f32() * (room.x - size.x),
            0.0,
            rng.next_f32() * (room.z - size.z),
        );
        boxes.push((min, min + size));
    }
    let mut out = SyntheticLights {
        positions: Vec::with_capacity(n),
        normals: Vec::with_capacity(n),
        intensity: Vec::with_capacity(n),
    };
    for i in 0..n {
        let mut r = Rng::new(&[seed, i as u64]);
        let (u, v) = (r.next_f32(), r.next_f32());
        let (p, nrm) = if r.next_f32() < 0.6 {
            let face = (r.next_f32() * 6.0) as usize % 6;
            face_point(Vec3::ZERO, room, face, u, v, true)
        } else {
            let (lo, hi) = boxes[(r.next_f32() * 24.0) as usize % 24];
            // Faces 0..5 without the bottom (face 2 = y min).
            let face = [0, 1, 3, 4, 5][(r.next_f32() * 5.0) as usize % 5];
            face_point(lo, hi, face, u, v, false)
        };
        out.positions.push(p);
        out.normals.push(nrm);
        out.intensity.push(Vec3::new(
            0.5 + r.next_f32(),
            0.5 + r.next_f32(),
            0.5 + r.next_f32(),
        ));
    }
    out
}

/// A point on face `face` (0: x min, 1: x max, 2: y min, 3: y max, 4: z min, 5: z max) of the
/// box lo..hi at face coordinates (u, v), with the face normal pointing inwards or outwards.
fn face_point(lo: Vec3, hi: Vec3, face: usize, u: f32, v: f32, inwards: bool) -> (Vec3, Vec3) {
    let axis = face / 2;
    let at_max = face % 2 == 1;
    let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut p = lo;
    p[axis] = if at_max { hi[axis] } else { lo[axis] };
    p[a] = lo[a] + u * (hi[a] - lo[a]);
    p[b] = lo[b] + v * (hi[b] - lo[b]);
    let mut n = Vec3::ZERO;
    n[axis] = if at_max != inwards { 1.0 } else { -1.0 };
    (p, n)
}
