// Counts every list's lights (integer adds: the counts do not depend on the order).

@group(0) @binding(5) var<storage, read_write> counts: array<atomic<u32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    for (var i = id.x; i < P.lights; i += nw.x * 64u) {
        let s = light_span(i);
        let c = spheres[i].xyz;
        let r = spheres[i].w;
        for (var ty = s.lo.y; ty <= s.hi.y; ty++) {
            for (var tx = s.lo.x; tx <= s.hi.x; tx++) {
                let l = list_of(i, tx, ty);
                if (may_reach(bounds[l], s, c, r)) {
                    atomicAdd(&counts[l], 1u);
                }
            }
        }
    }
}
