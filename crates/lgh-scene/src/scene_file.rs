//! The TOML scene file: a mesh file plus camera, lights and exposure.
//!
//! ```toml
//! # Paths are relative to this file; "$LGH_SCENES/..." reads the LGH_SCENES folder.
//! mesh = "$LGH_SCENES/sponza/sponza.obj"
//! exposure = 1.0               # optional, multiplies radiance before tone mapping
//!
//! [camera]                     # optional: else the glTF camera, else one framing the mesh
//! position = [-13.0, 2.0, -0.5]
//! look_at = [10.0, 5.0, 0.5]
//! up = [0.0, 1.0, 0.0]         # optional, default +y
//! fov = 60.0                   # optional, vertical, degrees; default 45
//!
//! [[lights]]
//! type = "directional"         # point | spot | directional
//! direction = [0.25, -1.0, 0.15]   # the way the light travels (normalised on load)
//! irradiance = [8.0, 8.0, 8.0]     # W/m^2
//!
//! [[lights]]
//! type = "point"
//! position = [0.0, 5.0, 0.0]
//! intensity = [10.0, 10.0, 10.0]   # W/sr
//!
//! [[lights]]
//! type = "spot"
//! position = [0.0, 5.0, 0.0]
//! direction = [0.0, -1.0, 0.0]
//! intensity = [50.0, 50.0, 50.0]
//! inner_angle = 20.0           # degrees (half-angle of full intensity)
//! outer_angle = 30.0           # degrees (half-angle where it reaches zero)
//! ```
//!
//! The file's lights are added to the mesh's own (emissive materials, glTF punctual lights).
//! An optional `[animation]` table moves the camera, the file's lights and named objects of
//! the mesh over time (see [`crate::animation`]).

use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::Deserialize;

use crate::animation::{Animation, CameraKey, LightKey, ObjectKey};
use crate::{Camera, Light, Scene, SceneError};

/// Name of the environment variable that points to the shared test scenes.
pub const SCENES_ENV: &str = "LGH_SCENES";

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    mesh: String,
    name: Option<String>,
    exposure: Option<f32>,
    camera: Option<CameraDesc>,
    #[serde(default)]
    lights: Vec<LightDesc>,
    animation: Option<AnimationDesc>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AnimationDesc {
    #[serde(default)]
    camera: Vec<CameraKeyDesc>,
    #[serde(default)]
    lights: Vec<LightKeyDesc>,
    #[serde(default)]
    objects: Vec<ObjectKeyDesc>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectKeyDesc {
    object: String,
    time: f32,
    #[serde(default)]
    translation: [f32; 3],
    #[serde(default)]
    rotation: [f32; 3],
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraKeyDesc {
    time: f32,
    position: [f32; 3],
    look_at: [f32; 3],
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LightKeyDesc {
    light: usize,
    time: f32,
    position: Option<[f32; 3]>,
    direction: Option<[f32; 3]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraDesc {
    position: [f32; 3],
    look_at: [f32; 3],
    up: Option<[f32; 3]>,
    fov: Option<f32>,
}

#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
enum LightDesc {
    Point {
        position: [f32; 3],
        intensity: [f32; 3],
    },
    Spot {
        position: [f32; 3],
        direction: [f32; 3],
        intensity: [f32; 3],
        inner_angle: f32,
        outer_angle: f32,
    },
    Directional {
        direction: [f32; 3],
        irradiance: [f32; 3],
    },
}

impl LightDesc {
    fn to_light(&self) -> Light {
        match *self {
            LightDesc::Point {
                position,
                intensity,
            } => Light::Point {
                position: position.into(),
                intensity: intensity.into(),
            },
            LightDesc::Spot {
                position,
                direction,
                intensity,
                inner_angle,
                outer_angle,
            } => Light::Spot {
                position: position.into(),
                direction: Vec3::from(direction).normalize_or_zero(),
                intensity: intensity.into(),
                cos_inner: inner_angle.max(0.0).min(outer_angle).to_radians().cos(),
                cos_outer: outer_angle.clamp(0.0, 180.0).to_radians().cos(),
            },
            LightDesc::Directional {
                direction,
                irradiance,
            } => Light::Directional {
                direction: Vec3::from(direction).normalize_or_zero(),
                irradiance: irradiance.into(),
            },
        }
    }
}

/// The `[animation]` table: keyframes sorted by time, light numbers checked against the
/// file's `[[lights]]` (offset by the mesh's own lights, which come first), object names
/// against the mesh's.
fn animation(
    path: &Path,
    a: AnimationDesc,
    first_light: usize,
    file_lights: usize,
    object_names: &[String],
) -> Result<Animation, SceneError> {
    let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
    let mut out = Animation::default();
    for k in a.camera {
        if !finite(&[k.time]) || !finite(&k.position) || !finite(&k.look_at) {
            return Err(SceneError::new(
                path,
                "animation.camera: a keyframe has a non-finite number",
            ));
        }
        if k.position == k.look_at {
            return Err(SceneError::new(
                path,
                format!(
                    "animation.camera: the keyframe at time {} looks at its own position",
                    k.time
                ),
            ));
        }
        out.camera.push(CameraKey {
            time: k.time,
            position: k.position.into(),
            look_at: k.look_at.into(),
        });
    }
    for k in a.lights {
        if k.light >= file_lights {
            return Err(SceneError::new(
                path,
                format!(
                    "animation.lights: light {} does not exist (the file has {file_lights} [[lights]], numbered from 0)",
                    k.light
                ),
            ));
        }
        let ok = finite(&[k.time])
            && k.position.is_none_or(|p| finite(&p))
            && k.direction.is_none_or(|d| finite(&d));
        if !ok {
            return Err(SceneError::new(
                path,
                "animation.lights: a keyframe has a non-finite number",
            ));
        }
        out.lights.push(LightKey {
            light: first_light + k.light,
            time: k.time,
            position: k.position.map(Vec3::from),
            direction: k.direction.map(|d| Vec3::from(d).normalize_or_zero()),
        });
    }
    for k in a.objects {
        let Some(object) = object_names.iter().position(|n| *n == k.object) else {
            let mut known: Vec<&str> = object_names.iter().take(20).map(String::as_str).collect();
            if object_names.len() > known.len() {
                known.push("...");
            }
            return Err(SceneError::new(
                path,
                format!(
                    "animation.objects: the mesh has no object named \"{}\" (it has: {})",
                    k.object,
                    known.join(", ")
                ),
            ));
        };
        if !finite(&[k.time]) || !finite(&k.translation) || !finite(&k.rotation) {
            return Err(SceneError::new(
                path,
                "animation.objects: a keyframe has a non-finite number",
            ));
        }
        if k.translation
            .iter()
            .any(|x| x.abs() > crate::MAX_COORDINATE)
        {
            return Err(SceneError::new(
                path,
                format!(
                    "animation.objects: the keyframe of \"{}\" at time {} moves it beyond {:e} units (the most lgh takes)",
                    k.object,
                    k.time,
                    crate::MAX_COORDINATE
                ),
            ));
        }
        out.objects.push(ObjectKey {
            object: object as u32,
            time: k.time,
            translation: k.translation.into(),
            rotation_degrees: k.rotation.into(),
        });
    }
    out.camera.sort_by(|a, b| a.time.total_cmp(&b.time));
    out.lights.sort_by(|a, b| a.time.total_cmp(&b.time));
    out.objects.sort_by(|a, b| a.time.total_cmp(&b.time));
    Ok(out)
}

/// Resolves the `mesh` entry of a scene file: `$LGH_SCENES/...` (or `${LGH_SCENES}/...`)
/// against that variable, anything else against the scene file's folder.
///
/// # Errors
/// The path names `LGH_SCENES` and the variable is not set.
pub fn resolve_mesh_path(scene_file: &Path, mesh: &str) -> Result<PathBuf, SceneError> {
    for prefix in ["$LGH_SCENES", "${LGH_SCENES}"] {
        if let Some(rest) = mesh.strip_prefix(prefix) {
            let root = std::env::var_os(SCENES_ENV).ok_or_else(|| {
                SceneError::new(
                    scene_file,
                    format!("mesh \"{mesh}\" needs the {SCENES_ENV} environment variable (the folder of the shared scenes), which is not set"),
                )
            })?;
            return Ok(PathBuf::from(root).join(rest.trim_start_matches(['/', '\\'])));
        }
    }
    Ok(scene_file.parent().unwrap_or(Path::new(".")).join(mesh))
}

/// Loads a TOML scene file and the mesh it names, and finishes the scene.
///
/// # Errors
/// The file cannot be read or parsed (the message gives the TOML line), the mesh cannot be
/// loaded, or the finished scene is invalid (see [`Scene::finish`]).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let bytes =
        crate::file_kind::read_capped(path, crate::file_kind::MAX_TEXT_BYTES, "scene file")?;
    let text = String::from_utf8(bytes)
        .map_err(|_| SceneError::new(path, "cannot read scene file: not UTF-8 text"))?;
    let desc: SceneFile = toml::from_str(&text).map_err(|e| {
        let place = e.span().map_or_else(String::new, |span| {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
            format!(" at line {line}, column {column}")
        });
        SceneError::new(
            path,
            format!("invalid scene file{place}: {}", e.message().trim()),
        )
    })?;
    let mesh_path = resolve_mesh_path(path, &desc.mesh)?;
    let mut scene = crate::load_mesh_file(&mesh_path)?;
    if let Some(name) = desc.name {
        scene.name = name;
    } else if let Some(stem) = path.file_stem() {
        scene.name = stem.to_string_lossy().into_owned();
    }
    if let Some(e) = desc.exposure {
        scene.exposure = e;
    }
    if let Some(c) = desc.camera {
        scene.camera = Some(Camera {
            position: c.position.into(),
            look_at: c.look_at.into(),
            up: c.up.map_or(Vec3::Y, Vec3::from),
            fov_y_degrees: c.fov.unwrap_or(crate::camera::DEFAULT_FOV_DEGREES),
        });
    }
    for (k, light) in desc.lights.iter().enumerate() {
        if let LightDesc::Spot {
            inner_angle,
            outer_angle,
            ..
        } = *light
            && !(0.0 <= inner_angle && inner_angle <= outer_angle && outer_angle <= 180.0)
        {
            return Err(SceneError::new(
                path,
                format!(
                    "light {}: a spot light needs 0 <= inner_angle <= outer_angle <= 180 (got {inner_angle} and {outer_angle})",
                    k + 1
                ),
            ));
        }
    }
    let first_file_light = scene.lights.len();
    scene
        .lights
        .extend(desc.lights.iter().map(LightDesc::to_light));
    if let Some(a) = desc.animation {
        scene.animation = animation(
            path,
            a,
            first_file_light,
            desc.lights.len(),
            &scene.mesh.object_names,
        )?;
    }
    scene.finish(path)?;
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Writes a one-quad OBJ and a scene file with `extra` appended; returns the scene path.
    fn write_scene(name: &str, extra: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("lgh-scene-file-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("quad.obj"),
            "o quad\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 3 2\nf 1 4 3\n",
        )
        .unwrap();
        let text = format!(
            "mesh = \"quad.obj\"\n[[lights]]\ntype = \"point\"\nposition = [0.5, 1.0, 0.5]\nintensity = [1.0, 1.0, 1.0]\n{extra}"
        );
        let path = dir.join("scene.toml");
        std::fs::write(&path, text).unwrap();
        path
    }

    #[test]
    fn animation_keyframes_load_and_move_the_light() {
        let path = write_scene(
            "ok",
            "[[animation.lights]]\nlight = 0\ntime = 1.0\nposition = [1.0, 1.0, 0.5]\n\
             [[animation.lights]]\nlight = 0\ntime = 0.0\nposition = [0.0, 1.0, 0.5]\n\
             [[animation.camera]]\ntime = 0.0\nposition = [0.5, 3.0, 2.0]\nlook_at = [0.5, 0.0, 0.5]\n",
        );
        let scene = load(&path).unwrap();
        assert_eq!(scene.animation.lights.len(), 2);
        assert_eq!(scene.animation.lights[0].time, 0.0);
        let lights = scene.animation.lights_at(&scene.lights, 0.5);
        assert_eq!(
            lights[0],
            Light::Point {
                position: Vec3::new(0.5, 1.0, 0.5),
                intensity: Vec3::ONE
            }
        );
    }

    /// A `[camera]` may leave out `fov` (and `up`): 45 degrees and +y.
    #[test]
    fn a_camera_without_fov_takes_the_default() {
        let path = write_scene(
            "fov",
            "[camera]\nposition = [0.5, 3.0, 2.0]\nlook_at = [0.5, 0.0, 0.5]\n",
        );
        let camera = load(&path).unwrap().camera();
        assert_eq!(camera.fov_y_degrees, crate::camera::DEFAULT_FOV_DEGREES);
        assert_eq!(camera.up, Vec3::Y);
        assert_eq!(camera.position, Vec3::new(0.5, 3.0, 2.0));
    }

    #[test]
    fn animating_a_missing_light_is_an_error_naming_the_file() {
        let path = write_scene(
            "bad",
            "[[animation.lights]]\nlight = 3\ntime = 0.0\nposition = [0.0, 1.0, 0.5]\n",
        );
        let err = load(&path).unwrap_err().to_string();
        assert!(
            err.contains("scene.toml") && err.contains("light 3 does not exist"),
            "{err}"
        );
    }

    #[test]
    fn object_keyframes_name_an_object_of_the_mesh() {
        let path = write_scene(
            "objects",
            "[[animation.objects]]\nobject = \"quad\"\ntime = 2.0\ntranslation = [0.0, 1.0, 0.0]\n\
             [[animation.objects]]\nobject = \"quad\"\ntime = 0.0\nrotation = [0.0, 90.0, 0.0]\n",
        );
        let scene = load(&path).unwrap();
        let keys = &scene.animation.objects;
        assert_eq!(keys.len(), 2);
        assert_eq!(keys[0].time, 0.0);
        assert_eq!(keys[0].rotation_degrees, Vec3::new(0.0, 90.0, 0.0));
        assert_eq!(keys[1].translation, Vec3::Y);
        let mut posed = scene.mesh.clone();
        assert!(scene.animation.pose_mesh(&scene.mesh, 2.0, &mut posed));
        assert!((posed.positions[0] - scene.mesh.positions[0] - Vec3::Y).length() < 1e-6);

        let path = write_scene(
            "no-object",
            "[[animation.objects]]\nobject = \"teapot\"\ntime = 0.0\n",
        );
        let err = load(&path).unwrap_err().to_string();
        assert!(
            err.contains("scene.toml")
                && err.contains("no object named \"teapot\"")
                && err.contains("quad"),
            "{err}"
        );
    }
}
