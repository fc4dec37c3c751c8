//! The one error type of scene loading.

use std::path::{Path, PathBuf};

/// A problem with a scene input: the file it concerns and what is wrong, in one line.
#[derive(Debug, Clone, thiserror::Error)]
#[error("{}: {message}", path.display())]
pub struct SceneError {
    /// The file the problem is in.
    pub path: PathBuf,
    /// What is wrong, for a person.
    pub message: String,
}

impl SceneError {
    /// A new error about `path`.
    pub fn new(path: &Path, message: impl Into<String>) -> Self {
        Self {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

/// Runs the loader `f` of a `format` file, turning a panic inside it (a bug of a third-party
/// parser on a malformed file: they do not validate everything) into an error naming the
/// file, so that no input can crash the program. The panic message is kept off stderr while
/// `f` runs, so that the user sees one line.
pub(crate) fn contain_panics<T>(
    path: &Path,
    format: &str,
    f: impl FnOnce() -> Result<T, SceneError>,
) -> Result<T, SceneError> {
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    std::panic::set_hook(hook);
    result.unwrap_or_else(|_| {
        Err(SceneError::new(
            path,
            format!(
                "malformed {format}: the loader failed on it (an accessor, buffer, index or \
                 value out of range?)"
            ),
        ))
    })
}
