//! Temporal filtering of shadows (LGH 2019 section 4.3, last paragraph): when VPLs are
//! regenerated every frame, the indirect light flickers; the paper prefers to accumulate only
//! the indirect shadows over time (a TAA on the shadow ratio), which calms flicker without
//! ghosting the lighting itself.
//!
//! Each frame, every pixel's world position is projected into the previous camera; the
//! previous value at that pixel is taken if the previous surface there is the same one (its
//! depth along the previous view matches within `depth_tolerance`, relative, and its normal
//! within `normal_cos`), clamped to the min-max box of the 3 x 3 neighbourhood of the current
//! frame's *unfiltered* estimate (which limits ghosting when lighting changes), and blended
//! by an exponential moving average: out = alpha x current + (1 - alpha) x previous. Rejected
//! pixels restart from the current value. [`TemporalTarget::Indirect`] accumulates the whole
//! indirect light instead, for comparison.
//!
//! Why the unfiltered estimate bounds the history: the a-trous filter makes the current
//! ratio smooth, so the min-max box of its neighbourhood is nearly a point and clamping to it
//! throws the history away (the shadow-ratio TAA then removed 10% of the flicker instead of
//! all the ratio's share). The raw S / U of the ray samples spreads as far as the ratio may
//! plausibly lie; when the lighting really changes, the raw samples move together and the box
//! moves with them.

use glam::Vec3;
use lgh_scene::camera::CameraFrame;
use rayon::prelude::*;

use crate::passes::gbuffer::GBuffer;
use crate::passes::par_copy_into;

/// What is accumulated over frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum TemporalTarget {
    /// The filtered shadow ratio D(S)/D(U) (the paper's choice; lgh, slc).
    #[cfg_attr(feature = "clap", value(name = "ratio"))]
    #[serde(rename = "ratio")]
    ShadowRatio,
    /// The whole indirect light.
    Indirect,
}

/// Settings of the temporal filter.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct TemporalSettings {
    /// Weight of the current frame in the temporal moving average.
    #[cfg_attr(feature = "clap", arg(id = "taa_alpha", long = "taa-alpha", value_name = "TAA_ALPHA", default_value_t = TemporalSettings::default().alpha))]
    pub alpha: f32,
    /// What the temporal filter accumulates: the shadow ratio (the paper's choice) or the
    /// whole indirect light.
    #[cfg_attr(feature = "clap", arg(id = "taa_target", long = "taa-target", value_name = "TAA_TARGET", value_enum, default_value_t = TemporalSettings::default().target))]
    pub target: TemporalTarget,
    /// Largest relative depth difference of a reprojected sample.
    #[cfg_attr(feature = "clap", arg(skip = TemporalSettings::default().depth_tolerance))]
    pub depth_tolerance: f32,
    /// Smallest cosine between the current and the previous normal.
    #[cfg_attr(feature = "clap", arg(skip = TemporalSettings::default().normal_cos))]
    pub normal_cos: f32,
}

impl TemporalSettings {
    /// Checks the values a type does not restrict.
    ///
    /// # Errors
    /// The blend weight is not in (0, 1].
    pub fn validate(&self) -> Result<(), crate::settings::SettingsError> {
        if self.alpha.is_finite() && self.alpha > 0.0 && self.alpha <= 1.0 {
            Ok(())
        } else {
            Err(crate::settings::SettingsError {
                name: "taa-alpha",
                value: self.alpha.to_string(),
                expected: "expected a number in (0, 1]".into(),
            })
        }
    }
}

impl Default for TemporalSettings {
    fn default() -> Self {
        Self {
            alpha: 0.1,
            target: TemporalTarget::ShadowRatio,
            depth_tolerance: 0.02,
            normal_cos: 0.9,
        }
    }
}

/// What the previous frame leaves for the next.
#[derive(Clone, Debug)]
pub struct History {
    frame: CameraFrame,
    /// The view of the G-buffer the history was made with ([`GBuffer::view`]).
    view: Option<(u64, CameraFrame)>,
    width: u32,
    height: u32,
    depth: Vec<f32>,
    normal: Vec<Vec3>,
    value: Vec<Vec3>,
}

impl History {
    /// The history of a frame seen through `frame` with G-buffer `g` and accumulated `value`.
    #[must_use]
    pub fn new(frame: CameraFrame, g: &GBuffer, value: Vec<Vec3>) -> Self {
        Self {
            frame,
            view: g.view,
            width: g.width,
            height: g.height,
            depth: g.depth.clone(),
            normal: g.normal.clone(),
            value,
        }
    }
}

/// The previous value seen at each current pixel of `g`, or `None` where it was not seen
/// (off screen, occluded, another surface).
#[must_use]
pub fn reproject(h: &History, g: &GBuffer, s: &TemporalSettings) -> Vec<Option<Vec3>> {
    let same = h.shows_view_of(g);
    (0..g.len())
        .into_par_iter()
        .map(|i| reproject_pixel(h, g, s, i, same))
        .collect()
}

impl History {
    /// True if the history was made with a G-buffer of the same known view as `g` (a
    /// camera standing still): every pixel then sees what it saw, and reprojection is the
    /// identity.
    fn shows_view_of(&self, g: &GBuffer) -> bool {
        g.view.is_some() && self.view == g.view && (self.width, self.height) == (g.width, g.height)
    }
}

/// [`reproject`] for pixel `i`; `same`: [`History::shows_view_of`] `g`.
#[inline]
fn reproject_pixel(
    h: &History,
    g: &GBuffer,
    s: &TemporalSettings,
    i: usize,
    same: bool,
) -> Option<Vec3> {
    if !g.is_hit(i) {
        return None;
    }
    if same {
        return Some(h.value[i]);
    }
    let (px, z) = h.frame.project(g.position[i])?;
    if px.x < 0.0 || px.y < 0.0 {
        return None;
    }
    let (x, y) = (px.x as u32, px.y as u32);
    if x >= h.width || y >= h.height {
        return None;
    }
    let j = (y * h.width + x) as usize;
    let dz = (h.depth[j] - z).abs();
    let same_depth = dz <= s.depth_tolerance * z;
    if !same_depth || h.normal[j].dot(g.normal[i]) < s.normal_cos {
        return None;
    }
    Some(h.value[j])
}

/// The moving average of `current` with the reprojected `previous`, each previous value
/// clamped to the min-max box of `spread` (the unfiltered estimate of `current`, or `current`
/// itself) over the 3 x 3 neighbourhood (pixels that see a surface).
#[must_use]
pub fn blend(
    current: &[Vec3],
    spread: &[Vec3],
    previous: &[Option<Vec3>],
    g: &GBuffer,
    alpha: f32,
) -> Vec<Vec3> {
    (0..g.len())
        .into_par_iter()
        .map(|i| blend_pixel(current, spread, previous[i], g, alpha, i))
        .collect()
}

/// [`blend`] for pixel `i`, whose previous value is `previous`.
#[inline]
fn blend_pixel(
    current: &[Vec3],
    spread: &[Vec3],
    previous: Option<Vec3>,
    g: &GBuffer,
    alpha: f32,
    i: usize,
) -> Vec3 {
    let Some(prev) = previous else {
        return current[i];
    };
    let (w, h) = (g.width as usize, g.height as usize);
    let (x, y) = (i % w, i / w);
    let (mut lo, mut hi) = (current[i], current[i]);
    for yy in y.saturating_sub(1)..(y + 2).min(h) {
        for xx in x.saturating_sub(1)..(x + 2).min(w) {
            let j = yy * w + xx;
            if g.is_hit(j) {
                lo = lo.min(spread[j]);
                hi = hi.max(spread[j]);
            }
        }
    }
    current[i] * alpha + prev.clamp(lo, hi) * (1.0 - alpha)
}

/// A temporal filter that keeps its history between frames.
#[derive(Clone, Debug, Default)]
pub struct TemporalFilter {
    history: Option<History>,
}

impl TemporalFilter {
    /// Filters this frame's `value` (seen through `frame` with G-buffer `g`; `spread`, its
    /// unfiltered estimate, bounds the history, see [`blend`]) against the history, stores
    /// the result as the new history and returns it. The first frame passes through
    /// unchanged.
    pub fn apply(
        &mut self,
        frame: CameraFrame,
        g: &GBuffer,
        value: &[Vec3],
        spread: &[Vec3],
        s: &TemporalSettings,
    ) -> Vec<Vec3> {
        // Reprojection and blend in one pass, and the history's planes refilled in place:
        // no intermediate image, no fresh memory to page in.
        let same = self.history.as_ref().is_some_and(|h| h.shows_view_of(g));
        let out: Vec<Vec3> = match &self.history {
            Some(h) => (0..g.len())
                .into_par_iter()
                .map(|i| {
                    let previous = reproject_pixel(h, g, s, i, same);
                    blend_pixel(value, spread, previous, g, s.alpha, i)
                })
                .collect(),
            None => value.to_vec(),
        };
        match &mut self.history {
            Some(h) => {
                (h.frame, h.view, h.width, h.height) = (frame, g.view, g.width, g.height);
                // The same view has the same depths and normals.
                if !same {
                    par_copy_into(&mut h.depth, &g.depth);
                    par_copy_into(&mut h.normal, &g.normal);
                }
                par_copy_into(&mut h.value, &out);
            }
            None => self.history = Some(History::new(frame, g, out.clone())),
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::World;
    use lgh_scene::{Camera, Material, Scene};

    /// A large floor at y = 0 seen from above.
    fn floor() -> World {
        let mut scene = Scene::new("floor");
        scene.materials.push(Material::default());
        let s = 10.0;
        let prim = lgh_scene::mesh::Primitive {
            positions: vec![
                Vec3::new(-s, 0.0, -s),
                Vec3::new(-s, 0.0, s),
                Vec3::new(s, 0.0, s),
                Vec3::new(s, 0.0, -s),
            ],
            uvs: vec![glam::Vec2::ZERO; 4],
            indices: vec![[0, 1, 2], [0, 2, 3]],
            material: 0,
            ..Default::default()
        };
        scene.mesh.append(&prim, glam::Mat4::IDENTITY, "plane");
        scene.lights.push(lgh_scene::Light::Point {
            position: Vec3::new(0.0, 2.0, 0.0),
            intensity: Vec3::ONE,
        });
        scene.finish(std::path::Path::new("<test>")).unwrap();
        World::new(scene)
    }

    fn camera(x: f32) -> Camera {
        Camera {
            position: Vec3::new(x, 3.0, 0.5),
            look_at: Vec3::new(x, 0.0, 0.0),
            up: Vec3::Y,
            fov_y_degrees: 50.0,
        }
    }

    /// A smooth function of world position, to check what reprojection fetches.
    fn field(p: Vec3) -> Vec3 {
        Vec3::splat(0.5 + 0.25 * (p.x * 2.0).sin() * (p.z * 1.5).cos())
    }

    /// A camera that stands still reprojects every pixel to itself: by projection (a
    /// G-buffer whose view is unknown) and by the shortcut for a known view.
    #[test]
    fn a_static_camera_reprojects_to_the_identity() {
        let world = floor();
        let (w, h) = (64, 48);
        let frame = camera(0.0).frame(w, h);
        let g = GBuffer::render(&world, &frame, w, h);
        let value: Vec<Vec3> = g.position.iter().map(|&p| field(p)).collect();
        let unknown = GBuffer {
            view: None,
            ..g.clone()
        };
        for (g, shortcut) in [(&g, true), (&unknown, false)] {
            let hist = History::new(frame, g, value.clone());
            assert_eq!(hist.shows_view_of(g), shortcut);
            let r = reproject(&hist, g, &TemporalSettings::default());
            for (i, v) in r.iter().enumerate() {
                assert_eq!(*v, g.is_hit(i).then_some(value[i]), "pixel {i}");
            }
        }
    }

    /// After the camera moves, a flat plane's reprojected values match the values of the
    /// current frame where the previous frame saw the point (within the field's change over
    /// one pixel), and at least 70% of the pixels are found.
    #[test]
    fn a_moved_camera_reprojects_a_plane() {
        let world = floor();
        let (w, h) = (96, 72);
        let f0 = camera(0.0).frame(w, h);
        let f1 = camera(0.4).frame(w, h);
        let g0 = GBuffer::render(&world, &f0, w, h);
        let g1 = GBuffer::render(&world, &f1, w, h);
        let v0: Vec<Vec3> = g0.position.iter().map(|&p| field(p)).collect();
        let hist = History::new(f0, &g0, v0);
        let r = reproject(&hist, &g1, &TemporalSettings::default());
        let mut found = 0;
        for (i, v) in r.iter().enumerate() {
            if let Some(v) = v {
                found += 1;
                let expected = field(g1.position[i]);
                assert!(
                    (*v - expected).abs().max_element() < 0.05,
                    "pixel {i}: {v} vs {expected}"
                );
            }
        }
        assert!(found > w as usize * h as usize * 7 / 10, "{found}");
    }

    /// The G-buffer of an 8 x 8 view of the floor (every pixel sees it).
    fn small_view() -> GBuffer {
        let frame = camera(0.0).frame(8, 8);
        GBuffer::render(&floor(), &frame, 8, 8)
    }

    #[test]
    fn blending_clamps_the_history_to_the_neighbourhood() {
        let g = small_view();
        let current = vec![Vec3::splat(0.5); 64];
        let prev = vec![Some(Vec3::splat(2.0)); 64];
        let out = blend(&current, &current, &prev, &g, 0.1);
        assert!(
            out.iter()
                .all(|v| (*v - Vec3::splat(0.5)).abs().max_element() < 1e-6)
        );
        let current: Vec<Vec3> = (0..64).map(|i| Vec3::splat(i as f32 / 64.0)).collect();
        let out = blend(&current, &current, &vec![None; 64], &g, 0.1);
        assert_eq!(out, current);
    }

    /// The box comes from the spread (the unfiltered estimate), not from the smooth current
    /// value: a history inside the spread's box is kept, one outside it is clamped to it.
    #[test]
    fn the_unfiltered_spread_bounds_the_history() {
        let g = small_view();
        let current = vec![Vec3::splat(0.5); 64];
        // Raw estimates alternating 0.25 and 0.75, as a few shadow samples give.
        let spread: Vec<Vec3> = (0..64)
            .map(|i| Vec3::splat(if (i + i / 8) % 2 == 0 { 0.25 } else { 0.75 }))
            .collect();
        let with_history =
            |v: f32| blend(&current, &spread, &vec![Some(Vec3::splat(v)); 64], &g, 0.1);
        let (kept, clamped) = (with_history(0.7), with_history(2.0));
        for i in 0..64 {
            assert!((kept[i] - Vec3::splat(0.05 + 0.63)).abs().max_element() < 1e-6);
            assert!((clamped[i] - Vec3::splat(0.05 + 0.675)).abs().max_element() < 1e-6);
        }
    }
}
