//! The edge resolve's sub-pixel samples on the GPU (`lgh_gpu::edges`) against the CPU's
//! `EdgeResolve::new` on the same G-buffer: the default scene, the three test scenes, with
//! and without the camera's sub-pixel jitter.

use std::collections::HashMap;

use glam::Vec2;
use lgh_render::passes::edge_aa::EdgeResolve;
use lgh_render::passes::gbuffer::GBuffer;

mod common;
use common::{SCENES, world};

/// The same edge pixels, and the same counts on at least 99% of them (a sub-pixel ray that
/// grazes an edge may hit the other triangle); a wrong offset, neighbour order or match
/// rule fails it.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_edge_resolve_is_the_cpu_one() {
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    let (w, h) = (96, 54);
    for rel in SCENES {
        let world = world(rel);
        for (jitter, samples) in [(Vec2::ZERO, 8), (Vec2::new(-0.27, 0.38), 5)] {
            let camera = world.scene.camera().frame(w, h).with_jitter(jitter);
            let g = GBuffer::render(&world, &camera, w, h);
            let cpu = EdgeResolve::new(&world, &camera, &g, samples, None);
            let gpu = lgh_gpu::edges::edge_resolve(ctx, &world, &camera, &g, samples).expect("gpu");
            let cpu_map: HashMap<u32, [u8; 9]> = cpu.edges().iter().copied().collect();
            assert_eq!(
                gpu.edge_pixels(),
                cpu.edge_pixels(),
                "{rel:?}: the same edge pixels"
            );
            assert!(gpu.edges().windows(2).all(|p| p[0].0 < p[1].0), "sorted");
            let same = gpu
                .edges()
                .iter()
                .filter(|(i, c)| cpu_map.get(i) == Some(c))
                .count();
            let share = same as f64 / cpu.edge_pixels().max(1) as f64;
            println!(
                "{rel:?} {samples}: {} edge pixels, {:.2}% equal",
                cpu.edge_pixels(),
                100.0 * share
            );
            assert!(cpu.edge_pixels() > 50, "{rel:?}: the view must have edges");
            assert!(
                share >= 0.99,
                "{rel:?}: {:.2}% of the counts equal",
                100.0 * share
            );
        }
    }
}
