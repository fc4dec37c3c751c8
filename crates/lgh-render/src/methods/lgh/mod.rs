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
//! | `shade.rs` | the lighting loop of one row (A and the shadow reservoirs) |
//! | [`light_batch`] | a tile's lights in lanes of eight for the lighting loop |

use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;
use lgh_core::lighting_grid::GridError;
use lgh_core::lighting_grid::partition::ShadedLevels;
use lgh_core::rng::Rng;
use lgh_core::timing::Timings;
use lgh_core::vpl::Vpls;
use rayon::prelude::*;

use crate::memory::FrameMemory;
use crate::methods::{IndirectMethod, Method, MethodInputs, MethodOutput};
use crate::passes::par_filled;
use crate::settings::RenderError;
use crate::shading::ratio::{RATIO_CORRECTION, RATIO_VISIBILITY, RatioFilter, shadowed_indirect};
use crate::shading::reservoirs::ReservoirLayout;
use crate::shading::shadow_pass::{ShadowPass, Targets};
use crate::shading::tiles::{AllBounds, InterleavedBins};

pub mod light_batch;
mod lights;
pub mod settings;
mod shade;

use lights::{LghTargets, ShadeLights, split_by_normal};
pub use settings::{
    DEFAULT_INTERLEAVE, DEFAULT_SHADOW_SAMPLES, Estimator, INTERACTIVE_INTERLEAVE, JitterAt,
    LghSettings, ShadowTarget, auto_tile,
};
use shade::{RowContext, RowScratch, shade_rows};

/// Random-stream tag of the grid offset of `--grid-jitter`.
const STREAM_GRID_SHIFT: u64 = 0x6a1d;

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
}

/// Renders the indirect light of the VPLs with the lighting grid hierarchy. With
/// `shadowed == false` (method `lgh-unshadowed`) no sample is selected and no ray traced.
/// The statistics are an [`LghStats`].
///
/// # Errors
/// The VPLs cannot form a hierarchy (non-finite values).
pub fn render_lgh(
    inputs: &MethodInputs,
    shadowed: bool,
    memory: &mut FrameMemory,
) -> Result<MethodOutput, GridError> {
    let MethodInputs {
        world,
        gbuffer: g,
        camera: frame,
        vpls,
        settings: all,
        ..
    } = *inputs;
    let (settings, seed) = (&all.lgh, all.seed);
    let builder = &mut memory.grid;
    builder.set_shift(settings.grid_jitter.then(|| {
        let mut rng = Rng::new(&[seed, STREAM_GRID_SHIFT]);
        Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32())
    }));
    let mut t = Timings::default();
    let n_px = g.len();
    let k = all.shadows.k(shadowed, DEFAULT_SHADOW_SAMPLES);
    let n = all.tiling.interleave.unwrap_or(DEFAULT_INTERLEAVE).max(1);
    let mut stats = LghStats {
        alpha: settings.alpha,
        shadow_samples: k as u32,
        interleave: n,
        ..LghStats::default()
    };
    if vpls.is_empty() {
        return Ok(MethodOutput {
            radiance: par_filled(n_px, Vec3::ZERO),
            lights_per_pixel: Some(par_filled(n_px, 0)),
            stats: Some(Arc::new(stats)),
            ..MethodOutput::default()
        });
    }
    // One hierarchy, or one per dominant normal direction (--normal-bins).
    let split;
    let groups: Vec<&Vpls> = if settings.normal_bins {
        split = split_by_normal(vpls);
        split.iter().collect()
    } else {
        vec![vpls]
    };
    let lowest = settings.start_level.min(1);
    let unbiased = settings.estimator == Estimator::Unbiased;
    let n2 = (n * n) as usize;
    let scale = n2 as f32;
    let mut lights = ShadeLights::default();
    let mut build_ms = 0.0;
    let mut lighting_ms = 0.0;
    let mut reps_ms = 0.0;
    for group in groups.iter().filter(|g| !g.is_empty()) {
        let input = group.as_input();
        let start = Instant::now();
        builder.build(&input, settings.levels, settings.construction)?;
        build_ms += start.elapsed().as_secs_f64() * 1e3;
        let Some(grid) = builder.grid() else { continue };
        let start = Instant::now();
        stats.grid_lights += grid.len();
        stats.levels = stats.levels.max(grid.l_max());
        let first = lights.position.len();
        lights.add_hierarchy(grid, group, lowest, settings.alpha, settings.emission, n2);
        lighting_ms += start.elapsed().as_secs_f64() * 1e3;
        if k > 0 && settings.shadow_target == ShadowTarget::Representative {
            let start = Instant::now();
            if unbiased {
                let levels = ShadedLevels {
                    lowest,
                    alpha: settings.alpha,
                };
                lights.add_unbiased(grid, group, levels, seed, first);
            } else {
                lights.add_representatives(
                    grid,
                    group,
                    lowest,
                    settings.shadow_from_level,
                    settings.construction,
                    seed,
                );
            }
            reps_ms += start.elapsed().as_secs_f64() * 1e3;
        }
    }
    t.push("lgh_build", build_ms);
    if reps_ms > 0.0 {
        t.push("representatives", reps_ms);
    }
    let lighting_start = Instant::now();
    stats.shaded_lights = lights.position.len();
    if let Some(level) = settings.only_level {
        lights.show_only_level(level);
    }
    let tile = all.tiling.tile.unwrap_or_else(|| auto_tile(n)).max(1);
    let bounds = memory
        .tile_bounds
        .get_or_insert_with(g, [n, tile, 0, 0], || AllBounds::new(g, n, tile * n));
    let bins = InterleavedBins::from_bounds(
        g,
        frame,
        bounds,
        &lights.position,
        &lights.reach,
        &lights.sub,
    );
    let eps2 = inputs.eps() * inputs.eps();
    let representative = settings.shadow_target == ShadowTarget::Representative;
    let packed = lights.packed(scale);
    // Per pixel: A and overdraw; and k reservoirs.
    let mut shaded: Vec<(Vec3, u32)> = par_filled(n_px, (Vec3::ZERO, 0));
    let layout = ReservoirLayout::new(k);
    let ctx = RowContext {
        g,
        bins: &bins,
        packed: &packed,
        lights: &lights,
        settings,
        layout,
        k,
        representative,
        eps2,
        seed,
        phases: n as usize,
    };
    let targets = LghTargets {
        lights: &lights,
        g,
        seed,
        eps2,
    };
    // One row of tiles per call, so that a tile's light batch serves all its rows.
    let pass = ShadowPass::new(world, g, k, seed).with_group_rows(bins.tile_pixels() as usize);
    let (estimates, times) = pass.shade_in_bands(
        &mut shaded,
        RowScratch::default,
        |scratch, y0, rows, res| shade_rows(&ctx, y0, rows, res, scratch),
        (representative && settings.jitter == JitterAt::Ray).then_some(&targets as &dyn Targets),
    );
    let overdraw: Vec<u32> = shaded.par_iter().map(|p| p.1).collect();
    stats.avg_overdraw = g.mean_over_hits(&overdraw);
    t.push(
        "lighting",
        lighting_ms
            + (lighting_start.elapsed().as_secs_f64() * 1e3 - times.resolve_ms - times.rays_ms),
    );
    if times.resolve_ms > 0.0 {
        t.push("shadow_targets", times.resolve_ms);
    }
    if k > 0 {
        t.push("shadow_rays", times.rays_ms);
    }
    let a: Vec<Vec3> = shaded.par_iter().map(|p| p.0).collect();
    let filter = RatioFilter {
        max_ratio: if unbiased {
            RATIO_CORRECTION
        } else {
            RATIO_VISIBILITY
        },
        ..all.ratio_filter(n)
    };
    let shadowed = shadowed_indirect(world, g, a, estimates, &filter, &mut t, memory);
    stats.shadow_rays = shadowed.rays;
    Ok(MethodOutput {
        radiance: shadowed.indirect,
        unshadowed: Some(shadowed.unshadowed),
        shadow_ratio: Some(shadowed.ratio),
        lights_per_pixel: Some(overdraw),
        shadow_rays: shadowed.rays,
        timings: t,
        stats: Some(Arc::new(stats)),
    })
}
