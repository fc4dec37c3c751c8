// The light paths' numbers (lgh-core's qmc::PathSampler): path k takes point k mod 2^16 of
// a 4D Owen-scrambled Sobol sequence (Burley 2020, "Practical Hash-based Owen Scrambling",
// as the sobol_burley crate computes it on the CPU), one separately seeded sequence per
// group of four dimensions. Integer arithmetic throughout, so the numbers are the CPU's,
// bit for bit. Needs `tables` (the first 16 entries: the direction vectors of the first
// four Sobol dimensions, bit-reversed, one vec4 per bit from the top) and `group_seed`.

// sobol_burley's hash.
fn burley_hash(x: u32) -> u32 {
    var n = x ^ 0xe6fe3bebu;
    n ^= n >> 16u;
    n *= 0x7feb352du;
    n ^= n >> 15u;
    n *= 0x846ca68bu;
    n ^= n >> 16u;
    return n;
}

// The Laine-Karras style scramble of a bit-reversed integer (sobol_burley's
// owen_scramble_rev), four lanes at once.
fn owen_rev(x: vec4<u32>, scramble: vec4<u32>) -> vec4<u32> {
    var n = x;
    n ^= n * 0x3d20adeau;
    n += scramble;
    n *= (scramble >> vec4<u32>(16u)) | vec4<u32>(1u);
    n ^= n * 0x05526c56u;
    n ^= n * 0x53a22864u;
    return n;
}

// sobol_burley::sample_4d(index, 0, seed).
fn sobol_4d(index: u32, seed: u32) -> vec4<f32> {
    let shuffled = owen_rev(vec4<u32>(reverseBits(index)), vec4<u32>(burley_hash(seed ^ 0x79c68e4au))).x;
    var sobol = vec4<u32>(0u);
    for (var b = 0u; b < 16u; b++) {
        if (((shuffled >> (31u - b)) & 1u) != 0u) {
            sobol ^= tables[b];
        }
    }
    let s = vec4<u32>(seed * 0x9c8f2d3bu)
        ^ vec4<u32>(0x912f69bau, 0x174f18abu, 0x691e72cau, 0xb40cc1b8u);
    let h = vec4<u32>(burley_hash(s.x), burley_hash(s.y), burley_hash(s.z), burley_hash(s.w));
    let bits = reverseBits(owen_rev(sobol, h));
    return bitcast<vec4<f32>>((bits >> vec4<u32>(9u)) | vec4<u32>(0x3f800000u)) - vec4<f32>(1.0);
}

// One path's sampler: its point's index in its block, where its groups' seeds are
// (`group_seed`), the next group, and the current group's numbers.
struct PathSampler {
    index: u32,
    seeds: u32,
    group: u32,
    used: u32,
    values: vec4<f32>,
}

fn next_f32(s: ptr<function, PathSampler>) -> f32 {
    if ((*s).used == 4u) {
        (*s).values = sobol_4d((*s).index, group_seed((*s).seeds + (*s).group));
        (*s).group += 1u;
        (*s).used = 0u;
    }
    let v = (*s).values[(*s).used];
    (*s).used += 1u;
    return v;
}

fn next_2d(s: ptr<function, PathSampler>) -> vec2<f32> {
    let x = next_f32(s);
    return vec2<f32>(x, next_f32(s));
}
