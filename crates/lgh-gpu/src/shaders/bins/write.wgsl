// Writes every light into the lists it is listed in, at its list's start plus a slot from an
// atomic cursor: the order within a list is the scheduler's until `sort.wgsl` sorts it.

@group(0) @binding(5) var<storage, read_write> cursors: array<atomic<u32>>;
// The lists buffer: the lists' starts, then their lights (from P.lights_base).
@group(0) @binding(6) var<storage, read_write> lists: array<u32>;

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
                    let slot = atomicAdd(&cursors[l], 1u);
                    lists[P.lights_base + lists[l] + slot] = i;
                }
            }
        }
    }
}
