//! Frame sequences: every frame regenerates its VPLs (LGH 2019 section 4: "when the lighting
//! condition changes, we regenerate all VPLs"), rebuilds the hierarchy, and optionally passes
//! through the temporal filter of [`crate::denoise::temporal`], and the flicker metric that measures
//! how much a static view changes from frame to frame.

use glam::Vec3;

use crate::denoise::temporal::{TemporalFilter, TemporalSettings, TemporalTarget};
use crate::display::{DisplayRequest, TaaRequest};
use crate::frame::{Frame, render_frame_shown, render_frame_with};
use crate::memory::FrameMemory;
use crate::passes::edge_aa::EdgeResolve;
use crate::progress::Progress;
use crate::settings::{RenderError, RenderSettings};
use crate::shading::ratio::composite;
use crate::world::World;

/// Renders frames one after another, keeping the temporal history.
#[derive(Clone, Debug, Default)]
pub struct Sequence {
    filter: TemporalFilter,
    /// Working memory reused from frame to frame.
    memory: FrameMemory,
    /// The last frame was filtered where it was shown ([`Sequence::render_shown`]), so the
    /// CPU's history is not its.
    filtered_there: bool,
    /// The temporal filter, or `None` for independent frames.
    pub taa: Option<TemporalSettings>,
}

impl Sequence {
    /// A sequence with the temporal filter `taa` (or none).
    #[must_use]
    pub fn new(taa: Option<TemporalSettings>) -> Self {
        Self {
            taa,
            ..Self::default()
        }
    }

    /// Renders the next frame of `world` with `settings` (whose seed should change per frame
    /// so that the VPLs and the shadow samples are new) and filters it.
    ///
    /// # Errors
    /// As [`crate::frame::render_frame`].
    pub fn render(
        &mut self,
        world: &World,
        settings: &RenderSettings,
        progress: &dyn Progress,
    ) -> Result<Frame, RenderError> {
        let f = render_frame_with(world, settings, progress, &mut self.memory)?;
        Ok(self.filter(world, f, settings))
    }

    /// [`Sequence::render`] for a viewer that shows the frame as `request` asks
    /// ([`render_frame_shown`]): where the method's backend shows it, the backend also runs
    /// the temporal filter of the shadow ratio, with a history of its own; else the frame
    /// comes back, is filtered here and `Frame::shown` is `None`. (Each side's history
    /// starts again where the last frame was filtered on the other.)
    ///
    /// # Errors
    /// As [`crate::frame::render_frame`].
    pub fn render_shown(
        &mut self,
        world: &World,
        settings: &RenderSettings,
        progress: &dyn Progress,
        request: DisplayRequest,
    ) -> Result<Frame, RenderError> {
        let taa = self.taa.map(|settings| TaaRequest {
            settings,
            restart: !self.filtered_there,
        });
        let request = DisplayRequest { taa, ..request };
        let f = render_frame_shown(world, settings, progress, &mut self.memory, request)?;
        if f.shown.is_some() {
            self.filtered_there = true;
            return Ok(f);
        }
        Ok(self.filter(world, f, settings))
    }

    /// Filters the frame `f` rendered with `settings` on the CPU (where the temporal
    /// filter is on): its indirect light recomposed from the filtered value, with its
    /// edges resolved again where the recipe resolved them.
    fn filter(&mut self, world: &World, mut f: Frame, settings: &RenderSettings) -> Frame {
        let Some(taa) = self.taa else {
            return f;
        };
        if std::mem::take(&mut self.filtered_there) {
            self.filter = TemporalFilter::default();
        }
        let start = std::time::Instant::now();
        let indirect = match (taa.target, &f.method.unshadowed, &f.method.shadow_ratio) {
            (TemporalTarget::ShadowRatio, Some(a), Some(ratio)) => {
                let r = &ratio.filtered;
                let ratio = self.filter.apply(f.camera, &f.gbuffer, r, &ratio.raw, &taa);
                let mut indirect = composite(&f.gbuffer, a, &ratio);
                // The recipe resolved the edges of the indirect light it composed: the same
                // resolve (kept for a whole frame; made again for a piece of one).
                let samples = settings.edge_samples;
                if samples > 1 {
                    let keep = crate::region::shaded_rect(settings);
                    let kept = self
                        .memory
                        .edge_resolve
                        .kept(&f.gbuffer, [samples, 0, 0, 0]);
                    match kept.filter(|_| keep.is_none()) {
                        Some(r) => r.apply(&mut indirect),
                        None => {
                            let g = &f.gbuffer;
                            EdgeResolve::new(world, &f.camera, g, samples, keep.as_ref())
                                .apply(&mut indirect);
                        }
                    }
                }
                indirect
            }
            (TemporalTarget::Indirect, Some(a), Some(ratio)) => {
                let raw = composite(&f.gbuffer, a, &ratio.raw);
                let v = &f.indirect.pixels;
                self.filter.apply(f.camera, &f.gbuffer, v, &raw, &taa)
            }
            _ => {
                let v = &f.indirect.pixels;
                self.filter.apply(f.camera, &f.gbuffer, v, v, &taa)
            }
        };
        f.set_indirect(indirect, settings.component);
        f.timings
            .push("temporal", start.elapsed().as_secs_f64() * 1e3);
        f
    }
}

impl Sequence {
    /// Hands back a frame the caller is done with: the next frame reuses its memory
    /// ([`FrameMemory::recycle_gbuffer`]).
    pub fn recycle(&mut self, frame: Frame) {
        self.memory.recycle_gbuffer(frame.gbuffer);
    }
}

/// Flicker between two consecutive frames of a static view: the mean absolute difference
/// of their luminance over the pixels, relative to the mean luminance of the later frame.
#[must_use]
pub fn flicker(previous: &[Vec3], current: &[Vec3]) -> f64 {
    let lum = |c: Vec3| f64::from(lgh_core::color::luminance(c));
    let n = current.len().max(1) as f64;
    let diff: f64 = previous
        .iter()
        .zip(current)
        .map(|(&a, &b)| (lum(a) - lum(b)).abs())
        .sum::<f64>()
        / n;
    let mean: f64 = current.iter().map(|&c| lum(c)).sum::<f64>() / n;
    if mean > 0.0 { diff / mean } else { 0.0 }
}
