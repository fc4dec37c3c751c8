//! Progress reporting from long passes, without tying the library to a terminal.

/// Receives progress from the passes of a frame. The command line shows it as progress bars;
/// a library user can ignore it ([`Silent`]) or forward it to a UI. Calls may come from any
/// thread.
pub trait Progress: Sync {
    /// A pass named `pass` starts, with `total` units of work.
    fn begin(&self, _pass: &str, _total: u64) {}
    /// `n` more units of the current pass are done.
    fn advance(&self, _n: u64) {}
    /// The current pass is finished.
    fn end(&self) {}
}

/// Reports nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {}
