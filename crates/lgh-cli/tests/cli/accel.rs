//! `--accel`: the ray tracer chosen on the command line of `render`, `view` and `bench rays`.

use super::{assert_error, lgh, render_stats, temp_dir};

/// The default is Embree in a build with the `embree` feature, else obvhs; the statistics
/// say which one traced, and how many triangles have alpha cut-outs.
#[test]
fn render_reports_its_ray_tracer_and_obvhs_is_always_there() {
    let d = temp_dir("accel");
    let default = if cfg!(feature = "embree") {
        "embree"
    } else {
        "obvhs"
    };
    let stats = render_stats(&d, &[]);
    assert_eq!(stats["accel"], default);
    assert_eq!(stats["device"], "cpu");
    assert_eq!(stats["cut_out_triangles"], 0);
    // The lattice scene's two screens (6 triangles) are cut by their texture's alpha: the
    // statistics and the summary line say so.
    let lattice = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenes/test/lattice.toml"
    );
    assert_eq!(render_stats(&d, &[lattice])["cut_out_triangles"], 6);
    let png = d.join("lattice.png");
    let out = lgh(&[
        "render",
        lattice,
        "--size",
        "32x18",
        "--vpls",
        "200",
        "--out",
        png.to_str().expect("path"),
    ]);
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(
        said.contains("12 triangles (6 with alpha cut-outs)"),
        "{said}"
    );
    assert_eq!(render_stats(&d, &["--accel", "obvhs"])["accel"], "obvhs");
    let out = lgh(&["bench", "rays", "--rays", "2000", "--rounds", "1", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let names: Vec<&str> = v["backends"]
        .as_array()
        .expect("backends")
        .iter()
        .filter_map(|b| b["accel"].as_str())
        .collect();
    let want: &[&str] = if cfg!(feature = "embree") {
        &["embree", "obvhs"]
    } else {
        &["obvhs"]
    };
    assert_eq!(names, want);
    for b in v["backends"].as_array().expect("backends") {
        assert!(
            b["shadow_rays_per_s"].as_f64().is_some_and(|r| r > 0.0),
            "{b}"
        );
    }
}

/// Without the feature, asking for Embree is one clear line and exit code 2, for every
/// command that takes the flag; with it, each command runs on Embree.
#[test]
fn embree_is_refused_clearly_where_not_built_and_used_where_built() {
    let d = temp_dir("accel-embree");
    let (shot, png) = (d.join("v.png"), d.join("r.png"));
    let (shot, png) = (shot.to_str().expect("path"), png.to_str().expect("path"));
    let runs: [Vec<&str>; 3] = [
        vec![
            "render", "--size", "32x18", "--vpls", "200", "--quiet", "--accel", "embree", "--out",
            png,
        ],
        vec![
            "view",
            "--headless",
            "--frames",
            "2",
            "--size",
            "32x18",
            "--vpls",
            "200",
            "--accel",
            "embree",
            "--screenshot",
            shot,
        ],
        vec![
            "bench", "rays", "--rays", "2000", "--rounds", "1", "--accel", "embree",
        ],
    ];
    for args in &runs {
        let out = lgh(args);
        if cfg!(feature = "embree") {
            assert!(
                out.status.success(),
                "{args:?}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        } else {
            assert_error(&out, &["no Embree", "--features embree"]);
        }
    }
    if cfg!(feature = "embree") {
        assert_eq!(render_stats(&d, &["--accel", "embree"])["accel"], "embree");
    }
    assert_error(&lgh(&["render", "--accel", "optix"]), &["optix"]);
}
