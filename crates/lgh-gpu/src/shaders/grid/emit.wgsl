// Every vertex's grid light from its sums (lgh_core's splat::Level::push): position
// origin + (v + P/W) h, variance (Q/W - (P/W)^2) h^2 as the deviation pi sigma, intensity,
// normal N/W and mass W; written level by level (S_1 first) as four words of four: vertex
// and mass, position and deviation x, intensity and deviation y, normal and deviation z.
// Zero-intensity lights are dropped on the way back (lgh_gpu::grid).

@group(0) @binding(1) var<storage, read> starts: array<u32>;
@group(0) @binding(2) var<storage, read> keys: array<u32>;
@group(0) @binding(3) var<storage, read> sums: array<f32>;
@group(0) @binding(4) var<storage, read_write> records: array<vec4<u32>>;

fn row3(at: u32) -> vec3<f32> {
    return vec3<f32>(sums[at], sums[at + 1u], sums[at + 2u]);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    for (var g = id.x; g < P.n; g += groups.x * GROUP) {
        // starts: the first vertex of each resolution in use (count + 1), then where each
        // resolution's records start (count).
        var k = 0u;
        while (k + 1u < P.count && starts[k + 1u] <= g) {
            k++;
        }
        let h = ldexp(P.h_top, -i32(k));
        let v = key_vertex(keys[g], 1u << k);
        let at = 16u * g;
        let w = sums[at];
        let inv_w = select(0.0, 1.0 / w, w > 0.0);
        let mean = row3(at + 1u) * inv_w;
        let position = P.origin + (vec3<f32>(v) + mean) * h;
        let variance = max(row3(at + 4u) * inv_w - mean * mean, vec3<f32>(0.0)) * (h * h);
        let deviation = sqrt(variance) * PI;
        let normal = row3(at + 10u) * inv_w;
        let out = 4u * (starts[P.count + 1u + k] + g - starts[k]);
        records[out] = vec4<u32>(v, bitcast<u32>(w));
        records[out + 1u] = bitcast<vec4<u32>>(vec4<f32>(position, deviation.x));
        records[out + 2u] = bitcast<vec4<u32>>(vec4<f32>(row3(at + 7u), deviation.y));
        records[out + 3u] = bitcast<vec4<u32>>(vec4<f32>(normal, deviation.z));
    }
}
