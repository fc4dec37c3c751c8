// The direct light's last step (lgh-render's direct/mod.rs, render_direct): per pixel the
// irradiance E = rest + U_a x D(S) / D(U) (per channel, clamped to [0, max_ratio], 1 where
// D(U) is zero; the analytic term only where the frame has analytic emitters) and the
// radiance albedo / pi x E.

struct Params {
    pixels: u32,
    // 1 if the frame has analytic emitters (else E is the rest alone).
    analytic: u32,
    max_ratio: f32,
    _p0: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> gbuffer: array<Pixel>;
// Per pixel: the rest, the analytic irradiance U_a.
@group(0) @binding(2) var<storage, read> lit: array<vec4<f32>>;
// Per pixel: the filtered S and U.
@group(0) @binding(3) var<storage, read> su: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> radiance: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= params.pixels) {
        return;
    }
    var e = lit[2u * i].xyz;
    if (params.analytic != 0u) {
        let s = su[2u * i].xyz;
        let u = su[2u * i + 1u].xyz;
        let ratio = select(vec3<f32>(1.0), clamp(s / u, vec3<f32>(0.0), vec3<f32>(params.max_ratio)), u > vec3<f32>(1e-20));
        e += lit[2u * i + 1u].xyz * ratio;
    }
    radiance[i] = vec4<f32>(gbuffer[i].albedo.xyz * (1.0 / PI) * e, 0.0);
}
