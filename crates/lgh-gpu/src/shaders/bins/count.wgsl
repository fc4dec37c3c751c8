// Counts every list's lights (integer adds: the counts do not depend on the order).

@group(0) @binding(5) var<storage, read_write> counts: array<atomic<u32>>;

fn listed(i: u32, l: u32) {
    atomicAdd(&counts[l], 1u);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    visit_listings(id.x, nw.x * 64u);
}
