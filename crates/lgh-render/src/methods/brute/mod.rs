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

/// Every pixel sums every VPL with an exact shadow ray (the reference).
pub const BRUTE: Method = Method::new(&Brute { shadowed: true });
/// Every pixel sums every VPL, without shadow rays.
pub const BRUTE_UNSHADOWED: Method = Method::new(&Brute { shadowed: false });

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
        let mut e = Vec3::ZERO;
        for j in 0..vpls.len() {
            let p = vpls.positions[j];
            let nv = vpls.normals[j];
            let c = vpl_irradiance(x, n, p, nv, vpls.flux[j], eps2);
            if c == Vec3::ZERO {
                continue;
            }
            if shadows && world.occluded_between(x, ng, p, nv) {
                continue;
            }
            e += c;
        }
        g.albedo[i] * FRAC_1_PI * e
    });
    progress.end();
    out
}
