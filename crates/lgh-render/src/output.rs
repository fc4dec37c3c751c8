//! Output files written safely: whole or not at all, never over anything but a regular file,
//! and never left half-written by an interrupted run.
//!
//! - A regular file (or a missing one) is written under a temporary name beside it,
//!   `.NAME.PID-N.partial`, unique to the process and to the write, then renamed over it: two
//!   processes writing one path leave one whole file of either, never a mix.
//! - A symbolic link is followed: the file it names is written (the link stays a link).
//! - A character device or FIFO (`/dev/null`, `/dev/stdout`, a pipe) is written through, as
//!   a shell's `>` would; it is never replaced by a plain file.
//! - A folder, block device or socket is refused by name.
//! - Temporary files of writes in flight are listed, so that a handler of Ctrl-C can remove
//!   them ([`remove_partial_files`]).

use std::fs::FileType;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

/// A problem with an output path, named in one line.
#[derive(Debug, thiserror::Error)]
#[error("{}: {message}", path.display())]
pub struct OutputError {
    /// The output path as given.
    pub path: PathBuf,
    /// What is wrong.
    pub message: String,
}

impl OutputError {
    fn new(path: &Path, message: impl Into<String>) -> Self {
        Self {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

/// How an output path is written.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Target {
    /// Written under a temporary name in the folder of the path, then renamed onto it.
    Replace(PathBuf),
    /// Opened and written in place (a character device or FIFO).
    Through(PathBuf),
}

/// What `path` is, following symbolic links, as a write would find it.
fn target(path: &Path) -> Result<Target, OutputError> {
    let meta = match std::fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return missing(path),
        Err(e) => return Err(OutputError::new(path, format!("cannot examine: {e}"))),
    };
    if meta.file_type().is_symlink() {
        // What the link names, as the kernel resolves it: /dev/stdout names a pipe or a
        // terminal through /proc, which has no path to canonicalize, so a device or FIFO is
        // written through the link itself; a regular file is replaced at its real path (the
        // link stays a link).
        let Ok(named) = std::fs::metadata(path) else {
            return Err(OutputError::new(
                path,
                "a symbolic link to nothing (dangling): name the file itself",
            ));
        };
        return match kind(path, &named.file_type())? {
            Target::Through(_) => Ok(Target::Through(path.to_path_buf())),
            Target::Replace(_) => std::fs::canonicalize(path)
                .map(Target::Replace)
                .map_err(|e| OutputError::new(path, format!("cannot resolve the link: {e}"))),
        };
    }
    kind(path, &meta.file_type())
}

/// A path that does not exist yet: its folder must.
fn missing(path: &Path) -> Result<Target, OutputError> {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() && !dir.is_dir() => Err(OutputError::new(
            path,
            format!("output folder {} does not exist", dir.display()),
        )),
        _ => Ok(Target::Replace(path.to_path_buf())),
    }
}

#[cfg(unix)]
fn kind(path: &Path, t: &FileType) -> Result<Target, OutputError> {
    use std::os::unix::fs::FileTypeExt;
    if t.is_file() {
        Ok(Target::Replace(path.to_path_buf()))
    } else if t.is_char_device() || t.is_fifo() {
        Ok(Target::Through(path.to_path_buf()))
    } else {
        let what = if t.is_dir() {
            "a folder"
        } else if t.is_block_device() {
            "a block device"
        } else if t.is_socket() {
            "a socket"
        } else {
            "not a regular file"
        };
        Err(OutputError::new(
            path,
            format!("is {what}: an output must be a file"),
        ))
    }
}

#[cfg(not(unix))]
fn kind(path: &Path, t: &FileType) -> Result<Target, OutputError> {
    if t.is_file() {
        Ok(Target::Replace(path.to_path_buf()))
    } else {
        Err(OutputError::new(
            path,
            "is not a regular file: an output must be a file",
        ))
    }
}

/// Checks, before any work, that `path` can be written: its folder exists and takes a new
/// file, and the path is not a folder or a device other than a character device or FIFO.
///
/// # Errors
/// As above, naming the path.
pub fn check_output(path: &Path) -> Result<(), OutputError> {
    match target(path)? {
        Target::Through(_) => Ok(()),
        Target::Replace(real) => {
            let tmp = temp_path(&real);
            std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&tmp)
                .map_err(|e| {
                    OutputError::new(path, format!("cannot create a file in its folder: {e}"))
                })?;
            let _ = std::fs::remove_file(&tmp);
            Ok(())
        }
    }
}

/// Checks a command's outputs before any work: each with [`check_output`], and no two of
/// them on one file. Each output comes with the flag that names it, for the message.
///
/// # Errors
/// The first problem, naming the path (and both flags for a shared path).
pub fn check_outputs(outputs: &[(&str, &Path)]) -> Result<(), OutputError> {
    for (i, (flag, path)) in outputs.iter().enumerate() {
        check_output(path)?;
        if let Some((other, _)) = outputs[..i].iter().find(|(_, p)| same_file(p, path)) {
            return Err(OutputError::new(
                path,
                format!("{other} and {flag} name one file: give each output its own path"),
            ));
        }
    }
    Ok(())
}

/// Writes `bytes` to `path` as described in the [module documentation](self).
///
/// # Errors
/// The path cannot be written (see [`check_output`]), or the write or rename fails.
pub fn write_output(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let fail = |e: std::io::Error| OutputError::new(path, format!("cannot write: {e}"));
    match target(path)? {
        Target::Through(real) => std::fs::OpenOptions::new()
            .write(true)
            .open(&real)
            .and_then(|mut f| f.write_all(bytes))
            .map_err(fail),
        Target::Replace(real) => {
            let tmp = temp_path(&real);
            in_flight(|list| list.push(tmp.clone()));
            let result = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, &real));
            if result.is_err() {
                let _ = std::fs::remove_file(&tmp);
            }
            in_flight(|list| list.retain(|p| *p != tmp));
            result.map_err(fail)
        }
    }
}

/// Removes the temporary files of writes in flight (for a handler of Ctrl-C, just before the
/// process exits); returns how many it removed.
pub fn remove_partial_files() -> usize {
    let mut removed = 0;
    in_flight(|list| {
        for p in list.drain(..) {
            removed += usize::from(std::fs::remove_file(&p).is_ok());
        }
    });
    removed
}

/// Whether two output paths name one file: equal after making them absolute, resolving
/// their folders' links and `..`, and following a link at the path itself.
#[must_use]
pub fn same_file(a: &Path, b: &Path) -> bool {
    let real = |p: &Path| -> PathBuf {
        if let Ok(r) = std::fs::canonicalize(p) {
            return r;
        }
        let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
        match (abs.parent(), abs.file_name()) {
            (Some(dir), Some(name)) => std::fs::canonicalize(dir)
                .map(|d| d.join(name))
                .unwrap_or(abs.clone()),
            _ => abs,
        }
    };
    real(a) == real(b)
}

static IN_FLIGHT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
static NEXT: AtomicU64 = AtomicU64::new(0);

fn in_flight(f: impl FnOnce(&mut Vec<PathBuf>)) {
    let mut list = IN_FLIGHT
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    f(&mut list);
}

/// `.NAME.PID-N.partial` beside `path`: unique to this process and this write.
fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}.{}-{n}.partial", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("lgh-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn temporary_names_differ_between_writes() {
        let p = Path::new("/x/out.png");
        assert_ne!(temp_path(p), temp_path(p));
        assert!(temp_path(p).to_string_lossy().contains(".out.png."));
    }

    #[test]
    fn a_link_is_followed_and_stays_a_link() {
        let d = dir("link");
        let real = d.join("real.json");
        std::fs::write(&real, "old").unwrap();
        let link = d.join("link.json");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        write_output(&link, b"new").unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read_to_string(&real).unwrap(), "new");
        let dangling = d.join("dangling.json");
        std::os::unix::fs::symlink(d.join("nothing"), &dangling).unwrap();
        assert!(write_output(&dangling, b"x").is_err());
    }

    #[test]
    fn devices_are_written_through_and_folders_refused() {
        use std::os::unix::fs::FileTypeExt;
        write_output(Path::new("/dev/null"), b"nothing").unwrap();
        assert!(
            std::fs::metadata("/dev/null")
                .unwrap()
                .file_type()
                .is_char_device()
        );
        let d = dir("folder");
        let e = write_output(&d, b"x").unwrap_err();
        assert!(e.message.contains("a folder"), "{e}");
        assert!(check_output(&d.join("none/x.png")).is_err());
        assert!(check_output(&d.join("x.png")).is_ok());
        assert_eq!(
            std::fs::read_dir(&d).unwrap().count(),
            0,
            "the probe file stays"
        );
    }

    #[test]
    fn two_outputs_on_one_file_are_refused() {
        let d = dir("two");
        let (a, b) = (d.join("x.png"), d.join("y.json"));
        assert!(check_outputs(&[("-o", &a), ("--stats", &b)]).is_ok());
        let e = check_outputs(&[("-o", &a), ("--stats", &d.join(".").join("x.png"))]).unwrap_err();
        assert!(e.message.contains("-o and --stats"), "{e}");
    }

    #[test]
    fn same_file_sees_through_spelling() {
        let d = dir("same");
        assert!(same_file(&d.join("a.png"), &d.join(".").join("a.png")));
        assert!(!same_file(&d.join("a.png"), &d.join("b.png")));
    }
}
