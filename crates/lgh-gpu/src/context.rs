//! The adapter, device and queue the GPU passes run on.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock, PoisonError};

use crate::gbuffer::GBufferCache;
use crate::pool::BufferPool;
use crate::scene::GpuScene;

/// Why the GPU backend cannot run.
#[derive(Clone, Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter: no Vulkan, Metal or DX12 driver (on Linux without a GPU, Mesa's lavapipe
    /// provides one: Debian's `mesa-vulkan-drivers`).
    #[error(
        "no GPU adapter found: --device gpu needs a Vulkan, Metal or DX12 driver (without a GPU, Mesa's lavapipe: apt-get install mesa-vulkan-drivers)"
    )]
    NoAdapter,
    /// The adapter refused a device.
    #[error("the GPU adapter {adapter} refused a device: {why}")]
    Device {
        /// The adapter's name.
        adapter: String,
        /// wgpu's message.
        why: String,
    },
    /// The scene or the frame does not fit the adapter's limits.
    #[error("{0}")]
    TooLarge(String),
    /// The GPU failed during the work (device lost, out of memory, a validation error).
    #[error("the GPU failed: {0}")]
    Failed(String),
    /// This method has no GPU version yet.
    #[error(
        "--method {0} does not run on the GPU yet (--device gpu runs: lgh, lgh-unshadowed, brute, brute-unshadowed)"
    )]
    NotPorted(String),
}

/// A wgpu device and queue with what was learnt of the adapter.
#[derive(Debug)]
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter: name, backend, driver.
    pub info: wgpu::AdapterInfo,
    /// The limits the device was created with (the adapter's own).
    pub limits: wgpu::Limits,
    /// The scene last uploaded, by [`lgh_render::World::geometry_id`]: frames of one
    /// scene (the viewer's, a benchmark's) upload it once.
    scene: Mutex<Option<(u64, Arc<GpuScene>)>>,
    /// The compute pipelines compiled so far, by kernel name.
    pipelines: Mutex<HashMap<&'static str, Arc<wgpu::ComputePipeline>>>,
    /// Buffers kept between frames ([`GpuContext::lease`]).
    pool: BufferPool,
    /// The last uploaded G-buffer ([`GpuContext::gbuffer`]).
    gbuffers: GBufferCache,
    /// What hierarchy builders keep between frames ([`crate::grid::GpuGridBuilder`]).
    grids: crate::grid::GridStates,
    /// The frame's VPLs kept for its hierarchy build ([`crate::vpls`]).
    resident_vpls: crate::vpls::resident::Slots,
    /// The yields that plan the batches of VPL generation ([`crate::vpls`]).
    vpl_yields: crate::vpls::plan::Yields,
    /// The running means and emission of shown frames ([`crate::display`]).
    display: crate::display::DisplayStates,
}

impl GpuContext {
    /// Opens the adapter wgpu prefers (a discrete GPU before an integrated one before a CPU
    /// implementation such as lavapipe), with its full limits. `WGPU_BACKEND` (e.g. `vulkan`)
    /// and `WGPU_ADAPTER_NAME` (a substring, e.g. `llvmpipe`) narrow the choice.
    ///
    /// # Errors
    /// No adapter, or it refuses a device.
    pub fn new() -> Result<Self, GpuError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(wgpu::util::initialize_adapter_from_env_or_default(
            &instance, None,
        ))
        .map_err(|_| GpuError::NoAdapter)?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        // Timestamps where the adapter has them: the passes' times in the statistics.
        let features = adapter.features() & wgpu::Features::TIMESTAMP_QUERY;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("lgh"),
            required_features: features,
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device {
            adapter: info.name.clone(),
            why: e.to_string(),
        })?;
        Ok(Self {
            device,
            queue,
            info,
            limits,
            scene: Mutex::default(),
            pipelines: Mutex::default(),
            pool: BufferPool::default(),
            gbuffers: GBufferCache::default(),
            grids: crate::grid::GridStates::default(),
            resident_vpls: crate::vpls::resident::Slots::default(),
            vpl_yields: crate::vpls::plan::Yields::default(),
            display: crate::display::DisplayStates::default(),
        })
    }

    /// The process's context, opened on first use (an adapter is costly to open, and one is
    /// enough for every frame).
    ///
    /// # Errors
    /// As [`GpuContext::new`], every time, if the first opening failed.
    pub fn shared() -> Result<&'static Self, GpuError> {
        static SHARED: OnceLock<Result<GpuContext, GpuError>> = OnceLock::new();
        SHARED.get_or_init(Self::new).as_ref().map_err(Clone::clone)
    }

    /// A one-line description of the adapter, e.g. "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)".
    #[must_use]
    pub fn adapter_name(&self) -> String {
        format!("{} ({:?})", self.info.name, self.info.backend)
    }

    /// A storage buffer of `data`, refused if larger than the adapter allows.
    ///
    /// # Errors
    /// Larger than `max_storage_buffer_binding_size`.
    pub fn storage<T: bytemuck::Pod>(
        &self,
        label: &str,
        data: &[T],
    ) -> Result<wgpu::Buffer, GpuError> {
        use wgpu::util::DeviceExt;
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let max = self.limits.max_storage_buffer_binding_size;
        if bytes.len() as u64 > max {
            return Err(GpuError::TooLarge(format!(
                "{label}: {} MB exceed the adapter's largest storage buffer ({} MB)",
                bytes.len() >> 20,
                max >> 20
            )));
        }
        // An empty binding is not allowed: one zero element stands for none.
        let zero = [0u8; 16];
        let contents = if bytes.is_empty() { &zero[..] } else { bytes };
        Ok(self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
            }))
    }

    /// The scene of `world` on the GPU: uploaded on first use and while the world's
    /// geometry is the one last uploaded, reused.
    ///
    /// # Errors
    /// The scene does not fit the adapter's limits.
    pub fn scene(&self, world: &lgh_render::World) -> Result<Arc<GpuScene>, GpuError> {
        let id = world.geometry_id();
        let mut slot = self.scene.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some((at, scene)) = slot.as_ref()
            && *at == id
        {
            return Ok(Arc::clone(scene));
        }
        let scene = Arc::new(GpuScene::new(
            self,
            &world.scene.mesh,
            world.cutouts.as_deref(),
        )?);
        *slot = Some((id, Arc::clone(&scene)));
        Ok(scene)
    }

    /// The compute pipeline of kernel `name` (entry point `main` of the WGSL `source()`),
    /// compiled on first use.
    pub fn pipeline(
        &self,
        name: &'static str,
        source: impl FnOnce() -> String,
    ) -> Arc<wgpu::ComputePipeline> {
        let mut map = self
            .pipelines
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        let pipeline = map.entry(name).or_insert_with(|| {
            let module = self
                .device
                .create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some(name),
                    source: wgpu::ShaderSource::Wgsl(source().into()),
                });
            Arc::new(
                self.device
                    .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(name),
                        layout: None,
                        module: &module,
                        entry_point: Some("main"),
                        compilation_options: Default::default(),
                        cache: None,
                    }),
            )
        });
        Arc::clone(pipeline)
    }

    /// A uniform buffer of its own holding `value`, for a uniform rewritten between
    /// submissions (the brute force's, per chunk of VPLs); a dispatch's uniform is
    /// [`crate::Batch::uniform`].
    #[must_use]
    pub fn uniform<T: bytemuck::Pod>(&self, label: &str, value: &T) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::bytes_of(value),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            })
    }

    /// The bind group of `pipeline`'s group 0 with `resources` at bindings 0, 1, ...
    /// (a whole buffer: `buffer.as_entire_binding()`; a leased one: `lease.binding()`).
    #[must_use]
    pub fn bind_group(
        &self,
        pipeline: &wgpu::ComputePipeline,
        resources: Vec<wgpu::BindingResource<'_>>,
    ) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry<'_>> = resources
            .into_iter()
            .enumerate()
            .map(|(i, resource)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource,
            })
            .collect();
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        })
    }

    /// The cache of the last uploaded G-buffer.
    pub(crate) fn gbuffers(&self) -> &GBufferCache {
        &self.gbuffers
    }

    /// The states of the hierarchy builders not in use.
    pub(crate) fn grid_states(&self) -> &crate::grid::GridStates {
        &self.grids
    }

    /// The frame's VPLs kept for its hierarchy build.
    pub(crate) fn resident_vpls(&self) -> &crate::vpls::resident::Slots {
        &self.resident_vpls
    }

    /// The yields of the last VPL generations.
    pub(crate) fn vpl_yields(&self) -> &crate::vpls::plan::Yields {
        &self.vpl_yields
    }

    /// What shown frames keep between frames.
    pub(crate) fn display_states(&self) -> &crate::display::DisplayStates {
        &self.display
    }

    /// The pool of buffers kept between frames.
    pub(crate) fn pool(&self) -> &BufferPool {
        &self.pool
    }
}
