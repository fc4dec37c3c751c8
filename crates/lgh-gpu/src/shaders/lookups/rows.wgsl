// Where each vertex row of every level starts among the grid lights (lgh_core's
// row_starts): entry e of level l is the grid index of the first kept record of the level
// whose row (z side + y) is at least e, i.e. the kept records before it (the count of all
// kept records after the last); and that record, for the children's searches.

@group(0) @binding(3) var<storage, read> kept_total: array<u32>;
@group(0) @binding(4) var<storage, read_write> words: array<u32>;
@group(0) @binding(5) var<storage, read_write> row_records: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    for (var e = id.x; e < params.row_entries; e += 64u * groups.x) {
        var l = 1u;
        while (l < params.l_max && e >= params.start[l + 1u].y) {
            l++;
        }
        let row = e - params.start[l].y;
        let side = level_side(l);
        var lo = params.start[l].x;
        var hi = params.start[l + 1u].x;
        while (lo < hi) {
            let mid = (lo + hi) / 2u;
            let v = record_vertex(mid);
            if (v.z * side + v.y < row) {
                lo = mid + 1u;
            } else {
                hi = mid;
            }
        }
        row_records[e] = lo;
        words[params.rows_base + e] = select(kept_total[0], index[lo], lo < params.count);
    }
}
