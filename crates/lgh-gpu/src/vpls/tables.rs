//! What the light-path kernel reads besides the scene (`tables` in
//! `shaders/vpl_paths.wgsl`): the Sobol direction vectors of [`lgh_core::qmc::PathSampler`]
//! and the lights of [`lgh_render::world::lights::LightSet`] with their choice by power, and
//! the scrambling seeds of a batch's blocks of paths.

use glam::Vec3;
use lgh_core::qmc::{BLOCK, block_seed, direction_vectors_4d, group_seed};
use lgh_render::World;
use lgh_scene::Light;

/// `vec4`s per light (`LIGHT_WORDS` in `shaders/emission.wgsl`).
const LIGHT_WORDS: usize = 6;
/// The seeds a batch's uniform holds (`seeds` in `shaders/vpl_paths.wgsl`: 64 x 4).
pub const MAX_SEEDS: usize = 256;

/// The kinds of light (`LIGHT_*` in `shaders/emission.wgsl`).
const POINT: u32 = 0;
const SPOT: u32 = 1;
const DIRECTIONAL: u32 = 2;
const EMITTER: u32 = 3;

fn word(v: Vec3, w: f32) -> [u32; 4] {
    [v.x, v.y, v.z, w].map(f32::to_bits)
}

/// The tables of `world`: 16 Sobol direction vectors, then six words per light
/// (punctual lights first, then emitters, as the CPU numbers them): (kind, probability, the
/// normalised cumulative weight as a high and a low `f32`), then the light's own data.
/// `None` if nothing emits.
#[must_use]
pub fn tables(world: &World) -> Option<Vec<[u32; 4]>> {
    let lights = &world.lights;
    let dist = lights.power_distribution()?;
    let mut out: Vec<[u32; 4]> = direction_vectors_4d().to_vec();
    for i in 0..lights.len() {
        let c = dist.cumulative(i);
        let hi = c as f32;
        let lo = (c - f64::from(hi)) as f32;
        let pmf = dist.pmf(i);
        let head = |kind: u32| [kind, pmf.to_bits(), hi.to_bits(), lo.to_bits()];
        let mut rec = [[0u32; 4]; LIGHT_WORDS];
        match lights.punctual.get(i) {
            Some(Light::Point {
                position,
                intensity,
            }) => {
                rec[0] = head(POINT);
                rec[1] = word(*position, 0.0);
                rec[2] = word(*intensity, 0.0);
            }
            Some(Light::Spot {
                position,
                direction,
                intensity,
                cos_inner,
                cos_outer,
            }) => {
                rec[0] = head(SPOT);
                rec[1] = word(*position, 0.0);
                rec[2] = word(*intensity, 0.0);
                rec[3] = word(*direction, 0.0);
                rec[4] = word(Vec3::new(*cos_inner, *cos_outer, 0.0), 0.0);
            }
            Some(Light::Directional {
                direction,
                irradiance,
            }) => {
                rec[0] = head(DIRECTIONAL);
                rec[1] = word(*direction, 0.0);
                rec[2] = word(*irradiance, 0.0);
            }
            None => {
                let e = &lights.emitters[i - lights.punctual.len()];
                rec[0] = head(EMITTER);
                rec[1] = word(e.v0, e.area);
                rec[2] = word(e.e1, 0.0);
                rec[3] = word(e.e2, 0.0);
                rec[4] = word(e.normal, 0.0);
                rec[5] = word(e.radiance, 0.0);
            }
        }
        out.extend(rec);
    }
    Some(out)
}

/// The 4D groups a path of at most `bounces` VPLs draws: 4 numbers to start it, 3 per
/// bounce after a VPL (roulette, direction).
#[must_use]
pub fn groups(bounces: u32) -> u32 {
    (4 + 3 * bounces.saturating_sub(1)).div_ceil(4)
}

/// The seeds of the groups of the blocks that paths `first..first + n` fall in, for the
/// point set of `set_seed`: block `b`'s group `g` at `(b - first / BLOCK) * groups + g`.
#[must_use]
pub fn seeds(set_seed: u64, first: u64, n: u64, groups: u32) -> Vec<u32> {
    let (b0, b1) = (first / BLOCK, (first + n.max(1) - 1) / BLOCK);
    (b0..=b1)
        .flat_map(|b| {
            let s = block_seed(set_seed, b);
            (0..groups).map(move |g| group_seed(s, g))
        })
        .collect()
}

/// The most paths one batch may hold so that its blocks' seeds fit the uniform (a batch
/// may straddle one more block than it fills).
#[must_use]
pub fn max_batch_for_seeds(groups: u32) -> u64 {
    let blocks = (MAX_SEEDS as u64 / u64::from(groups.max(1)))
        .saturating_sub(1)
        .max(1);
    blocks * BLOCK
}
