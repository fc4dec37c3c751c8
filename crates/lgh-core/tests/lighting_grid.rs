//! Tests of the lighting grid hierarchy construction (LGH 2019 section 3.1).

use glam::{DVec3, Vec3};
use lgh_core::lighting_grid::reference::build_reference;
use lgh_core::lighting_grid::synthetic::{SyntheticLights, lights_in_box, lights_on_surfaces};
use lgh_core::lighting_grid::{Construction, GridError, LevelCount, LightingGrid, MAX_LEVELS};
use proptest::prelude::*;

const ALL: [Construction; 3] = [
    Construction::GatherFromS1,
    Construction::ScatterAll,
    Construction::Restrict,
];

type Lights = SyntheticLights;

fn synthetic(n: usize, seed: u64) -> Lights {
    lights_on_surfaces(n, seed)
}

fn random_box(n: usize, seed: u64, scale: Vec3, offset: Vec3) -> Lights {
    lights_in_box(n, seed, scale, offset)
}

fn build(l: &Lights, levels: LevelCount, c: Construction) -> LightingGrid {
    LightingGrid::build(&l.input(), levels, c).unwrap().0
}

fn sum_d(v: impl Iterator<Item = Vec3>) -> DVec3 {
    v.map(|x| x.as_dvec3()).sum()
}

/// Every level keeps the total intensity (relative 1e-5), its mass-weighted centroid is the
/// input centroid (the gather levels count each S1 light with its mass), and every grid light
/// lies within one cell of its vertex, up to the f32 rounding of its coordinates (a few ulps
/// of their magnitude: with one light the grid is a tiny box far from the origin).
fn check_invariants(l: &Lights, g: &LightingGrid) {
    let total = sum_d(l.intensity.iter().copied());
    let centroid = sum_d(l.positions.iter().copied()) / l.positions.len() as f64;
    let scale = g.geometry.h_top as f64;
    for level in 1..=g.l_max() {
        let r = g.level_range(level);
        let s = sum_d(g.intensity[r.clone()].iter().copied());
        let rel = ((s - total).abs() / total.max_element()).max_element();
        assert!(rel < 1e-5, "level {level}: intensity {s} vs {total}");
        // Zero-intensity vertices are compacted away, so check the centroid only when all
        // inputs have intensity (then nothing is removed).
        if l.intensity.iter().all(|c| c.max_element() > 0.0) {
            let w: f64 = g.mass[r.clone()].iter().map(|&m| m as f64).sum();
            let c = r
                .clone()
                .map(|k| g.position[k].as_dvec3() * g.mass[k] as f64)
                .sum::<DVec3>()
                / w;
            assert!(
                (w - l.positions.len() as f64).abs() < 1e-3 * l.positions.len() as f64,
                "level {level}: mass {w}"
            );
            assert!(
                (c - centroid).abs().max_element() < 1e-4 * scale,
                "level {level}: centroid {c} vs {centroid}"
            );
        }
        let h = g.geometry.cell_size(level);
        for k in r {
            let v = g.geometry.vertex_position(level, g.vertex[k]);
            let d = (g.position[k] - v).abs().max_element();
            let rounding = 4.0 * f32::EPSILON * v.abs().max_element();
            assert!(
                d <= h * (1.0 + 1e-4) + rounding,
                "level {level}: light {d} from its vertex (h = {h})"
            );
            assert!(g.deviation[k].is_finite() && g.normal[k].length() <= 1.0 + 1e-4);
        }
    }
}

#[test]
fn invariants_hold_for_both_constructions_and_many_level_counts() {
    let l = synthetic(20_000, 3);
    for c in ALL {
        for levels in [
            LevelCount::Auto,
            LevelCount::Fixed(1),
            LevelCount::Fixed(4),
            LevelCount::Fixed(8),
        ] {
            check_invariants(&l, &build(&l, levels, c));
        }
    }
    // Far from the origin: local accumulation keeps the centroid and deviations accurate.
    let far = random_box(5000, 4, Vec3::new(3.0, 1.0, 2.0), Vec3::splat(1.0e4));
    for c in ALL {
        check_invariants(&far, &build(&far, LevelCount::Auto, c));
    }
}

/// The paper's level rule: |S_1| < N/2 with the chosen l_max, and not with one more level.
#[test]
fn automatic_level_count_follows_the_paper() {
    for n in [1000, 30_000] {
        let l = synthetic(n, 5);
        let g = build(&l, LevelCount::Auto, Construction::GatherFromS1);
        let lm = g.l_max();
        assert!(
            2 * g.level_range(1).len() < n,
            "|S1| = {}",
            g.level_range(1).len()
        );
        if lm < MAX_LEVELS {
            let finer = build(&l, LevelCount::Fixed(lm + 1), Construction::GatherFromS1);
            assert!(2 * finer.level_range(1).len() >= n);
        }
        assert_eq!(g.level_range(lm).len(), 8, "the top level is one cell");
    }
}

/// Both constructions build S_1 the same way (identical), and differ on coarser levels only by
/// the smoothing of gathering from S_1. Measured on 50k synthetic lights (auto levels, 8):
/// per level, the intensity moved between vertices, sum |I_gather - I_scatter| / sum I, is at
/// most about 0.05 (0.02 to 0.05 from S2 to S8); the bound is 0.1.
#[test]
fn gather_and_scatter_agree_on_s1_and_are_close_above() {
    let l = synthetic(50_000, 6);
    let g = build(&l, LevelCount::Auto, Construction::GatherFromS1);
    let s = build(&l, LevelCount::Auto, Construction::ScatterAll);
    assert_eq!(g.l_max(), s.l_max());
    let r1 = g.level_range(1);
    assert_eq!(r1, s.level_range(1));
    assert_eq!(g.position[r1.clone()], s.position[r1.clone()]);
    assert_eq!(g.intensity[r1.clone()], s.intensity[r1.clone()]);
    assert_eq!(g.deviation[r1.clone()], s.deviation[r1]);
    let total = sum_d(l.intensity.iter().copied()).element_sum();
    for level in 2..=g.l_max() {
        let map = |grid: &LightingGrid| {
            grid.level_range(level)
                .map(|k| (grid.vertex[k].to_array(), grid.intensity[k].as_dvec3()))
                .collect::<std::collections::BTreeMap<_, _>>()
        };
        let (mg, ms) = (map(&g), map(&s));
        let mut moved = 0.0;
        for (v, ig) in &mg {
            moved += (*ig - ms.get(v).copied().unwrap_or(DVec3::ZERO))
                .abs()
                .element_sum();
        }
        for (v, is) in &ms {
            if !mg.contains_key(v) {
                moved += is.abs().element_sum();
            }
        }
        let rel = moved / total;
        eprintln!("level {level}: relative intensity difference gather vs scatter {rel:.4}");
        assert!(rel < 0.1, "level {level}: {rel}");
    }
}

/// The restriction (each level from the one below through the (1/2, 1, 1/2)^3 stencil) is
/// exact: it gives the all-scatter hierarchy, to rounding, on every level (same vertices,
/// same grid lights within the tolerances of `assert_same`).
#[test]
fn restriction_equals_all_scatter() {
    for (l, levels) in [
        (synthetic(50_000, 7), LevelCount::Auto),
        (
            random_box(3000, 8, Vec3::new(3.0, 1.0, 2.0), Vec3::new(-5.0, 1.0, 0.0)),
            LevelCount::Fixed(5),
        ),
    ] {
        let r = build(&l, levels, Construction::Restrict);
        let s = build(&l, levels, Construction::ScatterAll);
        assert!(r.l_max() >= 5);
        assert_same(&r, &s);
    }
}

/// Two hierarchies are the same to rounding. A grid light's intensity may differ by 1e-5 of
/// itself plus 1e-6 of its level's brightest: a light that holds only a sliver of its
/// neighbours' intensity (trilinear weights near 0, computed as 1 - f near 1) carries their
/// rounding in absolute terms (n = 56, seed 382, 5 levels: 4e-8 on 0.0029, where 1e-5 of
/// itself allowed 3e-8).
fn assert_same(a: &LightingGrid, b: &LightingGrid) {
    assert_eq!(a.geometry, b.geometry);
    assert_eq!(a.level_start, b.level_start);
    assert_eq!(a.vertex, b.vertex);
    let h = a.geometry.h_top;
    let brightest: Vec<f32> = (1..=a.l_max())
        .map(|l| {
            a.intensity[a.level_range(l)]
                .iter()
                .map(|i| i.max_element())
                .fold(0.0, f32::max)
        })
        .collect();
    for k in 0..a.len() {
        assert!((a.position[k] - b.position[k]).abs().max_element() <= 1e-5 * h);
        let level = a.level_start.partition_point(|&s| s as usize <= k);
        let tol = 1e-5 * a.intensity[k].max_element().max(1e-6)
            + 1e-6
                * brightest
                    .get(level.saturating_sub(1))
                    .copied()
                    .unwrap_or(0.0);
        assert!((a.intensity[k] - b.intensity[k]).abs().max_element() <= tol);
        assert!((a.deviation[k] - b.deviation[k]).abs().max_element() <= 1e-3 * h);
        assert!((a.normal[k] - b.normal[k]).abs().max_element() <= 1e-5);
        assert!((a.mass[k] - b.mass[k]).abs() <= 1e-5 * a.mass[k].max(1.0));
    }
}

fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

proptest! {
    // A fixed seed: CI runs the same cases every time (a failure is a regression, not luck);
    // change the seed locally to explore.
    #![proptest_config(ProptestConfig {
        cases: 48,
        rng_seed: proptest::test_runner::RngSeed::Fixed(2019),
        ..ProptestConfig::default()
    })]
    /// The parallel builder equals the plain one-thread reference on random inputs, with 1 and
    /// 2 threads, for all three constructions; and 1 and 2 threads give bit-identical results.
    #[test]
    fn parallel_builder_matches_reference(
        n in 1usize..300,
        seed in 0u64..1000,
        levels in 0u32..6,
        flat in any::<bool>(),
    ) {
        let scale = if flat { Vec3::new(4.0, 0.0, 2.0) } else { Vec3::new(4.0, 1.0, 2.0) };
        let l = random_box(n, seed, scale, Vec3::new(-1.0, 2.0, 0.5));
        let lc = if levels == 0 { LevelCount::Auto } else { LevelCount::Fixed(levels) };
        for c in ALL {
            let one = in_pool(1, || build(&l, lc, c));
            let two = in_pool(2, || build(&l, lc, c));
            prop_assert_eq!(&one, &two);
            let reference = build_reference(&l.input(), one.geometry, c).unwrap();
            assert_same(&one, &reference);
            check_invariants(&l, &one);
        }
    }
}

/// One light on a flat box: the grid is a box 0.0025 wide around x = 2.49, so the S1 light's
/// distance to its vertex is h plus an ulp of the coordinates (CI run of session 11).
#[test]
fn one_light_on_a_tiny_grid_keeps_the_invariants() {
    let l = random_box(1, 868, Vec3::new(4.0, 0.0, 2.0), Vec3::new(-1.0, 2.0, 0.5));
    for c in ALL {
        let one = in_pool(1, || build(&l, LevelCount::Fixed(4), c));
        check_invariants(&l, &one);
    }
}

/// The case a random run of `parallel_builder_matches_reference` found (a tolerance relative to
/// a sliver of intensity alone; see `assert_same`), kept as a fixed test.
#[test]
fn a_light_holding_a_sliver_matches_the_reference() {
    let l = random_box(56, 382, Vec3::new(4.0, 1.0, 2.0), Vec3::new(-1.0, 2.0, 0.5));
    for c in ALL {
        let one = in_pool(1, || build(&l, LevelCount::Fixed(5), c));
        let reference = build_reference(&l.input(), one.geometry, c).unwrap();
        assert_same(&one, &reference);
    }
}

#[test]
fn edge_cases() {
    // One light: one level, its S1 lights sum to it.
    let one = Lights {
        positions: vec![Vec3::new(1.0, 2.0, 3.0)],
        intensity: vec![Vec3::ONE],
        normals: vec![Vec3::Y],
    };
    let g = build(&one, LevelCount::Auto, Construction::GatherFromS1);
    assert_eq!(g.l_max(), 1);
    check_invariants(&one, &g);
    // All lights at one point (zero-size box), with several levels forced.
    let point = Lights {
        positions: vec![Vec3::splat(-7.0); 100],
        intensity: vec![Vec3::new(1.0, 0.5, 0.25); 100],
        normals: vec![Vec3::Z; 100],
    };
    for levels in [LevelCount::Auto, LevelCount::Fixed(5)] {
        let g = build(&point, levels, Construction::GatherFromS1);
        check_invariants(&point, &g);
        assert!(
            g.position
                .iter()
                .all(|p| (*p - Vec3::splat(-7.0)).length() < 1e-3)
        );
    }
    // Lights on a plane (one flat axis).
    let plane = random_box(2000, 8, Vec3::new(5.0, 0.0, 3.0), Vec3::ZERO);
    for c in ALL {
        check_invariants(&plane, &build(&plane, LevelCount::Auto, c));
    }
    // Zero-intensity lights keep their share of nothing: sums still hold.
    let mut zero = random_box(500, 9, Vec3::ONE, Vec3::ZERO);
    for k in (0..500).step_by(3) {
        zero.intensity[k] = Vec3::ZERO;
    }
    for c in ALL {
        check_invariants(&zero, &build(&zero, LevelCount::Auto, c));
    }
    let all_zero = Lights {
        positions: vec![Vec3::ZERO, Vec3::ONE],
        intensity: vec![Vec3::ZERO; 2],
        normals: vec![Vec3::Y; 2],
    };
    assert!(build(&all_zero, LevelCount::Auto, Construction::GatherFromS1).is_empty());
    // Non-finite positions or intensities and negative intensities are clear errors.
    let mut bad = random_box(10, 1, Vec3::ONE, Vec3::ZERO);
    bad.positions[4].y = f32::NAN;
    let err = LightingGrid::build(&bad.input(), LevelCount::Auto, Construction::GatherFromS1)
        .unwrap_err();
    assert_eq!(err, GridError::InvalidLight { index: 4 });
    assert!(err.to_string().contains("light 4"));
    bad.positions[4].y = 0.0;
    bad.intensity[7].x = -1.0;
    assert!(LightingGrid::build(&bad.input(), LevelCount::Auto, Construction::ScatterAll).is_err());
    let empty = Lights {
        positions: vec![],
        intensity: vec![],
        normals: vec![],
    };
    assert_eq!(
        LightingGrid::build(&empty.input(), LevelCount::Auto, Construction::ScatterAll)
            .unwrap_err(),
        GridError::Empty
    );
}

/// 4 million lights build, and keep the invariants.
#[test]
fn four_million_lights() {
    let l = synthetic(4_000_000, 10);
    let g = build(&l, LevelCount::Auto, Construction::GatherFromS1);
    assert!(g.l_max() >= 8);
    check_invariants(&l, &g);
}

/// A builder reused across frames (different inputs, level counts and constructions) gives
/// exactly what a fresh build gives: no state leaks between builds.
#[test]
fn reused_builder_matches_fresh_builds() {
    use lgh_core::lighting_grid::GridBuilder;
    let a = synthetic(30_000, 11);
    let b = random_box(
        2_000,
        12,
        Vec3::new(2.0, 3.0, 1.0),
        Vec3::new(5.0, -3.0, 0.0),
    );
    let mut builder = GridBuilder::default();
    for (l, levels, c) in [
        (&a, LevelCount::Auto, Construction::GatherFromS1),
        (&b, LevelCount::Fixed(3), Construction::ScatterAll),
        (&a, LevelCount::Fixed(6), Construction::ScatterAll),
        (&b, LevelCount::Auto, Construction::GatherFromS1),
    ] {
        builder.build(&l.input(), levels, c).unwrap();
        assert_eq!(builder.grid().unwrap(), &build(l, levels, c));
    }
}

/// Large inputs go through the chunked parallel bucketing and the chunked coarse layers:
/// still the same hierarchy as the one-thread reference.
#[test]
fn large_inputs_match_the_reference() {
    let l = synthetic(150_000, 13);
    for c in ALL {
        let g = build(&l, LevelCount::Auto, c);
        let reference = build_reference(&l.input(), g.geometry, c).unwrap();
        assert_same(&g, &reference);
    }
}

/// The hierarchy does not depend on the units: lights in a box 1e-5 wide at the origin (a
/// tenth of a millimetre in metres) get the hierarchy of the same lights scaled to a box 1
/// wide, scaled (the same levels and lights per level, h_top in proportion). The top cell
/// was floored at 1e-3, 100 times the box, which wasted the finest levels.
#[test]
fn a_tiny_box_gets_the_hierarchy_of_a_large_one() {
    let large = random_box(3000, 21, Vec3::ONE, Vec3::splat(-0.5));
    let s = 1e-5;
    let tiny = Lights {
        positions: large.positions.iter().map(|&p| p * s).collect(),
        intensity: large.intensity.clone(),
        normals: large.normals.clone(),
    };
    let (a, b) = (
        build(&large, LevelCount::Auto, Construction::Restrict),
        build(&tiny, LevelCount::Auto, Construction::Restrict),
    );
    assert_eq!(a.l_max(), b.l_max());
    assert_eq!(a.level_start, b.level_start);
    let ratio = b.geometry.h_top / a.geometry.h_top;
    assert!(
        (ratio / s - 1.0).abs() < 1e-4,
        "h_top {} vs {}",
        b.geometry.h_top,
        a.geometry.h_top
    );
    check_invariants(&tiny, &b);
}
