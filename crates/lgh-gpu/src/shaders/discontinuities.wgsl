// The jumps the interleaving blur stops at (lgh-render's shading/interleave, discontinuities):
// per pixel, bit 1 if it jumps to its neighbour at (1, 0), bit 2 to the one at (0, 1): exactly
// one of the two sees a surface, or the depth differs by more than z_diff times the local
// depth slope (the larger over the axes of the smaller one-sided difference to a neighbour
// that sees a surface), or the normals by more than n_diff in 1 - n . n'; and bits 4 and 8
// the same with a_n_diff for the normals (the recombination of A).

struct Params {
    width: u32,
    height: u32,
    z_diff: f32,
    n_diff: f32,
    a_n_diff: f32,
    _p0: f32,
    _p1: f32,
    _p2: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> gbuffer: array<Pixel>;
@group(0) @binding(2) var<storage, read_write> jumps: array<u32>;

const BIG: f32 = 3.0e38;

// The least depth slope, relative to the pixel's depth (SLOPE_FLOOR of lgh-render's
// shading/interleave).
const SLOPE_FLOOR: f32 = 2e-5;

fn hit(i: u32) -> bool {
    return gbuffer[i].position.w != 0.0;
}

fn depth(i: u32) -> f32 {
    return gbuffer[i].albedo.w;
}

// The smaller |depth difference| to the neighbours a and b that exist (ok) and see a
// surface; BIG if none.
fn slope(i: u32, a: u32, a_ok: bool, b: u32, b_ok: bool) -> f32 {
    var s = BIG;
    if (a_ok && hit(a)) {
        s = min(s, abs(depth(a) - depth(i)));
    }
    if (b_ok && hit(b)) {
        s = min(s, abs(depth(b) - depth(i)));
    }
    return s;
}

// The bits of the pair (i, j): `wide | crease` for a jump, `crease` for a normal change
// above a_n_diff only, else 0.
fn jump(i: u32, j: u32, scale: f32, wide: u32, crease: u32) -> u32 {
    let hi = hit(i);
    if (hi != hit(j)) {
        return wide | crease;
    }
    if (!hi) {
        return 0u;
    }
    let dz = abs(depth(j) - depth(i)) / scale;
    let dn = 1.0 - dot(gbuffer[i].normal.xyz, gbuffer[j].normal.xyz);
    if (dz > params.z_diff || dn > params.n_diff) {
        return wide | crease;
    }
    return select(0u, crease, dn > params.a_n_diff);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    let w = params.width;
    if (i >= w * params.height) {
        return;
    }
    let x = i % w;
    let y = i / w;
    var scale = 1.0;
    if (hit(i)) {
        let gx = slope(i, i - 1u, x > 0u, i + 1u, x + 1u < w);
        let gy = slope(i, i - w, y > 0u, i + w, y + 1u < params.height);
        let fx = select(0.0, gx, gx < BIG);
        let fy = select(0.0, gy, gy < BIG);
        scale = max(max(fx, fy), SLOPE_FLOOR * depth(i));
    }
    var flags = 0u;
    if (x + 1u < w) {
        flags |= jump(i, i + 1u, scale, 1u, 4u);
    }
    if (y + 1u < params.height) {
        flags |= jump(i, i + w, scale, 2u, 8u);
    }
    jumps[i] = flags;
}
