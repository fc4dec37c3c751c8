//! Helpers shared by the per-pixel passes.

use glam::Vec3;
use rayon::prelude::*;

use crate::progress::Progress;

/// Runs `f` for every pixel index of a `width` x `len / width` image, rows in parallel, and
/// reports one unit of progress per row. Each pixel's value depends only on its index, so the
/// result is the same whatever the thread count.
pub fn per_pixel<F>(len: usize, width: usize, progress: &dyn Progress, f: F) -> Vec<Vec3>
where
    F: Fn(usize) -> Vec3 + Sync,
{
    let mut out = vec![Vec3::ZERO; len];
    out.par_chunks_mut(width.max(1))
        .enumerate()
        .for_each(|(y, row)| {
            let base = y * width;
            for (x, v) in row.iter_mut().enumerate() {
                *v = f(base + x);
            }
            progress.advance(1);
        });
    out
}
