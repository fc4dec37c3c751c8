//! Rendering with the lighting grid hierarchy (Lin & Yuksel 2019, sections 3.2, 3.3, 4.1).
//!
//! 1. **Hierarchy** of the VPLs ([`lgh_core::lighting_grid`], section 3.1).
//! 2. **Lighting computation** (3.2): the grid lights of levels l_min..=l_max (l_min = 0 by
//!    default, the VPLs themselves as S_0 with h_0 = h_1 / 2; the paper's 1, 4.1) are binned into
//!    screen tiles as spheres of radius 2 r_l, r_l = alpha h_l (the top level covers the whole
//!    screen), the CPU counterpart of rasterising light volumes. Each pixel x sums, over its
//!    tile's lights j, B_l(d_j) x Phi_j e_j(w) max(0, n_x . w) / (pi (d^2 + eps^2))
//!    (the unshadowed sum A), skipping lights whose blending weight is zero. The emission
//!    cosine e_j is max(0, -m_j . w) + (1 - |m_j|) / 4 for the mean normal m_j by default
//!    ([`lgh_core::vpl::GridEmission`]; max(0, -m_j . w) alone is the demo's, which loses light where normals
//!    disagree). The number of lights whose sphere covers the pixel is its overdraw (Fig. 5).
//!    With n x n interleaved sampling (4.3, `interleave` > 1), the lights of each level are
//!    dealt to the n^2 sub-images (light k to k mod n^2), each pixel sums only its
//!    sub-image's lights with n^2 times their intensity, and A, S and U are recombined by the
//!    discontinuity-aware blur of [`crate::shading::interleave`] before the shadow filter
//!    (A over exactly the n x n window, S and U over 17 x 17 pixels).
//! 3. **Shadow sample selection** (3.3, Appendix A): while shading, each pixel keeps k
//!    single-slot reservoirs; every candidate light is offered with weight f_j = luminance
//!    of its unshadowed contribution. With the unbiased estimate (the default,
//!    [`Estimator::Unbiased`]) every shaded level is a candidate; with the paper's, levels
//!    >= the shadow level (2 by default, 4.1, Fig. 3).
//! 4. **Shadow targets.** Unbiased estimate: each selected light walks down the levels to an
//!    S_1 light, drawn afresh per sample in proportion to its share
//!    ([`lgh_core::lighting_grid::descent`]), and one of that light's representative VPLs
//!    is picked by its contribution; the sample's S counts that VPL's own contribution with
//!    its blending share normalised to one ([`lgh_core::lighting_grid::partition`];
//!    docs/design.md, "Unbiased estimate"), a normalisation computed only once the ray has
//!    found the VPL visible ([`crate::shading::shadow_pass::Targets::visible_gain`]).
//!    Paper estimate: the target is one of the per-frame representatives of the light
//!    ([`ShadowTarget::Representative`], an extension that removes the darkening of
//!    centroids inside objects) or the paper's centroid jittered by its deviation
//!    (q = p_j + 0.5 t * deviation, t raised-cosine per axis; docs/design.md, "Shadow
//!    targets").
//! 5. **Shadow rays and the ratio estimator** (Heitz et al. 2018): one ray per reservoir;
//!    U_k = f^ f_j / lum(f_j) (an unbiased estimate of the candidates' sum A), S_k =
//!    V gain U_k (gain 1 for the paper's estimate, which then estimates the grid lights'
//!    shadowed sum; the VPLs' for the unbiased one); both are averaged over k, filtered by
//!    the same edge-avoiding a-trous filter ([`crate::denoise::atrous`]), and indirect =
//!    albedo / pi x A x D(S) / D(U) per channel (ratio 1 where D(U) is zero).
//!
//! | file | concept |
//! | --- | --- |
//! | `mod.rs` | the method: the passes above in order |
//! | [`settings`] | [`LghSettings`] and the choices where the paper is silent |
//! | `lights.rs` | the shaded lights (levels, radii, roles, representatives) |
//! | `prepared.rs` | a frame's steps: [`LghFrame::prepare`], the CPU lighting loop, [`LghFrame::finish`] |
//! | `shade.rs` | the lighting loop of one row (A and the shadow reservoirs) |
//! | [`tables`] | the lighting loop's inputs as flat tables, for another backend (the GPU) |
//! | [`light_batch`] | a tile's lights in lanes of eight for the lighting loop |

use crate::memory::FrameMemory;
use crate::methods::{IndirectMethod, Method, MethodInputs, MethodOutput};
use crate::settings::RenderError;
use lgh_core::lighting_grid::GridError;

pub mod light_batch;
mod lights;
mod normal_bins;
mod prepared;
mod rep_set;
pub mod settings;
mod shade;
pub mod tables;

pub use normal_bins::{NORMAL_BINS, normal_bin};
pub use prepared::{LghFrame, LightSpheres, LoopResult, Prepared};
pub use settings::{
    DEFAULT_INTERLEAVE, DEFAULT_SHADOW_SAMPLES, Estimator, INTERACTIVE_INTERLEAVE, JitterAt,
    LghSettings, ShadowTarget, auto_tile,
};

/// The lighting grid hierarchy with stochastic ray-traced shadows.
pub const LGH: Method = Method::new(&Lgh { shadowed: true });
/// The lighting grid hierarchy without shadows.
pub const LGH_UNSHADOWED: Method = Method::new(&Lgh { shadowed: false });

/// The `lgh` methods.
struct Lgh {
    /// Shadow rays through the ratio estimator (`lgh`), or none (`lgh-unshadowed`).
    shadowed: bool,
}

impl IndirectMethod for Lgh {
    fn name(&self) -> &'static str {
        if self.shadowed {
            "lgh"
        } else {
            "lgh-unshadowed"
        }
    }

    fn about(&self) -> &'static str {
        if self.shadowed {
            "Lighting grid hierarchy (Lin & Yuksel 2019) with stochastic ray-traced shadows"
        } else {
            "Lighting grid hierarchy without shadows"
        }
    }

    fn default_shadow_samples(&self) -> u32 {
        DEFAULT_SHADOW_SAMPLES
    }

    fn render(
        &self,
        inputs: &MethodInputs,
        memory: &mut FrameMemory,
    ) -> Result<MethodOutput, RenderError> {
        Ok(render_lgh(inputs, self.shadowed, memory)?)
    }
}

/// Statistics of an `lgh` frame (the paper's Table 3 and Fig. 5).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct LghStats {
    /// Grid lights in the hierarchy (all levels).
    pub grid_lights: usize,
    /// l_max.
    pub levels: u32,
    /// Lights shaded (grid lights of the shaded levels, plus VPLs when starting at 0).
    pub shaded_lights: usize,
    /// Mean overdraw (lights whose sphere covers a pixel) over pixels that see a surface.
    pub avg_overdraw: f64,
    /// Shadow rays traced.
    pub shadow_rays: u64,
    /// alpha of the blending radii.
    pub alpha: f32,
    /// Shadow samples per pixel used (0 without shadows).
    pub shadow_samples: u32,
    /// n of the n x n interleaving used.
    pub interleave: u32,
    /// Where the hierarchies were built: `cpu`, or `gpu` (`--device gpu`, unless the GPU's
    /// builder handed them to the CPU's: the gather construction, or inputs too large for
    /// the adapter).
    pub hierarchy_device: &'static str,
    /// Whether the CPU held the hierarchies' grids (its own builds, or grids read back);
    /// false where their builder kept them on its device (a GPU frame whose every step
    /// after the build runs there).
    pub grids_on_cpu: bool,
}

/// Renders the indirect light of the VPLs with the lighting grid hierarchy. With
/// `shadowed == false` (method `lgh-unshadowed`) no sample is selected and no ray traced.
/// The statistics are an [`LghStats`].
///
/// The frame's three steps are public, so that another backend can run the middle one:
/// [`LghFrame::prepare`] (hierarchies, shaded lights, tile bins), the lighting loop with
/// its shadow rays ([`LghFrame::shade`] here on the CPU; lgh-gpu's on the GPU from
/// [`LghFrame::tables`]), and [`LghFrame::finish`] (ratio estimator and filters).
///
/// # Errors
/// The VPLs cannot form a hierarchy (non-finite values).
pub fn render_lgh(
    inputs: &MethodInputs,
    shadowed: bool,
    memory: &mut FrameMemory,
) -> Result<MethodOutput, GridError> {
    match LghFrame::prepare(inputs, shadowed, memory, false)? {
        Prepared::Dark(output) => Ok(output),
        Prepared::Frame(frame) => {
            let shaded = frame.shade(inputs);
            Ok(frame.finish(inputs, shaded, memory))
        }
    }
}
