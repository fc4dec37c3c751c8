// One pass of the edge-avoiding a-trous filter of the ratio estimator's S and U (Dammertz et
// al. 2010; LGH 2019 section 3.3; lgh-render's denoise/atrous): every pixel that sees a
// surface sums its 5 x 5 taps, 2^pass pixels apart, with the B3-spline weights times
// exp(-(dg^2 inv_c + |dN|^2 inv_n + |dX|^2 inv_p + da^2 inv_a)) (g the guide, the ratio
// lum(S) / lum(U); a the key of the unshadowed sum A, ln lum(A), in U's w), the same weight
// for S and U, and writes the normalised sums and their new guide. A tap
// whose exponent reaches 40 weighs nothing, as on the CPU. One invocation a pixel; each sums
// its taps in a fixed order.

struct Params {
    width: u32,
    height: u32,
    step: u32,
    // vec4s per pixel in `geo`: the position (w: 1 where it sees a surface), then the normal.
    geo_stride: u32,
    inv_c: f32,
    inv_n: f32,
    inv_p: f32,
    inv_a: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
// Per pixel, params.geo_stride vec4s: position (w: 1 where it sees a surface), normal.
@group(0) @binding(1) var<storage, read> geo: array<vec4<f32>>;
// Per pixel: S (w: the guide), U (w: the key of A).
@group(0) @binding(2) var<storage, read> src: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> dst: array<vec4<f32>>;

const NEGLIGIBLE: f32 = 40.0;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.x;
    let w = params.width;
    if (p >= w * params.height) {
        return;
    }
    if (geo[params.geo_stride * p].w == 0.0) {
        dst[2u * p] = src[2u * p];
        dst[2u * p + 1u] = src[2u * p + 1u];
        return;
    }
    var h1 = array<f32, 5>(1.0 / 16.0, 1.0 / 4.0, 3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0);
    let x = i32(p % w);
    let y = i32(p / w);
    let xp = geo[params.geo_stride * p].xyz;
    let np = geo[params.geo_stride * p + 1u].xyz;
    let gp = src[2u * p].w;
    let ap = src[2u * p + 1u].w;
    let step = i32(params.step);
    var s = vec3<f32>(0.0);
    var u = vec3<f32>(0.0);
    var total = 0.0;
    for (var j = 0; j < 5; j++) {
        let qy = y + (j - 2) * step;
        if (qy < 0 || qy >= i32(params.height)) {
            continue;
        }
        for (var i = 0; i < 5; i++) {
            let qx = x + (i - 2) * step;
            if (qx < 0 || qx >= i32(w)) {
                continue;
            }
            let q = u32(qy) * w + u32(qx);
            let gq = geo[params.geo_stride * q];
            if (gq.w == 0.0) {
                continue;
            }
            let dg = gp - src[2u * q].w;
            let dn = np - geo[params.geo_stride * q + 1u].xyz;
            let dx = xp - gq.xyz;
            let da = ap - src[2u * q + 1u].w;
            let e = dg * dg * params.inv_c + dot(dn, dn) * params.inv_n + dot(dx, dx) * params.inv_p
                + da * da * params.inv_a;
            if (!(e < NEGLIGIBLE)) {
                continue;
            }
            let wt = h1[i] * h1[j] * exp(-e);
            s += wt * src[2u * q].xyz;
            u += wt * src[2u * q + 1u].xyz;
            total += wt;
        }
    }
    s = s / total;
    u = u / total;
    dst[2u * p] = vec4<f32>(s, filter_guide(s, u));
    dst[2u * p + 1u] = vec4<f32>(u, ap);
}
