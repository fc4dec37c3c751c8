// 1 / p as the CPU computes `1.0 / p as f32` (p converted to f32 rounded to nearest even,
// then divided, correctly rounded), for any u32 p > 0, by integer arithmetic: WGSL's
// division may be 2.5 ulp off, and refining it with fma needs a fused fma, which lavapipe's
// is not. (A VPL's flux scale, one over the light paths, must be the CPU's bit for bit.)
fn recip_rn(p: u32) -> f32 {
    // p rounded to 24 significant bits: m 2^s.
    var e = firstLeadingBit(p);
    var m = p;
    var s = 0u;
    if (e >= 24u) {
        s = e - 23u;
        m = p >> s;
        let r = p & ((1u << s) - 1u);
        let half = 1u << (s - 1u);
        if (r > half || (r == half && (m & 1u) == 1u)) {
            m += 1u;
        }
        e = firstLeadingBit(m);
    }
    if (m == (1u << e)) {
        return ldexp(1.0, -i32(e + s));
    }
    // 2^e < m < 2^(e+1): q = floor(2^(e+24) / m) has 24 bits; rounded to nearest even by
    // its remainder; 1 / m = q 2^-(e+24), exactly representable.
    var rem = 1u << e;
    var q = 0u;
    for (var k = 0u; k < 24u; k += 1u) {
        rem = 2u * rem;
        q = 2u * q;
        if (rem >= m) {
            rem -= m;
            q += 1u;
        }
    }
    if (2u * rem > m || (2u * rem == m && (q & 1u) == 1u)) {
        q += 1u;
    }
    return ldexp(f32(q), -i32(e + 24u + s));
}
