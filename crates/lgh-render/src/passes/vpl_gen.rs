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
//!
//! By default ([`PathNumbers::Sobol`]) path `k` draws its numbers from the `k`-th point of a
//! per-frame scrambled Sobol sequence ([`PathSampler`]), as Keller drew his from Halton
//! points: the VPLs of one frame spread more evenly, which on the Cornell box makes the
//! unshadowed indirect light flicker about 25% less from frame to frame when the VPLs are
//! regenerated every frame, and the total flux vary far less.

use lgh_core::qmc::{PathSampler, Sampler};
use lgh_core::rng::{Rng, hash};
use lgh_core::sampling::cosine_hemisphere;
use lgh_core::vpl::Vpls;
use rayon::prelude::*;

use crate::world::World;

/// Random-stream tag of light paths.
const STREAM_VPL: u64 = 0x7e1;
/// Light paths per parallel task.
const CHUNK: u64 = 1024;
/// The most paths traced in one parallel batch.
const MAX_BATCH: u64 = 1 << 20;

/// Where the uniform numbers of the light paths come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum PathNumbers {
    /// Path k uses point k of a per-frame scrambled Sobol sequence (`PathSampler`): the
    /// paths of one frame are stratified (default).
    #[default]
    Sobol,
    /// Independent random numbers per path (plain Monte Carlo, as in the paper's description).
    Random,
}

/// The VPLs of one frame and how many light paths made them.
#[derive(Clone, Debug, Default)]
pub struct VplSet {
    /// The VPLs, fluxes already divided by `paths`; empty where a backend keeps them
    /// (`kept`).
    pub vpls: Vpls,
    /// Number of light paths traced (M).
    pub paths: u64,
    /// The VPLs a method's backend made and keeps on its device without a copy here
    /// (`vpls` is then empty): a GPU frame whose every pass after the VPLs runs on the GPU
    /// needs none on the CPU ([`crate::methods::IndirectMethod::generate_vpls`]). Zero
    /// otherwise.
    pub kept: usize,
    /// Where the backend also split the kept VPLs by the dominant direction of their normal
    /// (`normal_bin` of `crate::methods::lgh`, for a frame with `--normal-bins`), the number
    /// in each bin; `None` otherwise.
    pub kept_bins: Option<[usize; crate::methods::lgh::NORMAL_BINS]>,
}

impl VplSet {
    /// The number of VPLs, here or kept on a device.
    #[must_use]
    pub fn len(&self) -> usize {
        self.vpls.len().max(self.kept)
    }

    /// Whether there is no VPL, here or on a device.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The seed of the Sobol point set of the light paths of frame seed `seed`
/// ([`PathNumbers::Sobol`]: path k uses `PathSampler::new(path_seed(seed), k)`).
#[must_use]
pub fn path_seed(seed: u64) -> u64 {
    hash(&[seed, STREAM_VPL])
}

/// The most light paths traced for `target` VPLs: `64 target + 10^6`, a cap for scenes where
/// light escapes.
#[must_use]
pub fn max_paths(target: usize) -> u64 {
    64 * target as u64 + 1_000_000
}

/// Traces light paths until at least `target` VPLs exist (whole paths only, so the count may
/// exceed it by up to `bounces - 1`), or until `64 target + 10^6` paths have been traced in a
/// scene where light escapes. Deterministic for a given `seed`, whatever the thread count.
///
/// The paths are traced in parallel batches, each path k with its own numbers, and kept in
/// order of k up to the first path that reaches `target`. The first batch has `target /
/// bounces` paths (no path leaves more than `bounces` VPLs, so none is wasted); later ones
/// as many as the VPLs per path seen so far say are missing, plus 5%, so that few paths are
/// traced beyond the last one kept. Each task writes its paths' VPLs into one list of its
/// own, with each path's count for the cut.
#[must_use]
pub fn generate_vpls(
    world: &World,
    target: usize,
    bounces: u32,
    seed: u64,
    numbers: PathNumbers,
) -> VplSet {
    let mut vpls = Vpls::with_capacity(target + bounces as usize);
    let max_paths = max_paths(target);
    let mut paths = 0u64;
    if target == 0 || bounces == 0 || world.lights.emits_nothing() {
        return VplSet {
            vpls,
            paths,
            ..VplSet::default()
        };
    }
    let sobol_seed = path_seed(seed);
    let path = |k: u64, out: &mut Vpls| match numbers {
        PathNumbers::Sobol => trace_path(world, bounces, &mut PathSampler::new(sobol_seed, k), out),
        PathNumbers::Random => {
            trace_path(world, bounces, &mut Rng::new(&[seed, k, STREAM_VPL]), out)
        }
    };
    'batches: while paths < max_paths {
        let missing = (target - vpls.len()) as f64;
        let planned = if paths == 0 {
            missing / f64::from(bounces)
        } else {
            1.05 * missing * paths as f64 / vpls.len().max(1) as f64
        };
        let n = (planned.ceil() as u64)
            .clamp(CHUNK, MAX_BATCH)
            .min(max_paths - paths);
        let first = paths;
        let chunks: Vec<(Vpls, Vec<u32>)> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let ks = first + c * CHUNK..first + ((c + 1) * CHUNK).min(n);
                let mut out = Vpls::with_capacity(ks.clone().count() * bounces.min(4) as usize);
                let counts = ks
                    .map(|k| {
                        let before = out.len();
                        path(k, &mut out);
                        (out.len() - before) as u32
                    })
                    .collect();
                (out, counts)
            })
            .collect();
        for (chunk, counts) in chunks {
            if vpls.len() + chunk.len() < target {
                vpls.extend(&chunk);
                paths += counts.len() as u64;
                continue;
            }
            // The paths of this chunk up to the one that reaches the target.
            let mut take = 0;
            for c in counts {
                take += c as usize;
                paths += 1;
                if vpls.len() + take >= target {
                    break;
                }
            }
            vpls.extend_prefix(&chunk, take);
            break 'batches;
        }
    }
    vpls.scale_flux(1.0 / paths as f32);
    VplSet {
        vpls,
        paths,
        ..VplSet::default()
    }
}

/// One light path: appends the VPL (position, normal, unnormalised flux) of each diffuse
/// hit to `out`, at most `bounces` of them.
fn trace_path(world: &World, bounces: u32, rng: &mut impl Sampler, out: &mut Vpls) {
    let Some(ray) = world.lights.sample_emission(rng) else {
        return;
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
        out.push(s.position, s.normal, reflected);
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// The mean over `paths` light paths of `f(path)`.
    fn mean_over(paths: u64, f: impl FnMut(u64) -> Vec3) -> Vec3 {
        (0..paths).map(f).sum::<Vec3>() / paths as f32
    }

    /// The reason for [`PathSampler`]: over 40 frames (seeds) of 2000 one-bounce paths in the
    /// Cornell box, the VPL centroid (flux-weighted mean position, a stand-in for where the
    /// indirect light lands) varies at least 2x less from frame to frame than with independent
    /// random numbers, and both agree on its mean within 4 standard errors (no bias).
    #[test]
    fn stratified_paths_vary_less_between_frames() {
        let world = World::new(lgh_scene::cornell::cornell_box());
        // The first VPL of a path, weighted by its flux.
        let first_vpl = |out: Vpls| {
            out.positions
                .first()
                .map_or(Vec3::ZERO, |&p| p * out.flux[0].element_sum())
        };
        let path = |sampler: &mut dyn FnMut(&mut Vpls)| {
            let mut out = Vpls::default();
            sampler(&mut out);
            out
        };
        let mut qmc = Vec::new();
        let mut rnd = Vec::new();
        for seed in 0..40u64 {
            qmc.push(mean_over(2000, |k| {
                first_vpl(path(&mut |out| {
                    trace_path(&world, 1, &mut PathSampler::new(seed, k), out);
                }))
            }));
            rnd.push(mean_over(2000, |k| {
                first_vpl(path(&mut |out| {
                    trace_path(&world, 1, &mut Rng::new(&[seed, k]), out);
                }))
            }));
        }
        let stats = |v: &[Vec3]| {
            let n = v.len() as f32;
            let mean = v.iter().sum::<Vec3>() / n;
            let var = v.iter().map(|c| (*c - mean).length_squared()).sum::<f32>() / (n - 1.0);
            (mean, var.sqrt())
        };
        let ((mq, sq), (mr, sr)) = (stats(&qmc), stats(&rnd));
        assert!(sq < 0.5 * sr, "std with QMC {sq}, random {sr}");
        let se = ((sq * sq + sr * sr) / 40.0).sqrt();
        assert!((mq - mr).length() < 4.0 * se, "means {mq} vs {mr}, se {se}");
    }
}
