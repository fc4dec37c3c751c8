// Per pixel, the sub-images its recombination window misses where it reaches fewer than
// fill_below n^2 of them (lgh-render's missed_sub_images; docs/design.md, "Filling cut
// windows"): bit s = sub-image s, as two words (n <= 8); zero where the window is full or
// the pixel sees nothing.

@group(0) @binding(0) var<uniform> fp: FillParams;
@group(0) @binding(1) var<storage, read> gbuffer: array<Pixel>;
@group(0) @binding(2) var<storage, read> jumps: array<u32>;
@group(0) @binding(3) var<storage, read_write> masks: array<vec2<u32>>;

// The mask of sub-images 0 .. n^2 - 1.
fn all_sub_images(n2: u32) -> vec2<u32> {
    let lo = select(0xffffffffu, (1u << (n2 & 31u)) - 1u, n2 < 32u);
    let hi = select(select((1u << ((n2 - 32u) & 31u)) - 1u, 0xffffffffu, n2 >= 64u), 0u, n2 <= 32u);
    return vec2<u32>(lo, hi);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    let w = fp.width;
    if (i >= w * fp.height) {
        return;
    }
    if (!hit(i)) {
        masks[i] = vec2<u32>(0u);
        return;
    }
    let n = fp.n;
    let down = run(i, true, true);
    let up = run(i, true, false);
    // Full: n rows, each n pixels wide (every sub-image reached).
    var full = down + up + 1u >= n;
    var reached = vec2<u32>(0u);
    for (var r = 0u; r <= up + down; r++) {
        let j = i - up * w + r * w;
        let right = run(j, false, true);
        let left = run(j, false, false);
        full = full && right + left + 1u >= n;
        for (var c = 0u; c <= left + right; c++) {
            let s = sub_image(j - left + c);
            if (s < 32u) {
                reached.x |= 1u << s;
            } else {
                reached.y |= 1u << (s - 32u);
            }
        }
    }
    let count = countOneBits(reached.x) + countOneBits(reached.y);
    if (full || !(f32(count) < fp.limit)) {
        masks[i] = vec2<u32>(0u);
        return;
    }
    masks[i] = all_sub_images(n * n) & ~reached;
}
