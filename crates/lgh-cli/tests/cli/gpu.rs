//! `--device gpu` as a user meets it where it cannot run: a method not ported yet, and a
//! machine without a GPU driver, each one clear line and exit code 2. (Where an adapter exists
//! the GPU brute force is compared with the CPU's in lgh-gpu's own tests.)

use std::process::Command;

use super::assert_error;

#[test]
fn gpu_refuses_methods_not_ported_and_machines_without_a_driver() {
    let run = |args: &[&str], no_driver: bool| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_lgh"));
        c.args(args).env_remove("LGH_SCENES");
        if no_driver {
            // The Vulkan loader finds no driver; the build has no GL backend to fall back to.
            c.env("VK_DRIVER_FILES", "/nonexistent/icd.json")
                .env("VK_ICD_FILENAMES", "/nonexistent/icd.json");
        }
        c.output().expect("runs")
    };
    let out = run(
        &[
            "render", "--device", "gpu", "--method", "slc", "--size", "32x18",
        ],
        false,
    );
    assert_error(
        &out,
        &["--method slc", "not run on the GPU yet", "lgh", "brute"],
    );
    let out = run(
        &[
            "render",
            "--device",
            "gpu",
            "--estimator",
            "paper",
            "--size",
            "32x18",
            "--out",
            "/tmp/lgh-cli-gpu-never.png",
        ],
        false,
    );
    #[cfg(gpu_adapter)]
    assert_error(&out, &["default shadow estimate", "--device cpu"]);
    #[cfg(not(gpu_adapter))]
    assert!(!out.status.success());
    let out = run(
        &[
            "render",
            "--device",
            "gpu",
            "--method",
            "brute",
            "--size",
            "32x18",
            "--out",
            "/tmp/lgh-cli-gpu-never.png",
        ],
        true,
    );
    assert_error(&out, &["no GPU adapter", "Vulkan"]);
    assert!(!std::path::Path::new("/tmp/lgh-cli-gpu-never.png").exists());
    let out = run(&["render", "--device", "tpu"], false);
    assert_error(&out, &["tpu"]);
    let out = run(
        &["view", "--headless", "--device", "gpu", "--frames", "1"],
        true,
    );
    assert_error(&out, &["no GPU adapter", "Vulkan"]);
}

/// `lgh render --device gpu` at its defaults (lgh, its lighting loop on the GPU) and `lgh
/// view --device gpu --headless --frames 10` run on the adapter, write their outputs, and
/// say where the frames were computed.
#[test]
#[cfg_attr(
    not(gpu_adapter),
    ignore = "needs a GPU adapter (a Vulkan driver: mesa-vulkan-drivers)"
)]
fn render_and_view_run_lgh_on_the_gpu() {
    let d = std::env::temp_dir().join(format!("lgh-cli-gpu-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temp dir");
    let (png, stats, shot) = (d.join("g.png"), d.join("g.json"), d.join("v.png"));
    let lgh = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_lgh"))
            .args(args)
            .env_remove("LGH_SCENES")
            .output()
            .expect("runs")
    };
    let path = |p: &std::path::Path| p.to_str().expect("utf-8").to_owned();
    let out = lgh(&[
        "render",
        "--device",
        "gpu",
        "--size",
        "64x36",
        "--vpls",
        "2000",
        "--out",
        &path(&png),
        "--stats",
        &path(&stats),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&stats).expect("stats")).expect("json");
    assert_eq!(v["method"], "lgh", "{v}");
    assert_ne!(v["device"], "cpu", "{v}");
    assert!(v["timings_ms"]["lighting"].as_f64().is_some(), "{v}");
    // The viewer headless for `frames` frames, with `more` flags: its stats.
    let view = |frames: &str, more: &[&str]| {
        let args = [
            "view",
            "--headless",
            "--device",
            "gpu",
            "--frames",
            frames,
            "--size",
            "64x36",
            "--vpls",
            "2000",
            "--screenshot",
            &path(&shot),
            "--stats",
            &path(&stats),
        ];
        let out = lgh(&[&args[..], more].concat());
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&stats).expect("stats")).expect("json");
        v
    };
    let v = view("10", &[]);
    assert_eq!(v["device"], "gpu", "{v}");
    assert_eq!(v["frames"], 10, "{v}");
    assert!(shot.exists());
    // The U key switches to the paper's estimate, which the GPU loop does not run: the
    // viewer goes on, on the CPU, and says so.
    let v = view("3", &["--keys", "u"]);
    assert_eq!(v["device"], "cpu", "{v}");
    let _ = std::fs::remove_dir_all(&d);
}
