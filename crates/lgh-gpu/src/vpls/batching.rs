//! The batches of VPL generation ([`super::plan`]) change how often the CPU waits, never
//! the VPLs.

use lgh_render::World;

use super::{Want, generate};
use crate::GpuContext;
use crate::batch::waits;

/// The two rooms (light through a doorway: many paths leave fewer than `bounces` VPLs).
fn two_rooms() -> World {
    let p =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/test/two-rooms.toml");
    World::new(lgh_scene::load(&p).expect("scene"))
}

/// Planned with nothing known (two batches), from the last generation's yield (one), from
/// a yield too small (two) or too large (one, paths traced and not kept), the VPLs and the
/// number of paths are the same bit for bit, read back or kept for the build; and the
/// conversion into the build's layout waits for nothing more.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn the_batches_change_the_waits_not_the_vpls() {
    let ctx = GpuContext::shared().expect("an adapter");
    let world = two_rooms();
    let (target, bounces, seed) = (7_000, 3, 4);
    let key = (world.geometry_id(), world.lights.len(), bounces);
    let run = |yield_: Option<f64>, want: Want| {
        ctx.vpl_yields().forget(key);
        if let Some(y) = yield_ {
            ctx.vpl_yields().set(key, (y * 1e6) as u64, 1_000_000);
        }
        let before = waits();
        let (set, _) = generate(ctx, &world, (target, bounces, seed), want).expect("vpls");
        (set, waits() - before)
    };
    let (first, w) = run(None, Want::Cpu);
    assert_eq!(w, 2, "nothing known");
    assert!(first.vpls.len() >= target);
    let per_vpl = first.paths as f64 / first.vpls.len() as f64;
    assert!(
        per_vpl > 1.0 / f64::from(bounces) * 1.2,
        "{per_vpl}: a first batch would do"
    );
    for (what, y, want_waits) in [
        ("known", per_vpl, 1),
        ("too small", per_vpl * 0.5, 2),
        ("too large", per_vpl * 3.0, 1),
    ] {
        let (set, w) = run(Some(y), Want::Cpu);
        assert_eq!(w, want_waits, "{what}");
        assert_eq!(set.paths, first.paths, "{what}");
        assert_eq!(set.vpls.positions, first.vpls.positions, "{what}");
        assert_eq!(set.vpls.normals, first.vpls.normals, "{what}");
        assert_eq!(set.vpls.flux, first.vpls.flux, "{what}");
        // Kept on the GPU: the bounds come back with the last batch's count.
        let (kept, w) = run(Some(y), Want::GridBins);
        assert_eq!(w, want_waits, "{what}: kept");
        assert_eq!((kept.kept, kept.paths), (first.vpls.len(), first.paths));
        let bins = kept.kept_bins.expect("bins");
        assert_eq!(bins.iter().sum::<usize>(), first.vpls.len(), "{what}");
        super::resident::clear(ctx);
    }
    ctx.vpl_yields().forget(key);
}

/// `shaders/recip.wgsl`'s `recip_rn(p)` is the CPU's `1.0 / p as f32` bit for bit: small
/// and large p, powers of two and their neighbours, p past 2^24 (rounded before the
/// division, as the CPU rounds it) up to `u32::MAX`, and random p.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn the_flux_scale_is_the_cpus_reciprocal() {
    let ctx = GpuContext::shared().expect("an adapter");
    let mut p: Vec<u32> = (1..=5000).collect();
    for e in 1..32 {
        let t = 1u32 << e;
        p.extend([t - 1, t, t + 1, t.wrapping_add(t / 2)]);
    }
    p.extend([
        u32::MAX,
        u32::MAX - 1,
        (1 << 24) + 3,
        (1 << 25) + 2,
        (1 << 25) + 6,
    ]);
    let mut rng = lgh_core::rng::Rng::new(&[11]);
    p.extend((0..20_000).map(|_| rng.next_u32().max(1)));
    p.extend((0..20_000).map(|_| (rng.next_u32() >> 8).max(1)));
    let source = crate::kernel(&[
        include_str!("../shaders/recip.wgsl"),
        "@group(0) @binding(0) var<storage, read> p: array<u32>;\n\
         @group(0) @binding(1) var<storage, read_write> out: array<f32>;\n\
         @compute @workgroup_size(64)\n\
         fn main(@builtin(global_invocation_id) id: vec3<u32>) {\n\
             if (id.x < arrayLength(&p)) { out[id.x] = recip_rn(p[id.x]); }\n\
         }\n",
    ]);
    let kernel = ctx.pipeline("test recip", || source);
    let input = ctx.upload("test recip in", &p).expect("upload");
    let out = ctx
        .output("test recip out", 4 * p.len() as u64)
        .expect("lease");
    let bind = ctx.bind_group(&kernel, vec![input.binding(), out.binding()]);
    let mut batch = crate::batch::Batch::new(ctx);
    batch
        .dispatch("test recip", &kernel, &bind, p.len())
        .expect("dispatch");
    batch.read(out.buffer(), 4 * p.len() as u64).expect("read");
    let (reads, _) = batch.finish().expect("ran");
    let got: &[f32] = bytemuck::cast_slice(&reads[0]);
    for (&p, &g) in p.iter().zip(got) {
        let want = 1.0 / p as f32;
        assert_eq!(g.to_bits(), want.to_bits(), "1 / {p}: {g:e} vs {want:e}");
    }
}
