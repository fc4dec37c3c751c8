// The frame's VPLs in the layout the hierarchy build reads (lgh_gpu::grid's uploaded
// lights: position, intensity, normal, nine floats each), the flux divided by the number of
// light paths as the CPU divides it (Vpls::scale_flux), so that the build reads on the GPU
// exactly what it would have uploaded from the read-back VPLs.

struct Params {
    count: u32,
    scale: f32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(2) var<storage, read_write> lights: array<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= params.count) {
        return;
    }
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
}
