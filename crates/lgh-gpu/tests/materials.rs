//! What a surface is, on the GPU against the CPU, on the lattice scene
//! (scenes/test/lattice.toml): alpha cut-outs (`cutouts.rs`, `shaders/bvh.wgsl`'s
//! `covers`: two screens whose holes exist only in their textures' alpha; the GPU's primary
//! rays, VPLs and shadow rays all pass through the holes as the CPU's do) and vertex
//! colours (`surfaces.rs`, `shaders/surface.wgsl`: the back wall's).

use lgh_render::image::metrics::diff;
use lgh_render::methods::brute::BRUTE;
use lgh_render::{Component, RenderSettings, Silent, World, render_frame};

mod common;

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
    let s = RenderSettings {
        method: BRUTE,
        width: 64,
        height: 36,
        vpls: 2000,
        component: Component::All,
        ..RenderSettings::default()
    };
    let cpu = render_frame(&w, &s, &Silent).expect("cpu").image;
    let gpu_settings = RenderSettings {
        method: lgh_gpu::brute::BRUTE_GPU,
        ..s.clone()
    };
    let gpu = render_frame(&w, &gpu_settings, &Silent).expect("gpu").image;
    let m = diff(&gpu, &cpu).expect("same size");
    eprintln!("lattice, brute, GPU against CPU: {m:?}");
    assert!(m.rel_rmse <= 0.005, "{m:?}");
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
