// Which tiles a light is listed in (lgh-render's TileBins::from_bounds): the tiles its
// screen rectangle covers whose bounds it may reach. The count and the write kernels visit
// the same tiles (`visit_listings`), each with its own `listed`.

@group(0) @binding(0) var<uniform> P: BinParams;
@group(0) @binding(1) var<uniform> C: Camera;
// Per light: centre and radius (finite; see the flags), then the normal of the plane behind
// which it gives nothing (zero: none; lgh-render's BinLights::facing) and the distance
// within which it gives nothing (BinLights::holes).
@group(0) @binding(2) var<storage, read> spheres: array<vec4<f32>>;
// Per light: its sub-image and flags.
@group(0) @binding(3) var<storage, read> flags: array<u32>;
@group(0) @binding(4) var<storage, read> bounds: array<TileBounds>;

// Relative rounding allowance of the tangent-plane test (lgh-render's ROUNDING).
const ROUNDING: f32 = 1e-5;

// A light's tiles: the tile rectangle [lo.x, hi.x] x [lo.y, hi.y] (none if lo.x > hi.x) and
// its depth range along the view.
struct Span {
    lo: vec2<u32>,
    hi: vec2<u32>,
    z: vec2<f32>,
    everywhere: bool,
}

// The light's tiles (lgh-render's screen_rect and CameraFrame::sphere_bounds).
fn light_span(i: u32) -> Span {
    var s = Span(vec2<u32>(1u, 0u), vec2<u32>(0u, 0u), vec2<f32>(0.0), false);
    let f = flags[i];
    if ((f & LISTED_NOWHERE) != 0u || P.width == 0u || P.height == 0u) {
        return s;
    }
    let full_lo = vec2<u32>(0u);
    let full_hi = vec2<u32>((P.width - 1u) / P.tile, (P.height - 1u) / P.tile);
    if ((f & REACHES_EVERYWHERE) != 0u) {
        s.lo = full_lo;
        s.hi = full_hi;
        s.everywhere = true;
        return s;
    }
    let c = spheres[2u * i].xyz;
    let r = spheres[2u * i].w;
    let d = c - C.origin;
    let cz = dot(d, C.forward);
    if (cz + r < 0.0) {
        return s;
    }
    s.z = vec2<f32>(cz - r, cz + r);
    let cx = dot(d, C.right);
    let cy = dot(d, C.up);
    let den = cz * cz - r * r;
    const MARGIN: f32 = 1e-5;
    if (!(cz > r && den > MARGIN * cz * cz)) {
        s.lo = full_lo;
        s.hi = full_hi;
        return s;
    }
    let root = r * sqrt(vec2<f32>(cx, cy) * vec2<f32>(cx, cy) + den);
    let mid = vec2<f32>(cx, cy) * cz;
    let slack = MARGIN * (abs(mid) + root) + 1.17549435e-38;
    let m_lo = (mid - root - slack) / den;
    let m_hi = (mid + root + slack) / den;
    let size = C.size;
    let lo_x = (m_lo.x / C.scale.x + 1.0) * 0.5 * size.x - C.jitter_x;
    let hi_x = (m_hi.x / C.scale.x + 1.0) * 0.5 * size.x - C.jitter_x;
    let lo_y = (1.0 - m_hi.y / C.scale.y) * 0.5 * size.y - C.jitter_y;
    let hi_y = (1.0 - m_lo.y / C.scale.y) * 0.5 * size.y - C.jitter_y;
    if (hi_x < 0.0 || hi_y < 0.0 || lo_x >= f32(P.width) || lo_y >= f32(P.height)) {
        return s;
    }
    let wm = f32(P.width - 1u);
    let hm = f32(P.height - 1u);
    s.lo = vec2<u32>(u32(clamp(lo_x, 0.0, wm)), u32(clamp(lo_y, 0.0, hm))) / P.tile;
    s.hi = vec2<u32>(u32(clamp(hi_x, 0.0, wm)), u32(clamp(hi_y, 0.0, hm))) / P.tile;
    return s;
}

// False only if no surface point of the tile of bounds `b` can lie in light i's sphere in
// front of its tangent plane and, for a light with normal m, in front of the light's own
// plane, and farther than `hole` from it (lgh-render's TileBounds::reach_lanes, any lane).
// An empty tile or slice holds no point and keeps no light, whatever its reach.
fn may_reach(b: TileBounds, s: Span, c: vec3<f32>, r: f32, m: vec3<f32>, hole: f32) -> bool {
    let facing = any(m != vec3<f32>(0.0));
    if (b.z.z == 0.0) {
        return false;
    }
    if (!s.everywhere && (b.z.x > s.z.y || b.z.y < s.z.x)) {
        return false;
    }
    for (var k = 0u; k < SLICES; k++) {
        if (b.lo[k].w == 0.0) {
            continue;
        }
        let lo = b.lo[k].xyz;
        let hi = b.hi[k].xyz;
        let d = max(max(lo - c, c - hi), vec3<f32>(0.0));
        let f = max(abs(c - lo), abs(hi - c));
        let far = sqrt(dot(f, f));
        let ns = b.normal[k].xyz;
        let nc = ns.x * c.x + ns.y * c.y + ns.z * c.z;
        let allowance = (length(c) + far) * ROUNDING;
        let behind = nc - b.normal[k].w + b.hi[k].w * far + allowance <= 0.0;
        // The greatest m . (x - c) over the box.
        let front = max((lo - c) * m, (hi - c) * m);
        let unlit = facing && front.x + front.y + front.z + allowance <= 0.0;
        let inside = far + allowance < hole;
        if ((s.everywhere || dot(d, d) <= r * r) && !behind && !unlit && !inside) {
            return true;
        }
    }
    return false;
}

// List l of tile (tx, ty) of light i's sub-image.
fn list_of(i: u32, tx: u32, ty: u32) -> u32 {
    return (flags[i] & 0xffffu) * P.tiles_x * P.tiles_y + ty * P.tiles_x + tx;
}

// Calls `listed(i, l)` (the kernel's own) for every list l that light i is listed in, for
// the lights i of this invocation (from `first` with the dispatch's `stride`).
fn visit_listings(first: u32, stride: u32) {
    for (var i = first; i < P.lights; i += stride) {
        let s = light_span(i);
        let c = spheres[2u * i].xyz;
        let r = spheres[2u * i].w;
        let m = spheres[2u * i + 1u].xyz;
        let hole = spheres[2u * i + 1u].w;
        for (var ty = s.lo.y; ty <= s.hi.y; ty++) {
            for (var tx = s.lo.x; tx <= s.hi.x; tx++) {
                let l = list_of(i, tx, ty);
                if (may_reach(bounds[l], s, c, r, m, hole)) {
                    listed(i, l);
                }
            }
        }
    }
}
