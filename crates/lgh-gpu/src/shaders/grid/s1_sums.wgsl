// S_1's fixed-point sums as floats: per vertex W, P (3), Q (3), I (3), N (3) in a row of 16
// (the rows of the coarser levels follow from these by restriction).

@group(0) @binding(1) var<storage, read> acc: array<u32>;
@group(0) @binding(2) var<storage, read_write> sums: array<f32>;

// The 96-bit sum j as a float (negated as an integer first: no cancellation).
fn fixed(j: u32) -> f32 {
    var v = vec3<u32>(acc[3u * j], acc[3u * j + 1u], acc[3u * j + 2u]);
    let negative = (v.z >> 31u) == 1u;
    if (negative) {
        v = negate96(v);
    }
    let x = f32(v.x) * 5.421010862427522e-20 + f32(v.y) * 2.3283064365386963e-10 + f32(v.z);
    return select(x, -x, negative);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    for (var j = id.x; j < P.n; j += groups.x * GROUP) {
        let row = 16u * (P.vert0 + j);
        for (var q = 0u; q < 13u; q++) {
            var v = fixed(13u * j + q);
            if (q >= 7u && q < 10u) {
                v *= P.imax;
            }
            sums[row + q] = v;
        }
    }
}
