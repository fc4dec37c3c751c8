// The rows of the VPLs shaded as S_0 (level 0), from the build's input lights (position,
// intensity, normal; nine floats each).

@group(0) @binding(0) var<uniform> params: LightParams;
@group(0) @binding(1) var<storage, read> src: array<u32>;
@group(0) @binding(2) var<storage, read_write> table: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> spheres: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> sub_flags: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    for (var v = id.x; v < params.count; v += 64u * groups.x) {
        let at = 9u * v;
        var m = vec3<f32>(0.0);
        if (params.normals == 1u) {
            m = float3(at + 6u);
        }
        write_light(params.base + v, v, 0u, float3(at), m, float3(at + 3u), 0u);
    }
}
