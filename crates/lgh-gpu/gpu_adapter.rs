// Shared by the build scripts of lgh-gpu and lgh-cli (`include!`d): whether a GPU adapter
// can be expected on this machine, as `cfg(gpu_adapter)`: on macOS and Windows (Metal, DX12)
// always, on Linux when a Vulkan driver is installed (an ICD file, e.g. Mesa's lavapipe from
// Debian's `mesa-vulkan-drivers`), or when `LGH_GPU_TESTS` is set.

/// Prints `cargo::rustc-cfg=gpu_adapter` where a GPU adapter can be expected (see the
/// build scripts that include this file), and what to rerun on.
fn emit_gpu_adapter_cfg() {
    println!("cargo::rustc-check-cfg=cfg(gpu_adapter)");
    println!("cargo::rerun-if-env-changed=LGH_GPU_TESTS");
    println!("cargo::rerun-if-env-changed=VK_DRIVER_FILES");
    let icd_dirs = [
        "/usr/share/vulkan/icd.d",
        "/etc/vulkan/icd.d",
        "/usr/local/share/vulkan/icd.d",
    ];
    for d in icd_dirs {
        println!("cargo::rerun-if-changed={d}");
    }
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    let vulkan_driver = std::env::var_os("VK_DRIVER_FILES").is_some()
        || icd_dirs.iter().any(|d| {
            std::fs::read_dir(d).is_ok_and(|mut e| {
                e.any(|f| f.is_ok_and(|f| f.path().extension().is_some_and(|x| x == "json")))
            })
        });
    if os == "macos"
        || os == "windows"
        || vulkan_driver
        || std::env::var_os("LGH_GPU_TESTS").is_some()
    {
        println!("cargo::rustc-cfg=gpu_adapter");
    }
}
