// The unbiased estimate's lookup tables made on the GPU from what a hierarchy build holds
// (lgh_gpu::lgh::lookups): the vertex rows of every level (lgh_core's row_starts) and the
// descent's children with the running sums of their weights (lgh_core's Descent), the CPU's
// tables of the same grid, written into the loop's words. A build's records are level by
// level from S_1, each level in vertex order ((z, y, x), x fastest), the zero-intensity ones
// among them: record r, if kept, is grid light index[r] (the exclusive scan of the flags).

struct LookupParams {
    // Records.
    count: u32,
    l_max: u32,
    // Where the rows, the descent's starts and its children begin in the words.
    rows_base: u32,
    starts_base: u32,
    children_base: u32,
    // Row entries over all levels.
    row_entries: u32,
    _p0: u32,
    _p1: u32,
    // x: the first record of level l (l = 1..=l_max; l_max + 1: the record count); y: the
    // first row entry of level l (l_max + 1: row_entries).
    start: array<vec4<u32>, 12>,
}

@group(0) @binding(0) var<uniform> params: LookupParams;
@group(0) @binding(1) var<storage, read> records: array<u32>;
@group(0) @binding(2) var<storage, read> index: array<u32>;

const NO_RECORD: u32 = 0xffffffffu;
// The most children of one light: the 27 vertices around twice its vertex.
const MAX_CHILDREN: u32 = 27u;

fn record_vertex(r: u32) -> vec3<u32> {
    return vec3<u32>(records[16u * r], records[16u * r + 1u], records[16u * r + 2u]);
}

fn record_intensity(r: u32) -> vec3<f32> {
    let at = 16u * r + 8u;
    return vec3<f32>(bitcast<f32>(records[at]), bitcast<f32>(records[at + 1u]), bitcast<f32>(records[at + 2u]));
}

// Whether the CPU keeps record r (a positive intensity; lgh_gpu::grid's unpacking).
fn is_kept(r: u32) -> bool {
    let i = record_intensity(r);
    return max(max(i.x, i.y), i.z) > 0.0;
}

// Vertices per axis of level l.
fn level_side(l: u32) -> u32 {
    return (1u << (params.l_max - l)) + 1u;
}

// The level whose records hold record r.
fn record_level(r: u32) -> u32 {
    var l = 1u;
    while (l < params.l_max && r >= params.start[l + 1u].x) {
        l++;
    }
    return l;
}
