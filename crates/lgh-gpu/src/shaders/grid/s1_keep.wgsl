// 1 for each S_1 vertex whose light is kept (non-zero intensity, as `emit` writes it and the
// read-back keeps it), 0 otherwise: their scan numbers the S_1 lights as the grid does.

@group(0) @binding(1) var<storage, read> sums: array<f32>;
@group(0) @binding(2) var<storage, read_write> keep: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    for (var j = id.x; j < P.n; j += groups.x * GROUP) {
        let at = 16u * (P.vert0 + j) + 7u;
        let c = vec3<f32>(sums[at], sums[at + 1u], sums[at + 2u]);
        keep[j] = select(0u, 1u, max(c.x, max(c.y, c.z)) > 0.0);
    }
}
