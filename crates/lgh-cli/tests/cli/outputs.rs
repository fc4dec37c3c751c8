//! Issue 38, outputs: what `-o`, `--stats`, `--screenshot` and the maps may replace, when
//! their paths are checked, and what two runs on one path leave. Each test failed before its
//! fix.

use super::{assert_error, lgh, s, temp_dir};

const SMALL: [&str; 5] = ["--size", "16x9", "--vpls", "50", "--quiet"];

fn render(args: &[&str]) -> std::process::Output {
    lgh(&[&["render"][..], &SMALL, args].concat())
}

#[test]
fn stats_never_replace_a_link_or_a_device() {
    let d = temp_dir("out-link");
    let target = d.join("target.json");
    std::fs::write(&target, "{}").unwrap();
    let link = d.join("link.json");
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let o = d.join("o.png");
    let r = render(&["-o", s(&o), "--stats", s(&link)]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert!(
        std::fs::read_to_string(&target)
            .unwrap()
            .contains("\"method\"")
    );
    // A character device is written through, and stays a device.
    let r = render(&["-o", s(&o), "--stats", "/dev/null"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    use std::os::unix::fs::FileTypeExt;
    assert!(
        std::fs::metadata("/dev/null")
            .unwrap()
            .file_type()
            .is_char_device()
    );
    // /dev/stdout into a pipe (a link, through /proc, to a pipe with no path): written
    // through.
    let r = render(&["-o", s(&o), "--stats", "/dev/stdout"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(String::from_utf8_lossy(&r.stdout).contains("\"scene\""));
    // A folder is refused by name, before the work.
    assert_error(&render(&["-o", s(&o), "--stats", s(&d)]), &["is a folder"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn outputs_are_checked_before_the_work_and_never_share_a_file() {
    let d = temp_dir("out-early");
    let x = d.join("x.png");
    // One file for the image and the statistics: refused, and nothing is written.
    let r = render(&["-o", s(&x), "--stats", s(&x)]);
    assert_error(&r, &["-o and --stats name one file"]);
    assert!(!x.exists());
    let r = render(&["-o", s(&x), "--heatmap", s(&d.join(".").join("x.png"))]);
    assert_error(&r, &["-o and --heatmap name one file"]);
    // A missing folder of --stats, an output that is a folder: refused before rendering
    // (a million VPLs would take seconds first).
    let many = ["--vpls", "1000000"];
    let r = lgh(&[
        &["render", "-o", s(&x), "--stats", "/nonexistent/s.json"][..],
        &many,
    ]
    .concat());
    assert_error(&r, &["/nonexistent/s.json", "does not exist"]);
    let folder = d.join("f.png");
    std::fs::create_dir_all(&folder).unwrap();
    assert_error(
        &lgh(&[&["render", "-o", s(&folder)][..], &many].concat()),
        &["is a folder"],
    );
    // The viewer's screenshot and statistics too.
    let v = |extra: &[&str]| {
        lgh(&[
            &["view", "--headless", "--frames", "1", "--size", "16x9"][..],
            extra,
        ]
        .concat())
    };
    assert_error(
        &v(&["--screenshot", s(&x), "--stats", s(&x)]),
        &["--screenshot and --stats name one file"],
    );
    assert_error(
        &v(&["--screenshot", "/nonexistent/x.png"]),
        &["does not exist"],
    );
    // diff's maps.
    let r = lgh(&["diff", s(&x), s(&x), "--map", s(&x), "--flip-map", s(&x)]);
    assert_error(&r, &["--map and --flip-map name one file"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn two_renders_to_one_file_leave_one_whole_image() {
    let d = temp_dir("out-race");
    let out = d.join("race.png");
    for trial in 0..6 {
        let spawn = |seed: &str| {
            std::process::Command::new(env!("CARGO_BIN_EXE_lgh"))
                .args(["render", "--size", "96x54", "--vpls", "2000", "--quiet"])
                .args(["--seed", seed, "-o", s(&out)])
                .spawn()
                .unwrap()
        };
        let (mut a, mut b) = (spawn("1"), spawn("2"));
        assert!(
            a.wait().unwrap().success() && b.wait().unwrap().success(),
            "trial {trial}"
        );
        let bytes = std::fs::read(&out).unwrap();
        let img = image::load_from_memory(&bytes).expect("one whole PNG");
        assert_eq!((img.width(), img.height()), (96, 54));
        let leftovers: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .filter_map(Result::ok)
            .filter(|e| e.file_name().to_string_lossy().ends_with(".partial"))
            .collect();
        assert!(leftovers.is_empty(), "{leftovers:?}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_hash_in_a_folder_name_is_not_a_frame_number() {
    let d = temp_dir("out-hash").join("take#2");
    std::fs::create_dir_all(&d).unwrap();
    let o = d.join("still.png");
    let r = render(&["-o", s(&o)]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(o.is_file());
    // With --frames, the '#' of the file name is the frame number.
    let seq = d.join("f_##.png");
    let r = render(&["-o", s(&seq), "--frames", "0..2"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(d.join("f_01.png").is_file());
    let _ = std::fs::remove_dir_all(d.parent().unwrap());
}

#[test]
fn ctrl_c_stops_with_130_and_leaves_no_partial_file() {
    let d = temp_dir("out-sigint");
    let o = d.join("slow.exr");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_lgh"))
        .args([
            "render", "--method", "brute", "--size", "320x180", "--vpls", "200000",
        ])
        .args(["--quiet", "-o", s(&o)])
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130));
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn viewer_flags_are_checked() {
    let v = |extra: &[&str]| lgh(&[&["view", "--headless", "--size", "16x9"][..], extra].concat());
    // H (help) and O (readout) are keys of the viewer, in either case.
    let r = v(&["--frames", "2", "--keys", "h,O"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert_error(
        &v(&["--frames", "10000000"]),
        &["--frames 10000000", "expected 1 to"],
    );
    // No frame: nothing to show, to screenshot or to measure.
    assert_error(&v(&["--frames", "0"]), &["--frames 0", "expected 1 to"]);
    for bad in ["nan", "inf", "1000"] {
        assert_error(
            &v(&["--frames", "1", "--light-speed", bad]),
            &["--light-speed"],
        );
    }
}
