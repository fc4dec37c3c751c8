//! The command line as a user meets it: successful renders and every kind of bad input.

mod accel;
mod bombs;
mod equal_time;
mod farm;
mod gpu;
mod hardening;
mod outputs;
mod view;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn lgh(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lgh"))
        .args(args)
        .env_remove("LGH_SCENES")
        .output()
        .unwrap()
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lgh-cli-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Runs `lgh render` with `args` at 32x18 and 200 VPLs, its image and statistics written in
/// `d`; asserts success and returns the statistics.
fn render_stats(d: &Path, args: &[&str]) -> serde_json::Value {
    let (out_file, stats) = (d.join("out.exr"), d.join("stats.json"));
    let base = ["render", "--size", "32x18", "--vpls", "200", "--quiet"];
    let out = lgh(&[
        &base[..],
        &["--out", s(&out_file), "--stats", s(&stats)],
        args,
    ]
    .concat());
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap()
}

/// Succeeds (its stderr is the message where it does not).
fn assert_ok(out: &Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Fails with exit code 2, one line on stderr that contains every `needles`, and no output.
fn assert_error(out: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "expected '{n}' in: {err}");
    }
}

#[test]
fn renders_the_default_scene_to_png_and_exr_with_stats_and_diffs_them() {
    let d = temp_dir("ok");
    let png = d.join("c.png");
    let exr = d.join("c.exr");
    let stats = d.join("c.json");
    let common = ["--size", "40x24", "--vpls", "200", "--quiet"];
    let out = lgh(&[
        &["render", "--out", s(&png), "--stats", s(&stats)][..],
        &common,
    ]
    .concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = lgh(&[&["render", "--out", s(&exr)][..], &common].concat());
    assert!(out.status.success());
    assert!(png.is_file() && exr.is_file());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    for key in [
        "scene", "width", "height", "vpls", "method", "seed", "threads",
    ] {
        assert!(json.get(key).is_some(), "missing {key}");
    }
    for key in [
        "bvh_build",
        "gbuffer",
        "vpl_generation",
        "direct",
        "indirect",
        "total",
    ] {
        assert!(json["timings_ms"][key].is_f64(), "missing timings_ms.{key}");
    }
    let out = lgh(&["diff", s(&exr), s(&exr), "--json"]);
    assert!(out.status.success());
    let m: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(m["rmse"], 0.0);
    assert_eq!(m["rel_bias"], 0.0);
    assert_eq!(m["flip"], 0.0);
    // PNG against EXR of the same render: same picture after tone mapping, FLIP near 0.
    let out = lgh(&["diff", s(&png), s(&exr), "--json"]);
    assert!(out.status.success());
    let m: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(m["flip"].as_f64().unwrap() < 0.01, "{m}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn bad_inputs_give_one_clear_error_and_exit_code_2() {
    let d = temp_dir("bad");
    let out_png = d.join("o.png");
    let o = s(&out_png);
    let w = |name: &str, text: &str| {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    // Missing scene file.
    assert_error(
        &lgh(&["render", "/no/such/scene.obj", "--out", o]),
        &["/no/such/scene.obj", "not found"],
    );
    // Malformed TOML.
    let bad_toml = w("bad.toml", "mesh = [1, 2\n");
    assert_error(
        &lgh(&["render", s(&bad_toml), "--out", o]),
        &["bad.toml", "invalid scene file"],
    );
    // Unknown key in a scene file.
    let unknown = w("unknown.toml", "mesh = \"x.obj\"\nfoo = 1\n");
    assert_error(
        &lgh(&["render", s(&unknown), "--out", o]),
        &["unknown.toml", "foo"],
    );
    // A scene file whose mesh does not exist.
    let missing_mesh = w("missing_mesh.toml", "mesh = \"nothing.obj\"\n");
    assert_error(
        &lgh(&["render", s(&missing_mesh), "--out", o]),
        &["nothing.obj", "not found"],
    );
    // $LGH_SCENES without the variable.
    let env_mesh = w("env.toml", "mesh = \"$LGH_SCENES/sponza/sponza.obj\"\n");
    assert_error(
        &lgh(&["render", s(&env_mesh), "--out", o]),
        &["env.toml", "LGH_SCENES"],
    );
    // Malformed OBJ.
    let bad_obj = w("bad.obj", "v 0 0 0\nv 1 0 0\nf 1 2 7\n");
    assert_error(&lgh(&["render", s(&bad_obj), "--out", o]), &["bad.obj"]);
    // Malformed glTF.
    let bad_gltf = w("bad.gltf", "{ not json");
    assert_error(
        &lgh(&["render", s(&bad_gltf), "--out", o]),
        &["bad.gltf", "glTF"],
    );
    // No lights in a scene file (a mesh file alone gets a light at the camera).
    w("dark.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let dark = w("dark.toml", "mesh = \"dark.obj\"\n");
    assert_error(
        &lgh(&["render", s(&dark), "--out", o]),
        &["dark.toml", "no lights"],
    );
    // No triangles.
    let empty = w("empty.obj", "# nothing\n");
    assert_error(
        &lgh(&["render", s(&empty), "--out", o]),
        &["empty.obj", "no triangles"],
    );
    // Only degenerate triangles.
    let degenerate = w("degenerate.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    assert_error(
        &lgh(&["render", s(&degenerate), "--out", o]),
        &["degenerate.obj", "zero area"],
    );
    // Non-finite vertex.
    let nan = w("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n");
    assert_error(&lgh(&["render", s(&nan), "--out", o]), &["nan.obj"]);
    // Unknown flag, bad size, zero size.
    assert_error(&lgh(&["render", "--frobnicate"]), &["--frobnicate"]);
    assert_error(&lgh(&["render", "--size", "0x10", "--out", o]), &["0x10"]);
    assert_error(&lgh(&["render", "--size", "big", "--out", o]), &["big"]);
    // Output in a missing folder, or with an unknown extension.
    let deep = d.join("missing/dir/o.png");
    assert_error(&lgh(&["render", "--out", s(&deep)]), &["does not exist"]);
    assert_error(
        &lgh(&["render", "--out", s(&d.join("o.jpg"))]),
        &["o.jpg", "extension"],
    );
    // diff of missing files and of images of different sizes.
    assert_error(
        &lgh(&["diff", "/no/a.exr", "/no/b.exr"]),
        &["/no/a.exr", "not found"],
    );
    // Nothing was written by any failed command.
    assert!(!out_png.exists());
    assert!(!deep.exists());
    let leftovers: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains("partial"))
        .collect();
    assert!(leftovers.is_empty());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn diff_rejects_images_of_different_sizes() {
    let d = temp_dir("sizes");
    let a = d.join("a.exr");
    let b = d.join("b.exr");
    for (p, size) in [(&a, "20x10"), (&b, "10x10")] {
        let out = lgh(&[
            "render",
            "--size",
            size,
            "--vpls",
            "50",
            "--out",
            s(p),
            "-q",
        ]);
        assert!(out.status.success());
    }
    assert_error(&lgh(&["diff", s(&a), s(&b)]), &["differ in size"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn help_explains_every_render_flag() {
    let out = lgh(&["render", "--help"]);
    let text = String::from_utf8_lossy(&out.stdout);
    for flag in [
        "--method",
        "--vpls",
        "--bounces",
        "--size",
        "--seed",
        "--out",
        "--component",
        "--stats",
        "--accumulate",
        "--direct",
        "--grid-jitter",
    ] {
        assert!(text.contains(flag), "{flag} missing from --help");
    }
}

#[test]
fn bench_build_reports_the_paper_table_as_json() {
    let out = lgh(&[
        "bench", "build", "--lights", "500,2000", "--runs", "1", "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let runs = v["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 6, "2 light counts x 3 variants");
    for r in runs {
        for key in [
            "lights",
            "variant",
            "levels",
            "lights_per_level",
            "steps_ms",
            "total_ms",
        ] {
            assert!(r.get(key).is_some(), "missing {key}");
        }
        assert!(["gather", "scatter", "restrict"].contains(&r["variant"].as_str().unwrap()));
        assert!(r["steps_ms"]["S1"].is_f64() && r["steps_ms"]["merge"].is_f64());
        let per_level = r["lights_per_level"].as_array().unwrap();
        assert_eq!(per_level.len() as u64, r["levels"].as_u64().unwrap());
    }
    assert_error(
        &lgh(&["bench", "build", "--levels", "11"]),
        &["--levels", "11"],
    );
    assert_error(&lgh(&["bench", "build", "--lights", "0"]), &["--lights"]);
}

#[test]
fn lgh_render_writes_stats_and_heatmap_and_bench_render_reports_tables() {
    let d = temp_dir("lgh");
    let (png, heat, stats) = (d.join("l.png"), d.join("h.png"), d.join("s.json"));
    let out = lgh(&[
        "render",
        "--method",
        "lgh",
        "--size",
        "48x32",
        "--vpls",
        "2000",
        "--out",
        s(&png),
        "--heatmap",
        s(&heat),
        "--stats",
        s(&stats),
        "-q",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(png.is_file() && heat.is_file());
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    for key in ["grid_lights", "levels", "avg_overdraw", "shadow_rays"] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    for key in [
        "lgh_build",
        "lighting",
        "shadow_rays",
        "shadow_filter",
        "composite",
    ] {
        assert!(v["timings_ms"][key].is_f64(), "missing timings_ms.{key}");
    }
    let out = lgh(&[
        "bench",
        "render",
        "--vpls",
        "500",
        "--size",
        "32x24",
        "--interleave",
        "1,4",
        "--runs",
        "2",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let b: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let row = &b["rows"][0];
    for k in [
        "shadow_samples_0",
        "shadow_samples_1",
        "shadow_samples_4",
        "shadow_samples_4_interleave_4",
    ] {
        assert!(row["runs"][k]["render_ms"].is_f64(), "missing {k}");
    }
    assert!(
        row["runs"]["shadow_samples_4_interleave_4"]["interleave_blur_ms"].as_f64() > Some(0.0)
    );
    assert_error(
        &lgh(&["bench", "render", "--interleave", "0"]),
        &["--interleave"],
    );
    assert_error(&lgh(&["bench", "render", "--runs", "0"]), &["--runs"]);
    assert_error(
        &lgh(&["render", "--method", "lgh", "--alpha=-1"]),
        &["--alpha"],
    );
    assert_error(
        &lgh(&["render", "--method", "lgh", "--shadow-samples", "99"]),
        &["--shadow-samples"],
    );
    assert_error(
        &lgh(&["render", "--method", "lgh", "--start-level", "3"]),
        &["--start-level"],
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn bench_temporal_reports_flicker_with_and_without_the_filter() {
    let out = lgh(&[
        "bench", "temporal", "--frames", "3", "--size", "32x18", "--vpls", "300", "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let without = v["flicker_without_taa"].as_f64().unwrap();
    let with = v["flicker_with_taa"].as_f64().unwrap();
    assert!(without > 0.0 && with > 0.0);
    let reduction = v["reduction_with_taa"].as_f64().unwrap();
    assert!((reduction - without / with).abs() < 1e-9 * reduction);
    assert!(v["reduction_with_taa_indirect"].as_f64().unwrap() > 0.0);
}

/// `render --accumulate` reports its frames; `bench quality` measures every series against
/// the brute force, the accumulation curve, and writes the plot.
#[test]
fn accumulate_and_bench_quality() {
    let d = temp_dir("quality");
    let accumulate = |extra: &[&str]| render_stats(&d, extra);
    let json = accumulate(&["--accumulate", "3"]);
    assert_eq!(json["accumulated_frames"], 3);
    // Frames of an accumulation take 16 shadow samples, unless --shadow-samples is given.
    assert_eq!(json["shadow_samples"], 16);
    for k in ["0", "2"] {
        let json = accumulate(&["--accumulate", "2", "--shadow-samples", k]);
        assert_eq!(json["shadow_samples"].to_string(), k);
    }
    assert_error(
        &lgh(&[
            "render",
            "--accumulate",
            "2",
            "--frames",
            "0..2",
            "--out",
            "f_####.png",
        ]),
        &["--accumulate", "--frames"],
    );
    let plot = d.join("q.png");
    let out = lgh(&[
        "bench",
        "quality",
        "builtin:cornell",
        "--size",
        "32x18",
        "--vpls",
        "300",
        "--accumulate",
        "1,2",
        "--accumulate-size",
        "24x16",
        "--accumulate-vpls",
        "200",
        "--plot",
        s(&plot),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let points = v["points"].as_array().unwrap();
    for series in [
        "lgh",
        "lgh 1x1",
        "lgh paper",
        "lgh paper alpha 2",
        "lgh paper 4x4",
        "slc",
        "slc-clamped",
        "lgh --accumulate",
    ] {
        assert!(
            points
                .iter()
                .any(|p| p["series"] == series && p["flip"].as_f64().unwrap() > 0.0),
            "{series}"
        );
    }
    assert!(std::fs::metadata(&plot).unwrap().len() > 1000);
}

/// Inputs that used to crash or hang: a glTF primitive naming an accessor that does not
/// exist (a panic inside the glTF crate), a node that is its own child (an endless loop), a
/// spot light whose inner angle exceeds its outer one, absurd thread and VPL counts.
#[test]
fn malformed_inputs_that_used_to_crash_are_refused() {
    let d = temp_dir("hard");
    let out_png = d.join("o.png");
    let o = s(&out_png);
    let w = |name: &str, text: &str| {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let accessor = w(
        "accessor.gltf",
        r#"{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":7}}]}]}"#,
    );
    assert_error(
        &lgh(&["render", s(&accessor), "--out", o]),
        &["accessor.gltf"],
    );
    let cycle = w(
        "cycle.gltf",
        r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"children":[1]},{"children":[0]}]}"#,
    );
    assert_error(
        &lgh(&["render", s(&cycle), "--out", o]),
        &["cycle.gltf", "node"],
    );
    w("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n");
    let spot = w(
        "spot.toml",
        "mesh = \"tri.obj\"\n[[lights]]\ntype = \"spot\"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\nintensity = [1, 1, 1]\ninner_angle = 40.0\nouter_angle = 30.0\n",
    );
    assert_error(
        &lgh(&["render", s(&spot), "--out", o]),
        &["spot.toml", "inner_angle <= outer_angle"],
    );
    assert_error(
        &lgh(&["render", "--threads", "10000", "--out", o]),
        &["--threads 10000"],
    );
    assert_error(
        &lgh(&["render", "--vpls", "100000000", "--out", o]),
        &["--vpls 100000000"],
    );
}

/// `--normal-bins` (on by default) is switched off with `=false`, and alone before the scene
/// it takes no value, so the scene stays the scene.
#[test]
fn normal_bins_take_an_optional_value() {
    let d = temp_dir("bins");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/test/two-rooms.toml");
    let bins = |args: &[&str]| render_stats(&d, args);
    let on = bins(&["--normal-bins", s(&scene)]);
    assert_eq!(on["settings"]["lgh"]["normal_bins"], true);
    assert!(on["scene"].as_str().unwrap().contains("two-rooms"), "{on}");
    assert_eq!(bins(&[])["settings"]["lgh"]["normal_bins"], true);
    let off = bins(&["--normal-bins=false"]);
    assert_eq!(off["settings"]["lgh"]["normal_bins"], false);
    assert_error(
        &lgh(&["render", "--normal-bins=maybe"]),
        &["--normal-bins", "maybe"],
    );
}

/// `bench quality --accumulate ""` runs without the curve (its help says so), a bad count is
/// refused with the range, and the summary names the defaults actually used.
#[test]
fn bench_quality_takes_an_empty_curve_and_names_its_defaults() {
    let d = temp_dir("quality-empty");
    let plot = d.join("q.png");
    let base = [
        "bench",
        "quality",
        "builtin:cornell",
        "--size",
        "32x18",
        "--vpls",
        "300",
        "--plot",
    ];
    let out = lgh(&[&base[..], &[s(&plot), "--accumulate", ""]].concat());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let k = lgh_render::methods::lgh::DEFAULT_SHADOW_SAMPLES;
    assert!(text.contains(&format!("lgh k={k},")), "{text}");
    assert!(
        !text.contains("lgh --accumulate"),
        "no curve was asked for: {text}"
    );
    assert_error(
        &lgh(&[&base[..], &[s(&plot), "--accumulate", "1,0"]].concat()),
        &["\"0\"", "1 to 65536"],
    );
}
