// Writes every light into the lists it is listed in, at its list's start plus a slot from an
// atomic cursor: the order within a list is the scheduler's until `sort.wgsl` sorts it.

@group(0) @binding(5) var<storage, read_write> cursors: array<atomic<u32>>;
// The lists buffer: the lists' starts, then their lights (from P.lights_base).
@group(0) @binding(6) var<storage, read_write> lists: array<u32>;

fn listed(i: u32, l: u32) {
    let slot = atomicAdd(&cursors[l], 1u);
    lists[P.lights_base + lists[l] + slot] = i;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    visit_listings(id.x, nw.x * 64u);
}
