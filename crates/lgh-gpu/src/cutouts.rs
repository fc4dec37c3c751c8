//! Alpha cut-outs on the GPU: [`lgh_scene::Cutouts`] packed after the triangles in the BVH's
//! triangle buffer, which `shaders/bvh.wgsl`'s `covers` reads with the CPU's arithmetic
//! (docs/design.md, "Alpha cut-outs"). No kernel's bindings change: every kernel that traces
//! rays already reads that buffer.
//!
//! Layout, in `vec4` slots after the 3 T triangle corners (T triangles, leaf order):
//! - the first corner's `w` of a triangle with a cut-out holds the slot of its record as
//!   bits (0: opaque; records come after the triangles, so no record is at slot 0);
//! - a record: its corners' texture coordinates (uv0, uv1), then (uv2, the slot of its
//!   cut-out as bits, 0);
//! - a cut-out: (width, height, wrap u | wrap v << 2, the slot of its first texel word) as
//!   bits, then (factor, cutoff, 1 if it reads a texture else 0, 0);
//! - a texture's alphas: 8 bits each, 4 a word, 16 a slot, row-major from the top row.

use glam::Vec4;
use lgh_scene::Cutouts;

/// `f32` slots holding `u32` bits.
fn bits(u: u32) -> f32 {
    f32::from_bits(u)
}

/// Appends the records of `cutouts` to `tris` (the triangles of the mesh in leaf order,
/// three corners each; `order` the mesh's index of each) and marks the triangles that have
/// one.
pub(crate) fn append(tris: &mut Vec<Vec4>, order: &[u32], cutouts: &Cutouts) {
    // The textures' alphas first, each once.
    let mut texel_slot = Vec::with_capacity(cutouts.textures().len());
    for t in cutouts.textures() {
        texel_slot.push(tris.len() as u32);
        for chunk in t.alpha.chunks(16) {
            let mut words = [0u32; 4];
            for (i, &a) in chunk.iter().enumerate() {
                words[i / 4] |= u32::from(a) << (8 * (i % 4));
            }
            tris.push(Vec4::from_array(words.map(bits)));
        }
    }
    // The cut-outs.
    let mut cut_slot = Vec::with_capacity(cutouts.cutouts().len());
    for c in cutouts.cutouts() {
        cut_slot.push(tris.len() as u32);
        // A texture without alpha reads 1 everywhere, as no texture does.
        let texture = c.texture.filter(|&t| {
            cutouts
                .textures()
                .get(t as usize)
                .is_some_and(|t| t.has_alpha())
        });
        let (w, h, first) = texture.map_or((1, 1, 0), |t| {
            let tex = &cutouts.textures()[t as usize];
            (tex.width, tex.height, texel_slot[t as usize])
        });
        let wrap = lgh_scene::texture::Wrap::pair_code(c.wrap);
        tris.push(Vec4::new(bits(w), bits(h), bits(wrap), bits(first)));
        let textured = if texture.is_some() { 1.0 } else { 0.0 };
        tris.push(Vec4::new(c.factor, c.cutoff, textured, 0.0));
    }
    // The records, in leaf order.
    for (leaf, &t) in order.iter().enumerate() {
        let Some((uv, k)) = cutouts.triangle(t) else {
            continue;
        };
        tris[3 * leaf].w = bits(tris.len() as u32);
        tris.push(Vec4::new(uv[0].x, uv[0].y, uv[1].x, uv[1].y));
        tris.push(Vec4::new(uv[2].x, uv[2].y, bits(cut_slot[k]), 0.0));
    }
}
