// Marks, at every resolution in use, the vertices a light gives a non-zero trilinear
// weight (the CPU's count_vertices), and finds the largest intensity component.

@group(0) @binding(1) var<storage, read> lights: array<f32>;
@group(0) @binding(2) var<storage, read> word_start: array<u32>;
@group(0) @binding(3) var<storage, read_write> bits: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> misc: array<atomic<u32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    for (var i = id.x; i < P.n; i += groups.x * GROUP) {
        let p = vec3<f32>(lights[9u * i], lights[9u * i + 1u], lights[9u * i + 2u]);
        let c = vec3<f32>(lights[9u * i + 3u], lights[9u * i + 4u], lights[9u * i + 5u]);
        // Non-negative floats order as their bits (intensities were validated).
        let m = max(c.x, max(c.y, c.z));
        atomicMax(&misc[0], select(0u, bitcast<u32>(m), m > 0.0));
        for (var k = 0u; k < P.count; k++) {
            let at = locate(p, k);
            let r = 1u << k;
            for (var j = 0u; j < 8u; j++) {
                let d = corner(j);
                if (corner_weight(at.f, d) > 0.0) {
                    let key = vertex_key(at.c + d, r);
                    atomicOr(&bits[word_start[k] + (key >> 5u)], 1u << (key & 31u));
                }
            }
        }
    }
}
