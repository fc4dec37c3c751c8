// The cut and compaction of a batch of light paths (lgh-render's generate_vpls keeps the
// paths in order up to the first one that brings the VPLs to the target): path k of the
// batch is kept if the VPLs before it, `done` from earlier batches plus its exclusive prefix
// sum, are fewer than the target; its VPLs go to out[done + prefix[k] + j]. The last kept
// path writes the batch's kept paths, the VPL count after it and the paths kept by all
// batches so far to status (one writer; path 0 is always kept, so every batch writes it):
// what follows the paths in the same submission (shaders/vpl_grid.wgsl) reads them there.

struct Params {
    paths: u32,
    bounces: u32,
    done: u32,
    target_count: u32,
    // The paths kept by the batches before (the number of the batch's first path).
    first: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> slots: array<Vpl>;
@group(0) @binding(2) var<storage, read> counts: array<u32>;
@group(0) @binding(3) var<storage, read> prefix: array<u32>;
@group(0) @binding(4) var<storage, read_write> out: array<Vpl>;
@group(0) @binding(5) var<storage, read_write> status: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if (k >= params.paths) {
        return;
    }
    let base = params.done + prefix[k];
    if (base >= params.target_count) {
        return;
    }
    let n = counts[k];
    for (var j = 0u; j < n; j++) {
        out[base + j] = slots[k * params.bounces + j];
    }
    let next_kept = k + 1u < params.paths && params.done + prefix[k + 1u] < params.target_count;
    if (!next_kept) {
        status[0] = k + 1u;
        status[1] = base + n;
        status[2] = params.first + k + 1u;
    }
}
