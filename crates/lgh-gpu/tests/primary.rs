//! Primary rays on the GPU (`lgh_gpu::primary`) against the CPU's G-buffer pass, on the
//! default scene, the three test scenes and a textured box, with the sub-pixel jitter of an
//! accumulation; and the traced G-buffer handed to the frame's passes without an upload.

use glam::{Vec2, Vec3};
use lgh_render::World;
use lgh_render::passes::gbuffer::GBuffer;
use lgh_scene::texture::{Texture, Wrap};

mod common;
use common::{SCENES, world};

/// The default scene with a 5 x 3 texture of distinct colours on every material, with
/// repeat, clamp and mirror wraps in u and v, and texture coordinates from the positions
/// that wrap several times across each wall (both signs, so that the wrap of negative
/// coordinates is exercised).
fn textured_box() -> World {
    let mut w = world(None);
    let scene = &mut w.scene;
    let bytes: Vec<u8> = (0..15u32)
        .flat_map(|i| [(i * 17) as u8, (255 - i * 13) as u8, (i * i % 251) as u8])
        .collect();
    scene.textures = vec![Texture::from_srgb8(5, 3, 3, &bytes).expect("texture")];
    // Each wrap in both axes on the first three materials, clamp in v only on the fourth.
    let wraps = [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror];
    for (i, m) in scene.materials.iter_mut().enumerate() {
        m.albedo_texture = Some(0);
        m.albedo = Vec3::new(0.9, 0.8, 1.0);
        m.albedo_wrap = [wraps[i % 3], wraps[(i / 3 + i) % 3]];
    }
    let (lo, hi) = scene.mesh.bounds();
    let size = (hi - lo).max_element();
    scene.mesh.uvs = scene
        .mesh
        .positions
        .iter()
        .map(|p| {
            let q = (*p - lo) / size;
            Vec2::new(3.3 * q.x - 1.1 * q.z - 0.7, 2.7 * q.y + 1.9 * q.z - 1.3)
        })
        .collect();
    World::new(w.scene)
}

/// Share of pixels where the two G-buffers disagree: one sees a surface and the other not,
/// or a plane differs by more than `tol` (relative to the scene's radius for positions).
fn disagreement(world: &World, a: &GBuffer, b: &GBuffer, tol: f32) -> f64 {
    let far = |x: Vec3, y: Vec3, scale: f32| (x - y).abs().max_element() > tol * scale;
    let bad = (0..a.len())
        .filter(|&i| {
            a.is_hit(i) != b.is_hit(i)
                || far(a.position[i], b.position[i], world.radius)
                || far(a.normal[i], b.normal[i], 1.0)
                || far(a.geo_normal[i], b.geo_normal[i], 1.0)
                || far(a.albedo[i], b.albedo[i], 1.0)
                || far(a.emission[i], b.emission[i], 1.0)
                || (a.is_hit(i) && (a.depth[i] - b.depth[i]).abs() > tol * world.radius)
        })
        .count();
    bad as f64 / a.len().max(1) as f64
}

/// Every plane of the GPU's G-buffer equals the CPU's within 1e-4 (positions: 1e-4 of the
/// scene's radius) on at least 99.5% of the pixels; the rest are rays that graze an edge.
/// A texture lookup off by one texel, a flipped normal or a wrong material fails it.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_primary_rays_give_the_cpu_gbuffer() {
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    let (w, h) = (96, 54);
    let worlds: Vec<(String, World)> = SCENES
        .iter()
        .map(|s| (format!("{s:?}"), world(*s)))
        .chain([("textured box".to_owned(), textured_box())])
        .collect();
    for (name, world) in &worlds {
        for jitter in [Vec2::ZERO, Vec2::new(0.31, -0.42)] {
            let camera = world.scene.camera().frame(w, h).with_jitter(jitter);
            let cpu = GBuffer::render(world, &camera, w, h);
            let mut gpu = GBuffer::default();
            lgh_gpu::primary::trace_gbuffer(ctx, world, &camera, w, h, &mut gpu).expect("gpu");
            assert_eq!((gpu.width, gpu.height, gpu.len()), (w, h, cpu.len()));
            assert_eq!(gpu.view, cpu.view, "{name}: the view is known");
            let d = disagreement(world, &gpu, &cpu, 1e-4);
            println!("{name} jitter {jitter}: {:.3}% of pixels differ", 100.0 * d);
            assert!(d <= 0.005, "{name}: {:.3}% of pixels differ", 100.0 * d);
            assert!(
                (0..cpu.len()).filter(|&i| cpu.is_hit(i)).count() > cpu.len() / 2,
                "{name}: the test must see surfaces"
            );
        }
    }
}

/// The textured box's albedo varies (so the texture is read), and a box without the
/// texture's variation would fail the comparison above: the CPU's and GPU's mean albedos
/// agree, and differ from the untextured box's.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn the_texture_shows_in_the_gpu_gbuffer() {
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    let textured = textured_box();
    let plain = world(None);
    let camera = plain.scene.camera().frame(64, 36);
    let mut gpu = GBuffer::default();
    lgh_gpu::primary::trace_gbuffer(ctx, &textured, &camera, 64, 36, &mut gpu).expect("gpu");
    let plain_g = GBuffer::render(&plain, &camera, 64, 36);
    let distinct = |g: &GBuffer| {
        let mut v: Vec<[u32; 3]> = g
            .albedo
            .iter()
            .map(|a| a.to_array().map(f32::to_bits))
            .collect();
        v.sort_unstable();
        v.dedup();
        v.len()
    };
    assert!(distinct(&gpu) > 100, "a texture gives many albedos");
    assert!(distinct(&plain_g) < 10, "the plain box has a few");
}

/// The traced G-buffer is the one the frame's passes read: the context hands it back for
/// the planes it filled (no upload), and its packed pixels are those planes.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn the_traced_gbuffer_stays_on_the_gpu() {
    // A context of its own: the tests beside this one use the shared context's G-buffer.
    let ctx = &lgh_gpu::GpuContext::new().expect("an adapter");
    let world = world(Some("test/two-rooms.toml"));
    let camera = world.scene.camera().frame(40, 30);
    let mut g = GBuffer::default();
    lgh_gpu::primary::trace_gbuffer(ctx, &world, &camera, 40, 30, &mut g).expect("gpu");
    let a = ctx.gbuffer(&g).expect("the traced buffer");
    let b = ctx.gbuffer(&g.clone()).expect("the traced buffer");
    assert!(std::sync::Arc::ptr_eq(&a, &b));
    // Its bytes are the planes packed as an upload packs them: upload a copy whose view
    // is unknown (a new buffer) and compare the two on the GPU's side.
    let mut unknown = g.clone();
    unknown.view = None;
    let c = ctx.gbuffer(&unknown).expect("upload");
    assert!(
        !std::sync::Arc::ptr_eq(&a, &c),
        "no planes are kept to compare with"
    );
    let bytes = 64 * g.len() as u64;
    let mut batch = lgh_gpu::Batch::new(ctx);
    batch.read(a.buffer(), bytes).expect("read");
    batch.read(c.buffer(), bytes).expect("read");
    let (reads, _) = batch.finish().expect("gpu");
    let (x, y): (&[u8], &[u8]) = (
        bytemuck::cast_slice(&reads[0]),
        bytemuck::cast_slice(&reads[1]),
    );
    assert_eq!(&x[..bytes as usize], &y[..bytes as usize]);
}

/// Sponza and the conference room (shared scenes: 66K and 69K triangles, thin columns and
/// chair legs, zero-length normals) at 160x90: the GPU's G-buffer is the CPU's on at least
/// 99.5% of the pixels, within 1e-4.
#[test]
#[cfg_attr(
    any(not(gpu_adapter), not(lgh_scenes)),
    ignore = "needs a GPU adapter and LGH_SCENES (the shared scenes)"
)]
fn gpu_primary_rays_give_the_cpu_gbuffer_on_the_shared_scenes() {
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    for name in ["sponza", "conference"] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join(format!("../../scenes/{name}.toml"));
        let world = World::new(lgh_scene::load(&path).expect("scene"));
        let (w, h) = (160, 90);
        let camera = world.scene.camera().frame(w, h);
        let cpu = GBuffer::render(&world, &camera, w, h);
        let mut gpu = GBuffer::default();
        lgh_gpu::primary::trace_gbuffer(ctx, &world, &camera, w, h, &mut gpu).expect("gpu");
        let d = disagreement(&world, &gpu, &cpu, 1e-4);
        println!("{name}: {:.3}% of pixels differ", 100.0 * d);
        assert!(d <= 0.005, "{name}: {:.3}% of pixels differ", 100.0 * d);
    }
}
