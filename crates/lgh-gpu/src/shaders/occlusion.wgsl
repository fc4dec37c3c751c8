// Occlusion between pairs of surface points (one invocation a pair), with the offsets of
// World::occluded_between: the GPU's counterpart of the CPU tracer's shadow rays, for tests
// and benchmarks of the traversal.

// Two surface points with their geometric normals; the offset in a.w.
struct Pair {
    a: vec4<f32>,
    na: vec4<f32>,
    b: vec4<f32>,
    nb: vec4<f32>,
}

@group(0) @binding(0) var<storage, read> pairs: array<Pair>;
@group(0) @binding(1) var<storage, read> nodes: array<Node>;
@group(0) @binding(2) var<storage, read> tris: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> blocked: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&pairs)) {
        return;
    }
    let p = pairs[i];
    blocked[i] = select(0u, 1u, occluded_between(p.a.xyz, p.na.xyz, p.b.xyz, p.nb.xyz, p.a.w));
}
