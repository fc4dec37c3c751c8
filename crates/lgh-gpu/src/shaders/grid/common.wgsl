// What the hierarchy build's kernels share (lgh_gpu::grid; Lin & Yuksel 2019 section 3.1).
// Resolution k has 2^k cells per axis of size h_top / 2^k: level l of a hierarchy of l_max
// levels is resolution l_max - l. Every build's vertices are numbered resolution by
// resolution, coarsest first, each in the CPU's vertex order (z, then y, then x).

// One dispatch's parameters (lgh_gpu::grid::GridParams).
struct GridParams {
    origin: vec3<f32>,
    h_top: f32,
    // Items of the dispatch (lights, words or vertices).
    n: u32,
    // Its resolution.
    k: u32,
    // Resolutions in use: 0..count.
    count: u32,
    // First word of resolution k's bit set, and of resolution k + 1's.
    word0: u32,
    fine_word0: u32,
    // First vertex of resolution k.
    vert0: u32,
    // The largest intensity component of the lights, and its reciprocal (0 if none).
    imax: f32,
    inv_imax: f32,
    // Which step of a kernel with several (cells.wgsl).
    step: u32,
    // The frame's seed (the representatives' draw).
    seed_lo: u32,
    seed_hi: u32,
    pad0: u32,
}

@group(0) @binding(0) var<uniform> P: GridParams;

// Each build kernel loops over its items with the stride of the whole dispatch (a dispatch
// has at most 65535 workgroups).
const GROUP: u32 = 64u;

// a / b correctly rounded: WGSL's division may be 2.5 ulp off, the CPU's is exact, and a
// light on a grid plane must get the CPU's fraction (zero) here too. One Newton step on the
// reciprocal and one on the quotient (Markstein).
fn div_rn(a: vec3<f32>, b: f32) -> vec3<f32> {
    var r = 1.0 / b;
    r = fma(fma(-b, r, 1.0), r, r);
    let rv = vec3<f32>(r);
    let q = a * rv;
    let e = fma(-q, vec3<f32>(b), a);
    return fma(e, rv, q);
}

// A point's cell at a resolution and its fraction in the cell, each in [0, 1].
struct Located {
    c: vec3<u32>,
    f: vec3<f32>,
}

// lgh_core's splat::locate at resolution k: h = h_top / 2^k exactly.
fn locate(p: vec3<f32>, k: u32) -> Located {
    let r = 1u << k;
    let u = div_rn(p - P.origin, ldexp(P.h_top, -i32(k)));
    let c = vec3<u32>(clamp(u, vec3<f32>(0.0), vec3<f32>(f32(r - 1u))));
    return Located(c, clamp(u - vec3<f32>(c), vec3<f32>(0.0), vec3<f32>(1.0)));
}

// Corner i (0..8) of a cell: x in bit 0, y in bit 1, z in bit 2.
fn corner(i: u32) -> vec3<u32> {
    return vec3<u32>(i & 1u, (i >> 1u) & 1u, i >> 2u);
}

// The trilinear weight of corner d for fraction f (lgh_core's splat::corner_weight).
fn corner_weight(f: vec3<f32>, d: vec3<u32>) -> f32 {
    let w = select(vec3<f32>(1.0) - f, f, d == vec3<u32>(1u));
    return w.x * w.y * w.z;
}

// Vertex v's number in a grid of r cells per axis (x fastest), and back.
fn vertex_key(v: vec3<u32>, r: u32) -> u32 {
    let s = r + 1u;
    return (v.z * s + v.y) * s + v.x;
}

fn key_vertex(key: u32, r: u32) -> vec3<u32> {
    let s = r + 1u;
    return vec3<u32>(key % s, (key / s) % s, key / (s * s));
}

// The two's complement of a 96-bit integer (words lo, mid, hi): the fixed-point sums of
// the splat (lgh_gpu::grid).
fn negate96(a: vec3<u32>) -> vec3<u32> {
    var v = ~a;
    v.x += 1u;
    let c0 = select(0u, 1u, v.x == 0u);
    v.y += c0;
    v.z += select(0u, 1u, c0 == 1u && v.y == 0u);
    return v;
}
