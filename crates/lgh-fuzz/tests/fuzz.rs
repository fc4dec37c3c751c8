//! The deterministic part of the fuzzing: a fixed run of every loader in the test suite.
//! The long run is `cargo run --release -p lgh-fuzz -- --cases 1000000`.

/// 4,000 cases (500 per target) of seed 1: no panic, no non-finite image, no slow case; and
/// the run is not vacuous: some inputs of every target load and some are refused.
#[test]
fn a_fixed_run_of_every_loader_finds_nothing() {
    let dir = std::env::temp_dir().join(format!("lgh-fuzz-test-{}", std::process::id()));
    let cases = 500 * lgh_fuzz::TARGETS.len() as u64;
    let report = lgh_fuzz::run(1, 0, cases, &dir, &|_| {});
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(report.cases, cases);
    for f in &report.findings {
        eprintln!("case {} ({:?}): {}", f.case, f.target, f.what);
    }
    assert!(
        report.findings.is_empty(),
        "{} findings",
        report.findings.len()
    );
    assert!(report.loaded > cases / 10, "{report:?}");
    assert!(report.refused > cases / 10, "{report:?}");
}

/// Mutated inputs depend only on the seed and case number, so a finding can be replayed.
#[test]
fn cases_are_reproducible_and_differ_from_their_seed() {
    for case in 0..64 {
        let (t1, a) = lgh_fuzz::case_input(5, case);
        let (t2, b) = lgh_fuzz::case_input(5, case);
        assert_eq!((t1, &a), (t2, &b));
    }
    let (_, x) = lgh_fuzz::case_input(5, 0);
    let (_, y) = lgh_fuzz::case_input(6, 0);
    assert_ne!(x, y);
}

/// Every seed file loads as it is: mutations start from valid inputs.
#[test]
fn the_seeds_load_and_render() {
    let dir = std::env::temp_dir().join(format!("lgh-fuzz-seeds-{}", std::process::id()));
    lgh_fuzz::write_seeds(&dir).unwrap();
    for name in ["scene.gltf", "scene.glb", "scene.obj", "scene.toml"] {
        let scene = lgh_scene::load(&dir.join(name)).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            scene.report.warnings.is_empty(),
            "{name}: {:?}",
            scene.report.warnings
        );
        assert!(scene.mesh.len() >= 4, "{name}");
    }
    assert!(lgh_render::Image::load(&dir.join("image.exr")).is_ok());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The hand-made hostile classes (special files, bombs, instancing): every case is refused or
/// loads, none panics, hangs or is slow; and the bombs and the instancing bomb are refused,
/// not loaded (a deep chain of 20 000 one-triangle nodes is a valid scene and loads).
#[test]
fn hostile_cases_by_class_are_refused_in_time() {
    let dir = std::env::temp_dir().join(format!("lgh-fuzz-hostile-{}", std::process::id()));
    let outcomes = lgh_fuzz::hostile::run(&dir);
    let mut bad = Vec::new();
    for o in &outcomes {
        eprintln!("{} ({:?}, {:.0} ms): {:?}", o.name, o.class, o.ms, o.result);
        // An unreadable texture or image is a warning: the material colour stands in.
        let must_refuse =
            o.name != "chain" && !o.name.starts_with("image:") && !o.name.starts_with("texture:");
        match &o.result {
            Err(e) => bad.push(format!("{}: {e}", o.name)),
            Ok(m) if must_refuse && m == "loaded" => bad.push(format!("{}: loaded", o.name)),
            Ok(_) => {}
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(outcomes.len() >= 20);
    assert!(bad.is_empty(), "{bad:?}");
}
