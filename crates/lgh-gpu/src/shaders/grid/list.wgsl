// Lists every marked vertex of the resolutions in use: keys[number] = its key in its
// resolution, from the bit sets and their scan (one invocation per word).

@group(0) @binding(1) var<storage, read> word_start: array<u32>;
@group(0) @binding(2) var<storage, read> bits: array<u32>;
@group(0) @binding(3) var<storage, read> prefix: array<u32>;
@group(0) @binding(4) var<storage, read_write> keys: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    for (var w = id.x; w < P.n; w += groups.x * GROUP) {
        var k = 0u;
        while (k + 1u < P.count && word_start[k + 1u] <= w) {
            k++;
        }
        var m = bits[w];
        var at = prefix[w];
        let base = (w - word_start[k]) * 32u;
        while (m != 0u) {
            keys[at] = base + firstTrailingBit(m);
            at++;
            m &= m - 1u;
        }
    }
}
