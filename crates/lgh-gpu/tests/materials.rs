//! What a surface is, on the GPU against the CPU, on the lattice scene
//! (scenes/test/lattice.toml): alpha cut-outs (`cutouts.rs`, `shaders/bvh.wgsl`'s
//! `covers`: two screens whose holes exist only in their textures' alpha; the GPU's primary
//! rays, VPLs and shadow rays all pass through the holes as the CPU's do) and vertex
//! colours (`surfaces.rs`, `shaders/surface.wgsl`: the back wall's).

use lgh_render::image::metrics::diff;
use lgh_render::methods::brute::BRUTE;
use lgh_render::{Component, RenderSettings, Silent, World, render_frame};

mod common;

/// The brute force, all light, at 64x36 with 2,000 VPLs.
fn settings() -> RenderSettings {
    RenderSettings {
        method: BRUTE,
        width: 64,
        height: 36,
        vpls: 2000,
        component: Component::All,
        ..RenderSettings::default()
    }
}

/// `world`'s CPU frame of `s`, after checking that the GPU's is within rel_rmse 0.005 of
/// it (`what` names the case).
fn cpu_frame_equal_to_the_gpus(world: &World, s: &RenderSettings, what: &str) -> lgh_render::Image {
    let cpu = render_frame(world, s, &Silent).expect("cpu").image;
    let gpu_settings = RenderSettings {
        method: lgh_gpu::brute::BRUTE_GPU,
        ..s.clone()
    };
    let gpu = render_frame(world, &gpu_settings, &Silent)
        .expect("gpu")
        .image;
    let m = diff(&gpu, &cpu).expect("same size");
    eprintln!("{what}, brute, GPU against CPU: {m:?}");
    assert!(m.rel_rmse <= 0.005, "{what}: {m:?}");
    cpu
}

/// The brute force, all light (direct and indirect), on the GPU and on the CPU: within
/// rel_rmse 0.005 (the area of the holes' edges where rounding decides the test differs
/// by a few pixels' worth); without the cut-outs, or without the vertex colours, the
/// CPU's image is far from both.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn the_gpu_sees_through_the_holes_and_the_colours_as_the_cpu_does() {
    let w = common::world(Some("test/lattice.toml"));
    assert_eq!(w.cutouts.as_ref().map(|c| c.len()), Some(6));
    let s = settings();
    let cpu = cpu_frame_equal_to_the_gpus(&w, &s, "lattice");
    // The scene without its cut-outs: solid screens.
    let mut solid = w.scene.clone();
    for m in &mut solid.materials {
        m.cutout = None;
    }
    let solid = render_frame(&World::new(solid), &s, &Silent)
        .expect("cpu")
        .image;
    let far = diff(&solid, &cpu).expect("same size");
    eprintln!("lattice without cut-outs against with: {far:?}");
    assert!(far.rel_rmse > 0.1, "{far:?}");
    // The scene without its vertex colours: a white back wall.
    let mut white = w.scene.clone();
    white.mesh.colors.clear();
    let white = render_frame(&World::new(white), &s, &Silent)
        .expect("cpu")
        .image;
    let far = diff(&white, &cpu).expect("same size");
    eprintln!("lattice without vertex colours against with: {far:?}");
    assert!(far.rel_rmse > 0.05, "{far:?}");
}

/// A normal map of ripples on the lattice scene's floor and walls (`NormalMap`, read as
/// data): the GPU's G-buffer normals bend as the CPU's do, and its light paths do not
/// (brute force, all light, rel_rmse within 0.005), and the image without the map is far
/// from it.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn the_gpu_bends_the_normals_the_camera_sees_as_the_cpu_does() {
    let mut scene = common::world(Some("test/lattice.toml")).scene.clone();
    let n = 16usize;
    let mut bytes = Vec::new();
    for y in 0..n {
        for x in 0..n {
            let a = std::f32::consts::TAU * x as f32 / n as f32;
            let b = std::f32::consts::TAU * y as f32 / n as f32;
            bytes
                .extend([128.0 + 100.0 * a.sin(), 128.0 + 100.0 * b.cos(), 190.0].map(|v| v as u8));
        }
    }
    let tex = lgh_scene::Texture::from_linear8(n as u32, n as u32, 3, &bytes).expect("texture");
    scene.textures.push(tex);
    let map = lgh_scene::normal_map::NormalMap {
        texture: scene.textures.len() as u32 - 1,
        wrap: [lgh_scene::texture::Wrap::Repeat; 2],
        scale: 0.8,
    };
    let flat = World::new(scene.clone());
    for m in &mut scene.materials {
        if m.name == "floor" || m.name == "wall" {
            m.normal_map = Some(map);
        }
    }
    let w = World::new(scene);
    let s = settings();
    let cpu = cpu_frame_equal_to_the_gpus(&w, &s, "normal-mapped lattice");
    let plain = render_frame(&flat, &s, &Silent).expect("cpu").image;
    let far = diff(&plain, &cpu).expect("same size");
    eprintln!("without the normal map against with: {far:?}");
    assert!(far.rel_rmse > 0.05, "{far:?}");
}
