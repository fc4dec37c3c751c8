// The camera's primary rays (lgh-scene's CameraFrame::sample_point and ::direction).

struct Camera {
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

// The sample point of pixel (x, y): its centre moved by the jitter.
fn sample_point(c: Camera, x: u32, y: u32) -> vec2<f32> {
    return vec2<f32>(f32(x) + 0.5, f32(y) + 0.5) + vec2<f32>(c.jitter_x, c.jitter_y);
}

// The unit direction through the image point `px` (pixels from the top-left corner).
fn camera_direction(c: Camera, px: vec2<f32>) -> vec3<f32> {
    let ndc = vec2<f32>(2.0 * px.x / c.size.x - 1.0, 1.0 - 2.0 * px.y / c.size.y);
    let v = c.forward + c.right * (ndc.x * c.scale.x) + c.up * (ndc.y * c.scale.y);
    return v * (1.0 / sqrt(dot(v, v)));
}

// The image point (pixels) of the world point `p` and its depth along the viewing direction
// (lgh-scene's CameraFrame::project); w is 0 behind the camera (the point is then not
// seen), else 1.
fn camera_project(c: Camera, p: vec3<f32>) -> vec4<f32> {
    let d = p - c.origin;
    let z = dot(d, c.forward);
    if (z <= 0.0) {
        return vec4<f32>(0.0);
    }
    let x = dot(d, c.right) / (z * c.scale.x);
    let y = dot(d, c.up) / (z * c.scale.y);
    let px = vec2<f32>((x + 1.0) * 0.5 * c.size.x, (1.0 - y) * 0.5 * c.size.y)
        - vec2<f32>(c.jitter_x, c.jitter_y);
    return vec4<f32>(px, z, 1.0);
}
