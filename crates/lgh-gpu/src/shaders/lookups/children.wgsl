// The children of a grid light of level l >= 2 (lgh_core's descent::for_each_child): the
// kept lights of level l - 1 at the 27 vertices around twice its vertex, in (z, y, x)
// order, each with the weight w lum(I_u), w the stencil's (1/2, 1, 1/2) per axis; those of
// zero weight left out, written as (grid index, bits of the running sum) into the record's
// 27 slots of `scratch` (which the kernel declares). A vertex is found as the CPU finds it:
// its row's records (the rows pass's), then its x among them.

@group(0) @binding(3) var<storage, read> row_records: array<u32>;

// The record at vertex u of level l, or NO_RECORD.
fn find_record(l: u32, u: vec3<u32>) -> u32 {
    let e = params.start[l].y + u.z * level_side(l) + u.y;
    var lo = row_records[e];
    var hi = row_records[e + 1u];
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        let x = records[16u * mid];
        if (x == u.x) {
            return mid;
        }
        if (x < u.x) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return NO_RECORD;
}

fn children(r: u32) -> u32 {
    let l = record_level(r);
    if (l < 2u || !is_kept(r)) {
        return 0u;
    }
    let v = vec3<i32>(record_vertex(r)) * 2;
    let side = i32(level_side(l - 1u));
    var n = 0u;
    var sum = 0.0;
    for (var dz = -1; dz <= 1; dz++) {
        for (var dy = -1; dy <= 1; dy++) {
            for (var dx = -1; dx <= 1; dx++) {
                let u = v + vec3<i32>(dx, dy, dz);
                if (min(min(u.x, u.y), u.z) < 0 || max(max(u.x, u.y), u.z) >= side) {
                    continue;
                }
                let c = find_record(l - 1u, vec3<u32>(u));
                if (c == NO_RECORD || !is_kept(c)) {
                    continue;
                }
                let stencil = select(0.5, 1.0, dx == 0) * select(0.5, 1.0, dy == 0) * select(0.5, 1.0, dz == 0);
                let w = stencil * luminance(record_intensity(c));
                if (w > 0.0) {
                    sum += w;
                    let at = 2u * (MAX_CHILDREN * (r - params.start[2].x) + n);
                    scratch[at] = index[c];
                    scratch[at + 1u] = bitcast<u32>(sum);
                    n++;
                }
            }
        }
    }
    return n;
}
