// A of the pixels that fill their cut recombination windows (lgh-render's
// recombine_filled; docs/design.md, "Filling cut windows"), after the blur recombined A
// (blur.wgsl): per sub-image the Gaussian-weighted mean of the loop's raw A over the taps
// of the window, plus the guests' sum of the missed sub-images, over n^2, so that every
// light counts once. Other pixels keep the blur's A.

@group(0) @binding(0) var<uniform> fp: FillParams;
@group(0) @binding(1) var<storage, read> gbuffer: array<Pixel>;
@group(0) @binding(2) var<storage, read> jumps: array<u32>;
@group(0) @binding(3) var<storage, read> masks: array<vec2<u32>>;
// Per pixel: the loop's A, the guests' sum (guests.wgsl).
@group(0) @binding(4) var<storage, read> fill: array<vec4<f32>>;
// The images the recombination blurred, `fp.planes` vec4s per pixel, A the first.
@group(0) @binding(5) var<storage, read_write> images: array<vec4<f32>>;

const MAX_SUB_IMAGES: u32 = 64u;

fn gauss(d: u32) -> f32 {
    let f = f32(d);
    return exp(-(f * f) / (2.0 * fp.sigma * fp.sigma));
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    let w = fp.width;
    if (i >= w * fp.height) {
        return;
    }
    let m = masks[i];
    if (m.x == 0u && m.y == 0u) {
        return;
    }
    let n2 = fp.n * fp.n;
    var sum: array<vec3<f32>, MAX_SUB_IMAGES>;
    var wsum: array<f32, MAX_SUB_IMAGES>;
    for (var s = 0u; s < n2; s++) {
        sum[s] = vec3<f32>(0.0);
        wsum[s] = 0.0;
    }
    // The taps in the CPU's order: down the column from its top, then along each row.
    let up = run(i, true, false);
    let down = run(i, true, true);
    for (var r = 0u; r <= up + down; r++) {
        let j = i - up * w + r * w;
        let dy = select(r - up, up - r, r < up);
        let left = run(j, false, false);
        let right = run(j, false, true);
        for (var c = 0u; c <= left + right; c++) {
            let t = j - left + c;
            let dx = select(c - left, left - c, c < left);
            let s = sub_image(t);
            let wt = gauss(dx) * gauss(dy);
            sum[s] += fill[2u * t].xyz * wt;
            wsum[s] += wt;
        }
    }
    var total = fill[2u * i + 1u].xyz;
    for (var s = 0u; s < n2; s++) {
        if (wsum[s] > 0.0) {
            total += sum[s] / wsum[s];
        }
    }
    let at = i * fp.planes;
    images[at] = vec4<f32>(total / f32(n2), images[at].w);
}
