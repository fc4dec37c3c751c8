//! The G-buffer: what the camera sees through each pixel's sample point (one primary ray per
//! pixel; the centre, or moved by the camera frame's jitter in an accumulation).

use std::sync::{Arc, OnceLock};

use glam::Vec3;
use rayon::prelude::*;

use crate::passes::par_filled;
use crate::settings::RenderError;
use crate::world::World;
use lgh_scene::camera::CameraFrame;

/// Per-pixel surface attributes, structure-of-arrays, row-major from the top-left pixel.
/// Pixels that see nothing have `depth = f32::INFINITY` and zero everywhere else. The
/// default is an empty 0 x 0 buffer, ready for [`GBuffer::render_into`].
///
/// A backend that traced the G-buffer on its device may leave the planes there
/// ([`GBuffer::defer_planes`]) for a frame whose every pass runs on that device (the
/// viewer's shown frames): code on the CPU then reads them through [`GBuffer::planes`], or
/// reads them back first with [`GBuffer::read_deferred`].
#[derive(Clone, Debug, Default)]
pub struct GBuffer {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// World position.
    pub position: Vec<Vec3>,
    /// Unit shading normal, facing the camera.
    pub normal: Vec<Vec3>,
    /// Unit geometric normal, facing the camera.
    pub geo_normal: Vec<Vec3>,
    /// Diffuse albedo (factor x texture).
    pub albedo: Vec<Vec3>,
    /// Linear depth: distance along the camera's viewing direction.
    pub depth: Vec<f32>,
    /// Emitted radiance towards the camera.
    pub emission: Vec<Vec3>,
    /// What the planes show, as [`GBuffer::render_into`] left them: the world's geometry id
    /// and the camera; `None` if unknown (set it to `None` after changing the planes).
    pub view: Option<(u64, CameraFrame)>,
    /// Where the planes are on a device, what reads them back ([`GBuffer::defer_planes`];
    /// the default: the planes are here).
    pub deferred: DeferredPlanes,
}

/// Planes that a backend keeps on its device and reads back only when code on the CPU asks
/// for them ([`GBuffer::defer_planes`]).
pub trait DevicePlanes: Send + Sync {
    /// Reads the planes back into `g`, whose width, height and view are set: every plane
    /// gets `width * height` pixels.
    ///
    /// # Errors
    /// The device failed (one line).
    fn read_into(&self, g: &mut GBuffer) -> Result<(), String>;

    /// The reader as `Any`, for its backend to find what it keeps on its device.
    fn as_any(&self) -> &dyn std::any::Any;
}

/// The deferred planes of a G-buffer ([`GBuffer::defer_planes`]): their reader, and a copy
/// read back by [`GBuffer::planes`] (kept, so that they cross from the device once). The
/// default: none, the planes are on the CPU.
#[derive(Clone, Default)]
pub struct DeferredPlanes {
    reader: Option<Arc<dyn DevicePlanes>>,
    read: OnceLock<Result<Box<GBuffer>, String>>,
}

impl std::fmt::Debug for DeferredPlanes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DeferredPlanes")
            .field("on_device", &self.reader.is_some())
            .field("read", &self.read.get().map(Result::is_ok))
            .finish()
    }
}

impl GBuffer {
    /// A `width` x `height` G-buffer of the given planes (the geometric normals the shading
    /// ones, white albedo, no emission, no view): the scenes of unit tests.
    #[cfg(test)]
    pub(crate) fn from_planes(
        (width, height): (u32, u32),
        position: Vec<Vec3>,
        normal: Vec<Vec3>,
        depth: Vec<f32>,
    ) -> Self {
        let n = position.len();
        Self {
            width,
            height,
            position,
            geo_normal: normal.clone(),
            normal,
            albedo: vec![Vec3::ONE; n],
            depth,
            emission: vec![Vec3::ZERO; n],
            view: None,
            deferred: Default::default(),
        }
    }

    /// Traces one primary ray per pixel centre, in parallel.
    #[must_use]
    pub fn render(world: &World, frame: &CameraFrame, width: u32, height: u32) -> Self {
        let mut g = Self::default();
        g.render_into(world, frame, width, height);
        g
    }

    /// True if the planes already show what [`GBuffer::render_into`] would render: the same
    /// geometry of `world` seen by the same camera `frame` at `width` x `height` (a viewer
    /// whose camera stands still while the light moves).
    #[must_use]
    pub fn shows(&self, world: &World, frame: &CameraFrame, width: u32, height: u32) -> bool {
        (self.width, self.height) == (width, height)
            && self.len() == width as usize * height as usize
            && self.view == Some((world.geometry_id(), *frame))
    }

    /// [`GBuffer::render`] into this buffer's planes, reusing their memory when the pixel
    /// count is unchanged (as a real-time renderer reuses its render targets): every pixel is
    /// written, so nothing is cleared first. Fresh planes are allocated in parallel.
    pub fn render_into(&mut self, world: &World, frame: &CameraFrame, width: u32, height: u32) {
        self.deferred = DeferredPlanes::default();
        self.view = Some((world.geometry_id(), *frame));
        let (w, n) = (width as usize, width as usize * height as usize);
        (self.width, self.height) = (width, height);
        if self.depth.len() != n {
            self.position = par_filled(n, Vec3::ZERO);
            self.normal = par_filled(n, Vec3::ZERO);
            self.geo_normal = par_filled(n, Vec3::ZERO);
            self.albedo = par_filled(n, Vec3::ZERO);
            self.depth = par_filled(n, f32::INFINITY);
            self.emission = par_filled(n, Vec3::ZERO);
        }
        // Each row writes its pixels straight into the planes: no per-pixel hit records
        // gathered first (80 B a pixel) and no serial copy after.
        let row = w.max(1);
        (
            self.position.par_chunks_mut(row),
            self.normal.par_chunks_mut(row),
            self.geo_normal.par_chunks_mut(row),
            self.albedo.par_chunks_mut(row),
            self.depth.par_chunks_mut(row),
            self.emission.par_chunks_mut(row),
        )
            .into_par_iter()
            .enumerate()
            .for_each(
                |(y, (position, normal, geo_normal, albedo, depth, emission))| {
                    for x in 0..position.len() {
                        let px = frame.sample_point(x as u32, y as u32);
                        let hit = world.trace_camera(frame.origin, frame.direction(px));
                        let Some(s) = hit else {
                            position[x] = Vec3::ZERO;
                            normal[x] = Vec3::ZERO;
                            geo_normal[x] = Vec3::ZERO;
                            albedo[x] = Vec3::ZERO;
                            depth[x] = f32::INFINITY;
                            emission[x] = Vec3::ZERO;
                            continue;
                        };
                        position[x] = s.position;
                        normal[x] = s.normal;
                        geo_normal[x] = s.geo_normal;
                        albedo[x] = s.albedo;
                        depth[x] = (s.position - frame.origin).dot(frame.forward);
                        emission[x] = s.emission;
                    }
                },
            );
    }

    /// Number of pixels.
    #[must_use]
    pub fn len(&self) -> usize {
        if self.planes_deferred() {
            self.width as usize * self.height as usize
        } else {
            self.depth.len()
        }
    }

    /// Leaves the planes on a backend's device: `width` x `height` pixels that show `view`,
    /// read back by `reader` when code on the CPU first asks for them ([`GBuffer::planes`],
    /// [`GBuffer::read_deferred`]). Until then the planes here are empty (their memory is
    /// kept for the read-back); the size, the view and [`GBuffer::len`] are the deferred
    /// planes'.
    pub fn defer_planes(
        &mut self,
        (width, height): (u32, u32),
        view: (u64, CameraFrame),
        reader: Arc<dyn DevicePlanes>,
    ) {
        for plane in [
            &mut self.position,
            &mut self.normal,
            &mut self.geo_normal,
            &mut self.albedo,
            &mut self.emission,
        ] {
            plane.clear();
        }
        self.depth.clear();
        (self.width, self.height, self.view) = (width, height, Some(view));
        self.deferred = DeferredPlanes {
            reader: Some(reader),
            read: OnceLock::new(),
        };
    }

    /// True while the planes are on a device ([`GBuffer::defer_planes`]).
    #[must_use]
    pub fn planes_deferred(&self) -> bool {
        self.deferred.reader.is_some()
    }

    /// The reader of deferred planes, for the backend that keeps them.
    #[must_use]
    pub fn device_planes(&self) -> Option<&dyn DevicePlanes> {
        self.deferred.reader.as_deref()
    }

    /// This G-buffer with its planes on the CPU: itself, or while they are deferred, a
    /// copy read back on the first call and kept for the later ones.
    ///
    /// # Errors
    /// The device failed to read them back.
    pub fn planes(&self) -> Result<&GBuffer, RenderError> {
        let Some(reader) = &self.deferred.reader else {
            return Ok(self);
        };
        let read = self.deferred.read.get_or_init(|| {
            let mut g = GBuffer {
                width: self.width,
                height: self.height,
                view: self.view,
                ..GBuffer::default()
            };
            reader.read_into(&mut g).map(|()| Box::new(g))
        });
        match read {
            Ok(g) => Ok(g),
            Err(e) => Err(RenderError::Backend(e.clone())),
        }
    }

    /// Brings deferred planes back into this buffer (the copy [`GBuffer::planes`] read, or
    /// read now); nothing to do for planes on the CPU.
    ///
    /// # Errors
    /// The device failed to read them back (the planes stay deferred).
    pub fn read_deferred(&mut self) -> Result<(), RenderError> {
        let Some(reader) = self.deferred.reader.take() else {
            return Ok(());
        };
        let read = std::mem::take(&mut self.deferred.read).into_inner();
        let result = match read {
            Some(Ok(g)) => {
                let g = *g;
                self.position = g.position;
                self.normal = g.normal;
                self.geo_normal = g.geo_normal;
                self.albedo = g.albedo;
                self.depth = g.depth;
                self.emission = g.emission;
                Ok(())
            }
            Some(Err(e)) => Err(e),
            None => reader.read_into(self),
        };
        result.map_err(|e| {
            self.deferred.reader = Some(reader);
            RenderError::Backend(e)
        })
    }

    /// Clears every pixel outside `keep` to "sees nothing", so that no pass shades it (a
    /// piece of a frame, [`crate::region`]); the planes no longer show a whole view.
    pub fn clear_outside(&mut self, keep: &crate::region::Region) {
        let w = self.width as usize;
        for i in 0..self.len() {
            let (x, y) = ((i % w) as u32, (i / w) as u32);
            if !keep.contains(x, y) {
                self.position[i] = Vec3::ZERO;
                self.normal[i] = Vec3::ZERO;
                self.geo_normal[i] = Vec3::ZERO;
                self.albedo[i] = Vec3::ZERO;
                self.depth[i] = f32::INFINITY;
                self.emission[i] = Vec3::ZERO;
            }
        }
        self.view = None;
    }

    /// True for a zero-size buffer.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// True if pixel `i` sees a surface.
    ///
    /// # Panics
    /// `i` is out of range, or the planes are deferred ([`GBuffer::planes`]).
    #[inline]
    #[must_use]
    pub fn is_hit(&self, i: usize) -> bool {
        self.depth[i].is_finite()
    }

    /// Sum of per-pixel counts divided by the number of pixels that see a surface (at
    /// least 1): mean overdraw or lights per pixel (pixels that see nothing count 0).
    #[must_use]
    pub fn mean_over_hits(&self, counts: &[u32]) -> f64 {
        let hits = (0..self.len()).filter(|&i| self.is_hit(i)).count().max(1);
        counts.iter().map(|&c| f64::from(c)).sum::<f64>() / hits as f64
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicUsize, Ordering};

    use super::*;

    /// A device that "keeps" the planes `GBuffer::render` traces for the Cornell box, and
    /// counts its read-backs (or fails them).
    struct Kept {
        world: World,
        frame: CameraFrame,
        reads: AtomicUsize,
        fail: bool,
    }

    impl DevicePlanes for Kept {
        fn read_into(&self, g: &mut GBuffer) -> Result<(), String> {
            self.reads.fetch_add(1, Ordering::Relaxed);
            if self.fail {
                return Err("the device is gone".into());
            }
            let traced = GBuffer::render(&self.world, &self.frame, g.width, g.height);
            (g.position, g.normal, g.geo_normal) =
                (traced.position, traced.normal, traced.geo_normal);
            (g.albedo, g.depth, g.emission) = (traced.albedo, traced.depth, traced.emission);
            Ok(())
        }

        fn as_any(&self) -> &dyn std::any::Any {
            self
        }
    }

    fn same_planes(a: &GBuffer, b: &GBuffer) -> bool {
        a.position == b.position
            && a.normal == b.normal
            && a.geo_normal == b.geo_normal
            && a.albedo == b.albedo
            && a.depth == b.depth
            && a.emission == b.emission
    }

    /// Deferred planes: the size and view are theirs while the planes here are empty; the
    /// first `planes` reads them back, later calls and `read_deferred` reuse that copy;
    /// a failed read-back is an error and leaves them deferred; `render_into` ends the
    /// deferral.
    #[test]
    fn deferred_planes_are_read_back_once_when_asked_for() {
        let world = World::new(lgh_scene::cornell::cornell_box());
        let (w, h) = (24, 16);
        let frame = world.scene.camera().frame(w, h);
        let want = GBuffer::render(&world, &frame, w, h);
        let view = (world.geometry_id(), frame);
        for fail in [false, true] {
            let kept = Arc::new(Kept {
                world: World::new(lgh_scene::cornell::cornell_box()),
                frame,
                reads: AtomicUsize::new(0),
                fail,
            });
            let mut g = GBuffer::render(&world, &frame, 8, 8);
            g.defer_planes((w, h), view, Arc::clone(&kept) as Arc<dyn DevicePlanes>);
            assert!(g.planes_deferred() && g.device_planes().is_some());
            assert!(g.position.is_empty() && g.depth.is_empty());
            assert_eq!((g.len(), g.is_empty()), (w as usize * h as usize, false));
            assert!(g.shows(&world, &frame, w, h));
            assert_eq!(kept.reads.load(Ordering::Relaxed), 0, "read before asked");
            if fail {
                assert!(matches!(g.planes(), Err(RenderError::Backend(_))));
                assert!(g.read_deferred().is_err());
                assert!(g.planes_deferred(), "a failed read-back ends the deferral");
                continue;
            }
            let read = g.planes().expect("read back");
            assert!(same_planes(read, &want) && read.view == Some(view));
            assert!(g.planes().is_ok());
            assert_eq!(kept.reads.load(Ordering::Relaxed), 1, "read back twice");
            g.read_deferred().expect("moved in");
            assert_eq!(kept.reads.load(Ordering::Relaxed), 1, "read back again");
            assert!(!g.planes_deferred() && same_planes(&g, &want));
            assert!(std::ptr::eq(g.planes().expect("here"), &g));
            // Read straight into the buffer where `planes` was not asked first; then traced
            // here, which ends a deferral.
            g.defer_planes((w, h), view, Arc::clone(&kept) as Arc<dyn DevicePlanes>);
            g.read_deferred().expect("read back");
            assert!(same_planes(&g, &want));
            g.defer_planes((w, h), view, Arc::clone(&kept) as Arc<dyn DevicePlanes>);
            g.render_into(&world, &frame, w, h);
            assert!(!g.planes_deferred() && same_planes(&g, &want));
            assert_eq!(kept.reads.load(Ordering::Relaxed), 2);
        }
    }
}
