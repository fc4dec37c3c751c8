//! Filters of noisy estimates, guided by the G-buffer.
//!
//! | module | what it does |
//! | --- | --- |
//! | [`atrous`] | edge-avoiding a-trous wavelet filter (Dammertz et al. 2010) of the shadow estimates |
//! | [`temporal`] | reprojection and exponential moving average across frames (LGH 2019 section 4.3) |

pub mod atrous;
pub mod temporal;
