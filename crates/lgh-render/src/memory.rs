//! Working memory that frames reuse.

use lgh_core::lighting_grid::GridBuilder;

use crate::denoise::atrous::AtrousBuffers;
use crate::passes::gbuffer::GBuffer;

/// Working memory that frames reuse: the hierarchy builder's, the shadow filters' (about
/// 90 MB each at 1280x720), and the G-buffer of a frame handed back with
/// [`FrameMemory::recycle_gbuffer`]. A renderer of frame after frame keeps one
/// ([`crate::frame::render_frame_with`]), so that no frame pays for paging in fresh memory.
/// A clone is empty: it is only a cache.
#[derive(Debug, Default)]
pub struct FrameMemory {
    /// The lighting grid hierarchy builder.
    pub grid: GridBuilder,
    /// The a-trous planes of the indirect light's shadow filter.
    pub filter: AtrousBuffers,
    /// The a-trous planes of the direct light's filter: its own, because its one pass lays
    /// the planes out with a narrower padding than the indirect filter's passes, and planes
    /// shared between the two would be laid out afresh (reallocated and paged in) twice a
    /// frame.
    pub direct_filter: AtrousBuffers,
    /// Planes for the next frame's G-buffer (1280x720: 57 MB).
    pub gbuffer: Option<GBuffer>,
}

impl FrameMemory {
    /// Takes back the G-buffer of a frame that is no longer needed, so that the next frame
    /// renders into the same planes, or, if it has the same camera and geometry, reuses them
    /// as they are ([`GBuffer::shows`]; a caller that changed the planes sets
    /// [`GBuffer::view`] to `None`).
    pub fn recycle_gbuffer(&mut self, g: GBuffer) {
        self.gbuffer = Some(g);
    }
}

impl Clone for FrameMemory {
    fn clone(&self) -> Self {
        Self::default()
    }
}
