// The children of every record (0 for S_1 and dropped records): their number, scanned
// into where each one's children start, and the children themselves (grid index, bits of
// the running sum) in 27 slots per record of level >= 2, compacted by `fill`.

@group(0) @binding(4) var<storage, read_write> counts: array<u32>;
@group(0) @binding(5) var<storage, read_write> scratch: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    for (var r = id.x; r < params.count; r += 64u * groups.x) {
        counts[r] = children(r);
    }
}
