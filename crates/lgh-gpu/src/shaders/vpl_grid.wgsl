// The frame's VPLs in the layout the hierarchy build reads (lgh_gpu::grid's uploaded
// lights: position, intensity, normal, nine floats each), the flux divided by the number of
// light paths as the CPU divides it (Vpls::scale_flux), so that the build reads on the GPU
// exactly what it would have uploaded from the read-back VPLs. With `bins`, sorted by normal
// bin (each bin's VPLs in their order, at the place shaders/vpl_bins.wgsl's bits and their
// prefix sum give), as the CPU splits them for one hierarchy per bin.
//
// Also, per bin (one bin without `bins`), the lights' bounds, the first invalid light and
// the number of lights, as lighting_grid::bounds finds them on the CPU, for a build whose
// VPLs are not read back: per component the least and the greatest position as
// order-preserving bits (`ordered`), and the least index (within the bin) of a light with a
// non-finite position or a non-finite or negative intensity. Min, max and integer sums do
// not depend on the order of the atomics, so neither does the result. Each workgroup
// reduces in its own memory first, then adds its result with one atomic per word.

//
// The number of VPLs and of light paths are read from the paths' status
// (shaders/vpl_compact.wgsl), so that the conversion can be recorded in the submission
// that traces them, before they are known; the dispatch covers `capacity` VPLs.

struct Params {
    capacity: u32,
    // 1: sorted by normal bin.
    bins: u32,
    // Words per bin of `bits`.
    words: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(2) var<storage, read_write> lights: array<f32>;
// Per bin: lo.xyz, hi.xyz (ordered bits), the first invalid index, the count; set to
// (max, max, max, 0, 0, 0, max, 0) before the dispatch.
@group(0) @binding(3) var<storage, read_write> bounds: array<atomic<u32>>;
// shaders/vpl_bins.wgsl's bits and their exclusive prefix sum (with `bins`).
@group(0) @binding(4) var<storage, read> bits: array<u32>;
@group(0) @binding(5) var<storage, read> prefix: array<u32>;
// The light paths' status: kept paths of the last batch, VPLs, kept paths in all.
@group(0) @binding(6) var<storage, read> status: array<u32>;

const BIN_WORDS: u32 = 48u;

var<workgroup> local_bounds: array<atomic<u32>, BIN_WORDS>;

// The bits of `x` as an unsigned number whose order is that of the floats.
fn ordered(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

// Whether word `k` of a bin's eight is a minimum (lo, the first invalid index).
fn is_min(k: u32) -> bool {
    return k < 3u || k == 6u;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    for (var k = li; k < BIN_WORDS; k += 64u) {
        atomicStore(&local_bounds[k], select(0u, 0xffffffffu, is_min(k % 8u)));
    }
    workgroupBarrier();
    let i = id.x;
    // One over the number of paths, as the CPU's `1.0 / paths as f32`.
    let scale = recip_rn(max(status[2], 1u));
    if (i < min(status[1], params.capacity)) {
        let v = vpls[i];
        var bin = 0u;
        var at = i;
        var first = 0u;
        if (params.bins != 0u) {
            bin = normal_bin(v.normal.xyz);
            let w = bin * params.words + i / 32u;
            first = prefix[bin * params.words];
            at = prefix[w] + countOneBits(bits[w] & ((1u << (i % 32u)) - 1u));
        }
        let f = v.flux.xyz * scale;
        let o = 9u * at;
        lights[o] = v.position.x;
        lights[o + 1u] = v.position.y;
        lights[o + 2u] = v.position.z;
        lights[o + 3u] = f.x;
        lights[o + 4u] = f.y;
        lights[o + 5u] = f.z;
        lights[o + 6u] = v.normal.x;
        lights[o + 7u] = v.normal.y;
        lights[o + 8u] = v.normal.z;
        let p = v.position.xyz;
        let b = 8u * bin;
        for (var c = 0u; c < 3u; c += 1u) {
            atomicMin(&local_bounds[b + c], ordered(p[c]));
            atomicMax(&local_bounds[b + 3u + c], ordered(p[c]));
        }
        let ok = finite(p.x) && finite(p.y) && finite(p.z) && finite(f.x) && finite(f.y)
            && finite(f.z) && min(f.x, min(f.y, f.z)) >= 0.0;
        if (!ok) {
            atomicMin(&local_bounds[b + 6u], at - first);
        }
        atomicAdd(&local_bounds[b + 7u], 1u);
    }
    workgroupBarrier();
    for (var k = li; k < BIN_WORDS; k += 64u) {
        let v = atomicLoad(&local_bounds[k]);
        let c = k % 8u;
        if (is_min(c)) {
            if (v != 0xffffffffu) {
                atomicMin(&bounds[k], v);
            }
        } else if (c < 6u) {
            if (v != 0u) {
                atomicMax(&bounds[k], v);
            }
        } else if (v != 0u) {
            atomicAdd(&bounds[k], v);
        }
    }
}
