// Traversal of a binary BVH (obvhs's BVH2, flattened on the CPU: an inner node's children
// are nodes[first] and nodes[first + 1], a leaf holds `count` triangles from `first` in leaf
// order) with the Moller-Trumbore triangle test: any hit (shadow rays) or the closest hit
// (primary rays). Included by the kernels that trace rays.
//
// Alpha cut-outs (lgh_gpu::cutouts, lgh-scene's Cutouts::covers) live in the same buffer as
// the triangles, after them: the w of a triangle's first corner holds, as bits, the index of
// its record (0: opaque); a record is two vec4s (its corners' texture coordinates, then the
// index of its cut-out), a cut-out two (width, height, wrap bits and the index of its first
// texel word; factor, cutoff, whether it has a texture), the texels 8-bit alphas, 16 a vec4.

struct Node {
    lo: vec3<f32>,
    count: u32,
    hi: vec3<f32>,
    first: u32,
}

// The slab test: the entry distance of the ray into the box, or a huge value if it misses
// the box within (0, t_max).
fn box_entry(lo: vec3<f32>, hi: vec3<f32>, o: vec3<f32>, inv_d: vec3<f32>, t_max: f32) -> f32 {
    let t0 = (lo - o) * inv_d;
    let t1 = (hi - o) * inv_d;
    let tn = max(max(min(t0.x, t1.x), min(t0.y, t1.y)), max(min(t0.z, t1.z), 0.0));
    let tf = min(min(max(t0.x, t1.x), max(t0.y, t1.y)), min(max(t0.z, t1.z), t_max));
    return select(3.4e38, tn, tn <= tf);
}

// Moller-Trumbore: (t, b1, b2) of the hit of triangle t within (0, t_max), with b1 and b2
// the barycentric weights of its second and third corners; t is negative for a miss.
fn triangle_hit(t: u32, o: vec3<f32>, d: vec3<f32>, t_max: f32) -> vec3<f32> {
    let a = tris[3u * t].xyz;
    let e1 = tris[3u * t + 1u].xyz - a;
    let e2 = tris[3u * t + 2u].xyz - a;
    let p = cross(d, e2);
    let det = dot(e1, p);
    // Only an exactly parallel ray is refused here (a bound on |det| in scene units would
    // miss every triangle of a small enough scene); a nearly parallel one gets barycentrics
    // far outside.
    if (det == 0.0) {
        return vec3<f32>(-1.0, 0.0, 0.0);
    }
    let inv = 1.0 / det;
    let s = o - a;
    let u = dot(s, p) * inv;
    let q = cross(s, e1);
    let v = dot(d, q) * inv;
    let tt = dot(e2, q) * inv;
    let inside = u >= 0.0 && v >= 0.0 && u + v <= 1.0 && tt > 0.0 && tt < t_max;
    return vec3<f32>(select(-1.0, tt, inside), u, v);
}

// A cut-out's alpha texel i (0..255) from the packed words at vec4 index `first`.
fn alpha_texel(first: u32, i: u32) -> f32 {
    let word = bitcast<u32>(tris[first + i / 16u][(i / 4u) % 4u]);
    return f32((word >> (8u * (i % 4u))) & 0xffu);
}

// Cutouts::covers: true if triangle t (leaf order) is there at barycentrics (b1, b2).
fn covers(t: u32, b1: f32, b2: f32) -> bool {
    let r = bitcast<u32>(tris[3u * t].w);
    if (r == 0u) {
        return true;
    }
    let c01 = tris[r];
    let c2 = tris[r + 1u];
    let uv = c01.xy * (1.0 - b1 - b2) + c01.zw * b1 + c2.xy * b2;
    let k = bitcast<u32>(c2.z);
    let head = tris[k];
    let consts = tris[k + 1u];
    var alpha = 1.0;
    if (consts.z != 0.0) {
        // Texture::alpha_at: bilinear, v up.
        let w = i32(bitcast<u32>(head.x));
        let h = i32(bitcast<u32>(head.y));
        let first = bitcast<u32>(head.w);
        let b = bilinear(uv, w, h, bitcast<u32>(head.z));
        let a00 = alpha_texel(first, b.i.x);
        let a01 = alpha_texel(first, b.i.y);
        let a10 = alpha_texel(first, b.i.z);
        let a11 = alpha_texel(first, b.i.w);
        let top = a00 + (a01 - a00) * b.f.x;
        let bottom = a10 + (a11 - a10) * b.f.x;
        alpha = (top + (bottom - top) * b.f.y) / 255.0;
    }
    return consts.x * alpha >= consts.y;
}

const STACK: u32 = 48u;
const NONE: u32 = 0xffffffffu;

// A ray's hit: distance t, the triangle (in leaf order; NONE for a miss) and the
// barycentric weights b1, b2 of its second and third corners.
struct Hit {
    t: f32,
    tri: u32,
    b1: f32,
    b2: f32,
}

// The triangles on o + t d, t in (0, t_max): the nearest one, or with `any` the first one
// found (a shadow ray needs no more).
fn trace(o: vec3<f32>, d: vec3<f32>, t_max: f32, any: bool) -> Hit {
    var best = Hit(t_max, NONE, 0.0, 0.0);
    if (arrayLength(&nodes) == 0u || !(t_max > 0.0)) {
        return best;
    }
    // Zero components become tiny ones: WGSL leaves x / 0 undefined.
    let inv_d = 1.0 / select(d, vec3<f32>(1e-20), abs(d) < vec3<f32>(1e-20));
    var stack: array<u32, STACK>;
    var top = 0u;
    var node = 0u;
    if (box_entry(nodes[0].lo, nodes[0].hi, o, inv_d, t_max) > 3.0e38) {
        return best;
    }
    loop {
        let n = nodes[node];
        // The node visited next; NONE: take one from the stack.
        var next = NONE;
        if (n.count > 0u) {
            for (var i = 0u; i < n.count; i++) {
                let h = triangle_hit(n.first + i, o, d, best.t);
                if (h.x > 0.0 && covers(n.first + i, h.y, h.z)) {
                    best = Hit(h.x, n.first + i, h.y, h.z);
                    if (any) {
                        return best;
                    }
                }
            }
        } else {
            let a = n.first;
            let b = n.first + 1u;
            let ta = box_entry(nodes[a].lo, nodes[a].hi, o, inv_d, best.t);
            let tb = box_entry(nodes[b].lo, nodes[b].hi, o, inv_d, best.t);
            let hit_a = ta < 3.0e38;
            let hit_b = tb < 3.0e38;
            if (hit_a && hit_b) {
                // Nearer child first, the other on the stack (the BVH's depth is checked
                // against STACK when it is uploaded).
                next = select(b, a, ta <= tb);
                stack[top] = select(a, b, ta <= tb);
                top++;
            } else if (hit_a) {
                next = a;
            } else if (hit_b) {
                next = b;
            }
        }
        if (next == NONE) {
            if (top == 0u) {
                break;
            }
            top--;
            next = stack[top];
        }
        node = next;
    }
    return best;
}

// True if any triangle lies on o + t d, t in (0, t_max).
fn occluded(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> bool {
    return trace(o, d, t_max, true).tri != NONE;
}

// World::offset: p moved off its surface (geometric normal n) by eps towards `towards`.
fn offset(p: vec3<f32>, n: vec3<f32>, towards: vec3<f32>, eps: f32) -> vec3<f32> {
    let s = select(-1.0, 1.0, dot(n, towards) >= 0.0);
    return p + n * (s * eps);
}

// World::occluded_between: both ends moved off their surfaces (geometric normals na, nb) by
// eps first, so that neither surface shadows itself.
fn occluded_between(a: vec3<f32>, na: vec3<f32>, b: vec3<f32>, nb: vec3<f32>, eps: f32) -> bool {
    let o = offset(a, na, b - a, eps);
    let e = offset(b, nb, a - b, eps);
    let d = e - o;
    let len = length(d);
    if (len <= eps) {
        return false;
    }
    return occluded(o, d / len, len * (1.0 - 1e-4));
}
