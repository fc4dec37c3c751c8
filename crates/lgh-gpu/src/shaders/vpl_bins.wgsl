// The frame's VPLs split by normal bin for a frame with one hierarchy per bin
// (`--normal-bins`), without reading them back: one bit per VPL in a bin-major bit array,
// bit i % 32 of word b x words + i / 32 set for VPL i of bin b (the array cleared before).
// The exclusive prefix sum of the words' population counts (crate::scan) then gives each
// VPL its place among the VPLs sorted by bin, in their own order within a bin, as the CPU's
// split keeps them (shaders/vpl_grid.wgsl writes them there). atomicOr does not depend on
// the order of the atomics, so neither does the result.

struct Params {
    count: u32,
    words: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(2) var<storage, read_write> bits: array<atomic<u32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= params.count) {
        return;
    }
    let b = normal_bin(vpls[i].normal.xyz);
    atomicOr(&bits[b * params.words + i / 32u], 1u << (i % 32u));
}
