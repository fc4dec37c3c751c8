//! Marks the build with `cfg(gpu_adapter)` where a GPU adapter can be expected: on macOS and
//! Windows (Metal, DX12) always, on Linux when a Vulkan driver is installed (an ICD file, e.g.
//! Mesa's lavapipe from Debian's `mesa-vulkan-drivers`), or when `LGH_GPU_TESTS` is set. The
//! tests that need an adapter are ignored elsewhere (shown as ignored, which CI refuses).
//! Also marks it with `cfg(lgh_scenes)` when `LGH_SCENES` names the shared scenes.

include!("gpu_adapter.rs");

fn main() {
    emit_gpu_adapter_cfg();
    // `cfg(lgh_scenes)` when `LGH_SCENES` names the shared scenes (as lgh-render's).
    println!("cargo::rustc-check-cfg=cfg(lgh_scenes)");
    println!("cargo::rerun-if-env-changed=LGH_SCENES");
    if std::env::var_os("LGH_SCENES").is_some_and(|v| !v.is_empty()) {
        println!("cargo::rustc-cfg=lgh_scenes");
    }
}
