// The S_1 lights' representatives (lgh_core's representative::s1_representatives, the
// same draw): SLOTS input lights per S_1 light in proportion to w_1(p_i) lum(I_i) over the
// lights of the 8 cells around its vertex (corner by corner, each cell's lights by index),
// stratified: one uniform u and offset o from the CPU's hash of (seed, 1, j), slot
// (s + o) mod SLOTS takes the light where the running total first exceeds
// (s + u) / SLOTS of the total. Two passes over the lights: the total, then the slots.

@group(0) @binding(1) var<storage, read> lights: array<f32>;
@group(0) @binding(2) var<storage, read> keys: array<u32>;
@group(0) @binding(3) var<storage, read> keep: array<u32>;
@group(0) @binding(4) var<storage, read> numbers: array<u32>;
@group(0) @binding(5) var<storage, read> cell_bits: array<u32>;
@group(0) @binding(6) var<storage, read> cell_prefix: array<u32>;
@group(0) @binding(7) var<storage, read> counts: array<u32>;
@group(0) @binding(8) var<storage, read> starts: array<u32>;
@group(0) @binding(9) var<storage, read> runs: array<u32>;
@group(0) @binding(10) var<storage, read_write> slots: array<u32>;

const SLOTS: u32 = 16u;
// Bits of the uniform: 24 - log2(SLOTS), as the CPU's U_BITS.
const U_BITS: u32 = 20u;

// 64-bit integers as (low, high) words, for the CPU's hash (lgh_core::rng::hash).
fn mul32(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let mid = (p00 >> 16u) + (p01 & 0xffffu) + (p10 & 0xffffu);
    return vec2<u32>((p00 & 0xffffu) | (mid << 16u), a1 * b1 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u));
}

fn mul64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let p = mul32(a.x, b.x);
    return vec2<u32>(p.x, p.y + a.x * b.y + a.y * b.x);
}

fn add64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    return vec2<u32>(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

fn shr64(a: vec2<u32>, n: u32) -> vec2<u32> {
    return vec2<u32>((a.x >> n) | (a.y << (32u - n)), a.y >> n);
}

// lgh_core::rng::mix64 (SplitMix64's finaliser).
fn mix64(z0: vec2<u32>) -> vec2<u32> {
    var z = mul64(z0 ^ shr64(z0, 30u), vec2<u32>(0x1ce4e5b9u, 0xbf58476du));
    z = mul64(z ^ shr64(z, 27u), vec2<u32>(0x133111ebu, 0x94d049bbu));
    return z ^ shr64(z, 31u);
}

const GOLDEN: vec2<u32> = vec2<u32>(0x7f4a7c15u, 0x9e3779b9u);

fn hash3(a: vec2<u32>, b: vec2<u32>, c: vec2<u32>) -> vec2<u32> {
    var h = GOLDEN;
    h = mix64(h ^ add64(a, GOLDEN));
    h = mix64(h ^ add64(b, GOLDEN));
    h = mix64(h ^ add64(c, GOLDEN));
    return h;
}

// The lights of the cell whose corner d is vertex v: (first, count) in `runs`.
fn cell_run(v: vec3<u32>, d: vec3<u32>, r: u32) -> vec2<u32> {
    if (any(v < d) || any(v - d >= vec3<u32>(r))) {
        return vec2<u32>(0u);
    }
    let c = v - d;
    let key = (c.z * r + c.y) * r + c.x;
    let w = key >> 5u;
    let m = cell_bits[w];
    let b = key & 31u;
    if (((m >> b) & 1u) == 0u) {
        return vec2<u32>(0u);
    }
    let cell = cell_prefix[w] + countOneBits(m & ((1u << b) - 1u));
    return vec2<u32>(starts[cell], counts[cell]);
}

// Light i's weight at corner d of its cell: w_1(p_i) lum(I_i).
fn weight(i: u32, d: vec3<u32>) -> f32 {
    let p = vec3<f32>(lights[9u * i], lights[9u * i + 1u], lights[9u * i + 2u]);
    let c = vec3<f32>(lights[9u * i + 3u], lights[9u * i + 4u], lights[9u * i + 5u]);
    return corner_weight(locate(p, P.k).f, d) * luminance(c);
}

// What a walk over the lights of a vertex's 8 cells found: their total weight, the last
// light with a weight, and the slots filled.
struct Walk {
    total: f32,
    last: u32,
    filled: u32,
}

// Walks the lights of vertex v's 8 cells (corner by corner, each cell's by index) with
// their weights; with `assign`, fills the slots from `out` on: slot (s + o) mod SLOTS takes
// the first light where the running total exceeds (s + u) / SLOTS of `total`.
fn walk(v: vec3<u32>, r: u32, assign: bool, total: f32, u: f32, o: u32, out: u32) -> Walk {
    var running = 0.0;
    var last = 0xffffffffu;
    var s = 0u;
    for (var corner_i = 0u; corner_i < 8u; corner_i++) {
        let d = corner(corner_i);
        let run = cell_run(v, d, r);
        for (var t = 0u; t < run.y; t++) {
            let i = runs[run.x + t];
            let w = weight(i, d);
            if (w > 0.0) {
                running += w;
                last = i;
                while (assign && s < SLOTS && running > (f32(s) + u) * (1.0 / f32(SLOTS)) * total) {
                    slots[out + (s + o) % SLOTS] = i;
                    s++;
                }
            }
        }
    }
    return Walk(running, last, s);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let r = 1u << P.k;
    for (var g = id.x; g < P.n; g += groups.x * GROUP) {
        if (keep[g] == 0u) {
            continue;
        }
        let j = numbers[g];
        let v = key_vertex(keys[P.vert0 + g], r);
        let out = SLOTS * j;
        let all = walk(v, r, false, 0.0, 0.0, 0u, out);
        if (all.last == 0xffffffffu) {
            for (var s = 0u; s < SLOTS; s++) {
                slots[out + s] = 0xffffffffu;
            }
            continue;
        }
        let bits = hash3(vec2<u32>(P.seed_lo, P.seed_hi), vec2<u32>(1u, 0u), vec2<u32>(j, 0u));
        let u = f32(bits.y >> (32u - U_BITS)) * (1.0 / f32(1u << U_BITS));
        let o = bits.x & (SLOTS - 1u);
        for (var s = walk(v, r, true, all.total, u, o, out).filled; s < SLOTS; s++) {
            slots[out + (s + o) % SLOTS] = all.last;
        }
    }
}
