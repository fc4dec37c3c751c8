// The grid lights' rows: record r, if kept, is grid light `index[r]` (the exclusive scan of
// the flags), of the level whose records hold r.

@group(0) @binding(0) var<uniform> params: LightParams;
@group(0) @binding(1) var<storage, read> src: array<u32>;
@group(0) @binding(2) var<storage, read> index: array<u32>;
@group(0) @binding(3) var<storage, read_write> table: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> spheres: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> sub_flags: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    for (var r = id.x; r < params.count; r += 64u * groups.x) {
        let at = 16u * r;
        let i = float3(at + 8u);
        if (!(max(max(i.x, i.y), i.z) > 0.0)) {
            continue;
        }
        var l = 1u;
        while (l < params.l_max && r >= params.start[l + 1u].x) {
            l++;
        }
        let g = index[r];
        let k = g - index[params.start[l].x];
        var m = vec3<f32>(0.0);
        if (params.normals == 1u) {
            m = float3(at + 12u);
        }
        write_light(params.base + g, k, l, float3(at + 4u), m, i, src[at]);
    }
}
