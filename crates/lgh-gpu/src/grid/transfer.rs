//! What crosses the bus in a hierarchy build: the lights up (where they are not on the GPU
//! already) and the grid lights back, unpacked into a [`LightingGrid`].

use glam::{UVec3, Vec3};
use lgh_core::lighting_grid::{GridGeometry, InputLights, LightingGrid};
use rayon::prelude::*;

use super::{LIGHT_FLOATS, LIGHTS_IN, RECORD_WORDS};
use crate::context::{GpuContext, GpuError};
use crate::pool::Lease;

/// The lights as a storage buffer of [`LIGHT_FLOATS`] floats each (the normal zero where
/// the lights have none), packed straight into the queue's staging memory in parallel.
pub(super) fn upload_lights<'c>(
    ctx: &'c GpuContext,
    lights: &InputLights,
) -> Result<Lease<'c>, GpuError> {
    let n = lights.positions.len();
    let lease = ctx.lease(
        LIGHTS_IN,
        4 * (LIGHT_FLOATS * n) as u64,
        GpuContext::STORAGE,
    )?;
    let value = |i: usize| -> f32 {
        let (light, c) = (i / LIGHT_FLOATS, i % LIGHT_FLOATS);
        let v = match c / 3 {
            0 => lights.positions[light],
            1 => lights.intensity[light],
            _ => lights.normals.map_or(Vec3::ZERO, |m| m[light]),
        };
        v[c % 3]
    };
    let floats = LIGHT_FLOATS * n;
    ctx.write_parallel(lease.buffer(), lease.bytes(), |at, out| {
        for (j, word) in out.chunks_exact_mut(4).enumerate() {
            let i = at / 4 + j;
            let v = if i < floats { value(i) } else { 0.0 };
            word.copy_from_slice(&v.to_ne_bytes());
        }
    });
    Ok(lease)
}

/// One grid light as read back.
#[derive(Clone, Copy)]
struct Record<'a>(&'a [u32]);

impl Record<'_> {
    fn float3(&self, at: usize) -> Vec3 {
        Vec3::new(
            f32::from_bits(self.0[at]),
            f32::from_bits(self.0[at + 1]),
            f32::from_bits(self.0[at + 2]),
        )
    }

    fn intensity(&self) -> Vec3 {
        self.float3(8)
    }
}

/// The read-back grid lights (`counts[l - 1]` of level l, level by level) into `grid`,
/// without the zero-intensity ones (the CPU build's compaction), normals zero where the
/// lights had none.
pub(super) fn unpack(
    geometry: GridGeometry,
    counts: &[usize],
    words: &[u32],
    normals: bool,
    grid: &mut LightingGrid,
) {
    grid.geometry = geometry;
    grid.level_start.clear();
    grid.level_start.push(0);
    let mut kept: Vec<Record<'_>> = Vec::new();
    let mut at = 0usize;
    for &c in counts {
        let end = (at + c).min(words.len() / RECORD_WORDS);
        kept.par_extend(
            words[RECORD_WORDS * at..RECORD_WORDS * end]
                .par_chunks_exact(RECORD_WORDS)
                .map(Record)
                .filter(|r| r.intensity().max_element() > 0.0),
        );
        grid.level_start.push(kept.len() as u32);
        at = end;
    }
    let fill = |out: &mut Vec<Vec3>, f: &(dyn Fn(&Record<'_>) -> Vec3 + Sync)| {
        out.clear();
        out.par_extend(kept.par_iter().map(f));
    };
    grid.vertex.clear();
    grid.vertex
        .par_extend(kept.par_iter().map(|r| UVec3::new(r.0[0], r.0[1], r.0[2])));
    grid.mass.clear();
    grid.mass
        .par_extend(kept.par_iter().map(|r| f32::from_bits(r.0[3])));
    fill(&mut grid.position, &|r| r.float3(4));
    fill(&mut grid.intensity, &|r| r.intensity());
    fill(&mut grid.normal, &|r| {
        if normals { r.float3(12) } else { Vec3::ZERO }
    });
    fill(&mut grid.deviation, &|r| {
        Vec3::new(
            f32::from_bits(r.0[7]),
            f32::from_bits(r.0[11]),
            f32::from_bits(r.0[15]),
        )
    });
}
