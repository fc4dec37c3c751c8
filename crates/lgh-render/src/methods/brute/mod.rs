//! The brute-force many-lights reference: every pixel sums every VPL.
//!
//! L_ind(x) = albedo(x) / pi x sum_i Phi_i max(0, n_i . w) max(0, n_x . -w) / (pi (d^2 + eps^2))
//! x V(x, p_i), with an exact shadow ray per VPL (V) unless shadows are off. This is the
//! ground truth the LGH and stochastic-light-culling results are measured against; the clamp
//! eps is the same one they use (docs/design.md, "Clamps"), so a comparison measures the
//! method, not the clamp.

use std::f32::consts::FRAC_1_PI;

use glam::Vec3;
use lgh_core::vpl::{Vpls, vpl_irradiance};

use crate::memory::FrameMemory;
use crate::methods::{IndirectMethod, Method, MethodInputs, MethodOutput};
use crate::passes::gbuffer::GBuffer;
use crate::passes::per_pixel;
use crate::progress::Progress;
use crate::settings::RenderError;
use crate::world::World;
use crate::world::accel::Segment;

/// Every pixel sums every VPL with an exact shadow ray (the reference).
pub const BRUTE: Method = Method::new(&Brute { shadowed: true });
/// Every pixel sums every VPL, without shadow rays.
pub const BRUTE_UNSHADOWED: Method = Method::new(&Brute { shadowed: false });

/// Every pixel sums every VPL unshadowed and estimates their visibility from `--brute-rays`
/// shadow rays drawn in proportion to each VPL's light (an unbiased estimate of [`BRUTE`];
/// the converged references' estimator, [`sampled`]).
pub const BRUTE_SAMPLED: Method = Method::new(&BruteSampled);

pub mod sampled;

/// The brute force with sampled visibility.
struct BruteSampled;

impl IndirectMethod for BruteSampled {
    fn name(&self) -> &'static str {
        "brute-sampled"
    }

    fn about(&self) -> &'static str {
        "Every pixel sums every VPL unshadowed, with visibility from --brute-rays shadow rays drawn by each VPL's light (unbiased for brute)"
    }

    fn render(
        &self,
        inputs: &MethodInputs,
        _memory: &mut FrameMemory,
    ) -> Result<MethodOutput, RenderError> {
        let radiance = sampled::render_brute_sampled(
            inputs.world,
            inputs.gbuffer,
            inputs.vpls,
            inputs.eps(),
            inputs.settings.brute_rays,
            inputs.settings.seed,
            inputs.progress,
        );
        Ok(MethodOutput {
            radiance,
            ..MethodOutput::default()
        })
    }
}

/// The brute-force methods.
struct Brute {
    /// One exact shadow ray per pixel and VPL, or none.
    shadowed: bool,
}

impl IndirectMethod for Brute {
    fn name(&self) -> &'static str {
        if self.shadowed {
            "brute"
        } else {
            "brute-unshadowed"
        }
    }

    fn about(&self) -> &'static str {
        if self.shadowed {
            "Every pixel sums every VPL with an exact shadow ray (the reference)"
        } else {
            "Every pixel sums every VPL without shadow rays"
        }
    }

    fn render(
        &self,
        inputs: &MethodInputs,
        _memory: &mut FrameMemory,
    ) -> Result<MethodOutput, RenderError> {
        let radiance = render_brute(
            inputs.world,
            inputs.gbuffer,
            inputs.vpls,
            inputs.eps(),
            self.shadowed,
            inputs.progress,
        );
        Ok(MethodOutput {
            radiance,
            ..MethodOutput::default()
        })
    }
}

/// Contributions to one point waiting for their shadow rays, traced together (Embree traces
/// a batch as a stream) and added to the point's sum one by one in the order they came, so
/// that the sum is the same as without batches.
pub(super) struct ShadowBatch {
    contribution: [Vec3; BATCH],
    /// The shadow ray, `None` when the points are too close for anything between them.
    segment: [Option<Segment>; BATCH],
    len: usize,
}

/// Shadow rays per batch.
const BATCH: usize = 64;

impl Default for ShadowBatch {
    fn default() -> Self {
        Self {
            contribution: [Vec3::ZERO; BATCH],
            segment: [None; BATCH],
            len: 0,
        }
    }
}

impl ShadowBatch {
    /// Adds `c` to the last contribution (a second sample of the same ray).
    ///
    /// # Panics
    /// If the batch is empty.
    #[inline]
    pub(super) fn add_to_last(&mut self, c: Vec3) {
        self.contribution[self.len - 1] += c;
    }

    /// Adds a contribution and its shadow ray; true when the batch is full.
    #[inline]
    pub(super) fn push(&mut self, c: Vec3, s: Option<Segment>) -> bool {
        self.contribution[self.len] = c;
        self.segment[self.len] = s;
        self.len += 1;
        self.len == BATCH
    }

    /// Traces the batch and adds its visible contributions to `e`, in order.
    pub(super) fn flush(&mut self, world: &World, e: &mut Vec3) {
        let n = std::mem::take(&mut self.len);
        let mut rays = [Segment::default(); BATCH];
        let mut m = 0;
        for s in self.segment[..n].iter().flatten() {
            rays[m] = *s;
            m += 1;
        }
        let mut blocked = [false; BATCH];
        world.accel.occluded_many(&rays[..m], &mut blocked);
        let mut r = 0;
        for (c, s) in self.contribution[..n].iter().zip(&self.segment[..n]) {
            let hidden = s.is_some() && blocked[r];
            r += usize::from(s.is_some());
            if !hidden {
                *e += *c;
            }
        }
    }
}

/// Indirect radiance towards the camera for every pixel, from all `vpls`.
///
/// `eps` clamps 1/d^2 as 1/(d^2 + eps^2). With `shadows` false no shadow ray is traced
/// (the "brute-unshadowed" reference for the lighting approximation alone).
#[must_use]
pub fn render_brute(
    world: &World,
    g: &GBuffer,
    vpls: &Vpls,
    eps: f32,
    shadows: bool,
    progress: &dyn Progress,
) -> Vec<Vec3> {
    let eps2 = eps * eps;
    progress.begin("indirect (brute force)", u64::from(g.height));
    let out = per_pixel(g.len(), g.width as usize, progress, |i| {
        if !g.is_hit(i) {
            return Vec3::ZERO;
        }
        let (x, n, ng) = (g.position[i], g.normal[i], g.geo_normal[i]);
        let mut batch = ShadowBatch::default();
        let mut e = Vec3::ZERO;
        for j in 0..vpls.len() {
            let p = vpls.positions[j];
            let nv = vpls.normals[j];
            let c = vpl_irradiance(x, n, p, nv, vpls.flux[j], eps2);
            if c == Vec3::ZERO {
                continue;
            }
            if !shadows {
                e += c;
                continue;
            }
            if batch.push(c, world.shadow_segment(x, ng, p, nv)) {
                batch.flush(world, &mut e);
            }
        }
        batch.flush(world, &mut e);
        g.albedo[i] * FRAC_1_PI * e
    });
    progress.end();
    out
}
