// Screen-tile binning of the shaded lights on the GPU: lgh-render's shading/tiles.rs (LGH 2019
// section 3.2; Tokuyoshi & Harada 2016 Algorithm 1), list for list the CPU's
// (`InterleavedBins::flatten`): list l is tile (tx, ty) of sub-image s under n x n
// interleaving, l = s tiles_x tiles_y + ty tiles_x + tx, and its lights ascend.
//
// The GPU has no infinities to rely on (WGSL lets a compiler assume there are none): empty
// tiles and slices, lights listed nowhere and lights of infinite reach are flags instead.

struct BinParams {
    width: u32,
    height: u32,
    // Interleaving n.
    n: u32,
    // Tile edge in full-resolution pixels (the sub-image tile times n).
    tile: u32,
    tiles_x: u32,
    tiles_y: u32,
    lists: u32,
    lights: u32,
    // Where the lights of the lists start in the lists buffer (after the lists + 1 starts).
    lights_base: u32,
    // Where the pixels sorted by list start, and where each pixel's list starts.
    order_base: u32,
    list_base: u32,
    // 1 where pixels fill their cut recombination windows: the bounds count the guests.
    fill: u32,
}

// Depth slices of a tile (lgh-render's DEPTH_SLICES).
const SLICES: u32 = 4u;

// What a tile sees (lgh-render's TileBounds).
struct TileBounds {
    // zmin, zmax; z: 1 if the tile sees a surface.
    z: vec4<f32>,
    // Per slice: the low corner of its box (w: 1 if the slice holds a point).
    lo: array<vec4<f32>, 4>,
    // The high corner (w: the spread, the largest |n_x - n_s|).
    hi: array<vec4<f32>, 4>,
    // The slice's first normal n_s (w: the plane, the lowest n_s . x).
    normal: array<vec4<f32>, 4>,
}

// Light flags beside the sub-image (the low 16 bits).
const LISTED_NOWHERE: u32 = 0x10000u;
const REACHES_EVERYWHERE: u32 = 0x20000u;

// The tile (tx, ty) and sub-image s of list l.
fn list_tile(l: u32) -> vec3<u32> {
    let per = P.tiles_x * P.tiles_y;
    let t = l % per;
    return vec3<u32>(t % P.tiles_x, t / P.tiles_x, l / per);
}
