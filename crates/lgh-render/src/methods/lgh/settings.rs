//! Settings of the LGH method, with its choices where the paper is silent
//! (docs/design.md, "Defaults" and the sections it names).

use lgh_core::lighting_grid::{Construction, LevelCount};
use lgh_core::vpl::GridEmission;

use crate::shading::interleave::DEFAULT_FILL_BELOW;

/// Settings of the LGH method. The shadow sample count, the shadow filter and the
/// interleaving are shared with `slc` ([`crate::settings::ShadowSettings`],
/// [`crate::settings::Tiling`]).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct LghSettings {
    /// lgh: alpha of the blending radii r_l = alpha h_l (larger = more accurate, slower; the
    /// paper uses 1).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = LghSettings::default().alpha))]
    pub alpha: f32,
    /// lgh: number of hierarchy levels, `auto` (largest with |S1| < VPLs/2) or 1..=10.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = LghSettings::default().levels))]
    pub levels: LevelCount,
    /// lgh: lowest level whose lights are shadow candidates (2 skips S1, as the paper; 0 adds
    /// the VPLs when --start-level is 0).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = LghSettings::default().shadow_from_level))]
    pub shadow_from_level: u32,
    /// lgh: lowest level shaded: 0 (the VPLs themselves near the pixel, the default) or 1
    /// (S1, the paper's default).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = LghSettings::default().start_level))]
    pub start_level: u32,
    /// Scale of the jitter of centroid shadow targets (the authors' DevScale).
    #[cfg_attr(feature = "clap", arg(skip = LghSettings::default().dev_scale))]
    pub dev_scale: f32,
    /// lgh: how the levels above S_1 are built: `restrict` (exact, fastest; an extension),
    /// `gather` from S_1 (the paper) or `scatter` from all VPLs (the paper's baseline).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = LghSettings::default().construction))]
    pub construction: Construction,
    /// lgh: build six hierarchies, one per dominant normal direction of the VPLs (an
    /// extension of the paper, the default: grid lights then average only normals that
    /// roughly agree, where one hierarchy mixes the opposite faces of columns and furniture;
    /// docs/design.md, "Normal bins"). `--normal-bins=false` builds the paper's one hierarchy.
    #[cfg_attr(feature = "clap", arg(long, num_args = 0..=1, require_equals = true, default_value_t = LghSettings::default().normal_bins, default_missing_value = "true", value_name = "BOOL"))]
    pub normal_bins: bool,
    /// lgh: place the hierarchy's grids at a random offset drawn from the seed, so that
    /// frames of different seeds cluster the VPLs differently (`--accumulate` turns it on).
    #[cfg_attr(feature = "clap", arg(long))]
    pub grid_jitter: bool,
    /// lgh: how a grid light's emission depends on direction.
    #[cfg_attr(feature = "clap", arg(long = "grid-emission", value_enum, default_value_t = LghSettings::default().emission))]
    pub emission: GridEmission,
    /// lgh: when a shadow sample's target (jittered centroid or representative VPL) is
    /// drawn: per candidate before selection, weighting it by its contribution there (the
    /// authors' demo), or only for the k selected samples when their rays are traced (the
    /// default, faster).
    #[cfg_attr(feature = "clap", arg(long = "jitter-at", value_enum, default_value_t = LghSettings::default().jitter))]
    pub jitter: JitterAt,
    /// lgh: how the k shadow samples of a pixel are drawn among its candidates: `stratified`
    /// (the default; an extension: one pass over the pixel's light chunks, the k samples
    /// stratified over the cumulative weight) or `streaming` (the paper's Appendix A: k
    /// independent reservoirs updated light by light). Each sample has the same distribution
    /// either way (docs/design.md, "Stratified selection"). `--jitter-at candidate` always
    /// streams.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = LghSettings::default().selection))]
    pub selection: Selection,
    /// lgh: where the shadow ray of a selected grid light goes: one of the VPLs it stands
    /// for, drawn in proportion to its share (an extension, the default), or its jittered
    /// centroid (the paper; centroids inside objects or walls darken the image).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = LghSettings::default().shadow_target))]
    pub shadow_target: ShadowTarget,
    /// lgh: what the shadow samples estimate. `unbiased` (the default; an extension): the
    /// VPLs' own shadowed light, so that the ratio corrects the hierarchy's approximation as
    /// well as visibility, every shaded level is a shadow candidate, and the image converges
    /// to the brute force. `paper`: the grid lights' visibility only (section 3.3), biased by
    /// the hierarchy's approximation (docs/design.md, "Unbiased estimate").
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = LghSettings::default().estimator))]
    pub estimator: Estimator,
    /// lgh: shade the lights of this level only (0 = the VPLs themselves, with
    /// `--start-level 0`): what one level of the hierarchy adds to the image through its
    /// blending function. The rest of the method is unchanged, so the images of all levels
    /// sum to the full image (the grid-level view of `lgh view`, key G).
    #[cfg_attr(feature = "clap", arg(long, value_name = "LEVEL"))]
    pub only_level: Option<u32>,
    /// lgh, with interleaving: a pixel whose n x n recombination window reaches fewer than
    /// this fraction of the n^2 sub-images (thin or folded geometry: the window stops at
    /// its edges) shades the lights of the sub-images it misses itself, so that each light
    /// counts once there too (an extension; docs/design.md, "Filling cut windows"). 0:
    /// never. Both backends' loops (`--device gpu` with its blur on the GPU).
    #[cfg_attr(feature = "clap", arg(long, default_value_t = LghSettings::default().fill_below, value_name = "FRACTION"))]
    pub fill_below: f32,
}

/// What the shadow samples of `lgh` estimate (docs/design.md, "Unbiased estimate").
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Estimator {
    /// The paper (section 3.3): S and U estimate the grid lights' shadowed and unshadowed
    /// sums, so indirect = A x D(S) / D(U) corrects visibility only, and keeps the error of
    /// the hierarchy's approximation A. Candidates from `--shadow-from-level`.
    Paper,
    /// An extension: each sample goes on from the selected grid light to one of its VPLs,
    /// drawn afresh per sample in proportion to its share, and S counts that VPL's own
    /// contribution with its share of the blending weights normalised to one. S then
    /// estimates the VPLs' shadowed sum without bias, and A x D(S) / D(U) converges to the
    /// brute force. Every shaded level is a candidate. Needs the restriction or the
    /// all-scatter construction.
    Unbiased,
}

/// Where the shadow ray of a selected grid light goes (docs/design.md, "Shadow targets").
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum ShadowTarget {
    /// The grid light's centroid, jittered by its deviation (the paper and the demo).
    /// Centroids that fall inside objects or walls report their light as occluded.
    Centroid,
    /// One of the VPLs the grid light stands for, drawn in proportion to its share (an
    /// extension, the default; `lgh_core::lighting_grid::representative`), then among the
    /// light's representatives by contribution (see `--jitter-at`).
    Representative,
}

/// When a shadow sample's target is drawn: the jittered point of [`ShadowTarget::Centroid`],
/// or the VPL of [`ShadowTarget::Representative`] (docs/design.md, "When targets are drawn").
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum JitterAt {
    /// Every candidate, before selection: its weight f_j is its contribution at its target
    /// (the authors' demo code).
    Candidate,
    /// The k selected samples, when their rays are traced: candidates are offered with the
    /// contribution already computed (the paper's text: f_i "based on the illumination
    /// contribution of each light"); the default.
    Ray,
}

/// How the k shadow samples of a pixel are drawn (docs/design.md, "Stratified selection").
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Selection {
    /// k independent single-slot reservoirs, each offered every candidate (LGH 2019
    /// Appendix A).
    Streaming,
    /// The pixel's cumulative weight inverted at k stratified points, one pass over its
    /// lights (`shading::reservoirs::stratified_picks`), with independent offsets per pixel.
    Stratified,
    /// The same, with the strata's offsets dithered over the screen
    /// (`shading::strata`): neighbouring pixels of a sub-image spread their samples over
    /// their lights jointly, so the filters average fewer repeats; the default.
    Dithered,
}

impl Selection {
    /// True if the k samples are drawn by stratified inversion after the pixel's loop.
    #[must_use]
    pub fn is_stratified(self) -> bool {
        matches!(self, Self::Stratified | Self::Dithered)
    }
}

impl Default for LghSettings {
    fn default() -> Self {
        Self {
            alpha: 3.0,
            levels: LevelCount::Auto,
            shadow_from_level: 2,
            start_level: 0,
            dev_scale: 0.5,
            construction: Construction::Restrict,
            normal_bins: true,
            grid_jitter: false,
            emission: GridEmission::EnergyConserving,
            jitter: JitterAt::Ray,
            selection: Selection::Dithered,
            shadow_target: ShadowTarget::Representative,
            estimator: Estimator::Unbiased,
            only_level: None,
            fill_below: DEFAULT_FILL_BELOW,
        }
    }
}

impl LghSettings {
    /// The paper's LGH (Lin & Yuksel 2019, sections 3.2-3.3 and its measurements): its
    /// shadow estimate, alpha 1, S_1 the lowest level shaded, one hierarchy; the rest (the
    /// representatives' shadow targets, the energy-conserving emission) as the defaults.
    #[must_use]
    pub fn paper() -> Self {
        Self {
            estimator: Estimator::Paper,
            alpha: 1.0,
            start_level: 1,
            normal_bins: false,
            ..Self::default()
        }
    }

    /// The lowest level whose lights are shadow candidates: every shaded level for the
    /// unbiased estimate, `shadow_from_level` for the paper's.
    #[must_use]
    pub fn candidates_from(&self) -> u32 {
        match self.estimator {
            Estimator::Unbiased => self.start_level.min(1),
            Estimator::Paper => self.shadow_from_level,
        }
    }

    /// Why these settings cannot give the unbiased estimate, if they ask for it: it draws
    /// its shadow targets among representatives when the rays are traced, and needs the
    /// trilinear shares of the all-scatter hierarchy.
    #[must_use]
    pub fn unbiased_conflict(&self) -> Option<(&'static str, &'static str)> {
        if self.estimator != Estimator::Unbiased {
            return None;
        }
        if self.shadow_target != ShadowTarget::Representative {
            Some((
                "shadow-target",
                "representative with --estimator unbiased (or --estimator paper)",
            ))
        } else if self.jitter != JitterAt::Ray {
            Some((
                "jitter-at",
                "ray with --estimator unbiased (or --estimator paper)",
            ))
        } else if self.construction == Construction::GatherFromS1 {
            Some((
                "construction",
                "restrict or scatter with --estimator unbiased (or --estimator paper)",
            ))
        } else {
            None
        }
    }
}

/// The default n of n x n interleaved sampling for `lgh` renders: 2 (an extension of the
/// paper's default, none; docs/design.md, "Defaults"). Interactive use takes 4
/// ([`INTERACTIVE_INTERLEAVE`]).
pub const DEFAULT_INTERLEAVE: u32 = 2;

/// Shadow samples k per pixel of `lgh` when `--shadow-samples` is not given: 5, stratified
/// (docs/design.md, "Defaults"; the paper's measurements use 1 and 4).
pub const DEFAULT_SHADOW_SAMPLES: u32 = 5;

/// The n of n x n interleaved sampling for interactive frame rates (the viewer's start,
/// and the paper's real-time measurements): each pixel shades 1/16 of the lights.
pub const INTERACTIVE_INTERLEAVE: u32 = 4;

/// The default tile edge, in sub-image pixels, for n x n interleaving: 16 full-resolution
/// pixels (16 / n sub-image pixels, at least 4). A sub-image tile of 16 sub-image pixels
/// spans 16 n pixels of the screen, so at n = 4 its lights would cover far more than a
/// pixel's (docs/design.md, "Tiles under interleaving").
#[must_use]
pub fn auto_tile(n: u32) -> u32 {
    (16 / n.max(1)).max(4)
}
