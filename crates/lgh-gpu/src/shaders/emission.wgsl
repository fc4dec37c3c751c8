// Starting a light path (lgh-render's LightSet::sample_emission) and the sample warps it
// and the bounces use (lgh-core's sampling). Needs `tables` (lgh_gpu::vpls: after the Sobol
// vectors, LIGHT_WORDS vec4s per light) and the params' light count, scene centre and
// radius.

const LIGHT_POINT: u32 = 0u;
const LIGHT_SPOT: u32 = 1u;
const LIGHT_DIRECTIONAL: u32 = 2u;
const LIGHT_EMITTER: u32 = 3u;
const LIGHTS_AT: u32 = 16u;
const LIGHT_WORDS: u32 = 6u;
const ONE_MINUS_EPSILON: f32 = 0.99999994;

// Light i's j-th vec4: 0 = (kind, pmf, normalised cdf as hi + lo, all as bits); then per
// kind: point (position, intensity), spot (position, intensity, axis, (cos_inner,
// cos_outer)), directional (direction, irradiance), emitter (v0 with w = area, e1, e2,
// normal, radiance).
fn light_word(i: u32, j: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(tables[LIGHTS_AT + LIGHT_WORDS * i + j]);
}

// glam's Vec3::normalize.
fn unit(v: vec3<f32>) -> vec3<f32> {
    return v * (1.0 / sqrt(dot(v, v)));
}

// sampling::orthonormal_basis (Duff et al. 2017).
fn basis(n: vec3<f32>) -> array<vec3<f32>, 2> {
    let sign = select(1.0, -1.0, (bitcast<u32>(n.z) & 0x80000000u) != 0u);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return array<vec3<f32>, 2>(
        vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        vec3<f32>(b, sign + n.y * n.y * a, -n.y),
    );
}

// sampling::concentric_disk.
fn concentric_disk(u: vec2<f32>) -> vec2<f32> {
    let o = 2.0 * u - vec2<f32>(1.0);
    if (o.x == 0.0 && o.y == 0.0) {
        return vec2<f32>(0.0);
    }
    var r = o.y;
    var theta = PI / 2.0 - (PI / 4.0) * (o.x / o.y);
    if (abs(o.x) > abs(o.y)) {
        r = o.x;
        theta = (PI / 4.0) * (o.y / o.x);
    }
    return r * vec2<f32>(cos(theta), sin(theta));
}

// sampling::cosine_hemisphere.
fn cosine_hemisphere(n: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let d = concentric_disk(u);
    let z = sqrt(max(1.0 - dot(d, d), 0.0));
    let tb = basis(n);
    return unit(tb[0] * d.x + tb[1] * d.y + n * z);
}

// sampling::uniform_cone.
fn uniform_cone(n: vec3<f32>, cos_max: f32, u: vec2<f32>) -> vec3<f32> {
    let cos_t = 1.0 - u.x * (1.0 - cos_max);
    let sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    let phi = 2.0 * PI * u.y;
    let tb = basis(n);
    return unit(tb[0] * (sin_t * cos(phi)) + tb[1] * (sin_t * sin(phi)) + n * cos_t);
}

// sampling::uniform_sphere.
fn uniform_sphere(u: vec2<f32>) -> vec3<f32> {
    let z = 1.0 - 2.0 * u.x;
    let r = sqrt(max(1.0 - z * z, 0.0));
    let phi = 2.0 * PI * u.y;
    return vec3<f32>(r * cos(phi), r * sin(phi), z);
}

// sampling::uniform_triangle.
fn uniform_triangle(u: vec2<f32>) -> vec2<f32> {
    let s = sqrt(u.x);
    return vec2<f32>(1.0 - s, u.y * s);
}

// Light::falloff of a spot light.
fn spot_falloff(axis: vec3<f32>, cos_inner: f32, cos_outer: f32, w: vec3<f32>) -> f32 {
    let c = dot(axis, w);
    if (c <= cos_outer) {
        return 0.0;
    }
    if (c >= cos_inner) {
        return 1.0;
    }
    let t = (c - cos_outer) / max(cos_inner - cos_outer, 1e-6);
    return t * t * (3.0 - 2.0 * t);
}

// True if the normalised cdf entry of light i is at most u (Distribution1D::find's
// comparison, on a double-float).
fn cdf_at_most(i: u32, u: f32) -> bool {
    let w = light_word(i, 0u);
    return w.z < u || (w.z == u && w.w <= 0.0);
}

struct EmittedRay {
    origin: vec3<f32>,
    dir: vec3<f32>,
    flux: vec3<f32>,
    ok: bool,
}

// LightSet::sample_emission: a light in proportion to its power picked with the first
// number, whose remainder in the light's interval places the point; then a direction.
fn sample_emission(s: ptr<function, PathSampler>) -> EmittedRay {
    let u0 = next_2d(s);
    let u_dir = next_2d(s);
    // Distribution1D::sample_remapped: the first light whose cdf exceeds u.
    var lo = 0u;
    var hi = params.lights;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (cdf_at_most(mid, u0.x)) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    let i = min(lo, params.lights - 1u);
    let head = light_word(i, 0u);
    let pmf = head.y;
    var below = vec2<f32>(0.0);
    if (i > 0u) {
        below = light_word(i - 1u, 0u).zw;
    }
    var rest = 0.0;
    if (pmf > 0.0) {
        rest = min(clamp(((u0.x - below.x) - below.y) / pmf, 0.0, 1.0), ONE_MINUS_EPSILON);
    }
    let u = vec2<f32>(rest, u0.y);
    let a = light_word(i, 1u).xyz;
    let b = light_word(i, 2u).xyz;
    var ray = EmittedRay(vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0), pmf > 0.0);
    switch (bitcast<u32>(head.x)) {
        case LIGHT_POINT: {
            ray.origin = a;
            ray.dir = uniform_sphere(u);
            ray.flux = b * (4.0 * PI);
        }
        case LIGHT_SPOT: {
            let axis = light_word(i, 3u).xyz;
            let cones = light_word(i, 4u);
            ray.origin = a;
            ray.dir = uniform_cone(axis, cones.y, u);
            ray.flux = b * (spot_falloff(axis, cones.x, cones.y, ray.dir) * 2.0 * PI * (1.0 - cones.y));
        }
        case LIGHT_DIRECTIONAL: {
            let tb = basis(a);
            let d = concentric_disk(u) * params.radius;
            ray.origin = params.centre - a * (2.0 * params.radius) + tb[0] * d.x + tb[1] * d.y;
            ray.dir = a;
            ray.flux = b * (PI * params.radius * params.radius);
        }
        default: {
            let v0 = light_word(i, 1u);
            let e1 = light_word(i, 2u).xyz;
            let e2 = light_word(i, 3u).xyz;
            let n = light_word(i, 4u).xyz;
            let bary = uniform_triangle(u);
            let p = v0.xyz + e1 * bary.x + e2 * bary.y;
            ray.origin = p + n * (1e-4 * params.radius);
            ray.dir = cosine_hemisphere(n, u_dir);
            ray.flux = light_word(i, 5u).xyz * (PI * v0.w);
        }
    }
    ray.flux = ray.flux / pmf;
    return ray;
}
