// The keys of the interleaving blur's stop on A (lgh-render's shading/ratio): per pixel,
// ln lum of plane `plane` (the recombined unshadowed sum A) of the images, `planes` vec4s
// per pixel (unshadowed_key, common.wgsl).

struct Params {
    pixels: u32,
    planes: u32,
    plane: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> images: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> keys: array<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= params.pixels) {
        return;
    }
    keys[i] = unshadowed_key(images[i * params.planes + params.plane].xyz);
}
