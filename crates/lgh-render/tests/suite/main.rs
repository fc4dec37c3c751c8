//! The integration tests of lgh-render, in one binary (one link instead of one per file).

mod accel;
mod accumulate;
mod analytic;
mod brute_sampled;
mod clamp;
mod common;
mod convergence;
mod cutouts;
mod determinism;
mod direct_light;
#[cfg(feature = "embree")]
mod embree;
mod formats;
mod hostile;
mod ism;
mod lgh_method;
mod normal_maps;
mod pt_method;
mod ratio_filter;
mod region;
mod sequence;
mod shared_scenes;
mod slc_method;
mod unbiased;
mod vertex_colors;
mod vpl_energy;
mod window_fill;
