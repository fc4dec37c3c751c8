// The LGH lighting loop on the GPU (Lin & Yuksel 2019 section 3.2, 3.3 and Appendix A), one
// invocation per pixel: the unshadowed sum A over the pixel's light list, k shadow samples
// drawn among its lights in proportion to f_j = lum(B_l I_j G_j) by stratified inversion of
// the running sum, and per sample the unbiased estimate's target (docs/design.md, "Unbiased
// estimate"): the walk down to an S_1 light, one of its representative VPLs by contribution,
// a shadow ray, and the gain (sum rho / SLOTS) colour / Lambda_i of a visible VPL, Lambda_i
// its shares weighted by their grid lights' geometry terms. It
// writes A, S = mean V U_k gain and U = mean U_k; lgh-render's ratio estimator finishes them.
// The CPU counterpart is lgh-render's methods/lgh (shade.rs, lights.rs); each pixel sums its
// own terms in a fixed order, so the result does not depend on scheduling.

const SLOTS: u32 = 16u;
// An empty representative slot.
const EMPTY_SLOT: u32 = 0xffffffffu;

// One hierarchy's tables (lgh-render's tables::HierarchyTables).
struct Hier {
    first: u32,
    grid_base: u32,
    lowest: u32,
    l_max: u32,
    origin: vec3<f32>,
    h_top: f32,
    alpha: f32,
    rows_base: u32,
    starts_base: u32,
    children_base: u32,
    reps_base: u32,
    vpl_base: u32,
    _p0: u32,
    _p1: u32,
}

struct Params {
    pixels: u32,
    k: u32,
    hierarchies: u32,
    list_lights: u32,
    // Where the pixel order starts in `lists`: invocation i shades pixel lists[order + i].
    order: u32,
    // Where each pixel's list starts in `lists`: pixel i's is lists[pixel_lists + i].
    pixel_lists: u32,
    eps2: f32,
    ray_eps: f32,
    seed_lo: u32,
    seed_hi: u32,
    // The dithered strata (lgh-render's shading::strata): the frame's rotation c in units of
    // 2^-32, and the image width times 256 plus the interleaving n times 2 plus 1 where
    // the selection is dithered (0: independent offsets).
    strata_key: u32,
    strata_shape: u32,
    hier: array<Hier, 8>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> nodes: array<Node>;
@group(0) @binding(2) var<storage, read> tris: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> gbuffer: array<Pixel>;
@group(0) @binding(4) var<storage, read> lights: array<Light>;
// The lists' starts, then their lights (from params.list_lights), then the pixels sorted by
// list (from params.order), so that a workgroup's threads read the same lights, then each
// pixel's list (from params.pixel_lists).
@group(0) @binding(5) var<storage, read> lists: array<u32>;
// Per hierarchy: vertex-row starts, descent starts, descent children as (child, bits of the
// running sum).
@group(0) @binding(6) var<storage, read> words: array<u32>;
// Per hierarchy, its VPLs as the hierarchy build read them (lgh_gpu::grid's lights,
// LIGHT_FLOATS each): position, flux, normal.
@group(0) @binding(7) var<storage, read> reps: array<f32>;
// Per hierarchy, per S_1 light its SLOTS representatives (indices into its VPLs).
@group(0) @binding(8) var<storage, read> slots: array<u32>;
// Per pixel: A (w: overdraw), S (w: rays traced), U.
@group(0) @binding(9) var<storage, read_write> out: array<vec4<f32>>;

const LIGHT_FLOATS: u32 = 9u;

// Three floats of the VPLs from `at`.
fn rep_vec(at: u32) -> vec3<f32> {
    return vec3<f32>(reps[at], reps[at + 1u], reps[at + 2u]);
}

// An RGB value at unit luminance (zero without luminance), as the CPU's `chroma`.
fn chroma(c: vec3<f32>) -> vec3<f32> {
    let l = luminance(c);
    return select(vec3<f32>(0.0), c / l, l > 0.0);
}

var<private> rng_state: u32;

fn next_f32() -> f32 {
    rng_state = hash(rng_state);
    return f32(rng_state >> 8u) * (1.0 / 16777216.0);
}

// The offset u_s of pixel i's stratum s: independent (the pixel's stream), or dithered over
// the screen, frac(a_1 x' + a_2 y' + c + s g) with (x', y') the pixel's place in its
// sub-image (lgh-render's shading::strata, the same integers).
fn stratum_offset(i: u32, s: u32) -> f32 {
    let shape = params.strata_shape;
    if ((shape & 1u) == 0u) {
        return next_f32();
    }
    let width = shape >> 8u;
    let n = max((shape >> 1u) & 127u, 1u);
    let xs = (i % width) / n;
    let ys = (i / width) / n;
    let v = xs * 3242174889u + ys * 2447445414u + params.strata_key + s * 0x9E3779B9u;
    return f32(v >> 8u) * (1.0 / 16777216.0);
}

// cos_x cos_q / (d^2 (d^2 + eps^2)) of a representative VPL (lights.rs, representative_weight).
fn rep_weight(x: vec3<f32>, nx: vec3<f32>, q: vec3<f32>, nq: vec3<f32>) -> f32 {
    let d = q - x;
    let d2 = dot(d, d);
    let w = max(dot(nx, d), 0.0) * max(-dot(nq, d), 0.0) / (d2 * (d2 + params.eps2));
    if (d2 > 0.0 && w < 3.0e38) {
        return w;
    }
    return 0.0;
}

fn hierarchy_of(j: u32) -> u32 {
    var h = 0u;
    for (var i = 1u; i < params.hierarchies; i++) {
        if (params.hier[i].first <= j) {
            h = i;
        }
    }
    return h;
}

// h_l (GridGeometry::cell_size): h_0 = h_1 / 2.
fn cell_size(h: Hier, l: u32) -> f32 {
    let h1 = h.h_top / f32(1u << (h.l_max - 1u));
    if (l == 0u) {
        return 0.5 * h1;
    }
    return h.h_top / f32(1u << (h.l_max - l));
}

// The role's floors of level l (LevelRole::of, then floors).
fn floors(h: Hier, l: u32) -> vec2<f32> {
    if (h.lowest == h.l_max) {
        return vec2<f32>(1.0, 1.0);
    }
    if (l == h.lowest) {
        return vec2<f32>(1.0, 0.0);
    }
    if (l == h.l_max) {
        return vec2<f32>(0.0, 1.0);
    }
    return vec2<f32>(0.0, 0.0);
}

// The light at vertex v of level l of hierarchy h, or 0xffffffff: its row, then its x.
fn find_vertex(h: Hier, rows: u32, side: u32, v: vec3<u32>) -> u32 {
    let row = v.z * side + v.y;
    var lo = words[rows + row];
    var hi = words[rows + row + 1u];
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        let x = bitcast<u32>(lights[h.grid_base + mid].role.w);
        if (x == v.x) {
            return mid;
        }
        if (x < v.x) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return 0xffffffffu;
}

// A grid light's emission normal and isotropic share as lgh-core's partition stores them
// (quantized_emission): m to 1/127 per component, the share to 1/1020.
fn stored_emission(e: vec4<f32>) -> vec4<f32> {
    let m = round(clamp(e.xyz, vec3<f32>(-1.0), vec3<f32>(1.0)) * 127.0) * (1.0 / 127.0);
    let iso = round(clamp(e.w * 4.0, 0.0, 1.0) * 255.0) * (0.25 / 255.0);
    return vec4<f32>(m, iso);
}

// The geometry term cos_x cos_v / (d^2 + eps^2) of a light at q with emission e (normal,
// isotropic share) at x with normal nx (lgh_core::vpl::light_geometry).
fn geometry(x: vec3<f32>, nx: vec3<f32>, q: vec3<f32>, e: vec4<f32>) -> f32 {
    let d = q - x;
    let d2 = dot(d, d);
    let inv_d = inverseSqrt(d2);
    let cos_x = dot(nx, d) * inv_d;
    let cos_v = max(-dot(e.xyz, d) * inv_d, 0.0) + e.w;
    return select(0.0, cos_x * cos_v / (d2 + params.eps2), cos_x > 0.0 && cos_v > 0.0 && d2 > 0.0);
}

// Lambda_i: the sum over the admitted levels (those whose blending weight at p's own
// distance is not zero: Partition::admits) of the blending weights at x of the grid lights
// that VPL p (normal np) is splatted to, each times its trilinear share and its geometry
// term at x with its stored emission (Partition::share_total).
fn share_total(h: Hier, x: vec3<f32>, nx: vec3<f32>, p: vec3<f32>, np: vec3<f32>) -> f32 {
    var total = 0.0;
    var rows = h.rows_base;
    for (var l = 1u; l < h.lowest; l++) {
        let side = (1u << (h.l_max - l)) + 1u;
        rows += side * side + 1u;
    }
    for (var l = h.lowest; l <= h.l_max; l++) {
        let r = h.alpha * cell_size(h, l);
        let fl = floors(h, l);
        if (l == 0u) {
            let g = geometry(x, nx, p, vec4<f32>(np, 0.0));
            if (g > 0.0) {
                total += blend(length(x - p) / r, fl.x, fl.y) * g;
            }
            continue;
        }
        let hl = cell_size(h, l);
        let cells = 1u << (h.l_max - l);
        let side = cells + 1u;
        if (!(blend(length(x - p) / r, fl.x, fl.y) > 0.0)) {
            rows += side * side + 1u;
            continue;
        }
        let u = (p - h.origin) * (1.0 / hl);
        let c = vec3<u32>(clamp(u, vec3<f32>(0.0), vec3<f32>(f32(cells - 1u))));
        let f = clamp(u - vec3<f32>(c), vec3<f32>(0.0), vec3<f32>(1.0));
        for (var corner = 0u; corner < 8u; corner++) {
            let d = vec3<u32>(corner & 1u, (corner >> 1u) & 1u, corner >> 2u);
            let g = find_vertex(h, rows, side, c + d);
            if (g == 0xffffffffu) {
                continue;
            }
            let fw = select(vec3<f32>(1.0) - f, f, d == vec3<u32>(1u));
            let lg = lights[h.grid_base + g];
            let q = lg.position.xyz;
            let geo = geometry(x, nx, q, stored_emission(lg.normal));
            total += fw.x * fw.y * fw.z * blend(length(q - x) / r, fl.x, fl.y) * geo;
        }
        rows += side * side + 1u;
    }
    return total;
}

// The S_1 light reached from grid light `node` of hierarchy h by the walk down the levels,
// a child per level in proportion to its share (lgh_core::lighting_grid::descent).
fn walk(h: Hier, start: u32) -> u32 {
    var node = start;
    loop {
        let a = words[h.starts_base + node];
        let b = words[h.starts_base + node + 1u];
        if (a >= b) {
            break;
        }
        let total = bitcast<f32>(words[h.children_base + 2u * (b - 1u) + 1u]);
        let goal = next_f32() * total;
        var pick = b - 1u;
        for (var e = a; e < b; e++) {
            if (bitcast<f32>(words[h.children_base + 2u * e + 1u]) > goal) {
                pick = e;
                break;
            }
        }
        node = words[h.children_base + 2u * pick];
    }
    return node;
}

// What one shadow sample of light j (contribution c, weight f, of W in all) adds to S, and
// whether it traced a ray.
fn shadow_sample(x: vec3<f32>, n: vec3<f32>, ng: vec3<f32>, j: u32, u_k: vec3<f32>, c: vec3<f32>) -> vec4<f32> {
    let hi = hierarchy_of(j);
    let h = params.hier[hi];
    let lj = lights[j];
    var q = lj.position.xyz;
    var nq = lj.normal.xyz;
    var colour = vec3<f32>(1.0);
    var mean_rho = 0.0;
    if (j < h.grid_base) {
        // A VPL shaded as S_0 stands for itself.
        mean_rho = rep_weight(x, n, q, nq);
    } else {
        let s1 = walk(h, j - h.grid_base);
        let base = h.reps_base + SLOTS * s1;
        var w: array<f32, 16>;
        var total = 0.0;
        for (var s = 0u; s < SLOTS; s++) {
            let v = slots[base + s];
            w[s] = 0.0;
            if (v != EMPTY_SLOT) {
                let r = LIGHT_FLOATS * (h.vpl_base + v);
                w[s] = rep_weight(x, n, rep_vec(r), rep_vec(r + 6u));
                total += w[s];
            }
        }
        if (!(total > 0.0)) {
            return vec4<f32>(0.0);
        }
        var t = next_f32() * total;
        var pick = SLOTS - 1u;
        for (var s = 0u; s < SLOTS; s++) {
            if (t < w[s]) {
                pick = s;
                break;
            }
            t -= w[s];
        }
        // Rounding can leave t beyond the weights: the last slot with a weight.
        if (w[pick] <= 0.0) {
            for (var s = 0u; s < SLOTS; s++) {
                if (w[s] > 0.0) {
                    pick = s;
                }
            }
        }
        let r = LIGHT_FLOATS * (h.vpl_base + slots[base + pick]);
        q = rep_vec(r);
        nq = rep_vec(r + 6u);
        let colour_v = chroma(rep_vec(r + 3u));
        let chroma_c = chroma(c);
        colour = select(vec3<f32>(0.0), colour_v / chroma_c, chroma_c > vec3<f32>(0.0));
        mean_rho = total / f32(SLOTS);
    }
    if (!(mean_rho > 0.0)) {
        return vec4<f32>(0.0);
    }
    if (occluded_between(x, ng, q, nq, params.ray_eps)) {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    // A grid light's share was weighed with its stored emission: its own emission cosine
    // over that one (ShadeLights::unbiased_gain; 1 for a VPL shaded as S_0).
    var cosines = 1.0;
    if (j >= h.grid_base) {
        // Only the levels admitted at the VPL's own distance share its light (checked
        // before Lambda_i, which such a sample does not need).
        if (!(blend(length(x - q) / lj.intensity.w, lj.role.x, lj.role.y) > 0.0)) {
            return vec4<f32>(0.0, 0.0, 0.0, 1.0);
        }
        let w = normalize(lj.position.xyz - x);
        let e = stored_emission(lj.normal);
        cosines = (max(-dot(e.xyz, w), 0.0) + e.w) / (max(-dot(lj.normal.xyz, w), 0.0) + lj.normal.w);
    }
    let lambda = share_total(h, x, n, q, nq);
    if (!(lambda > 0.0)) {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    let gain = colour * mean_rho * (cosines / lambda);
    if (any(abs(gain) > vec3<f32>(3.0e38)) || any(gain != gain)) {
        return vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    return vec4<f32>(u_k * gain, 1.0);
}

// Chunks of a pixel's list whose running weights the lighting loop keeps, so that the
// stratified selection's second pass walks only the chunks its thresholds fall in.
const CHUNKS: u32 = 16u;

// The lights the stratified selection picked (lgh-render's MAX_SHADOW_SAMPLES at most), with
// their contribution c and weight f.
var<private> picked: array<u32, 16>;
var<private> picked_cf: array<vec4<f32>, 16>;

// The pixel's sums over its samples: S, U and the rays traced.
var<private> s_sum: vec3<f32>;
var<private> u_sum: vec3<f32>;
var<private> rays: u32;

// Takes the shadow sample of light j with contribution c, drawn with probability f / W
// (`w_ratio` = W / f): adds U_k = c W / f and its S term, and counts its ray.
fn take(x: vec3<f32>, n: vec3<f32>, ng: vec3<f32>, j: u32, c: vec3<f32>, w_ratio: f32) {
    let u_k = c * w_ratio;
    u_sum += u_k;
    let r = shadow_sample(x, n, ng, j, u_k, c);
    s_sum += r.xyz;
    rays += u32(r.w);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= params.pixels) {
        return;
    }
    let i = lists[params.order + id.x];
    let px = gbuffer[i];
    if (px.position.w == 0.0) {
        out[3u * i] = vec4<f32>(0.0);
        out[3u * i + 1u] = vec4<f32>(0.0);
        out[3u * i + 2u] = vec4<f32>(0.0);
        return;
    }
    let x = px.position.xyz;
    let n = px.normal.xyz;
    let ng = px.geo_normal.xyz;
    let list = lists[params.pixel_lists + i];
    let first = lists[list];
    let last = lists[list + 1u];
    // The lighting loop: A, the overdraw and the candidates' total weight W, with the
    // running weight at the end of each of CHUNKS chunks of the list, and the last light
    // with a weight.
    var a = vec3<f32>(0.0);
    var overdraw = 0u;
    var total = 0.0;
    var ends: array<f32, CHUNKS>;
    let size = max((last - first + CHUNKS - 1u) / CHUNKS, 1u);
    var last_j = 0xffffffffu;
    var last_c = vec3<f32>(0.0);
    var last_f = 0.0;
    for (var e = first; e < last; e++) {
        let j = lists[params.list_lights + e];
        let l = lights[j];
        let d = l.position.xyz - x;
        overdraw += select(0u, 1u, dot(d, d) < l.position.w);
        let c = light_factor(l, x, n, params.eps2) * l.intensity.xyz;
        a += c;
        let f = luminance(c);
        if (f > 0.0 && f < 3.0e38) {
            total += f;
            last_j = j;
            last_c = c;
            last_f = f;
        }
        ends[(e - first) / size] = total;
    }
    s_sum = vec3<f32>(0.0);
    u_sum = vec3<f32>(0.0);
    rays = 0u;
    let k = params.k;
    if (k > 0u && total > 0.0 && total < 3.0e38) {
        rng_state = hash(params.seed_lo ^ hash(params.seed_hi ^ hash(i)));
        // Stratified selection: sample s takes the light where the running weight passes
        // t_s = (s + u_s) / k W (shading.rs, stratified_picks); the second pass meets the
        // thresholds in order, walking only the chunks they fall in (at most k of the
        // CHUNKS), from the first pass's running weight at the chunk's start.
        var s = 0u;
        var t = stratum_offset(i, 0u) / f32(k) * total;
        var acc = 0.0;
        let chunks = (last - first + size - 1u) / size;
        for (var ch = 0u; ch < chunks && s < k; ch++) {
            if (ends[ch] <= t) {
                acc = ends[ch];
                continue;
            }
            let end = min(first + (ch + 1u) * size, last);
            for (var e = first + ch * size; e < end && s < k; e++) {
                let j = lists[params.list_lights + e];
                let l = lights[j];
                let c = light_factor(l, x, n, params.eps2) * l.intensity.xyz;
                let f = luminance(c);
                if (!(f > 0.0 && f < 3.0e38)) {
                    continue;
                }
                acc += f;
                while (s < k && acc > t) {
                    picked[s] = j;
                    picked_cf[s] = vec4<f32>(c, f);
                    s++;
                    t = (f32(s) + stratum_offset(i, s)) / f32(k) * total;
                }
            }
        }
        // Thresholds that rounding left beyond the last running sum take the last light.
        while (s < k && last_j != 0xffffffffu) {
            picked[s] = last_j;
            picked_cf[s] = vec4<f32>(last_c, last_f);
            s++;
        }
        // The picks' shadow samples, after the walk over the list: the rays and walks of
        // the samples run apart from the list's loop.
        for (var q = 0u; q < s; q++) {
            let cf = picked_cf[q];
            take(x, n, ng, picked[q], cf.xyz, total / cf.w);
        }
    }
    let kf = f32(max(k, 1u));
    out[3u * i] = vec4<f32>(a, f32(overdraw));
    out[3u * i + 1u] = vec4<f32>(s_sum / kf, f32(rays));
    out[3u * i + 2u] = vec4<f32>(u_sum / kf, 0.0);
}
