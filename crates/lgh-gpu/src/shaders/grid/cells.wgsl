// S_1's cells and the lights in each (for the representatives' draw), in three passes over
// the lights chosen by P.step: 0 marks each light's cell in a bit set; 1 counts the lights
// per marked cell (integer atomics: the counts do not depend on the order); 2 puts each
// light's index in its cell's run (the scan of the counts gives where runs start; the order
// within a run is the atomics', which `cell_sort` then fixes).

@group(0) @binding(1) var<storage, read> lights: array<f32>;
@group(0) @binding(2) var<storage, read_write> cell_bits: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read> cell_prefix: array<u32>;
@group(0) @binding(4) var<storage, read_write> counts: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read> starts: array<u32>;
@group(0) @binding(6) var<storage, read_write> fill: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> runs: array<u32>;

// The number of marked cell `key` (it is marked).
fn cell_number(key: u32) -> u32 {
    let w = key >> 5u;
    let m = atomicLoad(&cell_bits[w]);
    return cell_prefix[w] + countOneBits(m & ((1u << (key & 31u)) - 1u));
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let r = 1u << P.k;
    for (var i = id.x; i < P.n; i += groups.x * GROUP) {
        let p = vec3<f32>(lights[9u * i], lights[9u * i + 1u], lights[9u * i + 2u]);
        let c = locate(p, P.k).c;
        let key = (c.z * r + c.y) * r + c.x;
        if (P.step == 0u) {
            atomicOr(&cell_bits[key >> 5u], 1u << (key & 31u));
        } else if (P.step == 1u) {
            atomicAdd(&counts[cell_number(key)], 1u);
        } else {
            let cell = cell_number(key);
            runs[starts[cell] + atomicAdd(&fill[cell], 1u)] = i;
        }
    }
}
