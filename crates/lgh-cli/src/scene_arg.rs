//! Turning the optional SCENE argument into a scene.

use std::path::Path;

use anyhow::Result;
use lgh_scene::Scene;

/// Loads `path`, or builds the default Cornell box when there is none. Warnings from loading
/// go to stderr.
pub fn load_scene(path: Option<&Path>) -> Result<Scene> {
    let scene = match path {
        Some(p) => lgh_scene::load(p)?,
        None => {
            let mut s = lgh_scene::cornell::cornell_box();
            s.finish(Path::new("<built-in cornell box>"))?;
            s
        }
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
