// The surface at a ray's hit, as lgh-render's World::surface computes it: the geometric
// normal facing the ray, the interpolated shading normal (the geometric one where a corner
// has none), the albedo (factor x bilinear texture, clamped to [0, 1], x the interpolated
// vertex colours) and the one-sided
// emission. It declares bindings 1-5 of every kernel that includes it, in the order of
// lgh_gpu::surfaces::GpuSurfaces::bindings: the BVH's nodes and triangles (bvh.wgsl), the
// triangles' shading data, the materials and the texels.

// One triangle's shading data, in the BVH's leaf order: the unit face normal (w: the
// material's index, as bits) and the corners' normals and texture coordinates.
struct TriShade {
    face: vec4<f32>,
    n0: vec4<f32>,  // w: u0
    n1: vec4<f32>,  // w: v0
    n2: vec4<f32>,  // w: u1
    uv: vec4<f32>,  // v1, u2, v2, the first texel word of the corners' colours (0: white)
}

// A material: albedo factor (w: the texture's index, as bits; NO_TEXTURE for none),
// emitted radiance (w: the texture's wrap in u | in v << 2, as bits: lgh-scene's
// Wrap::code) and the normal map (its texture's index as bits or NO_TEXTURE, its scale, its
// wrap as bits).
struct Material {
    albedo: vec4<f32>,
    emission: vec4<f32>,
    normal: vec4<f32>,
}

@group(0) @binding(1) var<storage, read> nodes: array<Node>;
@group(0) @binding(2) var<storage, read> tris: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> shade: array<TriShade>;
@group(0) @binding(4) var<storage, read> materials: array<Material>;
@group(0) @binding(5) var<storage, read> texels: array<u32>;

const NO_TEXTURE: u32 = 0xffffffffu;
// `texels` holds the sRGB decoding table (256 floats, as bits), then a header per texture
// (first texel, width, height, 1 for data read as code / 255 else 0 for sRGB), then the
// texels (8-bit codes, r | g << 8 | b << 16),
// then the vertex colours of each triangle that has them (9 floats as bits).
const TEXTURE_HEADERS: u32 = 256u;

struct Surface {
    position: vec3<f32>,
    geo_normal: vec3<f32>,
    normal: vec3<f32>,
    albedo: vec3<f32>,
    emission: vec3<f32>,
}

// A texel decoded to linear RGB: through the sRGB table, or as code / 255 for data.
fn texel(at: u32, linear: bool) -> vec3<f32> {
    let t = texels[at];
    let code = vec3<u32>(t & 0xffu, (t >> 8u) & 0xffu, (t >> 16u) & 0xffu);
    if (linear) {
        return vec3<f32>(code) / 255.0;
    }
    return vec3<f32>(
        bitcast<f32>(texels[code.x]),
        bitcast<f32>(texels[code.y]),
        bitcast<f32>(texels[code.z]),
    );
}

// glam's Vec3::lerp.
fn lerp3(a: vec3<f32>, b: vec3<f32>, s: f32) -> vec3<f32> {
    return a * (1.0 - s) + b * s;
}

// lgh-scene's Texture::sample_wrapped: bilinear, v up, `wrap` in u | in v << 2.
fn sample_texture(k: u32, uv: vec2<f32>, wrap: u32) -> vec3<f32> {
    let head = TEXTURE_HEADERS + 4u * k;
    let first = texels[head];
    let w = i32(texels[head + 1u]);
    let h = i32(texels[head + 2u]);
    let linear = texels[head + 3u] != 0u;
    let b = bilinear(uv, w, h, wrap);
    let top = lerp3(texel(first + b.i.x, linear), texel(first + b.i.y, linear), b.f.x);
    let bottom = lerp3(texel(first + b.i.z, linear), texel(first + b.i.w, linear), b.f.x);
    return lerp3(top, bottom, b.f.y);
}

// glam's normalize_or_zero.
fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let len = sqrt(dot(v, v));
    return select(vec3<f32>(0.0), v * (1.0 / len), len > 0.0 && len < 3.0e38);
}

// lgh-scene's normal_map::bend: n bent to the tangent-space normal m in the frame of the
// triangle of corners p0..p2 and texture coordinates t0..t2.
fn bend_normal(
    n: vec3<f32>,
    geo: vec3<f32>,
    p0: vec3<f32>,
    p1: vec3<f32>,
    p2: vec3<f32>,
    t0: vec2<f32>,
    t1: vec2<f32>,
    t2: vec2<f32>,
    m: vec3<f32>,
) -> vec3<f32> {
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let d1 = t1 - t0;
    let d2 = t2 - t0;
    let det = d1.x * d2.y - d1.y * d2.x;
    if (det == 0.0 || !(abs(det) < 3.4e38)) {
        return n;
    }
    let dpdu = (e1 * d2.y - e2 * d1.y) / det;
    let dpdv = (e2 * d1.x - e1 * d2.x) / det;
    let tangent = normalize_or_zero(dpdu - n * dot(n, dpdu));
    let b = dpdv - n * dot(n, dpdv);
    let bitangent = normalize_or_zero(b - tangent * dot(tangent, b));
    let bent = normalize_or_zero(tangent * m.x + bitangent * m.y + n * m.z);
    let zero = vec3<f32>(0.0);
    if (all(tangent == zero) || all(bitangent == zero) || dot(bent, geo) <= 0.0) {
        return n;
    }
    return bent;
}

// The surface that the ray o + t d (d of unit length) meets at `hit` (a hit, not a miss):
// World::camera_surface with `bend` (camera rays: the normal map bends the normal),
// World::surface without (light paths).
fn surface_at(hit: Hit, o: vec3<f32>, d: vec3<f32>, bend: bool) -> Surface {
    let s = shade[hit.tri];
    let b1 = hit.b1;
    let b2 = hit.b2;
    let b0 = 1.0 - b1 - b2;
    let front = dot(s.face.xyz, d) < 0.0;
    let geo = select(-s.face.xyz, s.face.xyz, front);
    var normal = vec3<f32>(0.0);
    let zero = vec3<f32>(0.0);
    if (any(s.n0.xyz != zero) && any(s.n1.xyz != zero) && any(s.n2.xyz != zero)) {
        normal = normalize_or_zero(s.n0.xyz * b0 + s.n1.xyz * b1 + s.n2.xyz * b2);
    }
    if (all(normal == zero)) {
        normal = geo;
    } else if (dot(normal, geo) < 0.0) {
        normal = -normal;
    }
    let uv = vec2<f32>(s.n0.w, s.n1.w) * b0 + vec2<f32>(s.n2.w, s.uv.x) * b1 + s.uv.yz * b2;
    let m = materials[bitcast<u32>(s.face.w)];
    let nk = bitcast<u32>(m.normal.x);
    if (bend && nk != NO_TEXTURE) {
        // NormalMap::bend.
        let tn = sample_texture(nk, uv, bitcast<u32>(m.normal.z)) * 2.0 - vec3<f32>(1.0);
        let mn = vec3<f32>(tn.x * m.normal.y, tn.y * m.normal.y, tn.z);
        normal = bend_normal(
            normal,
            geo,
            tris[3u * hit.tri].xyz,
            tris[3u * hit.tri + 1u].xyz,
            tris[3u * hit.tri + 2u].xyz,
            vec2<f32>(s.n0.w, s.n1.w),
            vec2<f32>(s.n2.w, s.uv.x),
            s.uv.yz,
            mn,
        );
    }
    let k = bitcast<u32>(m.albedo.w);
    var t = vec3<f32>(1.0);
    if (k != NO_TEXTURE) {
        t = sample_texture(k, uv, bitcast<u32>(m.emission.w));
        if (any(abs(t) > vec3<f32>(3.4e38)) || any(t != t)) {
            t = vec3<f32>(0.0);
        }
    }
    var albedo = clamp(m.albedo.xyz * t, vec3<f32>(0.0), vec3<f32>(1.0));
    let c = bitcast<u32>(s.uv.w);
    if (c != 0u) {
        // Mesh::color_at.
        let c0 = vec3<f32>(bitcast<f32>(texels[c]), bitcast<f32>(texels[c + 1u]), bitcast<f32>(texels[c + 2u]));
        let c1 = vec3<f32>(bitcast<f32>(texels[c + 3u]), bitcast<f32>(texels[c + 4u]), bitcast<f32>(texels[c + 5u]));
        let c2 = vec3<f32>(bitcast<f32>(texels[c + 6u]), bitcast<f32>(texels[c + 7u]), bitcast<f32>(texels[c + 8u]));
        albedo = albedo * (c0 * b0 + c1 * b1 + c2 * b2);
    }
    return Surface(
        o + d * hit.t,
        geo,
        normal,
        albedo,
        select(vec3<f32>(0.0), m.emission.xyz, front),
    );
}
