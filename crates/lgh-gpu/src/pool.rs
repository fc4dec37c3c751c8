//! Buffers kept from frame to frame: a frame's tables, images and read-back copies are the
//! same size every frame, and allocating (and zeroing) 100 MB of device memory each frame
//! cost more than the lighting loop itself on an H200 (docs/performance.md, "The GPU
//! frame's transfers"). A frame leases what it needs ([`GpuContext::lease`]) and the lease
//! returns the buffer on drop; two frames at once (tests on threads) lease two buffers, so
//! no frame writes into another's.

use std::collections::HashMap;
use std::num::NonZeroU64;
use std::sync::{Mutex, PoisonError};

use rayon::prelude::*;

use crate::context::{GpuContext, GpuError};

/// The free buffers, by label and usage.
#[derive(Debug, Default)]
pub(crate) struct BufferPool {
    free: Mutex<HashMap<(&'static str, u32), Vec<wgpu::Buffer>>>,
}

/// Bytes per piece of [`GpuContext::write_parallel`] (a multiple of 64, the largest element
/// a kernel reads, so that a piece holds whole elements).
pub(crate) const WRITE_PIECE: usize = 1 << 20;

/// Free buffers kept per label and usage (two frames at once, and room).
const KEPT: usize = 2;

impl BufferPool {
    /// A free buffer of at least `bytes` under `key`, the smallest such, taken out.
    fn take(&self, key: (&'static str, u32), bytes: u64) -> Option<wgpu::Buffer> {
        let mut free = self.free.lock().unwrap_or_else(PoisonError::into_inner);
        let list = free.get_mut(&key)?;
        let at = (0..list.len())
            .filter(|&i| list[i].size() >= bytes)
            .min_by_key(|&i| list[i].size())?;
        Some(list.swap_remove(at))
    }

    /// Puts `buffer` back under `key`, dropping the smallest beyond [`KEPT`].
    fn give(&self, key: (&'static str, u32), buffer: wgpu::Buffer) {
        let mut free = self.free.lock().unwrap_or_else(PoisonError::into_inner);
        let list = free.entry(key).or_default();
        list.push(buffer);
        if list.len() > KEPT {
            list.sort_by_key(|b| std::cmp::Reverse(b.size()));
            list.truncate(KEPT);
        }
    }
}

/// A buffer leased from the context's pool for one frame, `bytes` of it in use; it goes
/// back to the pool when dropped.
#[derive(Debug)]
pub struct Lease<'c> {
    ctx: &'c GpuContext,
    key: (&'static str, u32),
    buffer: Option<wgpu::Buffer>,
    bytes: u64,
}

impl Lease<'_> {
    /// The buffer (possibly larger than [`Lease::bytes`]).
    #[must_use]
    pub fn buffer(&self) -> &wgpu::Buffer {
        // The option is emptied only by drop.
        self.buffer.as_ref().unwrap_or_else(|| unreachable!())
    }

    /// The bytes in use.
    #[must_use]
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// The binding of the bytes in use (a shader's `arrayLength` sees them alone).
    #[must_use]
    pub fn binding(&self) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: self.buffer(),
            offset: 0,
            size: NonZeroU64::new(self.bytes),
        })
    }
}

/// A lease's buffer kept beyond its frame's work ([`Lease::detach`]): a frame's VPLs in
/// the hierarchy build's layout, kept on the GPU for the build that follows
/// ([`crate::vpls`]). Attached again ([`GpuContext::attach`]), it is a lease that returns
/// the buffer to the pool; dropped detached, the buffer is freed.
#[derive(Debug)]
pub(crate) struct Detached {
    key: (&'static str, u32),
    buffer: wgpu::Buffer,
    bytes: u64,
}

impl Lease<'_> {
    /// The buffer, no longer returned to the pool when this is dropped.
    pub(crate) fn detach(mut self) -> Detached {
        let buffer = self.buffer.take().unwrap_or_else(|| unreachable!());
        Detached {
            key: self.key,
            buffer,
            bytes: self.bytes,
        }
    }
}

impl Detached {
    /// The buffer.
    pub(crate) fn buffer(&self) -> &wgpu::Buffer {
        &self.buffer
    }

    /// The buffer, no longer a pool's.
    pub(crate) fn into_buffer(self) -> wgpu::Buffer {
        self.buffer
    }
}

impl GpuContext {
    /// `d` as a lease again.
    pub(crate) fn attach(&self, d: Detached) -> Lease<'_> {
        Lease {
            ctx: self,
            key: d.key,
            buffer: Some(d.buffer),
            bytes: d.bytes,
        }
    }
}

impl Drop for Lease<'_> {
    fn drop(&mut self) {
        if let Some(b) = self.buffer.take() {
            self.ctx.pool().give(self.key, b);
        }
    }
}

impl GpuContext {
    /// A buffer of at least `bytes` (rounded up to 16; at least 16) with `usage`, from the
    /// pool where one is free, else new (with an eighth more room, so that a frame slightly
    /// larger than the last reuses it). Its contents are whatever was there.
    ///
    /// # Errors
    /// A storage buffer larger than the adapter's `max_storage_buffer_binding_size`.
    pub fn lease(
        &self,
        label: &'static str,
        bytes: u64,
        usage: wgpu::BufferUsages,
    ) -> Result<Lease<'_>, GpuError> {
        let bytes = bytes.max(16).next_multiple_of(16);
        let max = self.limits.max_storage_buffer_binding_size;
        if usage.contains(wgpu::BufferUsages::STORAGE) && bytes > max {
            return Err(GpuError::TooLarge(format!(
                "{label}: {} MB exceed the adapter's largest storage buffer ({} MB)",
                bytes >> 20,
                max >> 20
            )));
        }
        let key = (label, usage.bits());
        let buffer = match self.pool().take(key, bytes) {
            Some(b) => b,
            None => {
                let mut size = (bytes + bytes / 8).next_multiple_of(256);
                if usage.contains(wgpu::BufferUsages::STORAGE) {
                    size = size.min(max).max(bytes);
                }
                self.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage,
                    mapped_at_creation: false,
                })
            }
        };
        Ok(Lease {
            ctx: self,
            key,
            buffer: Some(buffer),
            bytes,
        })
    }

    /// A storage buffer (leased) holding `data`, written through the queue (it arrives
    /// before the next submitted work). An empty `data` is one zero element: an empty
    /// binding is not allowed.
    ///
    /// # Errors
    /// As [`GpuContext::lease`].
    pub fn upload<T: bytemuck::Pod>(
        &self,
        label: &'static str,
        data: &[T],
    ) -> Result<Lease<'_>, GpuError> {
        self.upload_parts(label, &[bytemuck::cast_slice(data)])
    }

    /// A storage buffer (leased) holding the concatenation of `parts`, written straight
    /// from them into the queue's staging memory: a frame's tables, made of several arrays,
    /// are not first copied into one.
    ///
    /// # Errors
    /// As [`GpuContext::lease`].
    pub fn upload_parts(
        &self,
        label: &'static str,
        parts: &[&[u8]],
    ) -> Result<Lease<'_>, GpuError> {
        let mut ends = Vec::with_capacity(parts.len());
        let mut total = 0usize;
        for part in parts {
            total += part.len();
            ends.push(total);
        }
        let lease = self.lease(label, total as u64, Self::STORAGE)?;
        self.write_parallel(lease.buffer(), lease.bytes(), |at, out| {
            out.fill(0);
            // The parts that overlap bytes at..at + out.len().
            let first = ends.partition_point(|&e| e <= at);
            for (k, part) in parts.iter().enumerate().skip(first) {
                let start = ends[k] - part.len();
                if start >= at + out.len() {
                    break;
                }
                let from = at.max(start);
                let to = (at + out.len()).min(ends[k]);
                out[from - at..to - at].copy_from_slice(&part[from - start..to - start]);
            }
        });
        Ok(lease)
    }

    /// Writes the first `bytes` of `buffer` through the queue's staging memory (they arrive
    /// before the next submitted work), filled in parallel pieces: `fill(at, out)` writes
    /// bytes `at..at + out.len()` (pieces of [`WRITE_PIECE`] bytes, the last shorter). One
    /// thread's copy of a frame's tens of megabytes took milliseconds.
    pub(crate) fn write_parallel(
        &self,
        buffer: &wgpu::Buffer,
        bytes: u64,
        fill: impl Fn(usize, &mut [u8]) + Sync,
    ) {
        let Some(size) = std::num::NonZeroU64::new(bytes) else {
            return;
        };
        let Some(mut view) = self.queue.write_buffer_with(buffer, 0, size) else {
            return;
        };
        // Whole pieces as arrays (a write-only slice cannot cross threads; an array can),
        // the rest on this thread.
        let (whole, mut rest) = view.slice(..).into_chunks::<WRITE_PIECE>();
        let pieces: Vec<wgpu::WriteOnly<'_, [u8; WRITE_PIECE]>> = whole.into_iter().collect();
        let tail = pieces.len() * WRITE_PIECE;
        pieces.into_par_iter().enumerate().for_each(|(i, piece)| {
            let mut piece: wgpu::WriteOnly<'_, [u8]> = piece.into();
            let mut tmp = vec![0u8; WRITE_PIECE];
            fill(i * WRITE_PIECE, &mut tmp);
            piece.copy_from_slice(&tmp);
        });
        let mut tmp = vec![0u8; rest.len()];
        fill(tail, &mut tmp);
        rest.copy_from_slice(&tmp);
    }

    /// A storage buffer (leased) of `bytes` that a kernel writes in full.
    ///
    /// # Errors
    /// As [`GpuContext::lease`].
    pub fn output(&self, label: &'static str, bytes: u64) -> Result<Lease<'_>, GpuError> {
        self.lease(label, bytes, Self::STORAGE)
    }

    /// The usage of the storage buffers: read and written by kernels, copied to and from.
    pub(crate) const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
        .union(wgpu::BufferUsages::COPY_SRC)
        .union(wgpu::BufferUsages::COPY_DST);
}
