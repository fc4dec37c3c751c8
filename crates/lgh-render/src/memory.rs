//! Working memory that frames reuse.

use lgh_core::lighting_grid::GridBuilder;
use lgh_scene::camera::CameraFrame;

use crate::denoise::atrous::AtrousBuffers;
use crate::passes::edge_aa::EdgeResolve;
use crate::passes::gbuffer::GBuffer;
use crate::shading::tiles::AllBounds;

/// Working memory that frames reuse: the hierarchy builder's, the shadow filters' (about
/// 90 MB each at 1280x720), and the G-buffer of a frame handed back with
/// [`FrameMemory::recycle_gbuffer`], with what that G-buffer alone decides ([`ViewCache`]).
/// A renderer of frame after frame keeps one ([`crate::frame::render_frame_with`]), so that
/// no frame pays for paging in fresh memory or derives again what its still view kept.
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
    /// The tile bounds of the light binning, while the G-buffer shows the same view.
    pub tile_bounds: ViewCache<AllBounds>,
    /// The interleave blur's discontinuities, while the G-buffer shows the same view.
    pub discontinuities: ViewCache<Vec<u8>>,
    /// The sub-images each pixel's recombination window misses
    /// ([`crate::shading::interleave::missed_sub_images`]; `None`: none misses any).
    pub missed_sub_images: ViewCache<Option<Vec<u64>>>,
    /// The edge resolve's sub-pixel samples (its primary rays), while the G-buffer shows
    /// the same view: a viewer whose camera stands still traces them once.
    pub edge_resolve: ViewCache<EdgeResolve>,
}

/// A value derived from the G-buffer alone (the binning's tile bounds, the blur's
/// discontinuities), kept while the G-buffer shows the same view ([`GBuffer::view`]: a
/// viewer whose camera stands still while the light moves) and is asked for with the same
/// parameters. A G-buffer whose view is unknown (`None`) always derives afresh.
#[derive(Debug)]
pub struct ViewCache<T> {
    key: Option<(u64, CameraFrame, [u32; 4])>,
    value: Option<T>,
}

impl<T> Default for ViewCache<T> {
    fn default() -> Self {
        Self {
            key: None,
            value: None,
        }
    }
}

impl<T> ViewCache<T> {
    /// The value for `g` with `params` (any numbers that change the value, as bits): the
    /// kept one if `g` shows the view it was made for with the same `params`, else `make()`.
    pub fn get_or_insert_with(
        &mut self,
        g: &GBuffer,
        params: [u32; 4],
        make: impl FnOnce() -> T,
    ) -> &T {
        let key = g.view.map(|(id, frame)| (id, frame, params));
        if key.is_none() || key != self.key {
            self.value = None;
            self.key = key;
        }
        self.value.get_or_insert_with(make)
    }

    /// True if the kept value is the one for `g` with `params`
    /// ([`ViewCache::get_or_insert_with`] would return it without making one).
    #[must_use]
    pub fn holds(&self, g: &GBuffer, params: [u32; 4]) -> bool {
        let key = g.view.map(|(id, frame)| (id, frame, params));
        key.is_some() && key == self.key && self.value.is_some()
    }

    /// The kept value, if it is the one for `g` with `params`.
    #[must_use]
    pub fn kept(&self, g: &GBuffer, params: [u32; 4]) -> Option<&T> {
        if self.holds(g, params) {
            self.value.as_ref()
        } else {
            None
        }
    }

    /// Keeps `value` as the one for `g` with `params`.
    pub fn insert(&mut self, g: &GBuffer, params: [u32; 4], value: T) {
        self.key = g.view.map(|(id, frame)| (id, frame, params));
        self.value = Some(value);
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use lgh_scene::Camera;

    fn view(x: f32) -> GBuffer {
        let camera = Camera {
            position: glam::Vec3::new(x, 0.0, 5.0),
            look_at: glam::Vec3::ZERO,
            up: glam::Vec3::Y,
            fov_y_degrees: 40.0,
        };
        GBuffer {
            view: Some((7, camera.frame(4, 4))),
            ..GBuffer::default()
        }
    }

    /// The value is kept for the same view and parameters, and derived afresh for another
    /// view, other parameters, or a G-buffer whose view is unknown.
    #[test]
    fn a_view_cache_keeps_its_value_only_for_the_same_view() {
        let mut cache = ViewCache::default();
        let mut made = 0;
        let mut get = |g: &GBuffer, p: u32| {
            *cache.get_or_insert_with(g, [p, 0, 0, 0], || {
                made += 1;
                made
            })
        };
        let (a, b) = (view(0.0), view(1.0));
        assert_eq!(get(&a, 1), 1);
        assert_eq!(get(&a, 1), 1, "same view and parameters");
        assert_eq!(get(&a, 2), 2, "other parameters");
        assert_eq!(get(&b, 2), 3, "another view");
        assert_eq!(get(&b, 2), 3);
        let unknown = GBuffer {
            view: None,
            ..view(1.0)
        };
        assert_eq!(get(&unknown, 2), 4, "unknown view");
        assert_eq!(get(&unknown, 2), 5, "unknown view, again");
    }
}
