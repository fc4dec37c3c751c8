//! The hierarchy built on the GPU (`lgh_gpu::grid`) against the CPU's build by restriction:
//! the same levels and vertices, the same grid lights to rounding, on lights on surfaces,
//! in a box, on a plane, far from the origin, one light; and the same from run to run.

use glam::Vec3;
use lgh_core::lighting_grid::synthetic::{SyntheticLights, lights_in_box, lights_on_surfaces};
use lgh_core::lighting_grid::{
    Construction, GridBuilder, HierarchyBuilder, LevelCount, LightingGrid,
};
use lgh_gpu::GpuContext;
use lgh_gpu::grid::GpuGridBuilder;

type Lights = SyntheticLights;

fn surfaces(n: usize, seed: u64) -> Lights {
    lights_on_surfaces(n, seed)
}

/// Lights in the box `offset + scale x [0, 1)^3` (a plane where a scale is 0), one in ten
/// dark.
fn in_box(n: usize, seed: u64, scale: Vec3, offset: Vec3) -> Lights {
    let mut l = lights_in_box(n, seed, scale, offset);
    for c in l.intensity.iter_mut().skip(3).step_by(10) {
        *c = Vec3::ZERO;
    }
    l
}

fn cpu(l: &Lights, levels: LevelCount, shift: Option<Vec3>) -> LightingGrid {
    let mut b = GridBuilder::default();
    b.set_shift(shift);
    b.build(&l.input(), levels, Construction::Restrict)
        .expect("cpu build");
    b.into_grid()
}

fn gpu(ctx: &GpuContext, l: &Lights, levels: LevelCount, shift: Option<Vec3>) -> LightingGrid {
    let mut b = GpuGridBuilder::new(ctx);
    HierarchyBuilder::set_shift(&mut b, shift);
    HierarchyBuilder::build(&mut b, &l.input(), levels, Construction::Restrict).expect("gpu build");
    assert_eq!(b.fallback, None, "the build fell back to the CPU");
    HierarchyBuilder::grid(&b).expect("a grid").clone()
}

/// The GPU's hierarchy equals the CPU's: the same geometry, levels and vertices; positions
/// within 1e-5 h_top (plus an ulp of far coordinates); intensities within 1e-4 of the
/// light plus 1e-6 of its level's brightest, masses within 1e-4 plus four ulps of a
/// light's offset in S_1's cells per light: that offset (up to 2^9) may differ by an ulp
/// from the CPU's (WGSL's division is not exact; `div_rn` corrects most of it), and the GPU
/// sums S_1 in fixed point and the coarser levels in f32, the CPU in f64. Deviations within
/// 1e-3 h_top, normals within 1e-4.
fn assert_close(a: &LightingGrid, b: &LightingGrid, what: &str) {
    assert_eq!(a.geometry, b.geometry, "{what}: geometry");
    assert_eq!(a.level_start, b.level_start, "{what}: levels");
    assert_eq!(a.vertex, b.vertex, "{what}: vertices");
    let h = a.geometry.h_top;
    let far = a.geometry.origin.abs().max_element() * 4.0 * f32::EPSILON;
    // Four ulps of a light's offset in S_1's cells (up to 2^(l_max - 1)): what a weight may
    // move by.
    let ulp_weight = 4.0 * f32::EPSILON * (1u32 << (a.l_max() - 1)) as f32;
    for l in 1..=a.l_max() {
        let r = a.level_range(l);
        let brightest = a.intensity[r.clone()]
            .iter()
            .fold(0.0f32, |m, c| m.max(c.max_element()));
        for k in r {
            let d = (a.position[k] - b.position[k]).abs().max_element();
            assert!(
                d <= 1e-5 * h + far,
                "{what}: level {l} light {k}: position {d}"
            );
            let tol = 1e-4 * a.intensity[k].max_element() + 1e-6 * brightest;
            let d = (a.intensity[k] - b.intensity[k]).abs().max_element();
            assert!(
                d <= tol,
                "{what}: level {l} light {k}: intensity {d} > {tol}"
            );
            let d = (a.deviation[k] - b.deviation[k]).abs().max_element();
            assert!(d <= 1e-3 * h, "{what}: level {l} light {k}: deviation {d}");
            let d = (a.normal[k] - b.normal[k]).abs().max_element();
            assert!(d <= 1e-4, "{what}: level {l} light {k}: normal {d}");
            let d = (a.mass[k] - b.mass[k]).abs();
            let tol = 1e-4 * a.mass[k] + ulp_weight;
            assert!(
                d <= tol,
                "{what}: level {l} light {k}: mass {a} vs {b}",
                a = a.mass[k],
                b = b.mass[k]
            );
        }
    }
}

#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_hierarchy_equals_the_cpu_restriction() {
    let ctx = GpuContext::shared().expect("an adapter");
    let shift = Some(Vec3::new(0.3, 0.71, 0.05));
    let cases = [
        (
            "surfaces, auto",
            surfaces(20_000, 3),
            LevelCount::Auto,
            None,
        ),
        (
            "surfaces, shifted",
            surfaces(5000, 4),
            LevelCount::Auto,
            shift,
        ),
        (
            "box, 5 levels",
            in_box(3000, 8, Vec3::new(3.0, 1.0, 2.0), Vec3::new(-5.0, 1.0, 0.0)),
            LevelCount::Fixed(5),
            None,
        ),
        (
            "plane, auto",
            in_box(4000, 9, Vec3::new(4.0, 0.0, 2.0), Vec3::new(-1.0, 2.0, 0.5)),
            LevelCount::Auto,
            None,
        ),
        (
            "far, auto",
            in_box(2000, 10, Vec3::new(3.0, 1.0, 2.0), Vec3::splat(1.0e4)),
            LevelCount::Auto,
            None,
        ),
        (
            "one light",
            in_box(1, 11, Vec3::ONE, Vec3::ZERO),
            LevelCount::Fixed(3),
            None,
        ),
    ];
    for (what, lights, levels, shift) in &cases {
        let a = cpu(lights, *levels, *shift);
        let b = gpu(ctx, lights, *levels, *shift);
        assert_close(&a, &b, what);
    }
}

/// Integer sums do not depend on the order of the atomic adds: two builds are identical.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_hierarchy_is_the_same_from_run_to_run() {
    let ctx = GpuContext::shared().expect("an adapter");
    let lights = surfaces(30_000, 5);
    let a = gpu(ctx, &lights, LevelCount::Auto, None);
    let b = gpu(ctx, &lights, LevelCount::Auto, None);
    assert_eq!(a, b);
}

/// A builder takes its memory from the context's pool, not its settings: after a builder
/// with a grid shift and a draw is dropped, a new one on the same context has no grid, no
/// representatives, and builds the unshifted grid without a draw. (The pooled state once
/// kept the shift, and the representatives' test failed when it ran after a shifted build.)
/// A context of its own, so that no other test's builder takes the dropped state.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn a_new_builder_keeps_nothing_of_a_dropped_one() {
    let ctx = GpuContext::new().expect("an adapter");
    let lights = surfaces(4000, 12);
    let mut a = GpuGridBuilder::new(&ctx);
    HierarchyBuilder::set_shift(&mut a, Some(Vec3::new(0.4, 0.6, 0.2)));
    HierarchyBuilder::draw_representatives(&mut a, Some(5));
    HierarchyBuilder::build(
        &mut a,
        &lights.input(),
        LevelCount::Auto,
        Construction::Restrict,
    )
    .expect("gpu build");
    assert!(HierarchyBuilder::representatives(&a).is_some());
    drop(a);
    let mut b = GpuGridBuilder::new(&ctx);
    assert!(
        HierarchyBuilder::grid(&b).is_none(),
        "a grid before a build"
    );
    assert!(HierarchyBuilder::representatives(&b).is_none());
    HierarchyBuilder::build(
        &mut b,
        &lights.input(),
        LevelCount::Auto,
        Construction::Restrict,
    )
    .expect("gpu build");
    assert!(
        HierarchyBuilder::representatives(&b).is_none(),
        "drawn unasked"
    );
    let got = HierarchyBuilder::grid(&b).expect("a grid").clone();
    assert_close(
        &cpu(&lights, LevelCount::Auto, None),
        &got,
        "after a shifted builder",
    );
}

/// The S_1 representatives drawn on the GPU with the build are the CPU's draw
/// (`s1_representatives`, same seed): the same hash, the same order of the lights. A slot
/// may differ where a weight rounds differently (a light's offset an ulp off, a fused
/// multiply-add in the luminance): at least 99% of the slots are equal, and every slot is
/// one of the input lights exactly where the CPU's is.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_representatives_are_the_cpu_draw() {
    use lgh_core::lighting_grid::representative::{NONE, s1_representatives};
    let ctx = GpuContext::shared().expect("an adapter");
    let cases = [
        ("surfaces", surfaces(20_000, 3), 7),
        (
            "box with dark lights",
            in_box(
                6000,
                12,
                Vec3::new(3.0, 1.0, 2.0),
                Vec3::new(-5.0, 1.0, 0.0),
            ),
            1234,
        ),
    ];
    for (what, lights, seed) in &cases {
        let mut b = GpuGridBuilder::new(ctx);
        HierarchyBuilder::draw_representatives(&mut b, Some(*seed));
        HierarchyBuilder::build(
            &mut b,
            &lights.input(),
            LevelCount::Auto,
            Construction::Restrict,
        )
        .expect("gpu build");
        assert_eq!(b.fallback, None);
        let gpu = HierarchyBuilder::representatives(&b)
            .expect("drawn on the GPU")
            .to_vec();
        let grid = cpu(lights, LevelCount::Auto, None);
        let want = s1_representatives(&grid, &lights.input(), *seed, |s| *s);
        assert_eq!(gpu.len(), want.len(), "{what}: S_1 lights");
        let (mut same, mut all) = (0, 0);
        for (g, c) in gpu.iter().zip(&want) {
            for (a, b) in g.iter().zip(c) {
                all += 1;
                same += usize::from(a == b);
                assert_eq!(*a == NONE, *b == NONE, "{what}: an empty slot differs");
                assert!(*a == NONE || (*a as usize) < lights.positions.len());
            }
        }
        assert!(
            same as f64 >= 0.99 * all as f64,
            "{what}: {same} of {all} slots equal"
        );
        eprintln!("{what}: {same} of {all} slots equal");
    }
}

/// The gather construction is not built on the GPU: the builder hands it to the CPU's (the
/// same hierarchy as the CPU builder's), without representatives, and says nothing failed.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn the_gather_construction_is_built_by_the_cpu() {
    let ctx = GpuContext::shared().expect("an adapter");
    let lights = surfaces(3000, 6);
    let mut b = GpuGridBuilder::new(ctx);
    HierarchyBuilder::draw_representatives(&mut b, Some(3));
    HierarchyBuilder::build(
        &mut b,
        &lights.input(),
        LevelCount::Auto,
        Construction::GatherFromS1,
    )
    .expect("build");
    assert_eq!(b.fallback, None);
    assert!(HierarchyBuilder::representatives(&b).is_none());
    let mut c = GridBuilder::default();
    c.build(
        &lights.input(),
        LevelCount::Auto,
        Construction::GatherFromS1,
    )
    .expect("cpu build");
    assert_eq!(HierarchyBuilder::grid(&b), c.grid());
}

/// The GPU's exclusive prefix sum equals the CPU's, of values and of population counts, over
/// sizes that need one block, several, and more block totals than one pass of the second
/// step holds (over 256 blocks of 1024).
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn gpu_scan_equals_the_cpu_prefix_sum() {
    let ctx = GpuContext::shared().expect("an adapter");
    let mut rng = lgh_core::rng::Rng::new(&[5, 5]);
    for n in [1usize, 1000, 5000, 300_000] {
        let values: Vec<u32> = (0..n).map(|_| rng.next_u32()).collect();
        for popcount in [false, true] {
            let small: Vec<u32> = if popcount {
                values.clone()
            } else {
                values.iter().map(|v| v % 1000).collect()
            };
            let src = ctx.upload("test scan src", &small).expect("upload");
            let dst = ctx.output("test scan dst", 4 * n as u64).expect("lease");
            let total = ctx.output("test scan total", 16).expect("lease");
            let mut batch = lgh_gpu::Batch::new(ctx);
            lgh_gpu::scan::record(ctx, &mut batch, &src, &dst, &total, n, popcount).expect("scan");
            batch.read(dst.buffer(), dst.bytes()).expect("read");
            batch.read(total.buffer(), 16).expect("read");
            let (reads, _) = batch.finish().expect("finish");
            let got: &[u32] = bytemuck::cast_slice(&reads[0]);
            let got_total: &[u32] = bytemuck::cast_slice(&reads[1]);
            let mut sum = 0u32;
            for (k, v) in small.iter().enumerate() {
                assert_eq!(got[k], sum, "n {n}, popcount {popcount}: element {k}");
                sum = sum.wrapping_add(if popcount { v.count_ones() } else { *v });
            }
            assert_eq!(got_total[0], sum, "n {n}: total");
        }
    }
}

/// Bad lights are refused by the GPU builder as by the CPU's, with the same error, before
/// any GPU work: a non-finite position, a negative intensity, none at all.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn bad_lights_are_refused_as_on_the_cpu() {
    use lgh_core::lighting_grid::GridError;
    let ctx = GpuContext::shared().expect("an adapter");
    let mut nan = lights_in_box(10, 1, Vec3::ONE, Vec3::ZERO);
    nan.positions[4].y = f32::NAN;
    let mut negative = lights_in_box(10, 1, Vec3::ONE, Vec3::ZERO);
    negative.intensity[7].x = -1.0;
    let empty = SyntheticLights::default();
    for (lights, want) in [
        (&nan, GridError::InvalidLight { index: 4 }),
        (&negative, GridError::InvalidLight { index: 7 }),
        (&empty, GridError::Empty),
    ] {
        let mut b = GpuGridBuilder::new(ctx);
        let got = HierarchyBuilder::build(
            &mut b,
            &lights.input(),
            LevelCount::Auto,
            Construction::Restrict,
        );
        assert_eq!(got.err(), Some(want));
    }
}

/// An `lgh` frame's statistics say where its hierarchies were built: on the GPU with the
/// GPU methods (shadowed, whose build also draws the representatives, and unshadowed), on
/// the CPU with the CPU method; and whether the CPU held the grids.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn lgh_statistics_say_where_the_hierarchy_was_built() {
    use lgh_render::methods::lgh::{LGH, LghStats};
    use lgh_render::{RenderSettings, Silent, World, render_frame};
    let world = World::new({
        let mut s = lgh_scene::cornell::cornell_box();
        s.finish(std::path::Path::new("<built-in cornell>"))
            .expect("scene");
        s
    });
    let base = RenderSettings {
        width: 32,
        height: 18,
        vpls: 2000,
        ..RenderSettings::default()
    };
    // The shadowed GPU frame keeps its grids on the GPU; without shadows the CPU packs
    // the shaded lights from the grids read back.
    for (method, want, on_cpu) in [
        (lgh_gpu::lgh::LGH_GPU, "gpu", false),
        (lgh_gpu::lgh::LGH_UNSHADOWED_GPU, "gpu", true),
        (LGH, "cpu", true),
    ] {
        let s = RenderSettings {
            method,
            ..base.clone()
        };
        let frame = render_frame(&world, &s, &Silent).expect("frame");
        let stats = frame.stats::<LghStats>().expect("lgh statistics");
        assert_eq!(stats.hierarchy_device, want, "{}", method.name());
        assert_eq!(stats.grids_on_cpu, on_cpu, "{}", method.name());
    }
}

/// A build that keeps its grid on the GPU hands back no grid, and its shape (the level
/// ranges, read back instead) is that of the same build read back: on lights on surfaces,
/// in a box with dark lights (dropped records), and one light.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn a_grid_kept_on_the_gpu_has_the_read_back_grids_shape() {
    let ctx = GpuContext::shared().expect("an adapter");
    let cases = [
        surfaces(20_000, 3),
        in_box(5_000, 4, Vec3::ONE, Vec3::ZERO),
        in_box(1, 5, Vec3::ONE, Vec3::ZERO),
    ];
    for (i, l) in cases.iter().enumerate() {
        let read = gpu(ctx, l, LevelCount::Auto, None);
        let mut b = GpuGridBuilder::new(ctx);
        b.keep_grid(true);
        HierarchyBuilder::build(&mut b, &l.input(), LevelCount::Auto, Construction::Restrict)
            .expect("gpu build");
        assert_eq!(b.fallback, None, "case {i}: the build fell back to the CPU");
        assert!(
            HierarchyBuilder::grid(&b).is_none(),
            "case {i}: a grid came back"
        );
        assert_eq!(HierarchyBuilder::shape(&b), Some(read.shape()), "case {i}");
        assert!(HierarchyBuilder::makes_lookups(&b), "case {i}");
        let held = b.take_held();
        assert!(matches!(held.as_slice(), [Some(h)] if h.numbered.is_some()));
    }
}
