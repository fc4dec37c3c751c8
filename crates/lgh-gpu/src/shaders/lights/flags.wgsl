// 1 for each record the CPU keeps (a positive intensity), else 0: scanned into the records'
// shaded indices.

@group(0) @binding(0) var<uniform> params: LightParams;
@group(0) @binding(1) var<storage, read> src: array<u32>;
@group(0) @binding(2) var<storage, read_write> kept: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    for (var r = id.x; r < params.count; r += 64u * groups.x) {
        let i = float3(16u * r + 8u);
        kept[r] = select(0u, 1u, max(max(i.x, i.y), i.z) > 0.0);
    }
}
