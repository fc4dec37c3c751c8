// 1 for each emitted record the CPU keeps (a positive intensity: the read-back drops the
// others), 0 otherwise: their exclusive scan is each record's grid index.

@group(0) @binding(1) var<storage, read> records: array<u32>;
@group(0) @binding(2) var<storage, read_write> kept: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    for (var r = id.x; r < P.n; r += groups.x * GROUP) {
        let at = 16u * r + 8u;
        let i = vec3<f32>(bitcast<f32>(records[at]), bitcast<f32>(records[at + 1u]), bitcast<f32>(records[at + 2u]));
        kept[r] = select(0u, 1u, max(i.x, max(i.y, i.z)) > 0.0);
    }
}
