// The brute-force reference on the GPU (lgh-render's methods/brute): every pixel sums every
// VPL i of one chunk, Phi_i max(0, n_i . w) max(0, n_x . -w) / (pi (d^2 + eps^2)) x V, with an
// exact shadow ray per VPL (V) unless shadows are off, and adds the chunk's sum to its
// running total. One invocation per pixel; each pixel's sum runs over its VPLs in order, so
// the result does not depend on scheduling.

struct Params {
    pixels: u32,
    first_vpl: u32,
    vpl_count: u32,
    shadows: u32,
    eps2: f32,
    ray_eps: f32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> nodes: array<Node>;
@group(0) @binding(2) var<storage, read> tris: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> gbuffer: array<Pixel>;
@group(0) @binding(4) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(5) var<storage, read_write> irradiance: array<vec4<f32>>;

// lgh_core::vpl::light_irradiance of a VPL (no isotropic part).
fn vpl_irradiance(x: vec3<f32>, n_x: vec3<f32>, p: vec3<f32>, n_v: vec3<f32>, flux: vec3<f32>) -> vec3<f32> {
    let d = p - x;
    let d2 = dot(d, d);
    let inv_d = inverseSqrt(d2);
    let cos_x = dot(n_x, d) * inv_d;
    let cos_v = max(-dot(n_v, d) * inv_d, 0.0);
    if (cos_x <= 0.0 || cos_v <= 0.0 || d2 == 0.0) {
        return vec3<f32>(0.0);
    }
    return flux * (cos_x * cos_v / (PI * (d2 + params.eps2)));
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= params.pixels) {
        return;
    }
    let px = gbuffer[i];
    if (px.position.w == 0.0) {
        return;
    }
    let x = px.position.xyz;
    let n = px.normal.xyz;
    let ng = px.geo_normal.xyz;
    var e = vec3<f32>(0.0);
    for (var k = 0u; k < params.vpl_count; k++) {
        let v = vpls[params.first_vpl + k];
        let c = vpl_irradiance(x, n, v.position.xyz, v.normal.xyz, v.flux.xyz);
        if (any(c != vec3<f32>(0.0))) {
            var hidden = false;
            if (params.shadows != 0u) {
                hidden = occluded_between(x, ng, v.position.xyz, v.normal.xyz, params.ray_eps);
            }
            if (!hidden) {
                e += c;
            }
        }
    }
    irradiance[i] += vec4<f32>(e, 0.0);
}
