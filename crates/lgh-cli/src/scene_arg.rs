//! Turning the optional SCENE argument into a scene.

use std::path::Path;

use anyhow::Result;
use lgh_scene::Scene;

/// Names of the built-in scenes, usable as `builtin:NAME` in place of a file.
pub const BUILTIN: [&str; 4] = [
    "cornell",
    "cornell-moving-light",
    "cornell-moving-block",
    "emitter-room",
];

/// Loads `path`, or builds the default Cornell box when there is none; `builtin:NAME` names a
/// built-in scene (see [`BUILTIN`]). Warnings from loading go to stderr.
pub fn load_scene(path: Option<&Path>) -> Result<Scene> {
    let builtin = match path.and_then(Path::to_str) {
        None if path.is_none() => Some("cornell"),
        Some(p) => p.strip_prefix("builtin:"),
        None => None,
    };
    let scene = match (builtin, path) {
        (Some(name), _) => {
            let mut s = match name {
                "cornell" => lgh_scene::cornell::cornell_box(),
                "cornell-moving-light" => lgh_scene::cornell::cornell_moving_light(),
                "cornell-moving-block" => lgh_scene::cornell::cornell_moving_block(),
                "emitter-room" => lgh_scene::emitter_room::emitter_room(32),
                _ => anyhow::bail!(
                    "builtin:{name}: no such built-in scene (expected one of: {})",
                    BUILTIN.join(", ")
                ),
            };
            s.finish(Path::new(&format!("<built-in {name}>")))?;
            s
        }
        (None, Some(p)) => lgh_scene::load(p)?,
        (None, None) => anyhow::bail!("no scene"),
    };
    if scene.report.degenerate_triangles > 0 {
        eprintln!(
            "note: {} zero-area triangles removed",
            scene.report.degenerate_triangles
        );
    }
    for w in &scene.report.warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}
