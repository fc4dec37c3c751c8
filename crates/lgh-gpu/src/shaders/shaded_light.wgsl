// A shaded light of lgh's loop and its geometric factor at a pixel (LGH 2019 section 3.2,
// Eq. 3's blending B_l), shared by the lighting loop (lgh.wgsl) and the guests of cut
// recombination windows (fill/guests.wgsl).

// A shaded light: position and reach^2; mean normal and isotropic share; intensity (times
// n^2) and radius r_l; blending floors, level and the x of its vertex (bits of u32s).
struct Light {
    position: vec4<f32>,
    normal: vec4<f32>,
    intensity: vec4<f32>,
    role: vec4<f32>,
}

// B_l(d) for t = d / r_l with the role's floors (lgh_core::blending::LevelRole::floors).
fn blend(t: f32, rise: f32, fall: f32) -> f32 {
    return min(max(clamp(2.0 * t - 1.0, 0.0, 1.0), rise), max(clamp(2.0 - t, 0.0, 1.0), fall));
}

// The geometric factor of light `l` at x (normal n) with the clamp eps^2 = `eps2`:
// B_l(d) cos_x cos_v / (pi (d^2 + eps^2)), as lgh-render's LightBatch::eval; zero where the
// sphere does not reach x.
fn light_factor(l: Light, x: vec3<f32>, n: vec3<f32>, eps2: f32) -> f32 {
    let d = l.position.xyz - x;
    let d2 = dot(d, d);
    if (!(d2 < l.position.w) || d2 <= 0.0) {
        return 0.0;
    }
    let dl = sqrt(d2);
    let inv_d = 1.0 / dl;
    let b = blend(dl / l.intensity.w, l.role.x, l.role.y);
    let cos_x = dot(n, d) * inv_d;
    let cos_v = max(-dot(l.normal.xyz, d) * inv_d, 0.0) + l.normal.w;
    if (b <= 0.0 || cos_x <= 0.0 || cos_v <= 0.0) {
        return 0.0;
    }
    return b * cos_x * cos_v / (PI * (d2 + eps2));
}
