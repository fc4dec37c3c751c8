//! A frame's GPU work as one submission: its compute passes in order, each timed by the GPU's
//! timestamps where the adapter has them, and the copies of its results back to the CPU,
//! with one wait at the end. A wait per pass (and a read-back buffer allocated per copy) had
//! made the four a-trous passes cost more on an H200 than on 16 CPU cores.

use rayon::prelude::*;

use crate::context::{GpuContext, GpuError};
use crate::pool::Lease;

thread_local! {
    /// Bytes this thread's batches have copied back to the CPU ([`read_back_bytes`]).
    static READ_BACK: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
    /// Batches this thread has submitted and waited for ([`waits`]).
    static WAITS: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// The bytes that batches recorded on this thread have copied back from the GPU so far
/// ([`Batch::read`]); a frame's are the difference before and after it. The viewer's
/// shown frames of a moving camera read back their packed pixels (4 bytes a pixel), not
/// the G-buffer's planes (80).
#[must_use]
pub fn read_back_bytes() -> u64 {
    READ_BACK.with(std::cell::Cell::get)
}

/// The batches recorded on this thread that were submitted and waited for so far
/// ([`Batch::finish`]): each is a round trip in which the GPU drains its queue while the
/// CPU reads back and records the next work. A frame's are the difference before and
/// after it.
#[must_use]
pub fn waits() -> u64 {
    WAITS.with(std::cell::Cell::get)
}

/// Adds pass times to `times`, summed by name in the order first seen.
pub(crate) fn add_passes(
    times: &mut PassTimes,
    more: impl IntoIterator<Item = (&'static str, f64)>,
) {
    for (name, ms) in more {
        match times.iter_mut().find(|(n, _)| *n == name) {
            Some((_, sum)) => *sum += ms,
            None => times.push((name, ms)),
        }
    }
}

/// Timed passes one batch holds at most (further passes run untimed).
const MAX_TIMED: u32 = 128;

/// The times of a batch's passes, in milliseconds, summed by name in the order first seen.
pub type PassTimes = Vec<(&'static str, f64)>;

/// Compute passes and read-backs recorded for one submission.
pub struct Batch<'c> {
    ctx: &'c GpuContext,
    enc: wgpu::CommandEncoder,
    /// The timestamp queries and the names of the passes they time.
    queries: Option<wgpu::QuerySet>,
    names: Vec<&'static str>,
    /// The read-backs: (staging buffer, bytes).
    reads: Vec<Lease<'c>>,
    /// Leased buffers the recorded work uses, kept out of the pool until the work is done
    /// ([`Batch::keep`]).
    kept: Vec<Lease<'c>>,
    /// The dispatches' uniforms ([`Batch::uniform`]): leased buffers, each with the bytes
    /// written into it when the batch is submitted.
    uniforms: Vec<(Lease<'c>, Vec<u8>)>,
}

/// Bytes of one buffer of a batch's uniforms (256 uniforms at the usual 256-byte offset
/// alignment).
const UNIFORM_CHUNK: u64 = 64 << 10;

/// A uniform value in a batch's uniform buffer ([`Batch::uniform`]).
#[derive(Clone, Debug)]
pub struct Uniform {
    buffer: wgpu::Buffer,
    offset: u64,
    size: std::num::NonZeroU64,
}

impl Uniform {
    /// Its binding (named as `wgpu::Buffer`'s, for which it stands).
    #[must_use]
    pub fn as_entire_binding(&self) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.buffer,
            offset: self.offset,
            size: Some(self.size),
        })
    }
}

impl<'c> Batch<'c> {
    /// An empty batch on `ctx`.
    #[must_use]
    pub fn new(ctx: &'c GpuContext) -> Self {
        let timed = ctx
            .device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY);
        let queries = timed.then(|| {
            ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass times"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * MAX_TIMED,
            })
        });
        Self {
            ctx,
            enc: ctx.device.create_command_encoder(&Default::default()),
            queries,
            names: Vec::new(),
            reads: Vec::new(),
            kept: Vec::new(),
            uniforms: Vec::new(),
        }
    }

    /// `value` as a uniform of this batch's dispatches, valid for this batch's work alone
    /// (its buffer goes back to the pool with the batch: another batch makes its own). A
    /// buffer created per uniform (a
    /// frame makes about 220 with six hierarchies) cost 1 ms of the CPU's time a frame on
    /// the 2-core VM; here the uniforms share leased buffers at the adapter's offset
    /// alignment, and their bytes go up in one write per buffer when the batch is
    /// submitted (the queue applies it before the batch's work).
    ///
    /// # Errors
    /// A buffer could not be leased.
    pub fn uniform<T: bytemuck::Pod>(&mut self, value: &T) -> Result<Uniform, GpuError> {
        let bytes = bytemuck::bytes_of(value);
        let align = u64::from(self.ctx.limits.min_uniform_buffer_offset_alignment).max(16);
        let size = (bytes.len() as u64).max(16).next_multiple_of(16);
        let fits =
            |used: &Vec<u8>| (used.len() as u64).next_multiple_of(align) + size <= UNIFORM_CHUNK;
        if !self.uniforms.last().is_some_and(|(_, used)| fits(used)) {
            let lease = self.ctx.lease(
                "uniforms",
                UNIFORM_CHUNK.max(size),
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            )?;
            self.uniforms.push((lease, Vec::new()));
        }
        let Some((lease, used)) = self.uniforms.last_mut() else {
            return Err(GpuError::Failed("no uniform buffer".into()));
        };
        let offset = (used.len() as u64).next_multiple_of(align);
        used.resize(offset as usize, 0);
        used.extend_from_slice(bytes);
        used.resize((offset + size) as usize, 0);
        Ok(Uniform {
            buffer: lease.buffer().clone(),
            offset,
            size: std::num::NonZeroU64::new(size).unwrap_or(std::num::NonZeroU64::MIN),
        })
    }

    /// Writes the uniforms' bytes into their buffers (applied by the queue before the next
    /// submission's work, this batch's or an earlier one's, which does not read them).
    fn write_uniforms(&self) {
        for (lease, bytes) in &self.uniforms {
            if !bytes.is_empty() {
                self.ctx.queue.write_buffer(lease.buffer(), 0, bytes);
            }
        }
    }

    /// Records a pass of `pipeline` over `invocations` threads (workgroups of 64), timed
    /// under `name`.
    ///
    /// # Errors
    /// More workgroups than one dispatch allows.
    pub fn dispatch(
        &mut self,
        name: &'static str,
        pipeline: &wgpu::ComputePipeline,
        bind: &wgpu::BindGroup,
        invocations: usize,
    ) -> Result<(), GpuError> {
        let groups = u32::try_from(invocations.div_ceil(64))
            .ok()
            .filter(|&x| x <= self.ctx.limits.max_compute_workgroups_per_dimension)
            .ok_or_else(|| {
                GpuError::TooLarge(format!("{invocations} invocations exceed one dispatch"))
            })?;
        self.dispatch_groups(name, pipeline, bind, groups);
        Ok(())
    }

    /// Records a pass of `pipeline` over `groups` workgroups (of the kernel's own size),
    /// timed under `name`.
    pub fn dispatch_groups(
        &mut self,
        name: &'static str,
        pipeline: &wgpu::ComputePipeline,
        bind: &wgpu::BindGroup,
        groups: u32,
    ) {
        let slot = self.names.len() as u32;
        let timestamp_writes =
            self.queries
                .as_ref()
                .filter(|_| slot < MAX_TIMED)
                .map(|query_set| wgpu::ComputePassTimestampWrites {
                    query_set,
                    beginning_of_pass_write_index: Some(2 * slot),
                    end_of_pass_write_index: Some(2 * slot + 1),
                });
        if timestamp_writes.is_some() {
            self.names.push(name);
        }
        let mut pass = self.enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(name),
            timestamp_writes,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, bind, &[]);
        pass.dispatch_workgroups(groups, 1, 1);
    }

    /// Keeps `lease` (a buffer the recorded work reads or writes) until the batch is done. A
    /// lease dropped before then goes back to the pool, where another frame (another
    /// thread's) could lease it and write into it before this batch's work runs: every
    /// lease the batch uses must outlive it, held by the caller or kept here.
    pub fn keep(&mut self, lease: Lease<'c>) {
        self.kept.push(lease);
    }

    /// Records the copy of `bytes` of `from` (from byte `from_at`) into `to` (at byte
    /// `to_at`); offsets and size are multiples of 4.
    pub fn copy(&mut self, from: &Lease<'_>, from_at: u64, to: &Lease<'_>, to_at: u64, bytes: u64) {
        self.copy_buffer(from.buffer(), from_at, to, to_at, bytes);
    }

    /// [`Batch::copy`] from a buffer that is not leased (kept beyond its frame).
    pub(crate) fn copy_buffer(
        &mut self,
        from: &wgpu::Buffer,
        from_at: u64,
        to: &Lease<'_>,
        to_at: u64,
        bytes: u64,
    ) {
        self.enc
            .copy_buffer_to_buffer(from, from_at, to.buffer(), to_at, bytes);
    }

    /// Records the zeroing of `buffer`.
    pub fn clear(&mut self, buffer: &wgpu::Buffer) {
        self.enc.clear_buffer(buffer, 0, None);
    }

    /// Records the zeroing of the bytes of `lease` in use.
    pub fn clear_lease(&mut self, lease: &Lease<'_>) {
        self.enc
            .clear_buffer(lease.buffer(), 0, Some(lease.bytes()));
    }

    /// Records the copy of the first `bytes` of `from` back to the CPU; [`Batch::finish`]
    /// returns it (in the order of these calls).
    ///
    /// # Errors
    /// The read-back buffer could not be leased.
    pub fn read(&mut self, from: &wgpu::Buffer, bytes: u64) -> Result<(), GpuError> {
        let staging = self.ctx.lease(
            "read back",
            bytes,
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        )?;
        self.enc
            .copy_buffer_to_buffer(from, 0, staging.buffer(), 0, bytes.next_multiple_of(4));
        self.reads.push(staging);
        READ_BACK.with(|r| r.set(r.get() + bytes));
        Ok(())
    }

    /// The number of read-backs recorded so far (the index the next one will have in
    /// [`Batch::finish`]'s output).
    pub(crate) fn reads(&self) -> usize {
        self.reads.len()
    }

    /// Submits the batch without waiting for it, for work that only later submissions read
    /// (the queue runs them in order): a batch without [`Batch::read`]s; its passes' times
    /// are not kept.
    pub fn submit(self) {
        self.write_uniforms();
        self.ctx.queue.submit([self.enc.finish()]);
    }

    /// Submits the batch and waits for it: the bytes of each [`Batch::read`] and the passes'
    /// GPU times (empty without timestamp queries).
    ///
    /// # Errors
    /// The GPU failed.
    pub fn finish(mut self) -> Result<(Vec<Vec<Words>>, PassTimes), GpuError> {
        let ctx = self.ctx;
        let timed = self.names.len() as u32;
        let mut stamps = None;
        if let Some(q) = self.queries.as_ref().filter(|_| timed > 0) {
            let bytes = 16 * u64::from(timed);
            let resolved = ctx.lease(
                "pass times",
                bytes,
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            )?;
            self.enc
                .resolve_query_set(q, 0..2 * timed, resolved.buffer(), 0);
            let staging = ctx.lease(
                "pass times read back",
                bytes,
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            )?;
            self.enc
                .copy_buffer_to_buffer(resolved.buffer(), 0, staging.buffer(), 0, bytes);
            stamps = Some((resolved, staging, bytes));
        }
        self.write_uniforms();
        ctx.queue.submit([self.enc.finish()]);
        WAITS.with(|w| w.set(w.get() + 1));
        let mut maps: Vec<(&wgpu::Buffer, u64)> =
            self.reads.iter().map(|l| (l.buffer(), l.bytes())).collect();
        if let Some((_, staging, bytes)) = &stamps {
            maps.push((staging.buffer(), *bytes));
        }
        let mut out = map_all(ctx, &maps)?;
        let mut times: PassTimes = Vec::new();
        if stamps.is_some() {
            let raw = out.pop().unwrap_or_default();
            let ticks: &[u64] = bytemuck::cast_slice(&raw);
            let period = f64::from(ctx.queue.get_timestamp_period());
            add_passes(
                &mut times,
                self.names
                    .iter()
                    .zip(ticks.chunks_exact(2))
                    .map(|(&name, t)| (name, t[1].saturating_sub(t[0]) as f64 * period * 1e-6)),
            );
        }
        Ok((out, times))
    }
}

/// Sixteen bytes of a read-back, aligned for any of the kernels' element types (cast a
/// read-back with `bytemuck::cast_slice` to `Vec4`, `u32` or `u64`).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Words([u32; 4]);

/// Maps each (buffer, bytes) for reading after the submitted work, waits, and copies the
/// bytes out (in parallel: a frame's read-back is tens of megabytes).
fn map_all(
    ctx: &GpuContext,
    buffers: &[(&wgpu::Buffer, u64)],
) -> Result<Vec<Vec<Words>>, GpuError> {
    let (tx, rx) = std::sync::mpsc::channel();
    for (i, (b, bytes)) in buffers.iter().enumerate() {
        let tx = tx.clone();
        b.slice(..*bytes).map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send((i, r));
        });
    }
    drop(tx);
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| GpuError::Failed(e.to_string()))?;
    for (_, r) in rx.iter() {
        r.map_err(|e| GpuError::Failed(e.to_string()))?;
    }
    let mut out = Vec::with_capacity(buffers.len());
    for (b, bytes) in buffers {
        let slice = b.slice(..*bytes);
        let view = slice
            .get_mapped_range()
            .map_err(|e| GpuError::Failed(e.to_string()))?;
        let mut words = vec![Words::default(); (*bytes as usize).div_ceil(16)];
        let dst: &mut [u8] = bytemuck::cast_slice_mut(&mut words);
        dst.par_chunks_mut(1 << 20)
            .zip(view.par_chunks(1 << 20))
            .for_each(|(d, s)| d[..s.len()].copy_from_slice(s));
        out.push(words);
        drop(view);
        b.unmap();
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::{Batch, UNIFORM_CHUNK};
    use crate::GpuContext;

    /// Every dispatch of a batch reads its own uniform, past the first buffers of uniforms
    /// (their offsets at the adapter's alignment, a new buffer when one is full), and a
    /// second batch reusing the pooled buffers reads its own values, not the first's.
    #[test]
    #[cfg_attr(
        not(gpu_adapter),
        ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
    )]
    fn each_dispatch_reads_its_own_uniform() {
        let ctx = GpuContext::shared().expect("an adapter");
        let source = "struct P { v: vec4<u32> }\n\
            @group(0) @binding(0) var<uniform> p: P;\n\
            @group(0) @binding(1) var<storage, read_write> out: array<vec4<u32>>;\n\
            @compute @workgroup_size(1)\n\
            fn main() { out[p.v.x] = p.v; }\n";
        let kernel = ctx.pipeline("test uniforms", || crate::kernel(&[source]));
        let align = u64::from(ctx.limits.min_uniform_buffer_offset_alignment).max(16);
        let n = (2 * UNIFORM_CHUNK / align + 9) as u32;
        for salt in [7u32, 11] {
            let out = ctx
                .output("test uniforms out", 16 * u64::from(n))
                .expect("lease");
            let mut batch = Batch::new(ctx);
            for i in 0..n {
                let u = batch
                    .uniform(&[i, i * salt, i ^ 0x55, salt])
                    .expect("uniform");
                let bind = ctx.bind_group(&kernel, vec![u.as_entire_binding(), out.binding()]);
                batch.dispatch_groups("test", &kernel, &bind, 1);
            }
            assert!(
                batch.uniforms.len() >= 3,
                "{} buffers",
                batch.uniforms.len()
            );
            batch.read(out.buffer(), 16 * u64::from(n)).expect("read");
            let (reads, _) = batch.finish().expect("ran");
            let got: &[[u32; 4]] = bytemuck::cast_slice(&reads[0]);
            for (i, v) in got.iter().enumerate().take(n as usize) {
                let i = i as u32;
                assert_eq!(*v, [i, i * salt, i ^ 0x55, salt], "dispatch {i}");
            }
        }
    }
}
