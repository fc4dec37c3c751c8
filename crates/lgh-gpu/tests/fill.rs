//! The filling of cut recombination windows on the GPU (`lgh_gpu::fill`; docs/design.md,
//! "Filling cut windows") against the CPU's: the masks of the pixels that fill, and `lgh`'s
//! unshadowed frame under 4 x 4 interleaving, where the fill changes the image.

use glam::Vec3;
use lgh_render::image::Image;
use lgh_render::image::metrics::diff;
use lgh_render::methods::lgh::LGH_UNSHADOWED;
use lgh_render::passes::gbuffer::GBuffer;
use lgh_render::shading::interleave::{BlurParams, JUMP_X, discontinuities, missed_sub_images};
use lgh_render::{Component, RenderSettings, Silent, World, render_frame};

mod common;
use common::{SCENES, world};

/// The jumps and masks of the GPU (`lgh_gpu::interleave::discontinuities`,
/// `lgh_gpu::fill::missed_sub_images`) equal the CPU's (`discontinuities`,
/// `missed_sub_images`) on the G-buffers of the default scene and the three test scenes,
/// at interleaving n = 2, 3, 4 and 8 (64 sub-images: both words) and three thresholds, in
/// images whose width is not a multiple of n; they are integers from the same walks, so
/// they are equal bit for bit. Some pixels fill in every scene at n = 4.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_fill_masks_are_the_cpus() {
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    for rel in SCENES {
        let w = world(rel);
        let (width, height) = (101, 57);
        let camera = w.scene.camera().frame(width, height);
        let metres = GBuffer::render(&w, &camera, width, height);
        for (g, n) in [2, 3, 4, 8].into_iter().map(|n| (&metres, n)) {
            let p = BlurParams::defaults().with_phases(n);
            let disc = discontinuities(g, &p);
            let gpu_disc = lgh_gpu::interleave::discontinuities(ctx, g, &p).expect("gpu");
            let differ = (0..g.len()).filter(|&i| gpu_disc[i] != disc[i]).count();
            assert_eq!(
                differ, 0,
                "{rel:?} n = {n}: the jumps of {differ} pixels differ"
            );
            for below in [0.3, 0.6, 1.0] {
                let cpu = missed_sub_images(g, &disc, &p.recombination(), below);
                let gpu = lgh_gpu::fill::missed_sub_images(ctx, g, &p, below).expect("gpu");
                let filling = cpu
                    .as_ref()
                    .map_or(0, |m| m.iter().filter(|&&m| m != 0).count());
                eprintln!("{rel:?} n = {n}, below {below}: {filling} pixels fill");
                if n == 4 && below == 0.3 {
                    assert!(filling > 0, "{rel:?}: no pixel fills at n = 4");
                }
                // The GPU always gives masks; the CPU none where no pixel fills.
                let none = vec![0; g.len()];
                let (gpu, cpu) = (gpu.unwrap_or(none.clone()), cpu.unwrap_or(none));
                let differ: Vec<(usize, u64, u64)> = (0..g.len())
                    .filter(|&i| gpu[i] != cpu[i])
                    .map(|i| (i, gpu[i], cpu[i]))
                    .collect();
                assert!(
                    differ.is_empty(),
                    "{rel:?} n = {n}, below {below}: {} pixels differ (pixel, GPU, CPU): {:?}",
                    differ.len(),
                    &differ[..differ.len().min(8)]
                );
            }
        }
    }
}

/// The GPU's jumps equal the CPU's on a face-on plane whose depth steps by two units in the
/// last place (rounding) at one column and by 1% (an edge) at another, in units from
/// millimetres to 100 km: the depth test's floor is relative to the depth on both.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_jumps_are_the_cpus_in_any_units() {
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    let (w, h) = (24u32, 4u32);
    let n = (w * h) as usize;
    for s in [1e-5f32, 1e-3, 1.0, 1e3] {
        let base = 5.0 * s;
        let two_ulps = f32::from_bits(base.to_bits() + 2);
        let column = |i: usize| i as u32 % w;
        let g = GBuffer {
            width: w,
            height: h,
            position: (0..n)
                .map(|i| Vec3::new(column(i) as f32, (i as u32 / w) as f32, -5.0) * s)
                .collect(),
            normal: vec![Vec3::Z; n],
            geo_normal: vec![Vec3::Z; n],
            albedo: vec![Vec3::ONE; n],
            depth: (0..n)
                .map(|i| match column(i) {
                    x if x < 8 => base,
                    x if x < 16 => two_ulps,
                    _ => 1.01 * base,
                })
                .collect(),
            emission: vec![Vec3::ZERO; n],
            ..GBuffer::default()
        };
        let p = BlurParams::defaults().with_phases(4);
        let cpu = discontinuities(&g, &p);
        let gpu = lgh_gpu::interleave::discontinuities(ctx, &g, &p).expect("gpu");
        assert_eq!(gpu, cpu, "units {s}");
        let edges: Vec<u32> = (0..n)
            .filter(|&i| cpu[i] & JUMP_X != 0)
            .map(column)
            .collect();
        assert_eq!(edges, vec![15; h as usize], "units {s}");
    }
}

fn render(w: &World, s: &RenderSettings, method: lgh_render::Method) -> Image {
    let s = RenderSettings {
        method,
        ..s.clone()
    };
    render_frame(w, &s, &Silent).expect("frame").image
}

/// Under 4 x 4 interleaving, `lgh-unshadowed` on the GPU fills cut windows as the CPU's
/// does: the two frames are equal within rel_rmse 1e-4 (float rounding) on the same
/// G-buffer and VPLs, on every test scene, with the filling on (the default `fill_below`
/// 0.3, and 0.6). Without it the GPU's frame is at least 10 times further from the CPU's
/// filled one on some scene (the test sees the fill).
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_unshadowed_lgh_fills_cut_windows_as_the_cpu() {
    const ON_CPU_INPUTS: lgh_render::Method =
        lgh_render::Method::new(&common::OnCpuInputs(lgh_gpu::lgh::LGH_UNSHADOWED_GPU));
    let mut sees_the_fill = false;
    for rel in SCENES {
        let w = world(rel);
        let mut s = RenderSettings {
            width: 96,
            height: 54,
            vpls: 3000,
            component: Component::Indirect,
            ..RenderSettings::default()
        };
        s.tiling.interleave = Some(4);
        for below in [0.3, 0.6] {
            s.lgh.fill_below = below;
            let cpu = render(&w, &s, LGH_UNSHADOWED);
            let gpu = render(&w, &s, ON_CPU_INPUTS);
            let m = diff(&gpu, &cpu).expect("size");
            eprintln!("{rel:?} fill_below {below}: {m:?}");
            assert!(m.rel_rmse <= 1e-4, "{rel:?} fill_below {below}: {m:?}");
            assert!(gpu.pixels.iter().all(|p| p.is_finite()));
            if below == 0.3 {
                let mut off = s.clone();
                off.lgh.fill_below = 0.0;
                let unfilled = diff(&render(&w, &off, ON_CPU_INPUTS), &cpu).expect("size");
                eprintln!("{rel:?} the GPU without filling: {unfilled:?}");
                sees_the_fill |= unfilled.rel_rmse > 1e-3;
            }
        }
    }
    assert!(sees_the_fill, "filling changes no scene's frame");
}
