// The edge resolve of a shown frame (lgh-render's passes::edge_aa::EdgeResolve::apply) on
// its composed image. Mode 0: each edge pixel's resolved radiance, the sum over its 3 x 3
// neighbours (row by row) of the neighbour's radiance times the number of its sub-pixel
// samples that took it, times 1 / samples; mode 1: written over the image (after every
// edge pixel read the image as it was).

struct Params {
    edges: u32,
    width: u32,
    height: u32,
    mode: u32,
    inv_samples: f32,
    _p0: u32,
    _p1: u32,
    _p2: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
// Per edge pixel: its index, then the nine counts, one byte each, four to a word.
@group(0) @binding(1) var<storage, read> edges: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read_write> image: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> resolved: array<vec4<f32>>;
// The number of edge pixels in the list (its first word): `params.edges` bounds the
// dispatch, which for a list found on the GPU is the image's pixels.
@group(0) @binding(4) var<storage, read> edge_count: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let e = id.x;
    if (e >= min(params.edges, edge_count[0])) {
        return;
    }
    let edge = edges[e];
    let p = edge.x;
    if (params.mode == 1u) {
        image[p] = resolved[e];
        return;
    }
    let x = i32(p % params.width);
    let y = i32(p / params.width);
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < 9u; k++) {
        let count = (edge[1u + k / 4u] >> (8u * (k % 4u))) & 0xffu;
        let nx = x + i32(k % 3u) - 1;
        let ny = y + i32(k / 3u) - 1;
        let inside = nx >= 0 && ny >= 0 && nx < i32(params.width) && ny < i32(params.height);
        if (count > 0u && inside) {
            sum = sum + image[u32(ny) * params.width + u32(nx)].xyz * f32(count);
        }
    }
    resolved[e] = vec4<f32>(sum * params.inv_samples, 0.0);
}
