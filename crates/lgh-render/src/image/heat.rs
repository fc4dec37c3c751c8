//! The overdraw heat map's colours (LGH paper Fig. 5): lights per pixel through a
//! blue-cyan-green-yellow-red ramp, shared by `lgh render --heatmap` and the viewer.

use glam::Vec3;

/// Exposure that shows the ramp's linear colours legibly through the tone map.
pub const HEAT_EXPOSURE: f32 = 1.6;

/// The ramp at t in [0, 1] (clamped), linear RGB: dark blue at 0, red at 1.
#[must_use]
pub fn ramp(t: f32) -> Vec3 {
    const STOPS: [Vec3; 5] = [
        Vec3::new(0.0, 0.0, 0.35),
        Vec3::new(0.0, 0.6, 1.0),
        Vec3::new(0.1, 0.9, 0.1),
        Vec3::new(1.0, 0.9, 0.0),
        Vec3::new(0.9, 0.0, 0.0),
    ];
    let x = if t.is_nan() {
        0.0
    } else {
        t.clamp(0.0, 1.0) * 4.0
    };
    let i = (x.floor() as usize).min(3);
    STOPS[i].lerp(STOPS[i + 1], x - i as f32)
}

/// The heat map of per-pixel light counts, scaled to their maximum (at least 1); returns
/// the colours and that maximum.
#[must_use]
pub fn heat_map(counts: &[u32]) -> (Vec<Vec3>, u32) {
    let max = counts.iter().copied().max().unwrap_or(0).max(1);
    let colours = counts
        .iter()
        .map(|&c| ramp(c as f32 / max as f32))
        .collect();
    (colours, max)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The ramp runs from its first stop to its last, clamps outside [0, 1], maps NaN to
    /// the first stop; the map puts the largest count on the last stop.
    #[test]
    fn ramp_ends_and_map_scale() {
        assert_eq!(ramp(0.0), Vec3::new(0.0, 0.0, 0.35));
        assert_eq!(ramp(1.0), Vec3::new(0.9, 0.0, 0.0));
        assert_eq!(ramp(-3.0), ramp(0.0));
        assert_eq!(ramp(7.0), ramp(1.0));
        assert_eq!(ramp(f32::NAN), ramp(0.0));
        let (c, max) = heat_map(&[0, 5, 10]);
        assert_eq!(max, 10);
        assert_eq!(c, vec![ramp(0.0), ramp(0.5), ramp(1.0)]);
        assert_eq!(heat_map(&[0, 0]).1, 1);
    }
}
