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
    let out = run(&["render", "--device", "gpu", "--size", "32x18"], false);
    assert_error(&out, &["--method lgh", "not run on the GPU yet", "brute"]);
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
}
