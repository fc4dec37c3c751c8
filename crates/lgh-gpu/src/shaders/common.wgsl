// What the kernels share (lgh_gpu::kernel puts it before each kernel's source).

const PI: f32 = 3.14159265358979;

// A G-buffer pixel (lgh_gpu::gbuffer): position (w: 1 where the pixel sees a surface),
// shading normal (w: 1 where the surface emits towards the camera), geometric normal, albedo
// (w: the linear depth where it sees a surface).
struct Pixel {
    position: vec4<f32>,
    normal: vec4<f32>,
    geo_normal: vec4<f32>,
    albedo: vec4<f32>,
}

// A VPL as the kernels that read or write VPLs hold it (brute force, light paths):
// position, normal and flux, w unused.
struct Vpl {
    position: vec4<f32>,
    normal: vec4<f32>,
    flux: vec4<f32>,
}

// lgh_core::color::luminance.
fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.299, 0.587, 0.114));
}

// A PCG-style integer hash: the kernels' own random streams.
fn hash(v: u32) -> u32 {
    let s = v * 747796405u + 2891336453u;
    let w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    return (w >> 22u) ^ w;
}

// The a-trous filter's guide (lgh-render's denoise::atrous::filter_guide): lum(S) / lum(U)
// clamped to [0, 1]; 1 where U has no luminance.
fn filter_guide(s: vec3<f32>, u: vec3<f32>) -> f32 {
    let lu = luminance(u);
    if (lu > 1e-12) {
        return clamp(luminance(s) / lu, 0.0, 1.0);
    }
    return 1.0;
}

// The key of an unshadowed sum A that the a-trous filter's weight w_a compares (lgh-render's
// denoise::atrous::unshadowed_key): ln lum(A), lum(A) at least 1e-20.
fn unshadowed_key(a: vec3<f32>) -> f32 {
    return log(max(luminance(a), 1e-20));
}

// Rust's f32::rem_euclid(x, m).
fn rem_euclid(x: f32, m: f32) -> f32 {
    let r = x % m;
    return select(r, r + m, r < 0.0);
}

const WRAP_REPEAT: u32 = 0u;
const WRAP_CLAMP: u32 = 1u;

// lgh-scene's Wrap::coordinate: t brought into [0, 1].
fn wrap_coordinate(t: f32, wrap: u32) -> f32 {
    if (wrap == WRAP_REPEAT) {
        return rem_euclid(t, 1.0);
    }
    if (wrap == WRAP_CLAMP) {
        return clamp(t, 0.0, 1.0);
    }
    return 1.0 - abs(rem_euclid(t, 2.0) - 1.0);
}

// lgh-scene's Wrap::texel: the texel of index i of an axis of n.
fn wrap_texel(i: i32, n: i32, wrap: u32) -> i32 {
    if (wrap == WRAP_REPEAT) {
        return ((i % n) + n) % n;
    }
    return clamp(i, 0, n - 1);
}

// The four texels around `uv` in a w x h texture, row-major indices (x0 y0, x1 y0, x0 y1,
// x1 y1), and the bilinear weights (fx, fy): lgh-scene's Texture::bilinear, v up, `wrap`
// in u | in v << 2.
struct Bilinear {
    i: vec4<u32>,
    f: vec2<f32>,
}

fn bilinear(uv: vec2<f32>, w: i32, h: i32, wrap: u32) -> Bilinear {
    let wu = wrap & 3u;
    let wv = (wrap >> 2u) & 3u;
    let x = wrap_coordinate(uv.x, wu) * f32(w) - 0.5;
    let y = (1.0 - wrap_coordinate(uv.y, wv)) * f32(h) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let xa = wrap_texel(i32(x0), w, wu);
    let xb = wrap_texel(i32(x0) + 1, w, wu);
    let ya = wrap_texel(i32(y0), h, wv);
    let yb = wrap_texel(i32(y0) + 1, h, wv);
    return Bilinear(
        vec4<u32>(u32(ya * w + xa), u32(ya * w + xb), u32(yb * w + xa), u32(yb * w + xb)),
        vec2<f32>(x - x0, y - y0),
    );
}
