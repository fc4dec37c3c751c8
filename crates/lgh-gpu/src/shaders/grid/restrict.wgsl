// A coarser level by exact restriction (lgh_core's Construction::Restrict): a hat of
// spacing 2h is the sum of the hats of spacing h at the fine vertices 2V + d, d in
// {-1, 0, 1}^3, weighted (1/2, 1, 1/2) per axis, so coarse vertex V's sums are its fine
// neighbours' sums so weighted, with their moments moved to V and to coarse cells:
// x_c = (x_f + d) / 2. Each coarse vertex gathers its 27 neighbours in a fixed order.

@group(0) @binding(1) var<storage, read> keys: array<u32>;
@group(0) @binding(2) var<storage, read> bits: array<u32>;
@group(0) @binding(3) var<storage, read> prefix: array<u32>;
@group(0) @binding(4) var<storage, read_write> sums: array<f32>;

fn row3(at: u32) -> vec3<f32> {
    return vec3<f32>(sums[at], sums[at + 1u], sums[at + 2u]);
}

fn put3(at: u32, v: vec3<f32>) {
    sums[at] = v.x;
    sums[at + 1u] = v.y;
    sums[at + 2u] = v.z;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let r = 1u << P.k;
    let fine = 2u * r;
    for (var j = id.x; j < P.n; j += groups.x * GROUP) {
        let g = P.vert0 + j;
        let v = vec3<i32>(key_vertex(keys[g], r));
        var w = 0.0;
        var p = vec3<f32>(0.0);
        var q = vec3<f32>(0.0);
        var c = vec3<f32>(0.0);
        var n = vec3<f32>(0.0);
        for (var t = 0u; t < 27u; t++) {
            let d = vec3<i32>(i32(t % 3u), i32((t / 3u) % 3u), i32(t / 9u)) - vec3<i32>(1);
            let x = 2 * v + d;
            if (any(x < vec3<i32>(0)) || any(x > vec3<i32>(i32(fine)))) {
                continue;
            }
            let gf = find(vertex_key(vec3<u32>(x), fine), P.fine_word0);
            if (gf == NONE) {
                continue;
            }
            let dd = vec3<f32>(d);
            let a = select(vec3<f32>(1.0), vec3<f32>(0.5), d != vec3<i32>(0));
            let omega = a.x * a.y * a.z;
            let at = 16u * gf;
            let wf = sums[at];
            let pf = row3(at + 1u);
            w += omega * wf;
            p += omega * 0.5 * (pf + dd * wf);
            q += omega * 0.25 * (row3(at + 4u) + 2.0 * dd * pf + dd * dd * wf);
            c += omega * row3(at + 7u);
            n += omega * row3(at + 10u);
        }
        let at = 16u * g;
        sums[at] = w;
        put3(at + 1u, p);
        put3(at + 4u, q);
        put3(at + 7u, c);
        put3(at + 10u, n);
    }
}
