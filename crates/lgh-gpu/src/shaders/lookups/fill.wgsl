// The descent's tables: every kept record's children, from its 27 slots to its scanned
// offset, and where the next grid light's children start (grid light 0's: 0).

@group(0) @binding(3) var<storage, read> counts: array<u32>;
@group(0) @binding(4) var<storage, read> scratch: array<u32>;
@group(0) @binding(5) var<storage, read> offsets: array<u32>;
@group(0) @binding(6) var<storage, read_write> words: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    if (id.x == 0u) {
        words[params.starts_base] = 0u;
    }
    for (var r = id.x; r < params.count; r += 64u * groups.x) {
        if (!is_kept(r)) {
            continue;
        }
        let n = counts[r];
        let to = params.children_base + 2u * offsets[r];
        for (var e = 0u; e < 2u * n; e++) {
            words[to + e] = scratch[2u * MAX_CHILDREN * (r - params.start[2].x) + e];
        }
        words[params.starts_base + index[r] + 1u] = offsets[r] + n;
    }
}
