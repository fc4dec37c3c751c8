//! Shading machinery the tiled methods (`lgh`, `slc`) share, so that they are compared with
//! the same parts:
//!
//! | module | what it does |
//! | --- | --- |
//! | [`tiles`] | screen-tile binning of light volumes, per sub-image (what each tile sees: `tile_bounds`) |
//! | [`interleave`] | interleaved sampling: sub-image lattices, split/merge, the discontinuity-aware blur |
//! | [`reservoirs`] | the k shadow-sample reservoirs a pixel keeps while it is shaded (LGH Appendix A) |
//! | [`strata`] | screen-space dithered strata for the stratified selection |
//! | [`shadow_pass`] | shading in bands of rows, one shadow ray per selected sample |
//! | [`ratio`] | the ratio estimator: filtered S / U, composited with the unshadowed sum |

pub mod interleave;
pub mod ratio;
pub mod reservoirs;
pub mod shadow_pass;
pub mod strata;
mod tile_bounds;
pub mod tiles;
