//! Showing frames: what a viewer asks of a frame's display, and what comes back (the
//! running mean of a still view's frames, docs/design.md "Accumulation", tone-mapped to
//! packed 8-bit pixels).
//!
//! A frame rendered with [`crate::frame::render_frame_shown`] by a method whose backend
//! shows frames itself ([`crate::methods::IndirectMethod::render_shown`]: lgh-gpu's `lgh`)
//! is composed, resolved at its edges, added to the running mean and tone-mapped where its
//! parts are, and only the packed pixels come back ([`Displayed`]); the CPU's display is
//! [`RunningMean`], which a viewer uses for every other frame. Both give the same pixels
//! from the same parts: the sum in the frames' order, the mean as sum x (1 / frames), and
//! [`tonemap_pixel`].

use glam::Vec3;
use rayon::prelude::*;

use crate::denoise::temporal::TemporalSettings;
use crate::image::tonemap::tonemap_pixel;
use crate::passes::edge_aa::EdgeResolve;

/// What a viewer asks of a shown frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DisplayRequest {
    /// The exposure of the tone mapping ([`tonemap_pixel`]).
    pub exposure: f32,
    /// Starts a new running mean with this frame; else the frame is added to the mean so
    /// far (if that holds frames of the same size).
    pub restart: bool,
    /// Also brings back the linear mean (for a screenshot), not only the packed pixels.
    pub linear: bool,
    /// The temporal filter of the shadow ratio, for a sequence's moving frames
    /// ([`crate::sequence::Sequence::render_shown`]); `None` for none.
    pub taa: Option<TaaRequest>,
}

/// The temporal filter asked of a shown frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaaRequest {
    /// Its settings (a backend runs the target
    /// [`crate::denoise::temporal::TemporalTarget::ShadowRatio`] only).
    pub settings: TemporalSettings,
    /// The history kept where the frame is shown is not this sequence's (the last frame
    /// was filtered elsewhere): start again.
    pub restart: bool,
}

/// A shown frame: the running mean, tone-mapped.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Displayed {
    /// The tone-mapped mean, one `0x00RRGGBB` per pixel ([`pack_pixel`]; softbuffer's
    /// layout).
    pub pixels: Vec<u32>,
    /// Frames in the mean, this one included.
    pub frames: u32,
    /// The linear mean, where [`DisplayRequest::linear`] asked for it.
    pub mean: Option<Vec<Vec3>>,
}

/// What a backend that shows frames itself needs besides the method's inputs
/// ([`crate::methods::IndirectMethod::render_shown`]).
#[derive(Clone, Copy, Debug)]
pub struct ShowInputs<'a> {
    /// The frame's direct light is part of the image (else it is zero: the indirect
    /// component alone).
    pub direct: bool,
    /// The emission seen directly is part of the image (else the indirect light alone,
    /// [`crate::Component::Indirect`]).
    pub emission: bool,
    /// The resolve of the frame's edges, applied to the composed image (it is linear, so
    /// this equals resolving each part).
    pub edges: ShowEdges<'a>,
    /// The display asked for.
    pub request: DisplayRequest,
}

/// The edge resolve of a frame shown by its backend ([`ShowInputs::edges`]).
#[derive(Clone, Copy, Debug)]
pub enum ShowEdges<'a> {
    /// No resolve (one sample a pixel).
    None,
    /// This resolve, found before (and kept while the view stands still).
    Resolved(&'a EdgeResolve),
    /// Found by the backend itself with this many sub-pixel samples an edge pixel, in the
    /// frame's own work (a moving camera's frame: no resolve is kept for its view). A
    /// backend finds the same edge pixels and counts as `EdgeResolve::new`'s.
    Find(u32),
}

/// One linear pixel tone-mapped with `exposure` and packed as `0x00RRGGBB`.
#[inline]
#[must_use]
pub fn pack_pixel(p: Vec3, exposure: f32) -> u32 {
    let [r, g, b] = tonemap_pixel(p, exposure);
    (u32::from(r) << 16) | (u32::from(g) << 8) | u32::from(b)
}

/// The CPU's display: the running sum of the frames shown since the last restart.
#[derive(Clone, Debug, Default)]
pub struct RunningMean {
    sum: Vec<Vec3>,
    frames: u32,
}

impl RunningMean {
    /// Frames in the mean.
    #[must_use]
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// Adds `image` (taken: a restart keeps its memory as the sum) as `request` asks and
    /// shows the mean. The mean comes back always: it costs nothing more here.
    pub fn show(&mut self, image: Vec<Vec3>, request: &DisplayRequest) -> Displayed {
        if request.restart || self.frames == 0 || self.sum.len() != image.len() {
            self.sum = image;
            self.frames = 1;
        } else {
            self.sum
                .par_iter_mut()
                .zip(image.par_iter())
                .for_each(|(s, p)| *s += *p);
            self.frames += 1;
        }
        let inv = 1.0 / self.frames as f32;
        let exposure = request.exposure;
        let (mean, pixels): (Vec<Vec3>, Vec<u32>) = self
            .sum
            .par_iter()
            .map(|&s| {
                let m = s * inv;
                (m, pack_pixel(m, exposure))
            })
            .unzip();
        Displayed {
            pixels,
            frames: self.frames,
            mean: Some(mean),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_running_mean_restarts_and_averages() {
        let mut m = RunningMean::default();
        let r = |restart| DisplayRequest {
            exposure: 1.0,
            restart,
            linear: false,
            taa: None,
        };
        let a = m.show(vec![Vec3::splat(1.0); 4], &r(false));
        assert_eq!(a.frames, 1);
        let b = m.show(vec![Vec3::splat(3.0); 4], &r(false));
        assert_eq!(b.frames, 2);
        assert_eq!(b.mean.as_deref(), Some(&[Vec3::splat(2.0); 4][..]));
        assert_eq!(b.pixels[0], pack_pixel(Vec3::splat(2.0), 1.0));
        // A restart, and a frame of another size, start again.
        assert_eq!(m.show(vec![Vec3::ONE; 4], &r(true)).frames, 1);
        assert_eq!(m.show(vec![Vec3::ONE; 2], &r(false)).frames, 1);
        assert_eq!(pack_pixel(Vec3::new(f32::NAN, 1e30, 0.0), 1.0), 0x00ff00);
    }
}
