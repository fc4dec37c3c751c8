//! The tile binning on the GPU (`lgh_gpu::bins`) against the CPU's (`InterleavedBins`) on the
//! same lights and G-buffer: the default scene and the three test scenes (and Sponza and the
//! conference room with LGH_SCENES), with and without interleaving and the camera's jitter.

use glam::Vec2;
use lgh_render::memory::FrameMemory;
use lgh_render::methods::MethodInputs;
use lgh_render::methods::lgh::{LghFrame, Prepared};
use lgh_render::passes::gbuffer::GBuffer;
use lgh_render::passes::vpl_gen::generate_vpls;
use lgh_render::shading::tiles::{BinLights, FlatBins, InterleavedBins};
use lgh_render::{RenderSettings, Silent, World};

mod common;
use common::{SCENES, world};

/// The GPU's lists buffer of `world`'s lgh frame at `w` x `h` with `n` x `n` interleaving,
/// as (starts, lights, pixel order, pixel lists), and the CPU's bins of the same lights.
fn both(
    world: &World,
    (w, h): (u32, u32),
    (n, tile): (u32, Option<u32>),
    jitter: Vec2,
) -> ([Vec<u32>; 4], FlatBins) {
    let s = RenderSettings {
        width: w,
        height: h,
        vpls: 4000,
        tiling: lgh_render::settings::Tiling {
            interleave: Some(n),
            tile,
            ..Default::default()
        },
        ..RenderSettings::default()
    };
    let camera = world.scene.camera().frame(w, h).with_jitter(jitter);
    let g = GBuffer::render(world, &camera, w, h);
    let vpls = generate_vpls(world, s.vpls, s.bounces, s.seed, s.path_numbers);
    let inputs = MethodInputs {
        world,
        gbuffer: &g,
        camera: &camera,
        vpls: &vpls.vpls,
        vpl_count: vpls.vpls.len(),
        vpl_bins: None,
        settings: &s,
        progress: &Silent,
    };
    let mut memory = FrameMemory::default();
    let Ok(Prepared::Frame(frame)) = LghFrame::prepare(&inputs, true, &mut memory, true) else {
        panic!("a frame with VPLs");
    };
    let sp = frame.spheres();
    assert!(sp.facing.iter().any(|m| *m != glam::Vec3::ZERO));
    assert!(sp.holes.iter().any(|&h| h > 0.0));
    let lights = BinLights {
        centres: sp.centres,
        radii: sp.radii,
        facing: &sp.facing,
        holes: &sp.holes,
    };
    let cpu = InterleavedBins::build(&g, &camera, sp.tile, sp.n, lights, sp.sub).flatten(w, h);
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    let gbuffer = ctx.gbuffer(&g).expect("G-buffer");
    let first = lgh_gpu::Batch::new(ctx);
    let mut bins =
        lgh_gpu::bins::record(ctx, first, &g, &camera, &gbuffer, &sp, None, None).expect("bins");
    let words = bins.layout.words(g.len());
    bins.batch
        .read(bins.lists.buffer(), 4 * words)
        .expect("read");
    let layout = bins.layout;
    let (reads, _) = bins.batch.finish().expect("gpu");
    let all: &[u32] = bytemuck::cast_slice(&reads[0]);
    let part = |a: u32, b: u32| all[a as usize..b as usize].to_vec();
    let gpu = [
        part(0, layout.lights),
        part(layout.lights, layout.order),
        part(layout.order, layout.pixel_lists),
        part(layout.pixel_lists, layout.pixel_lists + g.len() as u32),
    ];
    (gpu, cpu)
}

/// The pixels sorted by list, stably (what the loop's invocations take).
fn order(list: &[u32]) -> Vec<u32> {
    let mut o: Vec<u32> = (0..list.len() as u32).collect();
    o.sort_by_key(|&p| list[p as usize]);
    o
}

/// Checks one case: the pixels' lists and their order equal the CPU's, every list ascends,
/// and at least 99.9% of the lists hold exactly the CPU's lights (a light at a tile's edge
/// may go either way by a rounding of the GPU's square roots and fused multiply-adds; the
/// binning is conservative either way). Returns the longest list's length.
fn check(label: &str, gpu: &[Vec<u32>; 4], cpu: &FlatBins) -> usize {
    let [starts, lights, pixel_order, list] = gpu;
    assert_eq!(list, &cpu.list, "{label}: each pixel's list");
    assert_eq!(
        pixel_order,
        &order(&cpu.list),
        "{label}: the pixels by list"
    );
    assert_eq!(starts.len(), cpu.offsets.len(), "{label}: the lists");
    let lists = starts.len() - 1;
    let (mut same, mut longest) = (0, 0);
    for l in 0..lists {
        let g = &lights[starts[l] as usize..starts[l + 1] as usize];
        let c = &cpu.lights[cpu.offsets[l] as usize..cpu.offsets[l + 1] as usize];
        assert!(
            g.windows(2).all(|p| p[0] < p[1]),
            "{label}: list {l} ascends"
        );
        same += usize::from(g == c);
        longest = longest.max(g.len());
    }
    let share = same as f64 / lists.max(1) as f64;
    println!(
        "{label}: {lists} lists, {} entries (CPU {}), the longest {longest}, {:.3}% equal",
        lights.len(),
        cpu.lights.len(),
        100.0 * share
    );
    assert!(
        cpu.lights.len() > lists,
        "{label}: the lists must hold lights"
    );
    assert!(
        share >= 0.999,
        "{label}: {:.3}% of the lists equal",
        100.0 * share
    );
    longest
}

#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_tile_bins_are_the_cpu_ones() {
    let mut longest = 0;
    for rel in SCENES {
        let world = world(rel);
        for (size, n, jitter) in [
            ((96, 54), (1, None), Vec2::ZERO),
            ((96, 54), (4, None), Vec2::new(-0.27, 0.38)),
            ((101, 37), (2, None), Vec2::ZERO),
            // Tiles of one pixel, and images smaller than a tile (sub-images without pixels).
            ((23, 11), (1, Some(1)), Vec2::ZERO),
            ((5, 3), (4, None), Vec2::ZERO),
        ] {
            let (gpu, cpu) = both(&world, size, n, jitter);
            let label = format!("{rel:?} {size:?} (n, tile) = {n:?}");
            longest = longest.max(check(&label, &gpu, &cpu));
        }
    }
    // Both sorts ran: lists longer than the workgroup's 2,048 keys sort in place.
    assert!(longest > 2048, "the longest list: {longest}");
}

#[test]
#[cfg_attr(
    any(not(gpu_adapter), not(lgh_scenes)),
    ignore = "needs a GPU adapter and LGH_SCENES (the shared scenes)"
)]
fn gpu_tile_bins_are_the_cpu_ones_on_the_shared_scenes() {
    for name in ["sponza", "conference"] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join(format!("../../scenes/{name}.toml"));
        let world = World::new(lgh_scene::load(&path).expect("scene"));
        for n in [1, 4] {
            let (gpu, cpu) = both(&world, (160, 90), (n, None), Vec2::ZERO);
            check(&format!("{name} n = {n}"), &gpu, &cpu);
        }
    }
}
