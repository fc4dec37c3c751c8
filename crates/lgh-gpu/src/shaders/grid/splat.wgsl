// The trilinear splat of the lights onto S_1 (resolution P.k; LGH 2019 section 3.1): each
// light adds to the 8 vertices of its cell its weight w, w (x - v), w (x - v)^2 per axis
// (x - v: its offset from the vertex, in cells), w I and w n. WGSL has no float atomics,
// and float sums would depend on the order of the adds: the sums are 96-bit fixed point
// (32 integer and 64 fraction bits; intensity in units of the largest component), added
// with three 32-bit integer atomics and carries, so that they are exact and the same
// whatever the order. 64 fraction bits keep the moments of a vertex that a light reaches
// with a weight of 1e-9 (a corner across its cell) to 1e-10 of themselves; 32 did not.

@group(0) @binding(1) var<storage, read> lights: array<f32>;
@group(0) @binding(2) var<storage, read> bits: array<u32>;
@group(0) @binding(3) var<storage, read> prefix: array<u32>;
@group(0) @binding(4) var<storage, read_write> acc: array<atomic<u32>>;

// |t| (below 2^32) in fixed point: integer part, first and second 32 fraction bits (each
// step exact in f32: subtracting the floor and scaling by 2^32).
fn to_fixed(a: f32) -> vec3<u32> {
    let hi = floor(a);
    let m = (a - hi) * 4294967296.0;
    let mid = floor(m);
    return vec3<u32>(u32((m - mid) * 4294967296.0), u32(mid), u32(hi));
}

// Adds t to the 96-bit sum j (words lo, mid, hi; two's complement across the three).
fn add_fixed(j: u32, t: f32) {
    var v = to_fixed(abs(t));
    if (t < 0.0) {
        v = negate96(v);
    }
    let old0 = atomicAdd(&acc[3u * j], v.x);
    let c0 = select(0u, 1u, old0 + v.x < old0);
    let a1 = v.y + c0;
    let wrapped = select(0u, 1u, a1 < v.y);
    let old1 = atomicAdd(&acc[3u * j + 1u], a1);
    let c1 = select(0u, 1u, old1 + a1 < old1) + wrapped;
    atomicAdd(&acc[3u * j + 2u], v.z + c1);
}

fn add3(j: u32, t: vec3<f32>) {
    add_fixed(j, t.x);
    add_fixed(j + 1u, t.y);
    add_fixed(j + 2u, t.z);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let r = 1u << P.k;
    for (var i = id.x; i < P.n; i += groups.x * GROUP) {
        let p = vec3<f32>(lights[9u * i], lights[9u * i + 1u], lights[9u * i + 2u]);
        let c = vec3<f32>(lights[9u * i + 3u], lights[9u * i + 4u], lights[9u * i + 5u]);
        let n = vec3<f32>(lights[9u * i + 6u], lights[9u * i + 7u], lights[9u * i + 8u]);
        let at = locate(p, P.k);
        for (var j = 0u; j < 8u; j++) {
            let d = corner(j);
            let w = corner_weight(at.f, d);
            if (w > 0.0) {
                let g = find(vertex_key(at.c + d, r), P.word0);
                if (g != NONE) {
                    let s = 13u * (g - P.vert0);
                    let x = at.f - vec3<f32>(d);
                    add_fixed(s, w);
                    add3(s + 1u, w * x);
                    add3(s + 4u, w * x * x);
                    add3(s + 7u, w * c * P.inv_imax);
                    add3(s + 10u, w * n);
                }
            }
        }
    }
}
