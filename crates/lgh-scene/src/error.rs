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
