// One axis of the interleaving blur (lgh-render's shading/interleave, blur_n; LGH 2019
// section 4.3): per pixel that sees a surface, a Gaussian walk outwards, r taps at most each
// way, stopping before a step that leaves the image, crosses a jump along the axis
// (discontinuities.wgsl; the recombination of A its creases too, jump_shift 2) or enters a
// pixel that sees nothing; with n x n interleaving (phases = n > 1) the taps are averaged
// phase by phase (taps k apart with the same k mod n come from the same sub-image) and the
// phase means count alike, as balanced_walk on the CPU (which for a full walk equals its
// phase-normalised convolution). With a_diff > 0 a walk also stops before a pixel whose key
// (ln lum A smoothed by the same walks, blur_keys.wgsl; blur_n_stopped with Stop::SmoothedA
// on the CPU) differs from the centre's by more than a_diff. Pixels that see nothing keep their values; w components pass through. Images:
// `planes` vec4s per pixel, this pass blurs planes plane_first .. plane_first + plane_count.

const MAX_PHASES: u32 = 16u;

struct Params {
    width: u32,
    height: u32,
    // 0: along x; 1: along y.
    vertical: u32,
    radius: u32,
    phases: u32,
    planes: u32,
    plane_first: u32,
    plane_count: u32,
    // The Gaussian's weights w_0 .. w_radius, four a vec4.
    weights: array<vec4<f32>, 5>,
    // The stop on A's key (0: none).
    a_diff: f32,
    // 0: the jumps of n_diff (bits 1, 2); 2: those of a_n_diff (bits 4, 8).
    jump_shift: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> gbuffer: array<Pixel>;
@group(0) @binding(2) var<storage, read> jumps: array<u32>;
@group(0) @binding(3) var<storage, read> src: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> dst: array<vec4<f32>>;
// Per pixel: the key of A (read only where a_diff > 0).
@group(0) @binding(5) var<storage, read> keys: array<f32>;

// True if the walk from `centre` may not enter `next` because A's key moved too far.
fn key_stops(centre: u32, next: u32) -> bool {
    return params.a_diff > 0.0 && abs(keys[next] - keys[centre]) > params.a_diff;
}

fn weight(k: u32) -> f32 {
    return params.weights[k / 4u][k % 4u];
}

fn hit(i: u32) -> bool {
    return gbuffer[i].position.w != 0.0;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    let w = params.width;
    if (i >= w * params.height) {
        return;
    }
    let planes = params.planes;
    if (!hit(i)) {
        for (var c = params.plane_first; c < params.plane_first + params.plane_count; c++) {
            dst[i * planes + c] = src[i * planes + c];
        }
        return;
    }
    let vertical = params.vertical != 0u;
    let pos = select(i % w, i / w, vertical);
    let len = select(w, params.height, vertical);
    let step = select(1u, w, vertical);
    let bit = select(1u, 2u, vertical) << params.jump_shift;
    // The walk's length each way.
    var fwd = 0u;
    var at = i;
    while (fwd < params.radius && pos + fwd + 1u < len) {
        let next = at + step;
        if ((jumps[at] & bit) != 0u || !hit(next) || key_stops(i, next)) {
            break;
        }
        fwd++;
        at = next;
    }
    var back = 0u;
    at = i;
    while (back < params.radius && back < pos) {
        let next = at - step;
        if ((jumps[next] & bit) != 0u || !hit(next) || key_stops(i, next)) {
            break;
        }
        back++;
        at = next;
    }
    let phases = clamp(params.phases, 1u, MAX_PHASES);
    for (var c = params.plane_first; c < params.plane_first + params.plane_count; c++) {
        var sum: array<vec3<f32>, MAX_PHASES>;
        var wsum: array<f32, MAX_PHASES>;
        for (var ph = 0u; ph < phases; ph++) {
            sum[ph] = vec3<f32>(0.0);
            wsum[ph] = 0.0;
        }
        sum[0] = src[i * planes + c].xyz * weight(0u);
        wsum[0] = weight(0u);
        for (var k = 1u; k <= fwd; k++) {
            let ph = k % phases;
            sum[ph] += src[(i + k * step) * planes + c].xyz * weight(k);
            wsum[ph] += weight(k);
        }
        for (var k = 1u; k <= back; k++) {
            let ph = (phases - k % phases) % phases;
            sum[ph] += src[(i - k * step) * planes + c].xyz * weight(k);
            wsum[ph] += weight(k);
        }
        var total = vec3<f32>(0.0);
        var count = 0.0;
        for (var ph = 0u; ph < phases; ph++) {
            if (wsum[ph] > 0.0) {
                total += sum[ph] / wsum[ph];
                count += 1.0;
            }
        }
        dst[i * planes + c] = vec4<f32>(total / count, src[i * planes + c].w);
    }
}
