//! Frames shown on the GPU (`lgh_gpu::display`, `lgh view --device gpu`) against the CPU's
//! display of the same parts (`lgh_render::display::RunningMean`): the composition, the edge
//! resolve, the running mean and the tone mapping. The GPU rounds floats on its own (fused
//! multiply-adds, its `pow`), so the linear means agree to a relative 1e-5 and the packed
//! pixels to one step of 8 bits in a channel.

mod common;

use glam::Vec3;
use lgh_gpu::GpuContext;
use lgh_render::display::{DisplayRequest, Displayed, RunningMean};
use lgh_render::passes::edge_aa::EdgeResolve;
use lgh_render::passes::gbuffer::GBuffer;
use lgh_render::{Component, RenderSettings, Silent, render_frame_shown, render_frame_with};

/// The largest difference of one 8-bit channel between two packed images, and the share of
/// pixels that differ at all.
fn packed_difference(a: &[u32], b: &[u32]) -> (u32, f64) {
    assert_eq!(a.len(), b.len());
    let mut worst = 0;
    let mut differ = 0;
    for (x, y) in a.iter().zip(b) {
        let d = (0..3)
            .map(|c| ((x >> (8 * c)) & 0xff).abs_diff((y >> (8 * c)) & 0xff))
            .max()
            .unwrap_or(0);
        worst = worst.max(d);
        differ += usize::from(d > 0);
    }
    (worst, differ as f64 / a.len().max(1) as f64)
}

/// The largest difference between two linear images relative to the larger value (and
/// 1e-3 of the brightest pixel, below which a difference is rounding).
fn relative_difference(a: &[Vec3], b: &[Vec3]) -> f32 {
    assert_eq!(a.len(), b.len());
    let top = a.iter().map(|p| p.max_element()).fold(0.0f32, f32::max);
    a.iter()
        .zip(b)
        .map(|(x, y)| {
            let scale = x
                .abs()
                .max(y.abs())
                .max_element()
                .max(1e-3 * top)
                .max(1e-30);
            (*x - *y).abs().max_element() / scale
        })
        .fold(0.0, f32::max)
}

/// Checks a GPU display against the CPU's.
fn assert_same(gpu: &Displayed, cpu: &Displayed, what: &str) {
    assert_eq!(gpu.frames, cpu.frames, "{what}: frames in the mean");
    let (worst, share) = packed_difference(&gpu.pixels, &cpu.pixels);
    assert!(
        worst <= 1 && share < 0.01,
        "{what}: packed {worst}, {share}"
    );
    let (Some(g), Some(c)) = (&gpu.mean, &cpu.mean) else {
        panic!("{what}: no linear mean");
    };
    let d = relative_difference(g, c);
    assert!(d < 1e-5, "{what}: linear mean {d}");
    assert!(c.iter().any(|p| p.max_element() > 0.0), "{what}: black");
}

/// Images of the parts: made-up radiance that varies from pixel to pixel and frame to
/// frame, with an outlier and a non-finite value (the display shows them as the CPU does).
fn part(n: usize, seed: u32, scale: f32) -> Vec<Vec3> {
    (0..n)
        .map(|i| {
            let h = lgh_core::rng::hash(&[i as u64, u64::from(seed)]);
            let f = |k: u32| ((h >> k) & 0xff) as f32 / 255.0;
            match i {
                5 => Vec3::splat(1e6),
                9 if seed == 1 => Vec3::new(f32::NAN, 0.5, f32::INFINITY),
                _ => Vec3::new(f(0), f(8), f(16)) * scale,
            }
        })
        .collect()
}

/// The emission, direct and indirect parts composed, their edges resolved, accumulated
/// over three frames (the first restarting the mean) and tone-mapped on the GPU, as the
/// CPU composes, resolves and shows them; a restart starts again; without the linear
/// mean, the pixels alone come back.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn parts_shown_on_the_gpu_are_the_cpus_display() {
    let ctx = GpuContext::shared().expect("an adapter");
    let world = common::world(None);
    let (w, h) = (61, 37);
    let camera = world.scene.camera().frame(w, h);
    let mut g = GBuffer::default();
    g.render_into(&world, &camera, w, h);
    let n = g.len();
    assert!(
        g.emission.iter().any(|e| *e != Vec3::ZERO),
        "no emitter seen"
    );
    let edges = EdgeResolve::new(&world, &camera, &g, 4, None);
    assert!(edges.edge_pixels() > 0);
    let mut cpu = RunningMean::default();
    for (frame, restart) in [(0u32, true), (1, false), (2, false), (3, true)] {
        let direct = part(n, 2 * frame + 1, 2.0);
        let indirect = part(n, 2 * frame + 2, 0.5);
        let request = DisplayRequest {
            exposure: 1.5,
            restart,
            linear: true,
            taa: None,
        };
        let parts = (true, &direct[..], &indirect[..]);
        let gpu =
            lgh_gpu::display::show_parts(ctx, &g, parts, Some(&edges), &request).expect("shown");
        let mut image: Vec<Vec3> = (0..n)
            .map(|p| g.emission[p] + direct[p] + indirect[p])
            .collect();
        edges.apply(&mut image);
        let image = lgh_render::Image::from_pixels(w, h, image).pixels;
        let want = cpu.show(image, &request);
        assert_same(&gpu, &want, &format!("frame {frame}"));
    }
    // The indirect part alone, without the mean: the pixels only.
    let indirect = part(n, 99, 1.0);
    let request = DisplayRequest {
        exposure: 1.0,
        restart: true,
        linear: false,
        taa: None,
    };
    let gpu = lgh_gpu::display::show_parts(ctx, &g, (false, &[], &indirect), None, &request)
        .expect("shown");
    assert!(gpu.mean.is_none());
    let want = RunningMean::default().show(indirect, &request);
    let (worst, share) = packed_difference(&gpu.pixels, &want.pixels);
    assert!(
        worst <= 1 && share < 0.01,
        "indirect alone: {worst}, {share}"
    );
}

/// The GPU's lgh at the viewer's settings (4 x 4 interleaving, 4 shadow samples, the edge
/// resolve of a moving frame), small.
fn viewer_settings() -> RenderSettings {
    let mut s = RenderSettings {
        width: 64,
        height: 36,
        vpls: 3000,
        method: lgh_gpu::lgh::LGH_GPU,
        edge_samples: 4,
        ..RenderSettings::default()
    };
    s.tiling.interleave = Some(4);
    s.shadows.samples = Some(4);
    s
}

/// A change of the settings.
type Change = fn(&mut RenderSettings);

/// `render_frame_shown` with the GPU's lgh (the viewer's `--device gpu`) shows on the GPU
/// the frame `render_frame_with` brings back and the CPU shows: at the viewer's settings
/// with the edge resolve, over two accumulated frames, for the indirect component alone,
/// and with one level shown alone (its grids read back to the CPU).
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_frames_shown_on_the_gpu_are_the_frames_brought_back() {
    for scene in [None, Some("test/two-rooms.toml")] {
        let world = common::world(scene);
        let s = viewer_settings();
        let cases: [(&str, Change); 3] = [
            ("viewer", |_| {}),
            ("indirect", |s| s.component = Component::Indirect),
            ("one level", |s| s.lgh.only_level = Some(2)),
        ];
        for (what, change) in cases {
            let mut s = s.clone();
            change(&mut s);
            let what = format!("{scene:?}, {what}");
            let mut cpu = RunningMean::default();
            let mut memory = lgh_render::FrameMemory::default();
            for (seed, restart) in [(3, true), (4, false)] {
                s.seed = seed;
                let request = DisplayRequest {
                    exposure: world.scene.exposure,
                    restart,
                    linear: true,
                    taa: None,
                };
                let mut shown =
                    render_frame_shown(&world, &s, &Silent, &mut memory, request).expect("shown");
                let gpu = shown.shown.take().expect("shown on the GPU");
                assert!(shown.image.pixels.is_empty());
                assert_eq!((shown.image.width, shown.image.height), (64, 36));
                memory.recycle_gbuffer(shown.gbuffer);
                let back = render_frame_with(&world, &s, &Silent, &mut memory).expect("frame");
                assert!(back.shown.is_none());
                let want = cpu.show(back.image.pixels, &request);
                assert_same(&gpu, &want, &format!("{what}, seed {seed}"));
                memory.recycle_gbuffer(back.gbuffer);
            }
        }
    }
}

/// A sequence's moving frames with the temporal filter of the shadow ratio
/// (`Sequence::render_shown`, the viewer's `--taa` with `--device gpu`) filtered and shown
/// on the GPU are the frames brought back and filtered by the CPU's `TemporalFilter`: the
/// camera turns a little every frame, so the history is reprojected. Reprojection picks a
/// pixel by truncating a projected coordinate, which the GPU's rounding moves across a
/// pixel's edge now and then: all but a few pixels in a thousand agree to a relative 1e-4
/// (on lavapipe, all of them).
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn the_temporal_filter_on_the_gpu_is_the_cpus() {
    use lgh_render::denoise::temporal::TemporalSettings;
    use lgh_render::sequence::Sequence;
    for scene in [None, Some("test/clutter.toml")] {
        let mut world = common::world(scene);
        let mut s = viewer_settings();
        let rest = world.scene.camera();
        let lights = world.scene.lights.clone();
        let taa = Some(TemporalSettings::default());
        let (mut cpu, mut gpu) = (Sequence::new(taa), Sequence::new(taa));
        let mut changed = 0.0;
        for frame in 0..4u32 {
            let mut camera = rest.clone();
            let turn = glam::Quat::from_rotation_y(0.01 * frame as f32);
            camera.look_at = camera.position + turn * (camera.look_at - camera.position);
            world.set_view(camera, lights.clone());
            s.seed = 10 + u64::from(frame);
            let request = DisplayRequest {
                exposure: world.scene.exposure,
                restart: true,
                linear: true,
                taa: None,
            };
            let mut shown = gpu
                .render_shown(&world, &s, &Silent, request)
                .expect("shown");
            let got = shown.shown.take().expect("shown on the GPU");
            gpu.recycle(shown);
            let back = cpu.render(&world, &s, &Silent).expect("frame");
            let plain = render_frame_with(&world, &s, &Silent, &mut Default::default())
                .expect("frame")
                .image
                .pixels;
            let want = RunningMean::default().show(back.image.pixels.clone(), &request);
            cpu.recycle(back);
            let (g, c) = (got.mean.expect("mean"), want.mean.expect("mean"));
            let top = c.iter().map(|p| p.max_element()).fold(0.0f32, f32::max);
            let far = |a: &[Vec3], b: &[Vec3], tol: f32| {
                let n = a
                    .iter()
                    .zip(b)
                    .filter(|(x, y)| {
                        let scale = x.abs().max(y.abs()).max_element().max(1e-3 * top);
                        (**x - **y).abs().max_element() > tol * scale
                    })
                    .count();
                n as f64 / a.len() as f64
            };
            let share = far(&g, &c, 1e-4);
            assert!(
                share < 0.003,
                "{scene:?}, frame {frame}: {share} of the pixels differ"
            );
            let (worst, differ) = packed_difference(&got.pixels, &want.pixels);
            assert!(
                differ < 0.02,
                "{scene:?}, frame {frame}: packed {worst}, {differ}"
            );
            if frame > 0 {
                // The filter did something: the frame is not the unfiltered one.
                changed += far(&c, &plain, 1e-3);
            }
        }
        assert!(changed > 0.1, "{scene:?}: the filter changed {changed}");
    }
}

/// `count` dim point lights in a row across the middle of `world`'s upper half.
fn row_of_lights(world: &lgh_render::World, count: usize) -> Vec<lgh_scene::light::Light> {
    let r = world.radius;
    (0..count)
        .map(|i| lgh_scene::light::Light::Point {
            position: world.centre
                + Vec3::new(0.4 * r * (i as f32 / count as f32 - 0.5), 0.3 * r, 0.0),
            intensity: Vec3::splat(r * r / count as f32),
        })
        .collect()
}

/// A moving camera's frames shown on the GPU (the viewer's `--device gpu`) leave the
/// G-buffer's planes and the edge list on the GPU: the default frame reads back its packed
/// pixels (4 bytes a pixel) and a few words, under 5 bytes a pixel where the planes alone
/// are 80 (64 packed, and 16 of emission) and the edge list here 4.8, and shows exactly
/// what the same frame shows from planes traced and read back first (and, its camera
/// standing still, from the edge list read back and sorted). So do the frames whose steps
/// fall back to the CPU: one level shown alone (the grids on the CPU; the planes stay), an
/// interleaving blur wider than the GPU's (the ratio filter on the CPU) and 65 point
/// lights (the direct light on the CPU), which read the planes back. With one hierarchy
/// per normal bin (the render's default) or one (the viewer's start), such a frame waits
/// for the GPU five times (six for the first, whose VPL yield is not known yet).
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn moving_frames_shown_on_the_gpu_leave_the_planes_there() {
    use lgh_gpu::batch::{read_back_bytes, waits};
    let ctx = GpuContext::shared().expect("an adapter");
    // Whether the frame reads the planes back: no, yes, or left open (one level alone reads
    // back VPLs and grids, not planes).
    let cases: [(&str, Change, Option<bool>); 5] = [
        ("viewer", |_| {}, Some(false)),
        ("one hierarchy", |s| s.lgh.normal_bins = false, Some(false)),
        ("one level", |s| s.lgh.only_level = Some(2), None),
        ("wide blur", |s| s.tiling.blur.radius = 24, Some(true)),
        ("65 lights", |_| {}, Some(true)),
    ];
    for (what, change, planes_back) in cases {
        let mut world = common::world(None);
        let rest = world.scene.camera();
        let mut lights = world.scene.lights.clone();
        if what == "65 lights" {
            lights = row_of_lights(&world, 65);
        }
        let mut s = viewer_settings();
        change(&mut s);
        let (w, h) = (s.width, s.height);
        let (mut lazy, mut eager) = (
            lgh_render::FrameMemory::default(),
            lgh_render::FrameMemory::default(),
        );
        for frame in 0..2u32 {
            let mut camera = rest.clone();
            let turn = glam::Quat::from_rotation_y(0.02 * frame as f32);
            camera.look_at = camera.position + turn * (camera.look_at - camera.position);
            world.set_view(camera, lights.clone());
            let request = DisplayRequest {
                exposure: world.scene.exposure,
                restart: true,
                linear: false,
                taa: None,
            };
            let (before, waited) = (read_back_bytes(), waits());
            let mut got =
                render_frame_shown(&world, &s, &Silent, &mut lazy, request).expect("shown");
            let bytes = read_back_bytes() - before;
            let waited = waits() - waited;
            if planes_back == Some(false) {
                // The VPLs (once their yield is known), the builds of all normal bins
                // (two), the tile counts and the frame; the first frame's VPLs twice.
                let most = if frame == 0 { 6 } else { 5 };
                assert!(waited <= most, "{what}, frame {frame}: {waited} waits");
            }
            let n = (w * h) as u64;
            assert!(got.gbuffer.planes_deferred(), "{what}: planes read back");
            match planes_back {
                Some(false) => assert!(bytes < 5 * n, "{what}: {bytes} bytes, {n} pixels"),
                Some(true) => assert!(bytes > 64 * n, "{what}: no fallback ({bytes} bytes)"),
                None => {}
            }
            let mut g = GBuffer::default();
            let view = world.scene.camera().frame(w, h);
            lgh_gpu::primary::trace_gbuffer(ctx, &world, &view, w, h, &mut g).expect("traced");
            eager.recycle_gbuffer(g);
            let mut want =
                render_frame_shown(&world, &s, &Silent, &mut eager, request).expect("shown");
            assert!(!want.gbuffer.planes_deferred());
            let (a, b) = (got.shown.take(), want.shown.take());
            let (a, b) = (a.expect("shown"), b.expect("shown"));
            assert!(
                a.pixels.iter().any(|&p| p & 0xff_ffff != 0),
                "{what}: black"
            );
            assert!(a.pixels == b.pixels, "{what}, frame {frame}: another image");
            lazy.recycle_gbuffer(got.gbuffer);
        }
    }
}
