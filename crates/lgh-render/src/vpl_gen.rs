//! VPL generation by light tracing (Keller 1997, "Instant Radiosity"; as in LGH 2019 section 4
//! and Tokuyoshi & Harada 2016 section 6).
//!
//! Each light path starts on a primary light chosen in proportion to its power, carrying flux
//! Phi = emitted / (densities of the choices). At each diffuse hit it leaves a VPL with the
//! flux it reflects, Phi x albedo, then continues in a cosine-distributed direction with
//! Russian roulette (survival probability q = the largest albedo channel, flux divided by q),
//! up to `bounces` VPLs per path. Dividing every flux by the number of paths M makes the VPL
//! set an unbiased estimate of the light reflected once, twice, ... `bounces` times.
//! Light leaving the primary lights themselves is not stored: direct light is computed
//! exactly, so VPLs carry only indirect light.

use glam::Vec3;
use lgh_core::rng::Rng;
use lgh_core::sampling::cosine_hemisphere;
use lgh_core::vpl::Vpls;
use rayon::prelude::*;

use crate::world::World;

/// Random-stream tag of light paths.
const STREAM_VPL: u64 = 0x7e1;
/// Paths traced per parallel batch.
const BATCH: u64 = 16_384;

/// The VPLs of one frame and how many light paths made them.
#[derive(Clone, Debug, Default)]
pub struct VplSet {
    /// The VPLs, fluxes already divided by `paths`.
    pub vpls: Vpls,
    /// Number of light paths traced (M).
    pub paths: u64,
}

/// Traces light paths until at least `target` VPLs exist (whole paths only, so the count may
/// exceed it by up to `bounces - 1`), or until `64 target + 10^6` paths have been traced in a
/// scene where light escapes. Deterministic for a given `seed`, whatever the thread count.
#[must_use]
pub fn generate_vpls(world: &World, target: usize, bounces: u32, seed: u64) -> VplSet {
    let mut vpls = Vpls::with_capacity(target + bounces as usize);
    let max_paths = 64 * target as u64 + 1_000_000;
    let mut paths = 0u64;
    if target == 0 || bounces == 0 || world.lights.is_empty() {
        return VplSet { vpls, paths };
    }
    'batches: while paths < max_paths {
        let batch: Vec<Vec<(Vec3, Vec3, Vec3)>> = (paths..paths + BATCH)
            .into_par_iter()
            .map(|k| trace_path(world, bounces, &mut Rng::new(&[seed, k, STREAM_VPL])))
            .collect();
        for path in batch {
            paths += 1;
            for (p, n, f) in path {
                vpls.push(p, n, f);
            }
            if vpls.len() >= target {
                break 'batches;
            }
        }
    }
    vpls.scale_flux(1.0 / paths as f32);
    VplSet { vpls, paths }
}

/// One light path: the (position, normal, unnormalised flux) of each VPL it leaves.
fn trace_path(world: &World, bounces: u32, rng: &mut Rng) -> Vec<(Vec3, Vec3, Vec3)> {
    let mut out = Vec::with_capacity(bounces as usize);
    let Some(ray) = world.lights.sample_emission(rng) else {
        return out;
    };
    let (mut origin, mut dir, mut flux) = (ray.origin, ray.dir, ray.flux);
    for bounce in 0..bounces {
        let Some(s) = world.trace(origin, dir) else {
            break;
        };
        let reflected = flux * s.albedo;
        if reflected.max_element() <= 0.0 || !reflected.is_finite() {
            break;
        }
        out.push((s.position, s.normal, reflected));
        if bounce + 1 == bounces {
            break;
        }
        let q = s.albedo.max_element().min(1.0);
        if rng.next_f32() >= q {
            break;
        }
        flux = reflected / q;
        dir = cosine_hemisphere(s.normal, rng.next_2d());
        if dir.dot(s.geo_normal) <= 0.0 {
            break;
        }
        origin = world.offset(s.position, s.geo_normal, dir);
    }
    out
}
