// The ratio estimator's steps around its a-trous filter (lgh-render's shading/ratio,
// shadowed_indirect_with), on the frame's [A (w: overdraw), S (w: rays), U] per pixel after
// the interleaving blur. mode 0: the filter's input, S with its guide lum(S) / lum(U)
// (clamped to [0, 1], 1 where U has no luminance) and U (w: the key of A, ln lum(A)).
// mode 1: per pixel [A, overdraw], [the raw ratio S / U, rays], [the filtered ratio
// D(S) / D(U)], each ratio per channel clamped to [0, max_ratio] and 1 where the divisor
// is at most 1e-20.

struct Params {
    pixels: u32,
    mode: u32,
    max_ratio: f32,
    _p0: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
// Per pixel: A, S, U.
@group(0) @binding(1) var<storage, read> asu: array<vec4<f32>>;
// Per pixel: S (w: guide), U (w: the key of A); mode 0 writes it, mode 1 reads the filtered one.
@group(0) @binding(2) var<storage, read_write> pair: array<vec4<f32>>;
// mode 1: per pixel [A, overdraw], [raw ratio, rays], [filtered ratio, 0].
@group(0) @binding(3) var<storage, read_write> result: array<vec4<f32>>;

fn ratio(s: vec3<f32>, u: vec3<f32>) -> vec3<f32> {
    let r = clamp(s / select(vec3<f32>(1.0), u, u > vec3<f32>(1e-20)), vec3<f32>(0.0), vec3<f32>(params.max_ratio));
    return select(vec3<f32>(1.0), r, u > vec3<f32>(1e-20));
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= params.pixels) {
        return;
    }
    let s = asu[3u * i + 1u];
    let u = asu[3u * i + 2u].xyz;
    if (params.mode == 0u) {
        pair[2u * i] = vec4<f32>(s.xyz, filter_guide(s.xyz, u));
        pair[2u * i + 1u] = vec4<f32>(u, unshadowed_key(asu[3u * i].xyz));
        return;
    }
    result[3u * i] = asu[3u * i];
    result[3u * i + 1u] = vec4<f32>(ratio(s.xyz, u), s.w);
    result[3u * i + 2u] = vec4<f32>(ratio(pair[2u * i].xyz, pair[2u * i + 1u].xyz), 0.0);
}
