//! The frame's G-buffer on the GPU, shared by the frame's passes (direct light, the lighting
//! loop, the filters) and kept from frame to frame while it does not change: the viewer's
//! G-buffer stands still with its camera, and uploading its 59 MB (1280x720) took longer
//! than the passes that read it on an H200 (docs/performance.md). A G-buffer whose view is
//! known ([`GBuffer::view`]: the world's geometry and the camera it was traced for, which
//! code that changes the planes sets to `None`) is the last one if its view is; one whose
//! view is unknown is compared with a copy of the last uploaded planes, byte for byte (in
//! parallel), so a changed G-buffer is never mistaken for the last.

use std::sync::{Arc, Mutex, PoisonError};

use glam::Vec3;
use lgh_render::passes::gbuffer::GBuffer;
use lgh_scene::camera::CameraFrame;
use rayon::prelude::*;

use crate::context::{GpuContext, GpuError};

/// Bytes per pixel of the packed G-buffer (`Pixel` in the kernels' WGSL).
const PIXEL_BYTES: u64 = 64;

/// The G-buffer as the kernels read it (`Pixel` in their WGSL), one `[vec4; 4]` per pixel,
/// packed into `bytes`: position (w: 1 where the pixel sees a surface), shading
/// normal (w: 1 where the surface emits towards the camera), geometric normal, albedo (w:
/// the linear depth where the pixel sees a surface);
/// `bytes` holds pixels from `first` on.
fn pack_into(g: &GBuffer, first: usize, bytes: &mut [u8]) {
    for (k, out) in bytes.chunks_exact_mut(PIXEL_BYTES as usize).enumerate() {
        let p = first + k;
        if p >= g.len() {
            out.fill(0);
            continue;
        }
        let hit = if g.is_hit(p) { 1.0 } else { 0.0 };
        let px = [
            g.position[p].extend(hit),
            g.normal[p].extend(if g.emission[p] == Vec3::ZERO {
                0.0
            } else {
                1.0
            }),
            g.geo_normal[p].extend(0.0),
            g.albedo[p].extend(if g.is_hit(p) { g.depth[p] } else { 0.0 }),
        ];
        out.copy_from_slice(bytemuck::bytes_of(&px));
    }
}

/// A G-buffer on the GPU.
#[derive(Debug)]
pub struct GpuGBuffer {
    buffer: wgpu::Buffer,
    /// The planes it was packed from: width, height, and position, normal, geometric normal,
    /// albedo, depth and emission as bytes.
    planes: (u32, u32, [Vec<u8>; 6]),
    /// The view of the G-buffer it was packed from.
    view: Option<(u64, CameraFrame)>,
    /// Its emission where the GPU traced it ([`crate::primary`]).
    emission: GpuEmission,
}

/// The emission of a G-buffer on the GPU.
#[derive(Debug)]
pub(crate) enum GpuEmission {
    /// Not on the GPU (the G-buffer was uploaded): its planes hold it.
    OnCpu,
    /// Zero everywhere.
    Zero,
    /// One vec4 a pixel.
    Kept(wgpu::Buffer),
}

impl GpuGBuffer {
    /// Its binding (`array<Pixel>`).
    #[must_use]
    pub fn binding(&self) -> wgpu::BindingResource<'_> {
        self.buffer.as_entire_binding()
    }

    /// The buffer.
    #[must_use]
    pub fn buffer(&self) -> &wgpu::Buffer {
        &self.buffer
    }

    /// Its emission, where the GPU traced it.
    pub(crate) fn emission(&self) -> &GpuEmission {
        &self.emission
    }

    /// True if it was packed from exactly the planes of `g`: the same known view, or the
    /// same bytes.
    fn holds(&self, g: &GBuffer) -> bool {
        let (w, h, planes) = &self.planes;
        if g.view.is_some() && g.view == self.view && (*w, *h) == (g.width, g.height) {
            return true;
        }
        *w == g.width
            && *h == g.height
            && plane_bytes(g)
                .iter()
                .zip(planes)
                .all(|(a, b)| a.len() == b.len() && same(a, b))
    }
}

/// The bytes of the planes the packed G-buffer depends on.
fn plane_bytes(g: &GBuffer) -> [&[u8]; 6] {
    [
        bytemuck::cast_slice::<Vec3, u8>(&g.position),
        bytemuck::cast_slice::<Vec3, u8>(&g.normal),
        bytemuck::cast_slice::<Vec3, u8>(&g.geo_normal),
        bytemuck::cast_slice::<Vec3, u8>(&g.albedo),
        bytemuck::cast_slice::<f32, u8>(&g.depth),
        bytemuck::cast_slice::<Vec3, u8>(&g.emission),
    ]
}

/// `a == b`, compared in parallel.
fn same(a: &[u8], b: &[u8]) -> bool {
    a.par_chunks(1 << 16)
        .zip(b.par_chunks(1 << 16))
        .all(|(x, y)| x == y)
}

/// The context's last uploaded G-buffer.
#[derive(Debug, Default)]
pub(crate) struct GBufferCache {
    last: Mutex<Option<Arc<GpuGBuffer>>>,
}

impl GpuContext {
    /// `g` on the GPU: where this context kept its planes there ([`GBuffer::defer_planes`]),
    /// that G-buffer; the last uploaded G-buffer if `g` has the same planes; else `g`
    /// packed (in parallel, straight into the upload's staging memory) and uploaded.
    ///
    /// # Errors
    /// Larger than the adapter's largest storage buffer, or deferred planes of another
    /// context could not be read back.
    pub fn gbuffer(&self, g: &GBuffer) -> Result<Arc<GpuGBuffer>, GpuError> {
        // Planes this context kept on the GPU: there. (Another context's: read back.)
        let kept = g
            .device_planes()
            .and_then(|r| r.as_any().downcast_ref::<OnDevice>());
        if let Some(on) = kept.filter(|on| std::ptr::eq(on.ctx, self)) {
            return Ok(Arc::clone(&on.gbuffer));
        }
        let g = g
            .planes()
            .map_err(|e| GpuError::Failed(format!("the G-buffer's planes: {e}")))?;
        let cache = &self.gbuffers().last;
        if let Some(last) = cache
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .as_ref()
            .filter(|last| last.holds(g))
        {
            return Ok(Arc::clone(last));
        }
        let (buffer, bytes) = self.gbuffer_buffer(g.len())?;
        self.write_parallel(&buffer, bytes, |at, out| {
            pack_into(g, at / PIXEL_BYTES as usize, out);
        });
        let (w, h) = (g.width, g.height);
        let planes = plane_bytes(g).map(<[u8]>::to_vec);
        let up = Arc::new(GpuGBuffer {
            buffer,
            planes: (w, h, planes),
            view: g.view,
            emission: GpuEmission::OnCpu,
        });
        *cache.lock().unwrap_or_else(PoisonError::into_inner) = Some(Arc::clone(&up));
        Ok(up)
    }

    /// A new buffer for a packed G-buffer of `pixels` pixels, and its size in bytes.
    ///
    /// # Errors
    /// Larger than the adapter's largest storage buffer.
    pub(crate) fn gbuffer_buffer(&self, pixels: usize) -> Result<(wgpu::Buffer, u64), GpuError> {
        let bytes = (pixels as u64 * PIXEL_BYTES).max(PIXEL_BYTES);
        if bytes > self.limits.max_storage_buffer_binding_size {
            return Err(GpuError::TooLarge(format!(
                "the G-buffer: {} MB exceed the adapter's largest storage buffer ({} MB)",
                bytes >> 20,
                self.limits.max_storage_buffer_binding_size >> 20
            )));
        }
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("g-buffer"),
            size: bytes,
            usage: Self::STORAGE,
            mapped_at_creation: false,
        });
        Ok((buffer, bytes))
    }

    /// Makes `buffer`, packed on the GPU for the G-buffer `g` (whose view is known:
    /// [`crate::primary`]), with its `emission`, the last uploaded G-buffer, so that the
    /// frame's passes read it where it is. No copy of its planes is kept: a G-buffer whose
    /// view is unknown is never taken for it.
    pub(crate) fn adopt_gbuffer(
        &self,
        buffer: wgpu::Buffer,
        (width, height): (u32, u32),
        view: (u64, CameraFrame),
        emission: GpuEmission,
    ) -> Arc<GpuGBuffer> {
        let up = Arc::new(GpuGBuffer {
            buffer,
            planes: (width, height, Default::default()),
            view: Some(view),
            emission,
        });
        *self
            .gbuffers()
            .last
            .lock()
            .unwrap_or_else(PoisonError::into_inner) = Some(Arc::clone(&up));
        up
    }
}

/// The planes of a G-buffer traced on the GPU and left there
/// ([`GBuffer::defer_planes`]): read back from its packed pixels and emission when the
/// CPU asks for them.
pub(crate) struct OnDevice {
    pub ctx: &'static GpuContext,
    pub gbuffer: Arc<GpuGBuffer>,
}

impl lgh_render::passes::gbuffer::DevicePlanes for OnDevice {
    fn read_into(&self, g: &mut GBuffer) -> Result<(), String> {
        let n = g.width as usize * g.height as usize;
        let mut batch = crate::batch::Batch::new(self.ctx);
        let read = |e: GpuError| e.to_string();
        batch
            .read(&self.gbuffer.buffer, n as u64 * PIXEL_BYTES)
            .map_err(read)?;
        if let GpuEmission::Kept(emission) = &self.gbuffer.emission {
            batch.read(emission, n as u64 * 16).map_err(read)?;
        }
        let (reads, _) = batch.finish().map_err(read)?;
        let pixels: &[[glam::Vec4; 4]] = reads.first().map_or(&[], |r| bytemuck::cast_slice(r));
        let emitted: Option<&[glam::Vec4]> = reads.get(1).map(|r| bytemuck::cast_slice(r));
        if pixels.len() < n || emitted.is_some_and(|e| e.len() < n) {
            return Err("the G-buffer's read-back is missing".into());
        }
        unpack(g, &pixels[..n], emitted.map(|e| &e[..n]));
        Ok(())
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

/// The planes of `g` from the packed pixels `packed` (as [`pack_into`] packs them) and the
/// emitted radiance `emission` (`None`: zero), one `Vec4` each per pixel, reusing the
/// planes' memory; `g`'s width, height and view are set by the caller.
pub(crate) fn unpack(g: &mut GBuffer, packed: &[[glam::Vec4; 4]], emission: Option<&[glam::Vec4]>) {
    fn fill<T: Send + Copy + Default>(
        plane: &mut Vec<T>,
        packed: &[[glam::Vec4; 4]],
        f: impl Fn(&[glam::Vec4; 4]) -> T + Sync,
    ) {
        plane.resize(packed.len(), T::default());
        plane
            .par_iter_mut()
            .zip(packed)
            .for_each(|(out, p)| *out = f(p));
    }
    fill(&mut g.position, packed, |p| p[0].truncate());
    fill(&mut g.normal, packed, |p| p[1].truncate());
    fill(&mut g.geo_normal, packed, |p| p[2].truncate());
    fill(&mut g.albedo, packed, |p| p[3].truncate());
    fill(&mut g.depth, packed, |p| {
        if p[0].w > 0.0 { p[3].w } else { f32::INFINITY }
    });
    g.emission.clear();
    match emission {
        Some(e) => g.emission.par_extend(e.par_iter().map(|e| e.truncate())),
        None => g.emission.resize(packed.len(), Vec3::ZERO),
    }
}
