//! What a path names, checked before a loader opens it: reading a FIFO blocks forever and a
//! device such as /dev/zero never ends, so only regular files are read, and anything else is
//! named for what it is.

use std::path::Path;

use crate::SceneError;

/// Ok if `path` names a regular file (after following symbolic links); otherwise an error
/// saying what it names instead: nothing, a folder, a FIFO, a device or a socket.
///
/// # Errors
/// As above, with the path.
pub fn regular_file(path: &Path) -> Result<(), SceneError> {
    let meta = std::fs::metadata(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => SceneError::new(path, "file not found"),
        _ => SceneError::new(path, format!("cannot read: {e}")),
    })?;
    let kind = meta.file_type();
    if kind.is_file() {
        return Ok(());
    }
    let what = if kind.is_dir() {
        "a folder"
    } else {
        special_kind(&kind)
    };
    Err(SceneError::new(
        path,
        format!("is {what}, not a regular file"),
    ))
}

/// Reads a regular file of at most `max` bytes (a text format with no size of its own: an
/// MTL or scene file), refusing a bigger one by name before reading it; `what` names the
/// format in the message.
///
/// # Errors
/// Not a regular file, bigger than `max`, or unreadable.
pub fn read_capped(path: &Path, max: u64, what: &str) -> Result<Vec<u8>, SceneError> {
    use std::io::Read;
    regular_file(path)?;
    let file = std::fs::File::open(path)
        .map_err(|e| SceneError::new(path, format!("cannot read: {e}")))?;
    let mut bytes = Vec::new();
    file.take(max + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| SceneError::new(path, format!("cannot read: {e}")))?;
    if bytes.len() as u64 > max {
        return Err(SceneError::new(
            path,
            format!("larger than the {} MiB a {what} may have", max >> 20),
        ));
    }
    Ok(bytes)
}

/// Reads `len` bytes from the start of a regular file (a glTF buffer: no more than its
/// `byteLength` says, whatever the file's size).
///
/// # Errors
/// Not a regular file, shorter than `len`, or unreadable.
pub fn read_exactly(path: &Path, len: u64) -> Result<Vec<u8>, SceneError> {
    use std::io::Read;
    regular_file(path)?;
    let file = std::fs::File::open(path)
        .map_err(|e| SceneError::new(path, format!("cannot read: {e}")))?;
    let mut bytes = Vec::new();
    file.take(len)
        .read_to_end(&mut bytes)
        .map_err(|e| SceneError::new(path, format!("cannot read: {e}")))?;
    if (bytes.len() as u64) < len {
        return Err(SceneError::new(
            path,
            format!("has {} bytes where the glTF file says {len}", bytes.len()),
        ));
    }
    Ok(bytes)
}

/// The most bytes of a text file that has no size of its own (MTL, scene file): 64 MiB.
pub const MAX_TEXT_BYTES: u64 = 64 << 20;

#[cfg(unix)]
fn special_kind(kind: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if kind.is_fifo() {
        "a FIFO (named pipe)"
    } else if kind.is_char_device() || kind.is_block_device() {
        "a device"
    } else if kind.is_socket() {
        "a socket"
    } else {
        "not a file"
    }
}

#[cfg(not(unix))]
fn special_kind(_: &std::fs::FileType) -> &'static str {
    "a special file"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_files_are_named_for_what_they_are() {
        let d = std::env::temp_dir().join(format!("lgh-file-kind-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("temp folder");
        let fifo = d.join("scene.obj");
        let _ = std::fs::remove_file(&fifo);
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|s| s.success()) {
            let e = regular_file(&fifo).expect_err("a FIFO").to_string();
            assert!(e.contains("FIFO") && e.contains("scene.obj"), "{e}");
            // The loaders refuse it without blocking on it.
            let e = crate::load(&fifo).expect_err("a FIFO").to_string();
            assert!(e.contains("FIFO"), "{e}");
        }
        let e = regular_file(&d).expect_err("a folder").to_string();
        assert!(e.contains("a folder"), "{e}");
        let e = crate::load(&d).expect_err("a folder").to_string();
        assert!(e.contains("a folder"), "{e}");
        #[cfg(unix)]
        {
            let e = regular_file(Path::new("/dev/zero"))
                .expect_err("a device")
                .to_string();
            assert!(e.contains("a device"), "{e}");
        }
        let e = regular_file(&d.join("missing.gltf"))
            .expect_err("nothing")
            .to_string();
        assert!(e.contains("file not found"), "{e}");
        let toml = d.join("fifo.toml");
        let _ = std::fs::remove_file(&toml);
        if std::process::Command::new("mkfifo")
            .arg(&toml)
            .status()
            .is_ok_and(|s| s.success())
        {
            let e = crate::load(&toml).expect_err("a FIFO").to_string();
            assert!(e.contains("FIFO"), "{e}");
        }
        let _ = std::fs::remove_dir_all(&d);
    }
}
