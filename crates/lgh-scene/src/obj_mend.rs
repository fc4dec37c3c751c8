//! OBJ files that the parser refuses, mended where what they mean is clear: read again as
//! text, changed line by line, parsed again, with a warning for each change.

use std::path::Path;

use crate::{SceneError, text};

/// The most bytes of an OBJ file that is read again to be mended ([`mended`]).
const MAX_MENDED_BYTES: u64 = 1 << 30;

/// The OBJ file at `path` as text the parser reads, with a warning for each change, where
/// it needs one: decoded from UTF-16 or ISO-8859-1 (the parser reads UTF-8); each
/// `usemtl` without a name (Blender writes one for a slot without a material; the parser
/// refuses it) naming no material, so that its faces take the default; and, where some
/// vertices have colours (`v x y z r g b`) and others not (the parser refuses the faces
/// that mix them), the others white. `None` where nothing needs mending (or the file is
/// over [`MAX_MENDED_BYTES`]).
pub(crate) fn mended(path: &Path) -> Result<Option<(String, Vec<String>)>, SceneError> {
    let size = std::fs::metadata(path).map_or(u64::MAX, |m| m.len());
    if size > MAX_MENDED_BYTES {
        return Ok(None);
    }
    let bytes = crate::file_kind::read_capped(path, MAX_MENDED_BYTES, "OBJ file")?;
    let (text, encoding) = text::decode(bytes).map_err(|e| SceneError::new(path, e))?;
    let mut notes: Vec<String> = encoding.warning("the OBJ file").into_iter().collect();
    let bare = |line: &str| {
        let mut words = line.split_whitespace();
        words.next() == Some("usemtl") && words.next().is_none()
    };
    let vertex_numbers = |line: &str| {
        let mut words = line.split_whitespace();
        (words.next() == Some("v")).then(|| words.count())
    };
    let coloured = text.lines().any(|l| vertex_numbers(l) == Some(6));
    let uncoloured = |line: &str| coloured && matches!(vertex_numbers(line), Some(3 | 4));
    if !text.lines().any(|l| bare(l) || uncoloured(l)) {
        return Ok((!notes.is_empty()).then_some((text, notes)));
    }
    let mut out = String::with_capacity(text.len());
    let mut whitened = 0usize;
    for (i, line) in text.lines().enumerate() {
        if bare(line) {
            notes.push(format!(
                "{} line {}: `usemtl` without a name: its faces take the default material",
                path.display(),
                i + 1
            ));
            out.push_str("usemtl (no name)\n");
        } else if uncoloured(line) {
            whitened += 1;
            out.push_str(&white_vertex(line));
            out.push('\n');
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    if whitened > 0 {
        notes.push(format!(
            "{}: {whitened} vertices have no colour where others have one; they are white",
            path.display()
        ));
    }
    Ok(Some((out, notes)))
}

/// The vertex line `v x y z [w]` with a white colour: `v x/w y/w z/w 1 1 1` (the colour
/// takes w's place, so w divides here as the parser would). A line that does not parse is
/// returned as it is, for the parser to report.
fn white_vertex(line: &str) -> String {
    let numbers: Option<Vec<f32>> = line
        .split_whitespace()
        .skip(1)
        .map(|w| w.parse().ok())
        .collect();
    match numbers.as_deref() {
        Some([x, y, z]) => format!("v {x} {y} {z} 1 1 1"),
        Some([x, y, z, w]) if *w != 0.0 => format!("v {} {} {} 1 1 1", x / w, y / w, z / w),
        _ => line.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertices_without_colours_are_made_white() {
        assert_eq!(white_vertex("v 1 2 3"), "v 1 2 3 1 1 1");
        assert_eq!(white_vertex("v 1 2 3 2"), "v 0.5 1 1.5 1 1 1");
        assert_eq!(white_vertex("v 1 2 3 0"), "v 1 2 3 0");
        assert_eq!(white_vertex("v 1 x 3"), "v 1 x 3");
    }

    /// A file whose first and last vertices have colours and the others not loads, with
    /// the others white and one warning (the parser refused it).
    #[test]
    fn a_file_with_some_vertex_colours_loads() {
        let d = std::env::temp_dir().join(format!("lgh-obj-mend-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let path = d.join("partial.obj");
        std::fs::write(
            &path,
            "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 1\nv 0 0 1 0 1 0\nf 1 2 3\nf 2 3 4\n",
        )
        .unwrap();
        let scene = crate::obj::load(&path).unwrap();
        let _ = std::fs::remove_dir_all(&d);
        let colors: Vec<[f32; 3]> = scene.mesh.colors.iter().map(|c| c.to_array()).collect();
        assert_eq!(colors.len(), 4);
        assert!(colors.contains(&[1.0, 0.0, 0.0]) && colors.contains(&[0.0, 1.0, 0.0]));
        assert_eq!(colors.iter().filter(|c| **c == [1.0; 3]).count(), 2);
        let w = &scene.report.warnings;
        assert!(
            w.iter().any(|w| w.contains("2 vertices have no colour")),
            "{w:?}"
        );
    }
}
