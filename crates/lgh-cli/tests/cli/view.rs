//! `lgh view`: the headless loop and its statistics, and the window under a virtual X server.

use super::{assert_error, lgh, s, temp_dir};

const SMALL: [&str; 6] = ["--size", "160x90", "--vpls", "5000", "--frames", "6"];

/// The viewer starts at interactive settings (alpha 1.5, S_1 first, 4 a-trous passes, 1
/// shadow sample) unless
/// the command line gives them; a flag given keeps its value, the others still get the
/// viewer's.
#[test]
fn view_starts_at_interactive_settings_unless_given() {
    let d = temp_dir("view-defaults");
    let stats = d.join("s.json");
    let settings = |extra: &[&str]| {
        let args = [
            &["view", "--headless", "--stats", s(&stats)][..],
            &SMALL[..4],
            &["--frames", "1"],
            extra,
        ]
        .concat();
        let r = lgh(&args);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        let lgh = &json["settings"]["lgh"];
        (
            lgh["alpha"].as_f64().unwrap(),
            lgh["start_level"].as_u64().unwrap(),
            json["settings"]["shadows"]["filter_passes"]
                .as_u64()
                .unwrap(),
            json["settings"]["shadows"]["samples"].as_u64(),
        )
    };
    // --help lists the keys after the flags.
    let help = String::from_utf8_lossy(&lgh(&["view", "--help"]).stdout).into_owned();
    for key in ["Controls", "W/S", "overdraw heat map", "Esc"] {
        assert!(help.contains(key), "{key}: {help}");
    }
    let one = Some(1);
    assert_eq!(settings(&[]), (1.5, 1, 4, one));
    assert_eq!(settings(&["--alpha", "4"]), (4.0, 1, 4, one));
    assert_eq!(settings(&["--start-level", "0"]), (1.5, 0, 4, one));
    assert_eq!(settings(&["--filter-passes", "5"]), (1.5, 1, 5, one));
    assert_eq!(settings(&["--shadow-samples", "4"]), (1.5, 1, 4, Some(4)));
}

#[test]
fn headless_view_reports_fps_and_pass_medians_and_follows_the_key_script() {
    let d = temp_dir("view");
    let stats = d.join("s.json");
    let shot = d.join("a.png");
    let moved = d.join("b.png");
    let run = |extra: &[&str], png: &std::path::Path| {
        let args = [
            &["view", "--headless", "--screenshot", s(png)][..],
            &SMALL,
            extra,
        ]
        .concat();
        let r = lgh(&args);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    };
    run(
        &["--stats", s(&stats), "--light-speed", "5", "--taa"],
        &shot,
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert!(json["fps"].as_f64().unwrap() > 0.0, "{json}");
    assert_eq!(json["frames"], 6);
    for pass in [
        "frame",
        "vpl_generation",
        "lgh_build",
        "gbuffer",
        "shadow_rays",
    ] {
        assert!(json["median_ms"][pass].as_f64().is_some(), "{pass}: {json}");
    }
    assert!(json["grid_lights"].as_u64().unwrap() > 0);
    // The script moves the camera: another image.
    run(&["--keys", "w,w,a,left"], &moved);
    let diff = lgh(&["diff", s(&moved), s(&shot), "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&diff.stdout).unwrap();
    assert!(v["flip"].as_f64().unwrap() > 0.01, "{v}");
    // V shows the heat map: the ramp's saturated colours everywhere (their channels differ
    // by 0.35 or more before the tone map), where the image has black and grey pixels.
    let heat = d.join("heat.png");
    run(&["--keys", "v"], &heat);
    let saturated = |png: &std::path::Path| {
        let img = lgh_render::Image::load(png).unwrap();
        let n = img
            .pixels
            .iter()
            .filter(|p| p.max_element() - p.min_element() > 0.2)
            .count();
        n as f64 / img.pixels.len() as f64
    };
    assert!(saturated(&shot) < 0.5, "{}", saturated(&shot));
    assert_eq!(saturated(&heat), 1.0);
    assert_error(&lgh(&["view", "--headless"]), &["--frames"]);
    assert_error(
        &lgh(&["view", "--headless", "--frames", "2", "--keys", "w,zz"]),
        &["--keys", "zz"],
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// The window opens under Xvfb, renders, takes the scripted keys and writes a screenshot
/// equal to the headless frame; with a GPU adapter (lavapipe in CI) the same with
/// `--device gpu`.
#[test]
#[cfg_attr(not(xvfb), ignore = "needs Debian's xvfb")]
fn the_window_under_xvfb_shows_the_headless_frame() {
    let d = temp_dir("xvfb");
    let devices: &[&str] = if cfg!(gpu_adapter) {
        &["cpu", "gpu"]
    } else {
        &["cpu"]
    };
    for device in devices {
        let window = d.join(format!("w-{device}.png"));
        let headless = d.join(format!("h-{device}.png"));
        let keys = ["--keys", "w,m,l,i", "--device", device];
        let bin = env!("CARGO_BIN_EXE_lgh");
        let args = [
            &["-a", bin, "view", "--screenshot", s(&window)][..],
            &SMALL,
            &keys,
        ]
        .concat();
        let r = std::process::Command::new("xvfb-run")
            .args(&args)
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        let r = lgh(&[
            &["view", "--headless", "--screenshot", s(&headless)][..],
            &SMALL,
            &keys,
        ]
        .concat());
        assert!(r.status.success());
        let diff = lgh(&["diff", s(&window), s(&headless), "--json"]);
        let v: serde_json::Value = serde_json::from_slice(&diff.stdout).unwrap();
        assert!(v["flip"].as_f64().unwrap() <= 0.01, "{device}: {v}");
    }
    let _ = std::fs::remove_dir_all(&d);
}
