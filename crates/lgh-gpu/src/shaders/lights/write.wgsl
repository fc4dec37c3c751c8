// What the row kernels write (they declare `table`, `spheres` and `sub_flags`).

// Writes shaded light `j` (sub-image index `k` within its level) of level `l`.
fn write_light(j: u32, k: u32, l: u32, p: vec3<f32>, m: vec3<f32>, i: vec3<f32>, vertex_x: u32) {
    let lv = params.level[l];
    let everywhere = lv.reach < 0.0;
    let reach2 = select(lv.reach * lv.reach, MAX_FLOAT, everywhere);
    let iso = iso_share(m, params.energy);
    table[4u * j] = vec4<f32>(p, reach2);
    table[4u * j + 1u] = vec4<f32>(m, iso);
    table[4u * j + 2u] = vec4<f32>(i * params.scale, lv.radius);
    table[4u * j + 3u] = vec4<f32>(lv.rise, lv.fall, f32(l), bitcast<f32>(vertex_x));
    spheres[2u * j] = vec4<f32>(p, select(lv.reach, 0.0, everywhere));
    // The normal of the plane behind which the light gives nothing (lgh-render's
    // emission_facing) and the distance within which it gives nothing (LevelRole::hole).
    let facing = select(vec3<f32>(0.0), m, iso == 0.0);
    spheres[2u * j + 1u] = vec4<f32>(facing, select(0.0, 0.5 * lv.radius, lv.rise == 0.0));
    sub_flags[j] = (k % params.n2) | select(0u, REACHES_EVERYWHERE, everywhere);
}
