// Each pixel's list, and the pixels sorted by list (stably: by pixel within a list), as the
// CPU's `FlatBins::list` and lgh-gpu's `pixel_order`, from the image's shape alone: list l's
// pixels start after those of every list before it, whose counts are counts of columns and
// rows of one phase.

@group(0) @binding(0) var<uniform> P: BinParams;
@group(0) @binding(1) var<storage, read_write> lists: array<u32>;

// The integers in [0, a) congruent to r modulo n.
fn phase_count(a: u32, r: u32) -> u32 {
    if (a <= r) {
        return 0u;
    }
    return (a - r + P.n - 1u) / P.n;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    let pixels = P.width * P.height;
    for (var p = id.x; p < pixels; p += nw.x * 64u) {
        let x = p % P.width;
        let y = p / P.width;
        let sx = x % P.n;
        let sy = y % P.n;
        let s = sy * P.n + sx;
        let tx = x / P.tile;
        let ty = y / P.tile;
        let l = s * P.tiles_x * P.tiles_y + ty * P.tiles_x + tx;
        lists[P.list_base + p] = l;
        // The pixels of the sub-images before s.
        var start = 0u;
        for (var q = 0u; q < s; q++) {
            start += phase_count(P.width, q % P.n) * phase_count(P.height, q / P.n);
        }
        // Then the rows of tiles above, then the tiles to the left in this row of tiles.
        let rows_above = phase_count(ty * P.tile, sy);
        let rows = phase_count(min((ty + 1u) * P.tile, P.height), sy) - rows_above;
        let cols_left = phase_count(tx * P.tile, sx);
        let cols = phase_count(min((tx + 1u) * P.tile, P.width), sx) - cols_left;
        start += phase_count(P.width, sx) * rows_above + rows * cols_left;
        let rank = (y - ty * P.tile - sy) / P.n * cols + (x - tx * P.tile - sx) / P.n;
        lists[P.order_base + start + rank] = p;
    }
}
