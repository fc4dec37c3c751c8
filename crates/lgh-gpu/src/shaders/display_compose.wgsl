// A shown frame's image (lgh-render's frame recipe, `compose`): per pixel the emission seen
// directly, plus the direct light, plus the indirect light, in that order. The indirect
// light comes as radiance (mode 1), or as the ratio estimator's result (mode 2: per pixel
// [A, overdraw], [raw ratio, rays], [filtered ratio, 0]; albedo / pi x A x filtered ratio,
// lgh-render's shading::ratio::composite), or as A alone (mode 3: the first of three
// vec4s; albedo / pi x A). Mode 0: the part is zero (and its buffer a stand-in).

struct Params {
    pixels: u32,
    emission: u32,
    direct: u32,
    indirect: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> gbuffer: array<Pixel>;
@group(0) @binding(2) var<storage, read> emission: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> direct: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> indirect: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> image: array<vec4<f32>>;

// std::f32::consts::FRAC_1_PI, as the CPU's composite multiplies by it.
const FRAC_1_PI: f32 = 0.318309886183790671538;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.x;
    if (p >= params.pixels) {
        return;
    }
    var c = vec3<f32>(0.0);
    if (params.emission == 1u) {
        c = emission[p].xyz;
    }
    if (params.direct == 1u) {
        c = c + direct[p].xyz;
    }
    let albedo = gbuffer[p].albedo.xyz;
    switch params.indirect {
        case 1u: {
            c = c + indirect[p].xyz;
        }
        case 2u: {
            c = c + albedo * FRAC_1_PI * indirect[3u * p].xyz * indirect[3u * p + 2u].xyz;
        }
        case 3u: {
            c = c + albedo * FRAC_1_PI * indirect[3u * p].xyz;
        }
        default: {}
    }
    image[p] = vec4<f32>(c, 0.0);
}
