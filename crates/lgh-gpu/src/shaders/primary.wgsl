// Primary rays into the G-buffer (lgh-render's GBuffer::render_into): one ray per pixel
// through its sample point (the centre moved by the jitter), the closest hit, the surface
// there. Writes the G-buffer's packed pixel (lgh_gpu::gbuffer: position with w = 1 for a
// hit, shading normal, geometric normal, albedo with w = the linear depth; zeros where the
// ray meets nothing) and the emitted radiance towards the camera.

struct Params {
    origin: vec3<f32>,
    width: u32,
    forward: vec3<f32>,
    height: u32,
    right: vec3<f32>,
    jitter_x: f32,
    up: vec3<f32>,
    jitter_y: f32,
    scale: vec2<f32>,
    size: vec2<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> nodes: array<Node>;
@group(0) @binding(2) var<storage, read> tris: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> shade: array<TriShade>;
@group(0) @binding(4) var<storage, read> materials: array<Material>;
@group(0) @binding(5) var<storage, read> texels: array<u32>;
@group(0) @binding(6) var<storage, read_write> gbuffer: array<Pixel>;
@group(0) @binding(7) var<storage, read_write> emission: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.x;
    if (p >= params.width * params.height) {
        return;
    }
    // CameraFrame::sample_point and CameraFrame::direction.
    let px = vec2<f32>(f32(p % params.width) + 0.5, f32(p / params.width) + 0.5)
        + vec2<f32>(params.jitter_x, params.jitter_y);
    let ndc = vec2<f32>(2.0 * px.x / params.size.x - 1.0, 1.0 - 2.0 * px.y / params.size.y);
    let v = params.forward + params.right * (ndc.x * params.scale.x)
        + params.up * (ndc.y * params.scale.y);
    let d = v * (1.0 / sqrt(dot(v, v)));
    let hit = trace(params.origin, d, 3.4e38, false);
    if (hit.tri == NONE) {
        gbuffer[p] = Pixel(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
        emission[p] = vec4<f32>(0.0);
        return;
    }
    let s = surface_at(hit, params.origin, d);
    let depth = dot(s.position - params.origin, params.forward);
    gbuffer[p] = Pixel(
        vec4<f32>(s.position, 1.0),
        vec4<f32>(s.normal, 0.0),
        vec4<f32>(s.geo_normal, 0.0),
        vec4<f32>(s.albedo, depth),
    );
    emission[p] = vec4<f32>(s.emission, 0.0);
}
