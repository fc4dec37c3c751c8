// A shown frame added to the running mean and tone-mapped (lgh-render's display): the
// sum restarts with the image (its non-finite components 0) or adds it, the mean is
// sum x (1 / frames), and each channel is lgh-render's tonemap_pixel (non-finite to 0,
// x exposure, the ACES fit of Narkowicz 2015, the sRGB curve, rounded to 8 bits), packed
// as 0x00RRGGBB.

struct Params {
    pixels: u32,
    restart: u32,
    inv_frames: f32,
    exposure: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> image: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> sum: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> packed: array<u32>;

// x, or 0 where it is not finite (by its bits: a compiler may fold x != x away).
fn finite_or_zero(x: f32) -> f32 {
    if ((bitcast<u32>(x) & 0x7f800000u) == 0x7f800000u) {
        return 0.0;
    }
    return x;
}

fn aces(x0: f32) -> f32 {
    let x = clamp(x0, 0.0, 1e4);
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

fn linear_to_srgb(c0: f32) -> f32 {
    let c = clamp(c0, 0.0, 1.0);
    if (c <= 0.0031308) {
        return 12.92 * c;
    }
    return 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

fn channel(c: f32) -> u32 {
    return u32(linear_to_srgb(aces(finite_or_zero(c) * params.exposure)) * 255.0 + 0.5);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.x;
    if (p >= params.pixels) {
        return;
    }
    // Non-finite components to 0, as the CPU's image (lgh-render's Image::from_pixels).
    let c = image[p].xyz;
    var s = vec3<f32>(finite_or_zero(c.x), finite_or_zero(c.y), finite_or_zero(c.z));
    if (params.restart == 0u) {
        s = sum[p].xyz + s;
    }
    sum[p] = vec4<f32>(s, 0.0);
    let m = s * params.inv_frames;
    packed[p] = (channel(m.x) << 16u) | (channel(m.y) << 8u) | channel(m.z);
}
