// Sorts each cell's run by light index (insertion sort; runs are short: at most 71 lights
// on the test scenes at 1M VPLs), so that the draw visits them in the CPU's order. A run
// longer than P.n_cap is left alone and flagged in misc[0]: the representatives are then
// drawn on the CPU. P.n bounds the cells (the lights).

@group(0) @binding(1) var<storage, read> counts: array<u32>;
@group(0) @binding(2) var<storage, read> starts: array<u32>;
@group(0) @binding(3) var<storage, read> total: array<u32>;
@group(0) @binding(4) var<storage, read_write> runs: array<u32>;
@group(0) @binding(5) var<storage, read_write> misc: array<atomic<u32>>;

const CAP: u32 = 4096u;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let cells = min(total[0], P.n);
    for (var c = id.x; c < cells; c += groups.x * GROUP) {
        let a = starts[c];
        let n = counts[c];
        if (n > CAP) {
            atomicMax(&misc[0], n);
            continue;
        }
        for (var k = 1u; k < n; k++) {
            let x = runs[a + k];
            var m = k;
            while (m > 0u && runs[a + m - 1u] > x) {
                runs[a + m] = runs[a + m - 1u];
                m--;
            }
            runs[a + m] = x;
        }
    }
}
