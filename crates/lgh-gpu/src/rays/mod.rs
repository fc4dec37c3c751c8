//! Batches of shadow rays traced on the GPU (`shaders/occlusion.wgsl`): occlusion between
//! pairs of surface points through the uploaded BVH, with the CPU's offsets
//! (`World::occluded_between`); used to test the GPU's rays against the CPU's.

use glam::Vec3;

use crate::batch::Batch;
use crate::context::{GpuContext, GpuError};
use crate::scene::GpuScene;

/// One shadow ray: from surface point `a` (geometric normal `na`) to `b` (normal `nb`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointPair {
    /// First point.
    pub a: Vec3,
    /// Its geometric normal.
    pub na: Vec3,
    /// Second point.
    pub b: Vec3,
    /// Its geometric normal.
    pub nb: Vec3,
}

/// The WGSL source of the kernel (with the BVH traversal).
#[must_use]
pub fn source() -> String {
    crate::kernel(&[
        include_str!("../shaders/occlusion.wgsl"),
        include_str!("../shaders/bvh.wgsl"),
    ])
}

/// For each pair, whether anything of `scene` lies between its points, both moved off their
/// surfaces by `eps` (`World::occluded_between` with `World::ray_epsilon`).
///
/// # Errors
/// The batch exceeds the adapter's limits, or the GPU failed.
pub fn occluded_between(
    ctx: &GpuContext,
    scene: &GpuScene,
    pairs: &[PointPair],
    eps: f32,
) -> Result<Vec<bool>, GpuError> {
    if pairs.is_empty() {
        return Ok(Vec::new());
    }
    let data: Vec<[glam::Vec4; 4]> = pairs
        .iter()
        .map(|p| {
            [
                p.a.extend(eps),
                p.na.extend(0.0),
                p.b.extend(0.0),
                p.nb.extend(0.0),
            ]
        })
        .collect();
    let segs = ctx.upload("point pairs", &data)?;
    let out = ctx.output("blocked", 4 * pairs.len() as u64)?;
    let pipeline = ctx.pipeline("occlusion", source);
    let bind = ctx.bind_group(
        &pipeline,
        vec![
            segs.binding(),
            scene.nodes.as_entire_binding(),
            scene.tris.as_entire_binding(),
            out.binding(),
        ],
    );
    let mut batch = Batch::new(ctx);
    batch.dispatch("occlusion", &pipeline, &bind, pairs.len())?;
    batch.read(out.buffer(), out.bytes())?;
    let (reads, _) = batch.finish()?;
    let blocked: &[u32] = bytemuck::cast_slice(&reads[0]);
    Ok(blocked[..pairs.len()].iter().map(|&b| b != 0).collect())
}
