// Direct light on the GPU (lgh-render's direct/mod.rs), one invocation per pixel: point, spot
// and directional lights exactly with a shadow ray each; area lights (emissive triangles) by
// `samples` points of the frame's stratified set under a digital shift per pixel, each
// emitter chosen by radiance x area and a point uniform on it, with a shadow ray; for the
// analytic emitters (Heitz, Hill & McGuire 2018's ratio estimator) the sample means S and U
// and the closed-form unshadowed irradiance (Lambert's formula, direct/polygon.rs). Writes
// per pixel the shadowed rest and the analytic irradiance (`lit`), and S (w: the filter's
// guide) and U (`su`) for the a-trous filter; direct_composite.wgsl finishes.

struct Params {
    pixels: u32,
    samples: u32,
    emitters: u32,
    punctual: u32,
    analytic: u32,
    // Where the tables start in `lights` (in vec4s).
    cdf_base: u32,
    punctual_base: u32,
    analytic_base: u32,
    points_base: u32,
    seed_lo: u32,
    seed_hi: u32,
    _p0: u32,
    ray_eps: f32,
    // How far a directional light's shadow ray goes (4 x the scene's radius).
    far: f32,
    _p1: f32,
    _p2: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> nodes: array<Node>;
@group(0) @binding(2) var<storage, read> tris: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> gbuffer: array<Pixel>;
// The lights' tables as 32-bit words: per emitter 5 vec4s (v0 and area; e1 and 1 if
// analytic; e2; normal; radiance), the emitters' CDF (normalised, 4 a vec4), per punctual
// light 3 vec4s (position and kind 0 point / 1 spot / 2 directional; direction and
// cos_inner; intensity or irradiance and cos_outer), the analytic emitters' indices (4 a
// vec4), the frame's points (2 a vec4, 32-bit fixed point).
@group(0) @binding(4) var<storage, read> lights: array<vec4<u32>>;
// Per pixel: the punctual lights plus the sampled non-analytic emitters (shadowed); the
// analytic emitters' closed-form unshadowed irradiance.
@group(0) @binding(5) var<storage, read_write> lit: array<vec4<f32>>;
// Per pixel: S (w: the guide lum(S) / lum(U)), U.
@group(0) @binding(6) var<storage, read_write> su: array<vec4<f32>>;

fn f4(i: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(lights[i]);
}

fn word(base: u32, k: u32) -> u32 {
    return lights[base + k / 4u][k % 4u];
}

// A 32-bit fixed-point number in [0, 1) as an f32 (its top 24 bits).
fn unit(x: u32) -> f32 {
    return f32(x >> 8u) * (1.0 / 16777216.0);
}

// Irradiance at p from punctual light l with its shadow ray.
fn punctual_one(l: u32, p: vec3<f32>, n: vec3<f32>, ng: vec3<f32>) -> vec3<f32> {
    let a = f4(params.punctual_base + 3u * l);
    let b = f4(params.punctual_base + 3u * l + 1u);
    let c = f4(params.punctual_base + 3u * l + 2u);
    let kind = u32(a.w);
    if (kind == 2u) {
        let w = -b.xyz;
        let cos = dot(n, w);
        if (cos <= 0.0 || dot(ng, w) <= 0.0) {
            return vec3<f32>(0.0);
        }
        let o = offset(p, ng, w, params.ray_eps);
        if (occluded(o, w, params.far)) {
            return vec3<f32>(0.0);
        }
        return c.xyz * cos;
    }
    let d = a.xyz - p;
    let d2 = dot(d, d);
    let w = d / sqrt(d2);
    let cos = dot(n, w);
    if (cos <= 0.0 || dot(ng, w) <= 0.0) {
        return vec3<f32>(0.0);
    }
    var f = 1.0;
    if (kind == 1u) {
        // Light::falloff: smoothstep between the outer and inner cones.
        let cl = dot(b.xyz, -w);
        if (cl <= c.w) {
            f = 0.0;
        } else if (cl < b.w) {
            let t = (cl - c.w) / max(b.w - c.w, 1e-6);
            f = t * t * (3.0 - 2.0 * t);
        }
    }
    if (f <= 0.0) {
        return vec3<f32>(0.0);
    }
    let o = offset(p, ng, w, params.ray_eps);
    let len = length(a.xyz - o);
    if (occluded(o, w, len * (1.0 - 1e-4))) {
        return vec3<f32>(0.0);
    }
    return c.xyz * (f * cos / d2);
}

// Distribution1D::sample_remapped over the normalised CDF: the emitter whose interval holds
// u, and u rescaled inside it (x), with its probability (y) as bits.
fn pick_emitter(u: f32) -> vec3<f32> {
    var lo = 0u;
    var hi = params.emitters;
    // The first k with cdf[k] > u (partition_point of cdf <= u).
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (bitcast<f32>(word(params.cdf_base, mid)) <= u) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    let i = min(lo, params.emitters - 1u);
    let below = select(0.0, bitcast<f32>(word(params.cdf_base, max(i, 1u) - 1u)), i > 0u);
    let width = bitcast<f32>(word(params.cdf_base, i)) - below;
    var rest = 0.0;
    if (width > 0.0) {
        rest = clamp((u - below) / width, 0.0, 1.0);
    }
    return vec3<f32>(f32(i), width, min(rest, 0.99999994));
}

// The projected solid angle of triangle (v0, v1, v2) from x with normal n, clipped to the
// hemisphere above x (direct/polygon.rs).
fn projected_solid_angle(x: vec3<f32>, n: vec3<f32>, v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>) -> f32 {
    var tri = array<vec3<f32>, 3>(v0 - x, v1 - x, v2 - x);
    var poly: array<vec3<f32>, 4>;
    var m = 0u;
    for (var k = 0u; k < 3u; k++) {
        let a = tri[k];
        let b = tri[(k + 1u) % 3u];
        let da = dot(n, a);
        let db = dot(n, b);
        if (da >= 0.0) {
            poly[m] = a;
            m++;
        }
        if ((da >= 0.0) != (db >= 0.0)) {
            poly[m] = a + (b - a) * (da / (da - db));
            m++;
        }
    }
    if (m < 3u) {
        return 0.0;
    }
    var sum = 0.0;
    for (var k = 0u; k < m; k++) {
        let pa = poly[k];
        let pb = poly[(k + 1u) % m];
        let ua = select(vec3<f32>(0.0), normalize(pa), dot(pa, pa) > 0.0);
        let ub = select(vec3<f32>(0.0), normalize(pb), dot(pb, pb) > 0.0);
        let c = cross(ua, ub);
        let len = length(c);
        if (len > 0.0) {
            sum += atan2(len, dot(ua, ub)) * dot(n, c) / len;
        }
    }
    return 0.5 * abs(sum);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= params.pixels) {
        return;
    }
    let px = gbuffer[i];
    if (px.position.w == 0.0) {
        lit[2u * i] = vec4<f32>(0.0);
        lit[2u * i + 1u] = vec4<f32>(0.0);
        su[2u * i] = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        su[2u * i + 1u] = vec4<f32>(0.0);
        return;
    }
    let p = px.position.xyz;
    let n = px.normal.xyz;
    let ng = px.geo_normal.xyz;
    var base = vec3<f32>(0.0);
    for (var l = 0u; l < params.punctual; l++) {
        base += punctual_one(l, p, n, ng);
    }
    // The pixel's digital shift of the frame's points (its own stream).
    let stream = hash(params.seed_lo ^ hash(params.seed_hi ^ 0xd1u));
    let shift_x = hash(stream ^ hash(2u * i));
    let shift_y = hash(stream ^ hash(2u * i + 1u));
    var s = vec3<f32>(0.0);
    var u = vec3<f32>(0.0);
    var rest = vec3<f32>(0.0);
    if (params.emitters > 0u) {
        for (var k = 0u; k < params.samples; k++) {
            let ux = unit(word(params.points_base, 2u * k) ^ shift_x);
            let uy = unit(word(params.points_base, 2u * k + 1u) ^ shift_y);
            let pick = pick_emitter(ux);
            let j = u32(pick.x);
            let e = 5u * j;
            let v0 = f4(e);
            let e1 = f4(e + 1u);
            // lgh-core's uniform_triangle.
            let sq = sqrt(pick.z);
            let bx = 1.0 - sq;
            let by = uy * sq;
            let q = v0.xyz + e1.xyz * bx + f4(e + 2u).xyz * by;
            let nq = f4(e + 3u).xyz;
            let d = q - p;
            let d2 = dot(d, d);
            let w = d / sqrt(d2);
            let cos_x = dot(n, w);
            let cos_l = -dot(nq, w);
            if (cos_x <= 0.0 || cos_l <= 0.0 || dot(ng, w) <= 0.0) {
                continue;
            }
            let pdf_area = pick.y / v0.w;
            let f = f4(e + 4u).xyz * (cos_x * cos_l / (d2 * pdf_area));
            if (!(all(abs(f) < vec3<f32>(3.0e38)))) {
                continue;
            }
            let visible = !occluded_between(p, ng, q, nq, params.ray_eps);
            let shadowed = select(vec3<f32>(0.0), f, visible);
            if (e1.w > 0.0) {
                u += f;
                s += shadowed;
            } else {
                rest += shadowed;
            }
        }
    }
    let inv = 1.0 / f32(max(params.samples, 1u));
    s *= inv;
    u *= inv;
    base += rest * inv;
    var analytic = vec3<f32>(0.0);
    for (var a = 0u; a < params.analytic; a++) {
        let e = 5u * word(params.analytic_base, a);
        let v0 = f4(e).xyz;
        // One-sided: the front is the counter-clockwise normal.
        if (dot(f4(e + 3u).xyz, p - v0) <= 0.0) {
            continue;
        }
        let psa = projected_solid_angle(p, n, v0, v0 + f4(e + 1u).xyz, v0 + f4(e + 2u).xyz);
        analytic += f4(e + 4u).xyz * psa;
    }
    lit[2u * i] = vec4<f32>(base, 0.0);
    lit[2u * i + 1u] = vec4<f32>(analytic, 0.0);
    su[2u * i] = vec4<f32>(s, filter_guide(s, u));
    su[2u * i + 1u] = vec4<f32>(u, 0.0);
}
