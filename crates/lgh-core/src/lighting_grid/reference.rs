//! A plain single-threaded reference builder, to test the parallel one against.
//!
//! It follows the definitions directly: every source adds its 8 trilinear weights into an
//! ordered map from vertex to sums, level by level. It shares only the final formulas (sums to
//! grid light, compaction, merge) with the parallel builder.

use std::collections::BTreeMap;

use glam::UVec3;

use super::splat::{Accum, Level, Sources, corner_weight, level_from_sums, locate};
use super::{Construction, GridError, GridGeometry, InputLights, LightingGrid};

/// The level from sums keyed by (z, y, x), which iterate in the parallel builder's vertex
/// order.
fn finish(sums: BTreeMap<(u32, u32, u32), Accum>, geom: &GridGeometry, level: u32) -> Level {
    level_from_sums(
        sums.into_iter()
            .map(|((z, y, x), a)| (UVec3::new(x, y, z), a)),
        geom,
        level,
    )
}

fn splat_reference(src: &Sources, geom: &GridGeometry, level: u32) -> Level {
    let h = geom.cell_size(level);
    let r = geom.cells_per_axis(level);
    let inv_h2 = 1.0 / (h * h);
    // Keyed by (z, y, x) so that iteration gives the parallel builder's vertex order.
    let mut sums: BTreeMap<(u32, u32, u32), Accum> = BTreeMap::new();
    for s in 0..src.positions.len() {
        let (c, f) = locate(src.positions[s], geom.origin, h, r);
        for dz in 0..2 {
            for dy in 0..2 {
                for dx in 0..2 {
                    let d = UVec3::new(dx, dy, dz);
                    let w = corner_weight(f, d);
                    if w > 0.0 {
                        let v = c + d;
                        sums.entry((v.z, v.y, v.x)).or_default().add_source(
                            src,
                            s,
                            w,
                            f - d.as_vec3(),
                            inv_h2,
                        );
                    }
                }
            }
        }
    }
    finish(sums, geom, level)
}

/// Level `level` by the restriction stencil from the grid lights of level `level - 1`
/// (uncompacted), written from its definition: fine vertex v adds to coarse vertex V with
/// weight prod over axes of (1 if v_a = 2 V_a, 1/2 if |v_a - 2 V_a| = 1).
fn restrict_reference(finer: &Level, normals: bool, geom: &GridGeometry, level: u32) -> Level {
    let src = finer.as_sources(normals);
    let h = geom.cell_size(level);
    let inv_h2 = 1.0 / (h * h);
    let mut sums: BTreeMap<(u32, u32, u32), Accum> = BTreeMap::new();
    for (s, &v) in finer.vertex.iter().enumerate() {
        let axis = |a: u32| -> Vec<(u32, f32)> {
            if a.is_multiple_of(2) {
                vec![(a / 2, 1.0)]
            } else {
                vec![(a / 2, 0.5), (a / 2 + 1, 0.5)]
            }
        };
        for &(z, wz) in &axis(v.z) {
            for &(y, wy) in &axis(v.y) {
                for &(x, wx) in &axis(v.x) {
                    let local = (src.positions[s] - geom.origin) / h
                        - glam::Vec3::new(x as f32, y as f32, z as f32);
                    sums.entry((z, y, x)).or_default().add_source(
                        &src,
                        s,
                        wx * wy * wz,
                        local,
                        inv_h2,
                    );
                }
            }
        }
    }
    finish(sums, geom, level)
}

/// Builds the hierarchy with the same geometry as `grid_geometry` (take it from a parallel
/// build, or make one), single-threaded.
///
/// # Errors
/// No lights.
pub fn build_reference(
    lights: &InputLights,
    geometry: GridGeometry,
    construction: Construction,
) -> Result<LightingGrid, GridError> {
    if lights.positions.is_empty() {
        return Err(GridError::Empty);
    }
    let src = lights.sources();
    let mut levels = vec![splat_reference(&src, &geometry, 1)];
    for l in 2..=geometry.l_max {
        let level = match construction {
            Construction::GatherFromS1 => splat_reference(
                &levels[0].as_sources(lights.normals.is_some()),
                &geometry,
                l,
            ),
            Construction::ScatterAll => splat_reference(&src, &geometry, l),
            Construction::Restrict => restrict_reference(
                &levels[l as usize - 2],
                lights.normals.is_some(),
                &geometry,
                l,
            ),
        };
        levels.push(level);
    }
    for level in &mut levels {
        super::compact(level);
    }
    let mut grid = LightingGrid::empty(geometry);
    super::merge_into(geometry, &levels, &mut grid);
    Ok(grid)
}
