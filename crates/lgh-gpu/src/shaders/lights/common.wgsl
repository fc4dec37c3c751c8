// lgh's shaded lights made on the GPU from what a hierarchy build holds (lgh_gpu::lgh::lights):
// the loop's light table (lgh-render's PackedLight as lgh_gpu's upload packs it: position and
// reach^2, normal and isotropic share, intensity times n^2 and radius, blending floors with
// level and vertex x) and the tile binning's spheres and flags, the same values as the
// CPU's ShadeLights (LGH 2019 section 3.2) in the same order: per hierarchy its VPLs as S_0
// (from its first light) where shaded, then its grid lights level by level from S_1 (from
// its grid base), the zero-intensity records dropped as the CPU drops them.

// One level's constants (l = 0 for the VPLs).
struct Level {
    // r_l.
    radius: f32,
    // The binning's sphere radius 2 r_l; negative: the level reaches everywhere (the top).
    reach: f32,
    // The blending floors of the level's role.
    rise: f32,
    fall: f32,
}

struct LightParams {
    // Records (flags, rows) or VPLs (VPL rows).
    count: u32,
    // The shaded index of the hierarchy's grid light 0 (rows) or of its VPL 0 (VPL rows).
    base: u32,
    // n^2 of the interleaving: light k of a level goes to sub-image k mod n^2.
    n2: u32,
    // 1 where the lights have normals.
    normals: u32,
    // n^2 as a float (the intensities' scale).
    scale: f32,
    // 1 for the energy-conserving emission: iso = (1 - |m|) / 4, else 0.
    energy: u32,
    l_max: u32,
    _p: u32,
    level: array<Level, 12>,
    // x: the first record of level l (l >= 1; l_max + 1: the record count).
    start: array<vec4<u32>, 12>,
}

// The tile binning's flag of a light that reaches every tile (lgh_gpu::bins).
const REACHES_EVERYWHERE: u32 = 0x20000u;
// The largest float (the table's reach^2 of the top level).
const MAX_FLOAT: f32 = 3.40282347e38;

fn iso_share(m: vec3<f32>, energy: u32) -> f32 {
    return select(0.0, 0.25 * clamp(1.0 - length(m), 0.0, 1.0), energy == 1u);
}

fn float3(at: u32) -> vec3<f32> {
    return vec3<f32>(bitcast<f32>(src[at]), bitcast<f32>(src[at + 1u]), bitcast<f32>(src[at + 2u]));
}
