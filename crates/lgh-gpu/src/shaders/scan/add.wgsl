// The last step of the prefix sum: each block's elements get the totals before the block.

@group(0) @binding(1) var<storage, read_write> dst: array<u32>;
@group(0) @binding(2) var<storage, read> blocks: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wid: vec3<u32>) {
    let add = blocks[wid.x];
    let base = wid.x * 1024u + lid.x * 4u;
    for (var j = 0u; j < 4u; j++) {
        if (base + j < P.n) {
            dst[base + j] += add;
        }
    }
}
