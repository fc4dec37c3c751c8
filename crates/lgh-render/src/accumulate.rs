//! Progressive rendering that converges: the mean of N frames of a static view, each with an
//! independent VPL set (and, for `lgh`, its own grid offset, so that the hierarchy's
//! structured error becomes noise that averages away; docs/design.md, "Accumulation").
//!
//! For `brute` the mean is the brute force over the union of the N VPL sets (each VPL with
//! 1/N of its flux), so `lgh` and `brute` accumulated over the same N are comparable, and
//! both converge to the solution of the light transport as N grows.

use glam::{Vec2, Vec3};
use lgh_core::rng::hash;

use crate::frame::{Frame, render_frame_with};
use crate::image::Image;
use crate::memory::FrameMemory;
use crate::progress::{Progress, Silent};
use crate::settings::{RenderError, RenderSettings};
use crate::world::World;

/// Shadow samples per pixel and frame of an accumulation when the caller has no preference
/// (the command line's `--accumulate` without `--shadow-samples`): the shadow filter shrinks
/// as the frames grow ([`accumulation_settings`]), so each frame's shadow estimate must be
/// less noisy; more samples per frame converge faster per unit of time than more frames
/// (docs/design.md, "Accumulation").
pub const ACCUMULATE_SHADOW_SAMPLES: u32 = 16;

/// Random-stream tag of the frame seeds.
const STREAM_ACCUMULATE: u64 = 0xacc;

/// The seed of frame `k` of an accumulation from `seed`: `seed` itself for the first frame,
/// so that one frame is the plain render.
#[must_use]
pub fn frame_seed(seed: u64, k: u32) -> u64 {
    if k == 0 {
        seed
    } else {
        hash(&[seed, u64::from(k), STREAM_ACCUMULATE])
    }
}

/// The settings of frame `k` of `frames`: its own seed (VPLs, shadow samples, direct-light
/// samples), SLC range seed, and for more than one frame a random grid offset for `lgh` and
/// its own sub-pixel position ([`subpixel_jitter`]), so that the mean is anti-aliased (and no
/// frame resolves its edges itself, [`crate::passes::edge_aa`]), each with the 1/d^2 clamp of
/// all the frames' VPLs together ([`RenderSettings::vpl_clamp`] / sqrt(frames)).
#[must_use]
pub fn frame_settings(s: &RenderSettings, k: u32, frames: u32) -> RenderSettings {
    let mut f = s.clone();
    f.seed = frame_seed(s.seed, k);
    f.slc.frame_seed = s.slc.frame_seed.wrapping_add(k);
    f.lgh.grid_jitter |= frames > 1;
    if frames > 1 {
        f.jitter = subpixel_jitter(k);
        f.edge_samples = 1;
        // The clamp of the union of the frames' VPLs, so that the mean converges to it.
        f.vpl_clamp = s.vpl_clamp / (frames as f32).sqrt();
    }
    f
}

/// The sub-pixel offset of frame `k` of an accumulation, in [-0.5, 0.5)^2: zero for the
/// first frame (one frame is the plain render), then Roberts' R2 sequence (the plastic
/// constant's additive recurrence), whose first N points cover the pixel evenly for every N,
/// so that an accumulation of any length box-filters the pixel.
#[must_use]
pub fn subpixel_jitter(k: u32) -> Vec2 {
    const A: [f64; 2] = [0.754_877_666_246_692_8, 0.569_840_290_998_053_2];
    let f = |a: f64| ((0.5 + a * f64::from(k)).fract() - 0.5) as f32;
    Vec2::new(f(A[0]), f(A[1]))
}

/// The settings of frame `k` of an accumulation of `frames` frames: [`frame_settings`], and
/// filters that shrink as the frames grow, so that the mean converges to the brute force:
/// the shadow ratio's a-trous filter keeps at most max(1, 5 - log2(frames)) passes (the
/// last, 5 x 5 pixels, keeps the noise of single samples from dominating), and `lgh` does without interleaving unless it is asked for (its blur of the
/// unshadowed sum A, 17 pixels wide, is a bias that no number of frames removes;
/// docs/design.md, "Accumulation").
#[must_use]
pub fn accumulation_settings(s: &RenderSettings, k: u32, frames: u32) -> RenderSettings {
    let mut f = frame_settings(s, k, frames);
    if frames > 1 {
        let passes = 5u32.saturating_sub(frames.ilog2()).max(1);
        f.shadows.filter_passes = f.shadows.filter_passes.min(passes);
        if f.method.name().starts_with("lgh") {
            f.tiling.interleave = Some(f.tiling.interleave.unwrap_or(1));
        }
    }
    f
}

/// Renders `frames` frames of `world` (at least one) and returns their mean: `image`,
/// `direct` and `indirect` are averaged, `timings` summed per pass, and the rest is the last
/// frame's (the method's per-pixel outputs of one frame are dropped, being of one frame
/// only). `progress` sees one unit per frame.
///
/// # Errors
/// As [`crate::frame::render_frame`].
pub fn render_accumulated(
    world: &World,
    s: &RenderSettings,
    frames: u32,
    progress: &dyn Progress,
    memory: &mut FrameMemory,
) -> Result<Frame, RenderError> {
    let frames = frames.max(1);
    let inner: &dyn Progress = if frames > 1 { &Silent } else { progress };
    progress.begin("frames", u64::from(frames));
    let mut f = render_frame_with(world, &accumulation_settings(s, 0, frames), inner, memory)?;
    progress.advance(1);
    let mut sums = [
        f.image.pixels.clone(),
        f.direct.pixels.clone(),
        f.indirect.pixels.clone(),
    ];
    for k in 1..frames {
        let next = render_frame_with(world, &accumulation_settings(s, k, frames), inner, memory)?;
        for (acc, p) in sums
            .iter_mut()
            .zip([&next.image, &next.direct, &next.indirect])
        {
            for (a, v) in acc.iter_mut().zip(&p.pixels) {
                *a += *v;
            }
        }
        for (name, ms) in &next.timings.0 {
            match f.timings.0.iter_mut().find(|(n, _)| n == name) {
                Some(entry) => entry.1 += ms,
                None => f.timings.push(name, *ms),
            }
        }
        let previous = std::mem::replace(&mut f, next);
        f.timings = previous.timings;
        memory.recycle_gbuffer(previous.gbuffer);
        progress.advance(1);
    }
    progress.end();
    let inv = 1.0 / frames as f32;
    let [img, dir, ind] = sums;
    let mean = |v: Vec<Vec3>, like: &Image| {
        Image::from_pixels(
            like.width,
            like.height,
            v.into_iter().map(|p| p * inv).collect(),
        )
    };
    f.image = mean(img, &f.image);
    f.direct = mean(dir, &f.direct);
    f.indirect = mean(ind, &f.indirect);
    if frames > 1 {
        f.method.unshadowed = None;
        f.method.shadow_ratio = None;
        f.method.lights_per_pixel = None;
    }
    Ok(f)
}
