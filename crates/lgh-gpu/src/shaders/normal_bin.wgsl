
// The normal bin of `n`, as lgh-render's `normal_bin` decides it: 2 x (the axis of the
// largest component, the first of equal ones) + (1 where that component is negative).
fn normal_bin(n: vec3<f32>) -> u32 {
    let a = abs(n);
    var axis = 2u;
    if (a.x >= a.y && a.x >= a.z) {
        axis = 0u;
    } else if (a.y >= a.z) {
        axis = 1u;
    }
    return 2u * axis + select(0u, 1u, n[axis] < 0.0);
}
