//! Render farms (issue 37): tiles of a frame merged equal the whole frame bit for bit, chunks
//! of a sequence equal one long run, bad pieces are refused, and the Open Job Description
//! template runs through `openjd run`.

use std::path::{Path, PathBuf};

use super::{assert_error, assert_ok, lgh, s, temp_dir};

/// `lgh diff A B --json`'s max_abs and flip.
fn diff(a: &Path, b: &Path) -> (f64, f64) {
    let out = lgh(&["diff", s(a), s(b), "--json"]);
    assert_ok(&out);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    (v["max_abs"].as_f64().unwrap(), v["flip"].as_f64().unwrap())
}

/// The sequence both chunk tests render: 8 frames of a moving light, small.
const SEQUENCE: [&str; 6] = [
    "builtin:cornell-moving-light",
    "--size",
    "96x54",
    "--vpls",
    "1000",
    "--quiet",
];

/// Renders [`SEQUENCE`]'s frames 0..8 in one run into `d` (named `name_F.exr`), and checks
/// every frame `ours(F)` against it: bit for bit without TAA, within FLIP 0.01 with it.
fn assert_matches_one_run(d: &Path, name: &str, taa: bool, ours: impl Fn(u32) -> PathBuf) {
    let long = d.join(format!("{name}_#.exr"));
    let t: &[&str] = if taa { &["--taa"] } else { &[] };
    assert_ok(&lgh(&[
        &["render"][..],
        &SEQUENCE,
        t,
        &["--frames", "0..8", "-o", s(&long)],
    ]
    .concat()));
    for f in 0..8 {
        let (max_abs, flip) = diff(&ours(f), &d.join(format!("{name}_{f}.exr")));
        if taa {
            assert!(flip <= 0.01, "frame {f}: FLIP {flip}");
        } else {
            assert_eq!(max_abs, 0.0, "frame {f}");
        }
    }
}

fn test_scene(name: &str) -> String {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes/test")
        .join(name);
    p.to_string_lossy().into_owned()
}

/// Renders the whole frame and `n` tiles, merges them, returns the merged frame's max_abs
/// against the whole.
fn tiles_against_whole(d: &Path, scene: &str, method: &str, n: u32, common: &[&str]) -> f64 {
    let whole = d.join("whole.exr");
    let base = [&["render", scene, "--method", method][..], common].concat();
    assert_ok(&lgh(&[&base[..], &["-o", s(&whole)]].concat()));
    let pieces: Vec<PathBuf> = (1..=n).map(|i| d.join(format!("t{i}.exr"))).collect();
    for (i, p) in pieces.iter().enumerate() {
        let tile = format!("{}/{n}", i + 1);
        assert_ok(&lgh(&[&base[..], &["--tile", &tile, "-o", s(p)]].concat()));
    }
    let merged = d.join("merged.exr");
    let mut args = vec!["merge"];
    args.extend(pieces.iter().map(|p| s(p)));
    args.extend(["-o", s(&merged)]);
    assert_ok(&lgh(&args));
    diff(&merged, &whole).0
}

#[test]
fn tiles_merge_into_the_whole_frame_bit_for_bit() {
    let d = temp_dir("farm-tiles");
    let two_rooms = test_scene("two-rooms.toml");
    for scene in ["builtin:cornell", two_rooms.as_str()] {
        for (method, common) in [
            (
                "lgh",
                &["--size", "320x180", "--vpls", "2000", "--quiet"][..],
            ),
            ("slc", &["--size", "320x180", "--vpls", "2000", "--quiet"]),
            ("brute", &["--size", "160x90", "--vpls", "200", "--quiet"]),
        ] {
            for n in [4, 9] {
                let max_abs = tiles_against_whole(&d, scene, method, n, common);
                assert_eq!(max_abs, 0.0, "{scene} {method} {n} tiles");
            }
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn bad_pieces_are_refused_by_name() {
    let d = temp_dir("farm-bad");
    let common = ["render", "--size", "64x36", "--vpls", "100", "--quiet"];
    let piece = |name: &str, tile: &str, extra: &[&str]| {
        let p = d.join(name);
        assert_ok(&lgh(
            &[&common[..], &["--tile", tile, "-o", s(&p)], extra].concat()
        ));
        p
    };
    let t: Vec<PathBuf> = (1..=4)
        .map(|i| piece(&format!("t{i}.exr"), &format!("{i}/4"), &[]))
        .collect();
    let out = d.join("f.exr");
    let merge = |pieces: &[&PathBuf]| {
        let mut args = vec!["merge".to_string()];
        args.extend(pieces.iter().map(|p| s(p).to_string()));
        args.extend(["-o".into(), s(&out).into()]);
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        lgh(&refs)
    };
    assert_ok(&merge(&[&t[0], &t[1], &t[2], &t[3]]));
    // Missing, overlapping, of another frame or other settings.
    assert_error(&merge(&[&t[0], &t[1], &t[2]]), &["missing"]);
    assert_error(
        &merge(&[&t[0], &t[1], &t[2], &t[3], &t[2]]),
        &["t3.exr", "overlaps"],
    );
    let seed = piece("seed.exr", "4/4", &["--seed", "9"]);
    assert_error(
        &merge(&[&t[0], &t[1], &t[2], &seed]),
        &["seed.exr", "settings"],
    );
    let size = d.join("size.exr");
    let r = lgh(&[
        "render",
        "--size",
        "64x38",
        "--vpls",
        "100",
        "--quiet",
        "--tile",
        "4/4",
        "-o",
        s(&size),
    ]);
    assert_ok(&r);
    assert_error(
        &merge(&[&t[0], &t[1], &t[2], &size]),
        &["size.exr", "frame size"],
    );
    let frames = d.join("seq_#.exr");
    assert_ok(&lgh(&[
        &common[..],
        &["--tile", "4/4", "--frames", "1..2", "-o", s(&frames)],
    ]
    .concat()));
    let other = d.join("seq_1.exr");
    assert_error(
        &merge(&[&t[0], &t[1], &t[2], &other]),
        &["seq_1.exr", "frame number"],
    );
    // A piece without its side file, and a piece that is not .exr.
    std::fs::remove_file(d.join("t2.exr.json")).unwrap();
    assert_error(
        &merge(&[&t[0], &t[1], &t[2], &t[3]]),
        &["t2.exr", "side file"],
    );
    assert_error(
        &lgh(&[&common[..], &["--tile", "1/4", "-o", s(&d.join("p.png"))]].concat()),
        &["p.png", ".exr"],
    );
    assert_error(&lgh(&[&common[..], &["--tile", "5/4"]].concat()), &["5/4"]);
    let _ = std::fs::remove_dir_all(&d);
}

/// Chunks of a sequence: without TAA each frame equals the long run's bit for bit; with TAA
/// and a warm-up of 4 frames, within FLIP 0.01.
#[test]
fn chunks_with_warm_up_match_one_long_run() {
    let d = temp_dir("farm-chunks");
    for taa in [false, true] {
        let t: &[&str] = if taa {
            &["--taa", "--warmup", "4"]
        } else {
            &[]
        };
        let chunk = d.join("chunk_#.exr");
        for start in [0, 2, 4, 6] {
            let frames = format!("{start}..{}", start + 2);
            let args = [
                &["render"][..],
                &SEQUENCE,
                t,
                &["--frames", &frames, "-o", s(&chunk)],
            ];
            assert_ok(&lgh(&args.concat()));
        }
        assert_matches_one_run(&d, "long", taa, |f| d.join(format!("chunk_{f}.exr")));
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// farm/openjd/lgh-render.yaml through `openjd run` (PyPI's openjd-cli, which CI installs):
/// builtin:cornell-moving-light, 8 frames in chunks of 2 and 2 tiles, merged, equals `lgh
/// render --frames 0..8` bit for bit without TAA and within FLIP 0.01 with it.
#[test]
#[cfg_attr(
    not(openjd),
    ignore = "needs openjd-cli (LGH_OPENJD or openjd on PATH)"
)]
fn the_openjd_template_runs_and_matches_one_render() {
    let openjd = option_env!("LGH_OPENJD_BIN").unwrap_or("openjd");
    let template =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../farm/openjd/lgh-render.yaml");
    let d = temp_dir("farm-openjd");
    for taa in ["off", "on"] {
        let out_dir = d.join(format!("job-{taa}"));
        let run = std::process::Command::new(openjd)
            .arg("run")
            .arg(&template)
            .args(["--step", "Merge", "--run-dependencies"])
            .args(["-p", &format!("Lgh={}", env!("CARGO_BIN_EXE_lgh"))])
            .args(["-p", &format!("OutputDir={}", out_dir.display())])
            .args([
                "-p",
                "Size=96x54",
                "-p",
                "Vpls=1000",
                "-p",
                "FirstFrame=0",
                "-p",
                "LastFrame=7",
            ])
            .args([
                "-p",
                "ChunkSize=2",
                "-p",
                "Tiles=2",
                "-p",
                &format!("Taa={taa}"),
            ])
            .output()
            .unwrap();
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stdout)
        );
        let name = format!("long-{taa}");
        assert_matches_one_run(&d, &name, taa == "on", |f| {
            out_dir.join(format!("frame_{f:04}.exr"))
        });
    }
    let _ = std::fs::remove_dir_all(&d);
}
