// VPL generation by light tracing (lgh-render's passes::vpl_gen::trace_path): one
// invocation per light path of the batch; path `first + k` leaves up to `bounces` VPLs
// (position, shading normal, reflected flux Phi x albedo, not yet divided by the number of
// paths) in slots k * bounces + j, and their count in counts[k]. Russian roulette with
// survival probability max(albedo), cosine-distributed bounces, as on the CPU.

struct Params {
    centre: vec3<f32>,
    radius: f32,
    first: u32,
    paths: u32,
    bounces: u32,
    lights: u32,
    ray_eps: f32,
    block0: u32,
    groups: u32,
    _pad: u32,
    // The 4D groups' seeds of the batch's blocks: seed of (block b, group g) at
    // (b - block0) * groups + g, four to an entry.
    seeds: array<vec4<u32>, 64>,
}

@group(0) @binding(0) var<uniform> params: Params;
// Bindings 1-5: the scene's BVH and surfaces (surface.wgsl).
@group(0) @binding(6) var<storage, read> tables: array<vec4<u32>>;
@group(0) @binding(7) var<storage, read_write> slots: array<Vpl>;
@group(0) @binding(8) var<storage, read_write> counts: array<u32>;

fn group_seed(i: u32) -> u32 {
    return params.seeds[i / 4u][i % 4u];
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if (k >= params.paths) {
        return;
    }
    let path = params.first + k;
    var s = PathSampler(path & 0xffffu, ((path >> 16u) - params.block0) * params.groups, 0u, 4u, vec4<f32>(0.0));
    var count = 0u;
    let ray = sample_emission(&s);
    if (ray.ok) {
        var origin = ray.origin;
        var dir = ray.dir;
        var flux = ray.flux;
        for (var bounce = 0u; bounce < params.bounces; bounce++) {
            let hit = trace(origin, dir, 3.4e38, false);
            if (hit.tri == NONE) {
                break;
            }
            let sf = surface_at(hit, origin, dir, false);
            let reflected = flux * sf.albedo;
            let finite = all(abs(reflected) <= vec3<f32>(3.4028235e38));
            if (max(reflected.x, max(reflected.y, reflected.z)) <= 0.0 || !finite) {
                break;
            }
            slots[k * params.bounces + count] = Vpl(
                vec4<f32>(sf.position, 0.0),
                vec4<f32>(sf.normal, 0.0),
                vec4<f32>(reflected, 0.0),
            );
            count++;
            if (bounce + 1u == params.bounces) {
                break;
            }
            let q = min(max(sf.albedo.x, max(sf.albedo.y, sf.albedo.z)), 1.0);
            if (next_f32(&s) >= q) {
                break;
            }
            flux = reflected / q;
            dir = cosine_hemisphere(sf.normal, next_2d(&s));
            if (dot(dir, sf.geo_normal) <= 0.0) {
                break;
            }
            origin = offset(sf.position, sf.geo_normal, dir, params.ray_eps);
        }
    }
    counts[k] = count;
}
