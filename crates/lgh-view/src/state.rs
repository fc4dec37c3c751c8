//! What the viewer shows: the settings, the camera and the light, and the actions that change
//! them. Independent of any window: a key press becomes an [`Action`], and the headless mode
//! and the tests drive the same [`ViewState::apply`].

use glam::{Quat, Vec3};
use lgh_render::RenderSettings;
use lgh_render::methods::{brute, lgh, slc};
use lgh_scene::{Camera, Light};

use crate::engine::ShownFrame;

/// One user action.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// Move along the view direction (+1) or back (-1).
    Forward(i8),
    /// Move right (+1) or left (-1).
    Strafe(i8),
    /// Move up (+1) or down (-1).
    Rise(i8),
    /// Turn the view: yaw and pitch steps (mouse look gives several at once).
    Look(i16, i16),
    /// The next method of [`METHOD_CYCLE`].
    NextMethod,
    /// alpha times 2 (+1) or divided by 2 (-1), within 0.25..=8.
    Alpha(i8),
    /// Interleaving 1, 2, 4, in turn.
    NextInterleave,
    /// Shadow samples 0, 1, 4, in turn.
    NextShadowSamples,
    /// The a-trous filter of the shadow ratio on or off.
    ToggleFilter,
    /// Temporal filtering on or off.
    ToggleTaa,
    /// VPLs times 10 (+1) or divided by 10 (-1), within 1,000..=1,000,000.
    Vpls(i8),
    /// Turn the first punctual light about the vertical axis through the scene's centre.
    TurnLight(i8),
    /// Component shown: all, direct, indirect, in turn.
    NextComponent,
    /// The overdraw heat map (lights evaluated per pixel) instead of the image, or back.
    ToggleHeatmap,
    /// The grid-level view: the lowest shaded level alone, the next, ... l_max, then all.
    NextLevel,
    /// lgh's shadow estimate: the unbiased one (the default, representative VPLs as targets)
    /// or the paper's (jittered centroids as targets), in turn.
    ToggleEstimator,
}

/// Methods the viewer cycles through, with what they are.
pub const METHOD_CYCLE: [(lgh_render::Method, &str); 4] = [
    (lgh::LGH, "lgh"),
    (lgh::LGH_UNSHADOWED, "lgh without shadows"),
    (slc::SLC, "slc"),
    (brute::BRUTE, "brute force (converges while still)"),
];

/// The keys, for the help text: (key, what it does).
pub const CONTROLS: [(&str, &str); 19] = [
    ("W/S", "move forward / back"),
    ("A/D", "move left / right"),
    ("Q/E", "move down / up"),
    ("drag / arrows", "look around"),
    (
        "M",
        "next method: lgh, lgh without shadows, slc, brute force",
    ),
    ("[ / ]", "alpha / 2, alpha x 2"),
    ("I", "interleaving 1, 2, 4"),
    ("K", "shadow samples 0, 1, 4"),
    ("F", "shadow filter on / off"),
    ("T", "temporal filter on / off"),
    (
        "U",
        "lgh's shadow estimate: unbiased / the paper's (faster, darker behind occluders)",
    ),
    ("- / =", "VPLs / 10, VPLs x 10"),
    ("J/L", "turn the light"),
    ("C", "show all / direct / indirect light"),
    ("V", "overdraw heat map (lights per pixel) on / off"),
    (
        "G",
        "grid-level view: one level of the hierarchy alone, the next, ..., all",
    ),
    ("H", "show / hide this help"),
    ("O", "show / hide the readout (fps, passes, lights)"),
    ("Esc", "quit"),
];

/// The controls as text: a heading and one line per key (for `--help` and the terminal).
#[must_use]
pub fn controls_help() -> String {
    let mut text = String::from("Controls (H shows them in the window):\n");
    for line in control_lines() {
        text.push_str("  ");
        text.push_str(&line);
        text.push('\n');
    }
    text
}

/// One line per control: the key, padded, and what it does.
pub fn control_lines() -> impl Iterator<Item = String> {
    CONTROLS
        .iter()
        .map(|(key, what)| format!("{key:<14} {what}"))
}

/// The state of the view.
#[derive(Clone, Debug)]
pub struct ViewState {
    /// The settings of the next frame.
    pub settings: RenderSettings,
    /// Camera position.
    pub position: Vec3,
    /// Heading about +y, radians (0 looks along -z).
    pub yaw: f32,
    /// Elevation, radians.
    pub pitch: f32,
    /// Vertical field of view, degrees.
    pub fov: f32,
    /// Angle of the first punctual light about the scene's vertical axis, radians.
    pub light_angle: f32,
    /// Temporal filtering of the shadows.
    pub taa: bool,
    /// Show the overdraw heat map (lights evaluated per pixel) instead of the image.
    pub heatmap: bool,
    /// The levels the last frame's hierarchy shaded (lowest, l_max), if it had one: the
    /// range the grid-level view steps through.
    pub grid_levels: Option<(u32, u32)>,
    /// Length of a step, in scene units.
    pub step: f32,
    /// Incremented by every change: accumulation restarts when it moves.
    pub version: u64,
}

impl ViewState {
    /// The view from `camera`, with steps of 1/20 of the scene radius.
    #[must_use]
    pub fn new(settings: RenderSettings, camera: &Camera, radius: f32, taa: bool) -> Self {
        let dir = (camera.look_at - camera.position).normalize_or_zero();
        Self {
            settings,
            position: camera.position,
            yaw: (-dir.x).atan2(-dir.z),
            pitch: dir.y.clamp(-1.0, 1.0).asin(),
            fov: camera.fov_y_degrees,
            light_angle: 0.0,
            taa,
            heatmap: false,
            grid_levels: None,
            step: radius / 20.0,
            version: 0,
        }
    }

    /// The unit view direction.
    #[must_use]
    pub fn forward(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(-sy * cp, sp, -cy * cp)
    }

    /// The camera of the view.
    #[must_use]
    pub fn camera(&self) -> Camera {
        Camera {
            position: self.position,
            look_at: self.position + self.forward(),
            up: Vec3::Y,
            fov_y_degrees: self.fov,
        }
    }

    /// The scene's punctual lights `rest` with the first one turned by `light_angle` about
    /// the vertical axis through `centre` (a point or spot light moves on a circle, a
    /// directional light turns).
    #[must_use]
    pub fn lights(&self, rest: &[Light], centre: Vec3) -> Vec<Light> {
        let mut out = rest.to_vec();
        let q = Quat::from_rotation_y(self.light_angle);
        if let Some(first) = out.first_mut() {
            match first {
                Light::Point { position, .. } => *position = centre + q * (*position - centre),
                Light::Spot {
                    position,
                    direction,
                    ..
                } => {
                    *position = centre + q * (*position - centre);
                    *direction = q * *direction;
                }
                Light::Directional { direction, .. } => *direction = q * *direction,
            }
        }
        out
    }

    /// Takes note of a frame shown: the levels of its hierarchy.
    pub fn saw(&mut self, frame: &ShownFrame) {
        self.grid_levels = frame.levels;
    }

    /// Applies `action`; returns a line saying what changed, for the terminal.
    pub fn apply(&mut self, action: Action) -> Option<String> {
        let s = &mut self.settings;
        let said = match action {
            Action::Forward(d) => {
                self.position += self.forward() * self.step * f32::from(d);
                None
            }
            Action::Strafe(d) => {
                let right = self.forward().cross(Vec3::Y).normalize_or_zero();
                self.position += right * self.step * f32::from(d);
                None
            }
            Action::Rise(d) => {
                self.position += Vec3::Y * self.step * f32::from(d);
                None
            }
            Action::Look(yaw, pitch) => {
                self.yaw -= f32::from(yaw) * 0.005;
                self.pitch = (self.pitch - f32::from(pitch) * 0.005).clamp(-1.5, 1.5);
                None
            }
            Action::NextMethod => {
                let i = METHOD_CYCLE
                    .iter()
                    .position(|(m, _)| *m == s.method)
                    .map_or(0, |i| (i + 1) % METHOD_CYCLE.len());
                s.method = METHOD_CYCLE[i].0;
                Some(format!("method: {}", METHOD_CYCLE[i].1))
            }
            Action::Alpha(d) => {
                let a = s.lgh.alpha * if d > 0 { 2.0 } else { 0.5 };
                s.lgh.alpha = a.clamp(0.25, 8.0);
                Some(format!("alpha: {}", s.lgh.alpha))
            }
            Action::NextInterleave => {
                let n = match s.tiling.interleave.unwrap_or(lgh::INTERACTIVE_INTERLEAVE) {
                    1 => 2,
                    2 => 4,
                    _ => 1,
                };
                s.tiling.interleave = Some(n);
                Some(format!("interleaving: {n}x{n}"))
            }
            Action::NextShadowSamples => {
                let k = match s.shadow_samples() {
                    0 => 1,
                    1 => 4,
                    _ => 0,
                };
                s.shadows.samples = Some(k);
                Some(format!("shadow samples: {k}"))
            }
            Action::ToggleFilter => {
                use lgh_render::settings::ShadowFilter;
                s.shadows.filter = match s.shadows.filter {
                    ShadowFilter::None => ShadowFilter::Atrous,
                    ShadowFilter::Atrous => ShadowFilter::None,
                };
                Some(format!("shadow filter: {:?}", s.shadows.filter))
            }
            Action::ToggleEstimator => {
                use lgh_render::methods::lgh::{Estimator, ShadowTarget};
                (s.lgh.estimator, s.lgh.shadow_target) = match s.lgh.estimator {
                    Estimator::Unbiased => (Estimator::Paper, ShadowTarget::Centroid),
                    Estimator::Paper => (Estimator::Unbiased, ShadowTarget::Representative),
                };
                Some(match s.lgh.estimator {
                    Estimator::Paper => "lgh shadow estimate: the paper's (centroids)".into(),
                    Estimator::Unbiased => "lgh shadow estimate: unbiased".into(),
                })
            }
            Action::ToggleTaa => {
                self.taa = !self.taa;
                Some(format!("temporal filter: {}", self.taa))
            }
            Action::Vpls(d) => {
                let v = if d > 0 { s.vpls * 10 } else { s.vpls / 10 };
                s.vpls = v.clamp(1_000, 1_000_000);
                Some(format!("VPLs: {}", s.vpls))
            }
            Action::TurnLight(d) => {
                self.light_angle += f32::from(d) * 0.1;
                None
            }
            Action::NextComponent => {
                use lgh_render::Component;
                s.component = match s.component {
                    Component::All => Component::Direct,
                    Component::Direct => Component::Indirect,
                    _ => Component::All,
                };
                Some(format!("showing: {:?}", s.component))
            }
            Action::ToggleHeatmap => {
                self.heatmap = !self.heatmap;
                Some(format!("overdraw heat map: {}", self.heatmap))
            }
            Action::NextLevel => {
                s.lgh.only_level = match (s.lgh.only_level, self.grid_levels) {
                    (None, Some((lowest, _))) => Some(lowest),
                    (Some(l), Some((_, top))) if l < top => Some(l + 1),
                    _ => None,
                };
                Some(match (s.lgh.only_level, self.grid_levels) {
                    (Some(l), Some((_, top))) => format!("grid level {l} of {top} alone"),
                    (None, None) => "grid-level view: needs a frame of lgh".to_string(),
                    _ => "grid-level view: all levels".to_string(),
                })
            }
        };
        self.version += 1;
        said
    }
}

/// The action of a key (a character as typed, or a named key), if it has one.
#[must_use]
pub fn action_of_key(key: &str) -> Option<Action> {
    Some(match key.to_ascii_lowercase().as_str() {
        "w" => Action::Forward(1),
        "s" => Action::Forward(-1),
        "d" => Action::Strafe(1),
        "a" => Action::Strafe(-1),
        "e" => Action::Rise(1),
        "q" => Action::Rise(-1),
        "arrowleft" | "left" => Action::Look(-20, 0),
        "arrowright" | "right" => Action::Look(20, 0),
        "arrowup" | "up" => Action::Look(0, -20),
        "arrowdown" | "down" => Action::Look(0, 20),
        "m" => Action::NextMethod,
        "[" => Action::Alpha(-1),
        "]" => Action::Alpha(1),
        "i" => Action::NextInterleave,
        "k" => Action::NextShadowSamples,
        "f" => Action::ToggleFilter,
        "t" => Action::ToggleTaa,
        "u" => Action::ToggleEstimator,
        "-" => Action::Vpls(-1),
        "=" | "+" => Action::Vpls(1),
        "j" => Action::TurnLight(-1),
        "l" => Action::TurnLight(1),
        "c" => Action::NextComponent,
        "v" => Action::ToggleHeatmap,
        "g" => Action::NextLevel,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state() -> ViewState {
        let cam = Camera {
            position: Vec3::new(0.0, 1.0, 4.0),
            look_at: Vec3::new(0.0, 1.0, 0.0),
            up: Vec3::Y,
            fov_y_degrees: 40.0,
        };
        ViewState::new(RenderSettings::default(), &cam, 2.0, false)
    }

    #[test]
    fn the_view_starts_as_the_scene_camera_and_moves_with_keys() {
        let mut v = state();
        assert!((v.forward() - Vec3::NEG_Z).length() < 1e-5);
        let c = v.camera();
        assert!((c.look_at - Vec3::new(0.0, 1.0, 3.0)).length() < 1e-5);
        v.apply(action_of_key("w").unwrap());
        assert!((v.position.z - 3.9).abs() < 1e-5);
        v.apply(action_of_key("d").unwrap());
        assert!(v.position.x > 0.09);
        assert_eq!(v.version, 2);
    }

    #[test]
    fn keys_cycle_the_settings_within_their_ranges() {
        let mut v = state();
        for _ in 0..4 {
            v.apply(Action::NextMethod);
        }
        assert_eq!(v.settings.method, METHOD_CYCLE[0].0);
        for _ in 0..10 {
            v.apply(Action::Alpha(1));
            v.apply(Action::Vpls(1));
        }
        assert_eq!(v.settings.lgh.alpha, 8.0);
        assert_eq!(v.settings.vpls, 1_000_000);
        // From the default 4 x 4: none, then 2 x 2.
        v.apply(Action::NextInterleave);
        v.apply(Action::NextInterleave);
        assert_eq!(v.settings.tiling.interleave, Some(2));
        assert!(v.settings.validate().is_ok());
        // The shadow estimate: the paper's, then back; each a valid, new view.
        use lgh_render::methods::lgh::{Estimator, ShadowTarget};
        let before = v.version;
        v.apply(action_of_key("u").unwrap());
        assert_eq!(v.settings.lgh.estimator, Estimator::Paper);
        assert_eq!(v.settings.lgh.shadow_target, ShadowTarget::Centroid);
        assert!(v.settings.validate().is_ok() && v.version > before);
        v.apply(action_of_key("u").unwrap());
        assert_eq!(v.settings.lgh.estimator, Estimator::Unbiased);
        assert_eq!(v.settings.lgh.shadow_target, ShadowTarget::Representative);
        assert!(v.settings.validate().is_ok());
    }

    #[test]
    fn the_light_turns_about_the_centre() {
        let mut v = state();
        let rest = [Light::Point {
            position: Vec3::new(1.0, 2.0, 0.0),
            intensity: Vec3::ONE,
        }];
        v.light_angle = std::f32::consts::FRAC_PI_2;
        let Light::Point { position, .. } = v.lights(&rest, Vec3::ZERO)[0] else {
            panic!()
        };
        assert!(
            (position - Vec3::new(0.0, 2.0, -1.0)).length() < 1e-5,
            "{position}"
        );
    }

    /// G steps through the levels the last frame shaded, then back to all of them; before
    /// any lgh frame it stays at all.
    #[test]
    fn the_grid_level_view_steps_through_the_levels() {
        let mut v = state();
        v.apply(action_of_key("g").unwrap());
        assert_eq!(v.settings.lgh.only_level, None);
        v.grid_levels = Some((1, 3));
        let mut seen = Vec::new();
        for _ in 0..4 {
            v.apply(action_of_key("G").unwrap());
            seen.push(v.settings.lgh.only_level);
        }
        assert_eq!(seen, [Some(1), Some(2), Some(3), None]);
        assert!(v.settings.validate().is_ok());
    }
}
