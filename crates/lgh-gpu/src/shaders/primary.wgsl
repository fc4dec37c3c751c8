// Primary rays into the G-buffer (lgh-render's GBuffer::render_into): one ray per pixel
// through its sample point (the centre moved by the jitter), the closest hit, the surface
// there. Writes the G-buffer's packed pixel (lgh_gpu::gbuffer: position with w = 1 for a
// hit, shading normal with w = 1 where the surface emits towards the camera, geometric
// normal, albedo with w = the linear depth; zeros where the ray meets nothing) and the
// emitted radiance towards the camera.

@group(0) @binding(0) var<uniform> camera: Camera;
// Bindings 1-5: the scene's BVH and surfaces (surface.wgsl).
@group(0) @binding(6) var<storage, read_write> gbuffer: array<Pixel>;
@group(0) @binding(7) var<storage, read_write> emission: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.x;
    if (p >= camera.width * camera.height) {
        return;
    }
    let d = camera_direction(camera, sample_point(camera, p % camera.width, p / camera.width));
    let hit = trace(camera.origin, d, 3.4e38, false);
    if (hit.tri == NONE) {
        gbuffer[p] = Pixel(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
        emission[p] = vec4<f32>(0.0);
        return;
    }
    let s = surface_at(hit, camera.origin, d, true);
    let depth = dot(s.position - camera.origin, camera.forward);
    gbuffer[p] = Pixel(
        vec4<f32>(s.position, 1.0),
        vec4<f32>(s.normal, select(0.0, 1.0, any(s.emission != vec3<f32>(0.0)))),
        vec4<f32>(s.geo_normal, 0.0),
        vec4<f32>(s.albedo, depth),
    );
    emission[p] = vec4<f32>(s.emission, 0.0);
}
