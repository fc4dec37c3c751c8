// The bounds of every list's tile (lgh-render's AllBounds::new), one invocation a list, its
// pixels in the CPU's order (row by row): the depth range of the pixels that see a surface,
// then per depth slice the box, the first normal n_s, the spread and the plane. Minima and
// maxima do not depend on the order; the first normal is the CPU's since the order is.
// Where pixels fill their cut recombination windows (P.fill; fill/masks.wgsl), a list's
// tile holds its sub-image's pixels and the tile's guests that miss the sub-image
// (lgh-render's AllBounds::with_guests), row by row as the CPU visits them.

@group(0) @binding(0) var<uniform> P: BinParams;
@group(0) @binding(1) var<storage, read> gbuffer: array<Pixel>;
@group(0) @binding(2) var<storage, read_write> bounds: array<TileBounds>;
// Per pixel, the sub-images it shades as a guest (read where P.fill is 1).
@group(0) @binding(3) var<storage, read> masks: array<vec2<u32>>;

// Whether pixel (x, y) counts in the bounds of a list of sub-image s, where the list's tile
// has `guests`: its own sub-image, or one it shades as a guest.
fn listed(x: u32, y: u32, s: u32, guests: bool) -> bool {
    if (!guests || (y % P.n) * P.n + x % P.n == s) {
        return true;
    }
    return has_bit(masks[y * P.width + x], s);
}

// Whether a pixel of tile t (tx, ty, sub-image s) shades sub-image s as a guest: the
// masks alone are read, an eighth of the pixels' bytes.
fn has_guests(t: vec3<u32>) -> bool {
    if (P.fill == 0u) {
        return false;
    }
    var all_masks = vec2<u32>(0u);
    for (var y = t.y * P.tile; y < min((t.y + 1u) * P.tile, P.height); y++) {
        for (var x = t.x * P.tile; x < min((t.x + 1u) * P.tile, P.width); x++) {
            all_masks |= masks[y * P.width + x];
        }
    }
    return has_bit(all_masks, t.z);
}

// a / b correctly rounded, as the CPU divides (WGSL's division may be 2.5 ulp off, and the
// quotient picks a slice).
fn div_rn1(a: f32, b: f32) -> f32 {
    var r = 1.0 / b;
    r = fma(fma(-b, r, 1.0), r, r);
    let q = a * r;
    return fma(fma(-q, b, a), r, q);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) nw: vec3<u32>) {
    for (var l = id.x; l < P.lists; l += nw.x * 64u) {
        let t = list_tile(l);
        let sx = t.z % P.n;
        let sy = t.z / P.n;
        // With guests every pixel of the tile, else its sub-image's alone.
        let guests = has_guests(t);
        let step = select(P.n, 1u, guests);
        let x0 = t.x * P.tile + select(sx, 0u, guests);
        let x1 = min((t.x + 1u) * P.tile, P.width);
        let y0 = t.y * P.tile + select(sy, 0u, guests);
        let y1 = min((t.y + 1u) * P.tile, P.height);
        var zmin = 0.0;
        var zmax = 0.0;
        var seen = false;
        for (var y = y0; y < y1; y += step) {
            for (var x = x0; x < x1; x += step) {
                let p = gbuffer[y * P.width + x];
                if (p.position.w > 0.5 && listed(x, y, t.z, guests)) {
                    let z = p.albedo.w;
                    if (seen) {
                        zmin = min(zmin, z);
                        zmax = max(zmax, z);
                    } else {
                        zmin = z;
                        zmax = z;
                        seen = true;
                    }
                }
            }
        }
        var b: TileBounds;
        b.z = vec4<f32>(zmin, zmax, select(0.0, 1.0, seen), 0.0);
        let span = zmax - zmin;
        for (var y = y0; y < y1 && seen; y += step) {
            for (var x = x0; x < x1; x += step) {
                let p = gbuffer[y * P.width + x];
                if (p.position.w <= 0.5 || !listed(x, y, t.z, guests)) {
                    continue;
                }
                var k = 0u;
                if (span > 0.0) {
                    k = min(u32(div_rn1(p.albedo.w - zmin, span) * f32(SLICES)), SLICES - 1u);
                }
                let x_ = p.position.xyz;
                let n = p.normal.xyz;
                if (b.lo[k].w == 0.0) {
                    // The slice's first point sets its normal.
                    b.lo[k] = vec4<f32>(x_, 1.0);
                    b.hi[k] = vec4<f32>(x_, 0.0);
                    b.normal[k] = vec4<f32>(n, dot(n, x_));
                } else {
                    let ns = b.normal[k].xyz;
                    b.lo[k] = vec4<f32>(min(b.lo[k].xyz, x_), 1.0);
                    b.hi[k] = vec4<f32>(max(b.hi[k].xyz, x_), max(b.hi[k].w, length(n - ns)));
                    b.normal[k].w = min(b.normal[k].w, dot(ns, x_));
                }
            }
        }
        bounds[l] = b;
    }
}
