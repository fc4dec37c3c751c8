//! The scene on the GPU: triangles and a binary BVH built on the CPU (obvhs's BVH2, the same
//! builder family as the CPU's tracer), flattened for traversal in compute
//! (`shaders/bvh.wgsl`).

use glam::{Vec3, Vec4};
use obvhs::BvhBuildParams;

use std::sync::Arc;

use crate::context::{GpuContext, GpuError};
use crate::surfaces::GpuSurfaces;

/// Deepest BVH the traversal's stack holds (`STACK` in `shaders/bvh.wgsl`).
pub const MAX_DEPTH: usize = 48;

/// One flattened BVH node, as `Node` in `shaders/bvh.wgsl` (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuNode {
    /// Box minimum.
    pub lo: [f32; 3],
    /// Triangles in a leaf, 0 for an inner node.
    pub count: u32,
    /// Box maximum.
    pub hi: [f32; 3],
    /// Inner node: the first of its two children; leaf: its first triangle (in leaf order).
    pub first: u32,
}

/// The scene's triangles and BVH in GPU buffers.
#[derive(Debug)]
pub struct GpuScene {
    /// BVH nodes (root first).
    pub nodes: wgpu::Buffer,
    /// Triangles in leaf order, three `vec4` corners each, then their alpha cut-outs
    /// (`cutouts.rs`).
    pub tris: wgpu::Buffer,
    /// Number of triangles.
    pub triangles: usize,
    /// The mesh's index of each triangle in leaf order.
    order: Vec<u32>,
    /// The triangles' shading data, materials and textures, uploaded on first use
    /// ([`GpuScene::surfaces`]).
    surfaces: std::sync::OnceLock<Result<Arc<GpuSurfaces>, GpuError>>,
}

/// A BVH flattened for the GPU (CPU side, for upload and tests).
#[derive(Clone, Debug, Default)]
pub struct FlatBvh {
    /// The nodes, root first.
    pub nodes: Vec<GpuNode>,
    /// The triangles in leaf order, three corners each (w: 0, or the first corner's the slot
    /// of its cut-out's record), then the cut-outs' records (`cutouts.rs`).
    pub tris: Vec<Vec4>,
    /// The mesh's index of each triangle in leaf order.
    pub order: Vec<u32>,
}

/// The flattened BVH and triangles of `mesh`, with the alpha cut-outs of its triangles.
///
/// # Errors
/// The BVH is deeper than the shader's stack ([`MAX_DEPTH`]).
pub fn flatten(
    mesh: &lgh_scene::Mesh,
    cutouts: Option<&lgh_scene::Cutouts>,
) -> Result<FlatBvh, GpuError> {
    if mesh.is_empty() {
        return Ok(FlatBvh::default());
    }
    let boxes = lgh_render::world::accel::padded_boxes(mesh);
    let bvh = obvhs::bvh2::builder::build_bvh2(
        &boxes,
        BvhBuildParams::medium_build(),
        &mut std::time::Duration::default(),
    );
    let nodes: Vec<GpuNode> = bvh
        .nodes
        .iter()
        .map(|n| GpuNode {
            lo: Vec3::from(n.aabb.min).into(),
            count: n.prim_count,
            hi: Vec3::from(n.aabb.max).into(),
            first: n.first_index,
        })
        .collect();
    let depth = depth(&nodes);
    if depth > MAX_DEPTH {
        return Err(GpuError::TooLarge(format!(
            "the scene's BVH is {depth} levels deep; the GPU traversal holds {MAX_DEPTH}"
        )));
    }
    let mut tris = bvh
        .primitive_indices
        .iter()
        .flat_map(|&i| mesh.vertices(i as usize).map(|v| v.extend(0.0)))
        .collect();
    if let Some(c) = cutouts {
        crate::cutouts::append(&mut tris, &bvh.primitive_indices, c);
    }
    Ok(FlatBvh {
        nodes,
        tris,
        order: bvh.primitive_indices,
    })
}

/// Depth of the tree (the root alone: 1).
fn depth(nodes: &[GpuNode]) -> usize {
    let mut deepest = 0;
    let mut todo = vec![(0usize, 1usize)];
    while let Some((i, d)) = todo.pop() {
        deepest = deepest.max(d);
        let n = nodes[i];
        if n.count == 0 {
            todo.push((n.first as usize, d + 1));
            todo.push((n.first as usize + 1, d + 1));
        }
    }
    deepest
}

impl GpuScene {
    /// Builds the BVH of `mesh` on the CPU and uploads it with the triangles and their
    /// alpha cut-outs.
    ///
    /// # Errors
    /// The BVH is too deep, or a buffer exceeds the adapter's limits.
    pub fn new(
        ctx: &GpuContext,
        mesh: &lgh_scene::Mesh,
        cutouts: Option<&lgh_scene::Cutouts>,
    ) -> Result<Self, GpuError> {
        let FlatBvh { nodes, tris, order } = flatten(mesh, cutouts)?;
        Ok(Self {
            nodes: ctx.storage("bvh nodes", &nodes)?,
            tris: ctx.storage("triangles", &tris)?,
            triangles: mesh.len(),
            order,
            surfaces: std::sync::OnceLock::new(),
        })
    }

    /// The surfaces of `world`'s triangles on the GPU (shading data in leaf order,
    /// materials, textures: [`GpuSurfaces`]), uploaded on first use. `world` must be the one
    /// this scene was uploaded for (the context's scene cache keys both by
    /// [`lgh_render::World::geometry_id`]).
    ///
    /// # Errors
    /// They do not fit the adapter's largest storage buffer.
    pub fn surfaces(
        &self,
        ctx: &GpuContext,
        world: &lgh_render::World,
    ) -> Result<Arc<GpuSurfaces>, GpuError> {
        self.surfaces
            .get_or_init(|| GpuSurfaces::new(ctx, world, &self.order).map(Arc::new))
            .clone()
    }
}

impl GpuScene {
    /// The first four bindings of a kernel that traces rays through the scene from the
    /// G-buffer's pixels (lgh, brute, direct light): its uniform `params`, the BVH nodes, the
    /// triangles and the G-buffer; the kernel's own buffers follow.
    #[must_use]
    pub fn bindings<'a>(
        &'a self,
        params: wgpu::BindingResource<'a>,
        gbuffer: &'a crate::gbuffer::GpuGBuffer,
    ) -> Vec<wgpu::BindingResource<'a>> {
        vec![
            params,
            self.nodes.as_entire_binding(),
            self.tris.as_entire_binding(),
            gbuffer.binding(),
        ]
    }
}
