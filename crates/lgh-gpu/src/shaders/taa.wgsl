// The temporal filter of the shadow ratio (lgh-render's denoise::temporal, LGH 2019 section
// 4.3) on a shown frame: per pixel that sees a surface, the previous frame's value where it
// saw the same surface (the identity for a camera that stood still; else the pixel's point
// projected into the previous camera, taken if the previous depth there is within
// depth_tolerance x z and the normals' cosine at least normal_cos), clamped to the min-max
// box of the raw ratio over the 3 x 3 pixels that see a surface (and the current value),
// blended: alpha x current + (1 - alpha) x previous. The result replaces the filtered ratio
// in the estimator's result and is the next frame's history, with the depths and normals.

struct Params {
    pixels: u32,
    width: u32,
    height: u32,
    // 0: no history (the value passes through); 1: a history seen through `previous`;
    // 2: a history of the same view (the identity).
    history: u32,
    alpha: f32,
    depth_tolerance: f32,
    normal_cos: f32,
    _p0: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<uniform> previous: Camera;
@group(0) @binding(2) var<storage, read> gbuffer: array<Pixel>;
// The ratio estimator's result: per pixel [A, overdraw], [raw ratio, rays], [filtered ratio, 0].
@group(0) @binding(3) var<storage, read_write> result: array<vec4<f32>>;
// The history: values, and normals with depths (w; -1 where the pixel saw nothing).
@group(0) @binding(4) var<storage, read> old_value: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> old_depth_normal: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> new_value: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> new_depth_normal: array<vec4<f32>>;

// The history's value seen at pixel i (w: 1), or w 0 where it was not seen.
fn reproject(i: u32) -> vec4<f32> {
    if (params.history == 2u) {
        return vec4<f32>(old_value[i].xyz, 1.0);
    }
    let px = camera_project(previous, gbuffer[i].position.xyz);
    if (px.w == 0.0 || px.x < 0.0 || px.y < 0.0) {
        return vec4<f32>(0.0);
    }
    let x = u32(px.x);
    let y = u32(px.y);
    if (x >= params.width || y >= params.height) {
        return vec4<f32>(0.0);
    }
    let j = y * params.width + x;
    let old = old_depth_normal[j];
    let z = px.z;
    let same_depth = abs(old.w - z) <= params.depth_tolerance * z;
    if (!same_depth || dot(old.xyz, gbuffer[i].normal.xyz) < params.normal_cos) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(old_value[j].xyz, 1.0);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= params.pixels) {
        return;
    }
    let px = gbuffer[i];
    let hit = px.position.w > 0.0;
    let current = result[3u * i + 2u].xyz;
    var out = current;
    if (hit && params.history != 0u) {
        let prev = reproject(i);
        if (prev.w > 0.0) {
            let x = i32(i % params.width);
            let y = i32(i / params.width);
            var lo = current;
            var hi = current;
            for (var yy = max(y - 1, 0); yy < min(y + 2, i32(params.height)); yy++) {
                for (var xx = max(x - 1, 0); xx < min(x + 2, i32(params.width)); xx++) {
                    let j = u32(yy) * params.width + u32(xx);
                    if (gbuffer[j].position.w > 0.0) {
                        let s = result[3u * j + 1u].xyz;
                        lo = min(lo, s);
                        hi = max(hi, s);
                    }
                }
            }
            out = current * params.alpha + clamp(prev.xyz, lo, hi) * (1.0 - params.alpha);
        }
    }
    result[3u * i + 2u] = vec4<f32>(out, 0.0);
    new_value[i] = vec4<f32>(out, 0.0);
    new_depth_normal[i] = vec4<f32>(px.normal.xyz, select(-1.0, px.albedo.w, hit));
}
