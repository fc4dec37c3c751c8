// The frame's VPLs split by normal bin for a frame with one hierarchy per bin
// (`--normal-bins`), without reading them back: one bit per VPL in a bin-major bit array,
// bit i % 32 of word b x words + i / 32 set for VPL i of bin b (the array cleared before).
// The exclusive prefix sum of the words' population counts (crate::scan) then gives each
// VPL its place among the VPLs sorted by bin, in their own order within a bin, as the CPU's
// split keeps them (shaders/vpl_grid.wgsl writes them there). atomicOr does not depend on
// the order of the atomics, so neither does the result.

//
// The number of VPLs is read from the light paths' status (shaders/vpl_compact.wgsl), so
// that the split can be recorded in the submission that traces them, before it is known;
// the dispatch covers `capacity` VPLs, every one the buffer can hold.

struct Params {
    capacity: u32,
    words: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(2) var<storage, read_write> bits: array<atomic<u32>>;
// The light paths' status: kept paths of the last batch, VPLs, kept paths in all.
@group(0) @binding(3) var<storage, read> status: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= min(status[1], params.capacity)) {
        return;
    }
    let b = normal_bin(vpls[i].normal.xyz);
    atomicOr(&bits[b * params.words + i / 32u], 1u << (i % 32u));
}
