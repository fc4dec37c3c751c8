//! The ratio estimator on the GPU (blur, a-trous, ratios) against the CPU's, on the same
//! inputs: the CPU lgh loop's A, S and U of a frame, through lgh-render's
//! `shadowed_indirect_with` and through `lgh_gpu::ratio::shadowed_indirect`. Both are
//! deterministic, so they agree to rounding (the sums run in other orders).

use glam::Vec3;
use lgh_render::memory::FrameMemory;
use lgh_render::methods::MethodInputs;
use lgh_render::methods::lgh::{LghFrame, Prepared};
use lgh_render::passes::gbuffer::GBuffer;
use lgh_render::passes::vpl_gen::generate_vpls;
use lgh_render::shading::ratio::shadowed_indirect_with;
use lgh_render::{RenderSettings, Silent, World};

mod common;
use common::world;

/// The largest difference between `a` and `b` relative to `b`'s largest value.
fn rel_max(a: &[Vec3], b: &[Vec3]) -> f32 {
    let scale = b.iter().map(|v| v.max_element()).fold(1e-12, f32::max);
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).abs().max_element())
        .fold(0.0, f32::max)
        / scale
}

/// One frame's comparison; returns the largest relative difference of the composite.
fn compare(w: &World, s: &RenderSettings, shadowed: bool) -> f32 {
    let camera = w.scene.camera().frame(s.width, s.height);
    let g = GBuffer::render(w, &camera, s.width, s.height);
    let vpls = generate_vpls(w, s.vpls, s.bounces, s.seed, s.path_numbers);
    let inputs = MethodInputs {
        world: w,
        gbuffer: &g,
        camera: &camera,
        vpls: &vpls.vpls,
        vpl_count: vpls.vpls.len(),
        vpl_bins: None,
        settings: s,
        progress: &Silent,
    };
    let mut memory = FrameMemory::default();
    let Ok(Prepared::Frame(frame)) = LghFrame::prepare(&inputs, shadowed, &mut memory, false)
    else {
        panic!("a frame with VPLs");
    };
    let filter = frame.ratio_filter(&inputs);
    let shaded = frame.shade(&inputs);
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    let gpu = lgh_gpu::ratio::shadowed_indirect(ctx, w, &g, &shaded.a, &shaded.estimates, &filter)
        .expect("gpu")
        .expect("supported");
    let mut t = lgh_core::timing::Timings::default();
    let cpu = shadowed_indirect_with(
        w,
        &g,
        shaded.a,
        shaded.estimates,
        &filter,
        &mut t,
        &mut memory,
        None,
    );
    let d = [
        rel_max(&gpu.unshadowed, &cpu.unshadowed),
        rel_max(&gpu.ratio.raw, &cpu.ratio.raw),
        rel_max(&gpu.ratio.filtered, &cpu.ratio.filtered),
        rel_max(&gpu.indirect, &cpu.indirect),
    ];
    eprintln!(
        "{} k {} n {:?}: A, raw, filtered, composite {d:?}",
        w.scene.name,
        frame_k(s, shadowed),
        s.tiling.interleave
    );
    assert_eq!(gpu.rays, cpu.rays);
    d.into_iter().fold(0.0, f32::max)
}

fn frame_k(s: &RenderSettings, shadowed: bool) -> u32 {
    if shadowed { s.shadow_samples() } else { 0 }
}

/// With 4 x 4 interleaving (the blur of A over the 4 x 4 neighbourhood, of S and U over 17
/// pixels, phase by phase), without interleaving (no blur), unshadowed (A alone), and with
/// a wide blur that crosses the scenes' right-angled creases where A's recombination stops
/// at them (`n_diff` 1.5 against `a_n_diff`), on the default scene and two test scenes at
/// 96x54: the GPU's A, ratios and composite within 1e-5 of the CPU's largest value, pixel
/// by pixel (measured on lavapipe: 1.3e-6 at most).
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_ratio_estimator_equals_the_cpu() {
    let scenes = [None, Some("test/two-rooms.toml"), Some("test/clutter.toml")];
    for rel in scenes {
        let w = world(rel);
        let cases = [
            (Some(4), true, false),
            (Some(1), true, false),
            (Some(4), false, false),
            (Some(2), true, true),
        ];
        for (interleave, shadowed, creases_only) in cases {
            let mut s = RenderSettings {
                width: 96,
                height: 54,
                vpls: 3000,
                ..RenderSettings::default()
            };
            s.tiling.interleave = interleave;
            if creases_only {
                s.tiling.blur.n_diff = 1.5;
                s.tiling.blur.a_n_diff = 0.05;
            }
            let d = compare(&w, &s, shadowed);
            assert!(
                d <= 1e-5,
                "{rel:?} {interleave:?} {shadowed} {creases_only}: {d}"
            );
        }
    }
}
