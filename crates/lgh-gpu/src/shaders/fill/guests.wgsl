// The guests of cut recombination windows (lgh-render's methods/lgh/shade.rs, guest_sum;
// docs/design.md, "Filling cut windows"): a pixel whose window misses sub-images sums the
// lights of each missed sub-image's list of its own tile at itself, A only (times n^2, as
// the loop's lights). It also keeps the loop's raw A of every pixel, which the
// recombination (recombine.wgsl) reads after the blur has overwritten it. Each pixel sums in
// a fixed order: the result does not depend on scheduling.

struct GuestParams {
    width: u32,
    height: u32,
    n: u32,
    // The binning's tile edge in full-resolution pixels and the tiles along x and y.
    tile: u32,
    tiles_x: u32,
    tiles_y: u32,
    // Where the lists' lights start in `lists`.
    list_lights: u32,
    eps2: f32,
}

@group(0) @binding(0) var<uniform> gp: GuestParams;
@group(0) @binding(1) var<storage, read> gbuffer: array<Pixel>;
@group(0) @binding(2) var<storage, read> lights: array<Light>;
@group(0) @binding(3) var<storage, read> lists: array<u32>;
@group(0) @binding(4) var<storage, read> masks: array<vec2<u32>>;
// The loop's A, S, U per pixel.
@group(0) @binding(5) var<storage, read> shaded: array<vec4<f32>>;
// Per pixel: the loop's A, the guests' sum.
@group(0) @binding(6) var<storage, read_write> fill: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    let w = gp.width;
    if (i >= w * gp.height) {
        return;
    }
    fill[2u * i] = shaded[3u * i];
    let m = masks[i];
    var sum = vec3<f32>(0.0);
    if (m.x != 0u || m.y != 0u) {
        let px = gbuffer[i];
        let x = px.position.xyz;
        let nx = px.normal.xyz;
        let tile = (i / w) / gp.tile * gp.tiles_x + (i % w) / gp.tile;
        let per = gp.tiles_x * gp.tiles_y;
        for (var s = 0u; s < gp.n * gp.n; s++) {
            if (!has_bit(m, s)) {
                continue;
            }
            let l = s * per + tile;
            for (var e = lists[l]; e < lists[l + 1u]; e++) {
                let light = lights[lists[gp.list_lights + e]];
                sum += light_factor(light, x, nx, gp.eps2) * light.intensity.xyz;
            }
        }
    }
    fill[2u * i + 1u] = vec4<f32>(sum, 0.0);
}
