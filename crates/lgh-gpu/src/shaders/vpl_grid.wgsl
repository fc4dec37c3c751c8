// The frame's VPLs in the layout the hierarchy build reads (lgh_gpu::grid's uploaded
// lights: position, intensity, normal, nine floats each), the flux divided by the number of
// light paths as the CPU divides it (Vpls::scale_flux), so that the build reads on the GPU
// exactly what it would have uploaded from the read-back VPLs.
//
// Also the lights' bounds and the first invalid light, as lighting_grid::bounds finds them
// on the CPU, for a build whose VPLs are not read back: per component the least and the
// greatest position as order-preserving bits (`ordered`), and the least index of a light
// with a non-finite position or a non-finite or negative intensity. Min and max do not
// depend on the order of the atomics, so neither does the result. Each workgroup reduces
// in its own memory first, then adds its result with one atomic per word.

struct Params {
    count: u32,
    scale: f32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(2) var<storage, read_write> lights: array<f32>;
// lo.xyz, hi.xyz (ordered bits), the first invalid index, unused; set to
// (max, max, max, 0, 0, 0, max, 0) before the dispatch.
@group(0) @binding(3) var<storage, read_write> bounds: array<atomic<u32>, 8>;

var<workgroup> local_bounds: array<atomic<u32>, 8>;

// The bits of `x` as an unsigned number whose order is that of the floats.
fn ordered(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    if (li < 8u) {
        let empty = select(0u, 0xffffffffu, li < 3u || li == 6u);
        atomicStore(&local_bounds[li], empty);
    }
    workgroupBarrier();
    let i = id.x;
    if (i < params.count) {
        let v = vpls[i];
        let f = v.flux.xyz * params.scale;
        let at = 9u * i;
        lights[at] = v.position.x;
        lights[at + 1u] = v.position.y;
        lights[at + 2u] = v.position.z;
        lights[at + 3u] = f.x;
        lights[at + 4u] = f.y;
        lights[at + 5u] = f.z;
        lights[at + 6u] = v.normal.x;
        lights[at + 7u] = v.normal.y;
        lights[at + 8u] = v.normal.z;
        let p = v.position.xyz;
        for (var c = 0u; c < 3u; c += 1u) {
            atomicMin(&local_bounds[c], ordered(p[c]));
            atomicMax(&local_bounds[3u + c], ordered(p[c]));
        }
        let ok = finite(p.x) && finite(p.y) && finite(p.z) && finite(f.x) && finite(f.y)
            && finite(f.z) && min(f.x, min(f.y, f.z)) >= 0.0;
        if (!ok) {
            atomicMin(&local_bounds[6], i);
        }
    }
    workgroupBarrier();
    if (li < 7u) {
        let v = atomicLoad(&local_bounds[li]);
        if (li < 3u || li == 6u) {
            atomicMin(&bounds[li], v);
        } else {
            atomicMax(&bounds[li], v);
        }
    }
}
