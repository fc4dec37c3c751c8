//! The G-buffer: what the camera sees through each pixel's sample point (one primary ray per
//! pixel; the centre, or moved by the camera frame's jitter in an accumulation).

use glam::Vec3;
use rayon::prelude::*;

use crate::passes::par_filled;
use crate::world::World;
use lgh_scene::camera::CameraFrame;

/// Per-pixel surface attributes, structure-of-arrays, row-major from the top-left pixel.
/// Pixels that see nothing have `depth = f32::INFINITY` and zero everywhere else. The
/// default is an empty 0 x 0 buffer, ready for [`GBuffer::render_into`].
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
}

impl GBuffer {
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
            && self.depth.len() == width as usize * height as usize
            && self.view == Some((world.geometry_id(), *frame))
    }

    /// [`GBuffer::render`] into this buffer's planes, reusing their memory when the pixel
    /// count is unchanged (as a real-time renderer reuses its render targets): every pixel is
    /// written, so nothing is cleared first. Fresh planes are allocated in parallel.
    pub fn render_into(&mut self, world: &World, frame: &CameraFrame, width: u32, height: u32) {
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
                        let hit = world.trace(frame.origin, frame.direction(px));
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
        self.depth.len()
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
        self.depth.is_empty()
    }

    /// True if pixel `i` sees a surface.
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
