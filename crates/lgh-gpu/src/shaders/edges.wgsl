// The edge resolve's sub-pixel samples (lgh-render's passes::edge_aa::EdgeResolve::new):
// a pixel whose 3 x 3 neighbourhood shows more than one surface traces `samples - 1`
// primary rays at the given sub-pixel offsets (the first sample is the pixel's own centre),
// and counts, per neighbour, the samples that take its radiance: the pixel itself if the
// sample lies on its surface, else the nearest neighbour whose does, else the pixel. Each
// edge pixel appends (pixel, its nine counts as bytes) to `edges`; the list's order is
// the scheduler's, and the CPU sorts it by pixel.

struct Params {
    camera: Camera,
    samples: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
    // Sub-pixel offsets, two to an entry.
    offsets: array<vec4<f32>, 32>,
}

@group(0) @binding(0) var<uniform> params: Params;
// Bindings 1-5: the scene's BVH and surfaces (surface.wgsl).
@group(0) @binding(6) var<storage, read> gbuffer: array<Pixel>;
@group(0) @binding(7) var<storage, read_write> edges: array<vec4<u32>>;
@group(0) @binding(8) var<storage, read_write> edge_count: atomic<u32>;

// SAME_SURFACE_COS and SAME_SURFACE_PLANE of edge_aa.
const SAME_COS: f32 = 0.95;
const SAME_PLANE: f32 = 2e-3;

// What a primary ray saw (edge_aa's Seen).
struct Seen {
    hit: bool,
    position: vec3<f32>,
    normal: vec3<f32>,
    emits: bool,
}

fn seen_pixel(j: u32) -> Seen {
    let px = gbuffer[j];
    return Seen(px.position.w > 0.0, px.position.xyz, px.geo_normal.xyz, px.normal.w > 0.0);
}

// The depth that scales the plane test: the pixel's, 1 where it sees nothing.
fn pixel_depth(j: u32) -> f32 {
    let px = gbuffer[j];
    return select(1.0, px.albedo.w, px.position.w > 0.0);
}

// Seen::on: a lies on b's surface, within a distance from its tangent plane relative to
// `depth`.
fn on(a: Seen, b: Seen, depth: f32) -> bool {
    if (a.emits != b.emits) {
        return false;
    }
    if (!a.hit && !b.hit) {
        return true;
    }
    if (a.hit && b.hit) {
        return dot(a.normal, b.normal) >= SAME_COS
            && abs(dot(b.normal, a.position - b.position)) <= SAME_PLANE * max(depth, 1e-6);
    }
    return false;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let c = params.camera;
    let i = id.x;
    if (i >= c.width * c.height) {
        return;
    }
    let x = i % c.width;
    let y = i / c.width;
    // The 3 x 3 neighbours, row by row (NONE outside the image).
    var near: array<u32, 9>;
    for (var k = 0u; k < 9u; k++) {
        let nx = i32(x) + i32(k % 3u) - 1;
        let ny = i32(y) + i32(k / 3u) - 1;
        let inside = nx >= 0 && ny >= 0 && nx < i32(c.width) && ny < i32(c.height);
        near[k] = select(NONE, u32(ny) * c.width + u32(nx), inside);
    }
    let here = seen_pixel(i);
    let d_here = pixel_depth(i);
    var edge = false;
    for (var k = 0u; k < 9u; k++) {
        if (near[k] != NONE && !on(seen_pixel(near[k]), here, d_here)) {
            edge = true;
        }
    }
    if (!edge) {
        return;
    }
    var counts: array<u32, 9>;
    counts[4] = 1u;
    let centre = sample_point(c, x, y);
    for (var s = 1u; s < params.samples; s++) {
        let pair = params.offsets[s / 2u];
        let o = select(pair.xy, pair.zw, (s & 1u) == 1u);
        let d = camera_direction(c, centre + o);
        let hit = trace(c.origin, d, 3.4e38, false);
        var seen = Seen(false, vec3<f32>(0.0), vec3<f32>(0.0), false);
        if (hit.tri != NONE) {
            let sf = surface_at(hit, c.origin, d, true);
            seen = Seen(true, sf.position, sf.geo_normal, any(sf.emission != vec3<f32>(0.0)));
        }
        // best_match: the pixel itself, else the nearest neighbour (the first of equals).
        var best = 4u;
        if (!on(seen, seen_pixel(i), pixel_depth(i))) {
            var best_d = 3.4e38;
            var found = false;
            for (var k = 0u; k < 9u; k++) {
                let j = near[k];
                if (j == NONE || !on(seen, seen_pixel(j), pixel_depth(j))) {
                    continue;
                }
                var dist = 0.0;
                if (seen.hit) {
                    let v = seen.position - gbuffer[j].position.xyz;
                    dist = dot(v, v);
                }
                if (!found || dist < best_d) {
                    found = true;
                    best_d = dist;
                    best = k;
                }
            }
        }
        counts[best] += 1u;
    }
    let at = atomicAdd(&edge_count, 1u);
    edges[at] = vec4<u32>(
        i,
        counts[0] | (counts[1] << 8u) | (counts[2] << 16u) | (counts[3] << 24u),
        counts[4] | (counts[5] << 8u) | (counts[6] << 16u) | (counts[7] << 24u),
        counts[8],
    );
}
