//! The passes every frame runs before its method: the G-buffer ([`gbuffer`]) and the VPLs by
//! light tracing ([`vpl_gen`]), the anti-aliasing of edges ([`edge_aa`]), with the helpers of per-pixel passes. The direct light is
//! [`crate::direct`].

use glam::Vec3;
use rayon::prelude::*;

use crate::progress::Progress;

pub mod edge_aa;
pub mod gbuffer;
pub mod vpl_gen;

/// `n` copies of `value`, written in parallel. `vec![value; n]` writes them on one thread,
/// and for an image-sized buffer that thread also takes every page fault of the fresh
/// memory, which costs as much as writing it.
#[must_use]
pub fn par_filled<T: Copy + Send + Sync>(n: usize, value: T) -> Vec<T> {
    (0..n).into_par_iter().map(|_| value).collect()
}

/// Makes `dst` a copy of `src`, written in parallel into `dst`'s own memory (`clone_from` of
/// an image-sized buffer is one thread's memcpy while the others wait).
pub fn par_copy_into<T: Copy + Send + Sync>(dst: &mut Vec<T>, src: &[T]) {
    dst.clear();
    dst.par_extend(src.par_iter().copied());
}

/// Runs `f` for every pixel index of a `width` x `len / width` image, rows in parallel, and
/// reports one unit of progress per row. Each pixel's value depends only on its index, so the
/// result is the same whatever the thread count.
pub fn per_pixel<F>(len: usize, width: usize, progress: &dyn Progress, f: F) -> Vec<Vec3>
where
    F: Fn(usize) -> Vec3 + Sync,
{
    per_pixel_with(len, width, progress, || (), |(), i| f(i))
}

/// [`per_pixel`] with scratch space: each worker makes its own with `init` and hands it to
/// `f` with every pixel it runs. The scratch must not carry a value from one pixel to the
/// next (only its memory), so that the result stays independent of the thread count.
pub fn per_pixel_with<S, I, F>(
    len: usize,
    width: usize,
    progress: &dyn Progress,
    init: I,
    f: F,
) -> Vec<Vec3>
where
    I: Fn() -> S + Sync + Send,
    F: Fn(&mut S, usize) -> Vec3 + Sync,
{
    let mut out = par_filled(len, Vec3::ZERO);
    out.par_chunks_mut(width.max(1))
        .enumerate()
        .for_each_init(init, |scratch, (y, row)| {
            let base = y * width;
            for (x, v) in row.iter_mut().enumerate() {
                *v = f(scratch, base + x);
            }
            progress.advance(1);
        });
    out
}
