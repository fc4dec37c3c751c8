//! VPL generation on the GPU (`lgh_gpu::vpls`) against the CPU's `generate_vpls` with the
//! same seed: the same light paths, drawn from the same Sobol numbers, on the default scene,
//! the three test scenes and a box lit by every kind of punctual light.

use glam::Vec3;
use lgh_render::World;
use lgh_render::passes::vpl_gen::{PathNumbers, VplSet, generate_vpls};
use lgh_scene::Light;

mod common;
use common::{SCENES, world};

/// The default box with a point light, a spot light and a sun beside its area light.
fn every_light() -> World {
    let mut scene = world(None).scene;
    scene.lights.extend([
        Light::Point {
            position: Vec3::new(0.3, 1.5, 0.2),
            intensity: Vec3::new(0.8, 0.7, 0.6),
        },
        Light::Spot {
            position: Vec3::new(-0.4, 1.7, 0.5),
            direction: Vec3::new(0.2, -1.0, -0.1).normalize(),
            intensity: Vec3::new(2.0, 2.5, 3.0),
            cos_inner: 0.9,
            cos_outer: 0.7,
        },
        Light::Directional {
            direction: Vec3::new(0.3, -1.0, 0.4).normalize(),
            irradiance: Vec3::splat(0.5),
        },
    ]);
    World::new(scene)
}

/// Share of VPLs of `a` whose position, normal and flux differ from `b`'s at the same index
/// by more than `tol` (positions relative to the scene's radius, flux to its own size).
fn mismatch(world: &World, a: &VplSet, b: &VplSet, tol: f32) -> f64 {
    let (a, b) = (&a.vpls, &b.vpls);
    let n = a.len().min(b.len());
    let bad = (0..n)
        .filter(|&i| {
            let dp = (a.positions[i] - b.positions[i]).abs().max_element();
            let dn = (a.normals[i] - b.normals[i]).abs().max_element();
            let df = (a.flux[i] - b.flux[i]).abs().max_element();
            dp > tol * world.radius || dn > tol || df > tol * b.flux[i].max_element().max(1e-30)
        })
        .count()
        + a.len().abs_diff(b.len());
    bad as f64 / b.len().max(1) as f64
}

/// The GPU's VPLs are the CPU's, VPL by VPL, within 1e-4: at least 99% of them, with the
/// same number of paths within 0.1% (a path that grazes an edge may leave another number of
/// VPLs, which shifts the ones after it; none did on these scenes). A wrong number of the
/// Sobol sequence, light choice, warp or roulette fails it.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_vpls_are_the_cpu_vpls() {
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    let worlds: Vec<(String, World)> = SCENES
        .iter()
        .map(|s| (format!("{s:?}"), world(*s)))
        .chain([("every light".to_owned(), every_light())])
        .collect();
    for (name, world) in &worlds {
        for (target, bounces, seed) in [(20_000, 3, 7u64), (3_000, 1, 1), (5_000, 6, 2)] {
            let cpu = generate_vpls(world, target, bounces, seed, PathNumbers::Sobol);
            let gpu = lgh_gpu::vpls::generate_vpls(ctx, world, target, bounces, seed).expect("gpu");
            let m = mismatch(world, &gpu, &cpu, 1e-4);
            println!(
                "{name} {target}/{bounces}: paths {} vs {}, VPLs {} vs {}, {:.3}% differ",
                gpu.paths,
                cpu.paths,
                gpu.vpls.len(),
                cpu.vpls.len(),
                100.0 * m
            );
            assert!(cpu.vpls.len() >= target);
            assert!(m <= 0.01, "{name}: {:.3}% of the VPLs differ", 100.0 * m);
            let dp = gpu.paths.abs_diff(cpu.paths) as f64 / cpu.paths as f64;
            assert!(dp <= 1e-3, "{name}: paths {} vs {}", gpu.paths, cpu.paths);
        }
    }
}

/// The same seed gives the same VPLs from run to run, bit for bit; another seed others.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_vpls_are_deterministic() {
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    let world = world(Some("test/two-rooms.toml"));
    let run = |seed| lgh_gpu::vpls::generate_vpls(ctx, &world, 10_000, 3, seed).expect("gpu");
    let (a, b, c) = (run(5), run(5), run(6));
    assert_eq!(a.paths, b.paths);
    assert_eq!(a.vpls.positions, b.vpls.positions);
    assert_eq!(a.vpls.flux, b.vpls.flux);
    assert_ne!(a.vpls.positions, c.vpls.positions);
}

/// Sponza's sun and the conference room's point lights (shared scenes): the GPU's 20,000
/// VPLs are the CPU's within 1e-4, at least 99% of them.
#[test]
#[cfg_attr(
    any(not(gpu_adapter), not(lgh_scenes)),
    ignore = "needs a GPU adapter and LGH_SCENES (the shared scenes)"
)]
fn gpu_vpls_are_the_cpu_vpls_on_the_shared_scenes() {
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    for name in ["sponza", "conference"] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join(format!("../../scenes/{name}.toml"));
        let world = World::new(lgh_scene::load(&path).expect("scene"));
        let cpu = generate_vpls(&world, 20_000, 3, 3, PathNumbers::Sobol);
        let gpu = lgh_gpu::vpls::generate_vpls(ctx, &world, 20_000, 3, 3).expect("gpu");
        let m = mismatch(&world, &gpu, &cpu, 1e-4);
        println!(
            "{name}: paths {} vs {}, {:.3}% differ",
            gpu.paths,
            cpu.paths,
            100.0 * m
        );
        assert!(m <= 0.01, "{name}: {:.3}% of the VPLs differ", 100.0 * m);
    }
}

/// A GPU frame's VPLs stay on the GPU for its hierarchy build: the build of exactly those
/// VPLs uploads nothing and gives the grid that uploading them gives; a copy of them (other
/// arrays) is uploaded, and the kept VPLs are gone after one build either way.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn a_frames_vpls_stay_on_the_gpu_for_its_build() {
    use lgh_core::lighting_grid::{Construction, HierarchyBuilder, LevelCount};
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    let world = world(Some("test/two-rooms.toml"));
    let s = lgh_render::RenderSettings {
        vpls: 8_000,
        seed: 4,
        ..lgh_render::RenderSettings::default()
    };
    let build = |vpls: &lgh_core::vpl::Vpls| {
        let mut b = lgh_gpu::grid::GpuGridBuilder::new(ctx);
        let t = b
            .build(&vpls.as_input(), LevelCount::Auto, Construction::Restrict)
            .expect("build");
        assert_eq!(b.fallback, None);
        (
            t.get("gpu_upload").is_some(),
            b.grid().expect("grid").clone(),
        )
    };
    let set = lgh_gpu::vpls::method_vpls(&world, &s, (true, false))
        .expect("gpu")
        .expect("vpls on the gpu");
    let (uploaded, kept) = build(&set.vpls);
    assert!(!uploaded, "the frame's VPLs were on the GPU");
    let (uploaded, again) = build(&set.vpls);
    assert!(uploaded, "a second build uploads");
    assert_eq!(kept, again, "the same grid");
    let set = lgh_gpu::vpls::method_vpls(&world, &s, (true, false))
        .expect("gpu")
        .expect("vpls on the gpu");
    let copy = set.vpls.clone();
    let (uploaded, from_copy) = build(&copy);
    assert!(uploaded, "a copy is uploaded");
    assert_eq!(from_copy, kept);
    let (uploaded, _) = build(&set.vpls);
    assert!(uploaded, "the kept VPLs went with the first build");
}

/// VPLs kept on the GPU without being read back: the CPU gets their number and light paths,
/// the build their bounds (found on the GPU: exactly the CPU's of the read-back VPLs) and
/// the same grid; a builder on another thread, or one asked for another count, finds
/// nothing, and a builder with nothing kept refuses (the frame then reads them back).
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn vpls_kept_without_a_copy_build_the_grid_of_the_read_back_ones() {
    use lgh_core::lighting_grid::{Construction, GridError, HierarchyBuilder, LevelCount};
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    for rel in [
        None,
        Some("test/two-rooms.toml"),
        Some("test/colonnade.toml"),
    ] {
        let world = world(rel);
        let mut s = lgh_render::RenderSettings {
            vpls: 6_000,
            seed: 2,
            ..lgh_render::RenderSettings::default()
        };
        s.lgh.normal_bins = false;
        let read = lgh_gpu::vpls::method_vpls(&world, &s, (true, false))
            .expect("gpu")
            .expect("vpls on the gpu");
        let grid_of_read = {
            let mut b = lgh_gpu::grid::GpuGridBuilder::new(ctx);
            b.build(
                &read.vpls.as_input(),
                LevelCount::Auto,
                Construction::Restrict,
            )
            .expect("build");
            b.grid().expect("grid").clone()
        };
        let keep = || {
            let set = lgh_gpu::vpls::method_vpls(&world, &s, (true, true))
                .expect("gpu")
                .expect("vpls on the gpu");
            assert!(set.vpls.is_empty(), "{rel:?}: read back");
            assert_eq!(
                (set.kept, set.len(), set.paths),
                (read.vpls.len(), read.len(), read.paths)
            );
            set
        };
        let set = keep();
        let mut b = lgh_gpu::grid::GpuGridBuilder::new(ctx);
        b.build_held(0, set.kept, LevelCount::Auto, Construction::Restrict)
            .expect("build of the kept VPLs");
        assert_eq!(b.grid(), Some(&grid_of_read), "{rel:?}: another grid");
        assert!(b.keeps_lights());
        // Taken by that build.
        assert_eq!(
            b.build_held(0, set.kept, LevelCount::Auto, Construction::Restrict)
                .unwrap_err(),
            GridError::KeptOnDevice
        );
        // Another count, another thread: not theirs.
        let set = keep();
        assert!(
            b.build_held(0, set.kept + 1, LevelCount::Auto, Construction::Restrict)
                .is_err()
        );
        let set = keep();
        std::thread::scope(|scope| {
            scope
                .spawn(|| {
                    let mut b = lgh_gpu::grid::GpuGridBuilder::new(ctx);
                    let e = b.build_held(0, set.kept, LevelCount::Auto, Construction::Restrict);
                    assert_eq!(e.unwrap_err(), GridError::KeptOnDevice);
                })
                .join()
                .expect("thread");
        });
        b.build_held(0, set.kept, LevelCount::Auto, Construction::Restrict)
            .expect("still kept for this thread");
        assert_eq!(b.grid(), Some(&grid_of_read));
    }
}

/// VPLs kept on the GPU for a frame with one hierarchy per normal bin: split there as the
/// CPU splits the read-back VPLs (each bin's number, and each bin's VPLs in order: the grid
/// of every bin, built from the kept part, equals the grid of the CPU's bin), whichever
/// order the parts are built in; a part taken after the last one with lights is gone.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn vpls_kept_in_normal_bins_build_the_grids_of_the_read_back_bins() {
    use lgh_core::lighting_grid::{Construction, GridError, HierarchyBuilder, LevelCount};
    use lgh_render::methods::lgh::{NORMAL_BINS, normal_bin};
    let ctx = lgh_gpu::GpuContext::shared().expect("an adapter");
    for (rel, vpls) in [
        (None, 5_000),
        (Some("test/clutter.toml"), 7_000),
        (Some("test/colonnade.toml"), 3_000),
    ] {
        let world = world(rel);
        let s = lgh_render::RenderSettings {
            vpls,
            seed: 3,
            ..lgh_render::RenderSettings::default()
        };
        assert!(s.lgh.normal_bins);
        let read = lgh_gpu::vpls::method_vpls(&world, &s, (true, false))
            .expect("gpu")
            .expect("vpls on the gpu");
        let mut bins = vec![lgh_core::vpl::Vpls::default(); NORMAL_BINS];
        for i in 0..read.vpls.len() {
            let n = read.vpls.normals[i];
            bins[normal_bin(n)].push(read.vpls.positions[i], n, read.vpls.flux[i]);
        }
        assert!(
            bins.iter().filter(|b| !b.is_empty()).count() >= 3,
            "{rel:?}: too few bins to test"
        );
        let grids: Vec<_> = bins
            .iter()
            .map(|bin| {
                (!bin.is_empty()).then(|| {
                    let mut b = lgh_gpu::grid::GpuGridBuilder::new(ctx);
                    b.build(&bin.as_input(), LevelCount::Auto, Construction::Restrict)
                        .expect("build");
                    b.grid().expect("grid").clone()
                })
            })
            .collect();
        let set = lgh_gpu::vpls::method_vpls(&world, &s, (true, true))
            .expect("gpu")
            .expect("vpls on the gpu");
        assert!(set.vpls.is_empty(), "{rel:?}: read back");
        let counts: [usize; NORMAL_BINS] = std::array::from_fn(|b| bins[b].len());
        assert_eq!(set.kept_bins, Some(counts), "{rel:?}");
        assert_eq!(set.kept, read.vpls.len());
        // The parts last to first but the last with lights, then that one.
        let last = (0..NORMAL_BINS)
            .rev()
            .find(|&b| counts[b] > 0)
            .expect("a bin");
        let order = (0..last).rev().chain([last]);
        let mut b = lgh_gpu::grid::GpuGridBuilder::new(ctx);
        for bin in order.filter(|&b| counts[b] > 0) {
            b.build_held(bin, counts[bin], LevelCount::Auto, Construction::Restrict)
                .expect("build of a kept bin");
            assert_eq!(b.grid(), grids[bin].as_ref(), "{rel:?}: bin {bin}");
        }
        let first = (0..NORMAL_BINS).find(|&b| counts[b] > 0).expect("a bin");
        assert_eq!(
            b.build_held(
                first,
                counts[first],
                LevelCount::Auto,
                Construction::Restrict
            )
            .unwrap_err(),
            GridError::KeptOnDevice
        );
    }
}
