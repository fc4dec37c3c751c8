//! Marks the build with `cfg(assimp_models)` when Debian's assimp-testmodels are installed
//! and `cfg(xvfb)` when Debian's xvfb is (`.ci/run` installs both), so that the tests that
//! need them are `#[ignore]`d, shown as ignored rather than passed, in a build without them.
//! Likewise `cfg(openjd)` when PyPI's openjd-cli is found (the `LGH_OPENJD` variable naming
//! its `openjd`, or `openjd` on the PATH), whose path the farm test gets as `LGH_OPENJD_BIN`.
//! And `cfg(gpu_adapter)` as lgh-gpu's build sets it, for the tests that run the GPU.

const MODELS: &str = "/usr/share/assimp/models";
const XVFB_RUN: &str = "/usr/bin/xvfb-run";

include!("../lgh-gpu/gpu_adapter.rs");

fn main() {
    emit_gpu_adapter_cfg();
    println!("cargo::rustc-check-cfg=cfg(assimp_models)");
    println!("cargo::rustc-check-cfg=cfg(xvfb)");
    println!("cargo::rerun-if-changed={XVFB_RUN}");
    if std::path::Path::new(XVFB_RUN).is_file() {
        println!("cargo::rustc-cfg=xvfb");
    }
    println!("cargo::rustc-check-cfg=cfg(openjd)");
    println!("cargo::rerun-if-env-changed=LGH_OPENJD");
    println!("cargo::rerun-if-env-changed=PATH");
    let named = std::env::var_os("LGH_OPENJD").map(std::path::PathBuf::from);
    let on_path = || {
        std::env::split_paths(&std::env::var_os("PATH")?)
            .map(|d| d.join("openjd"))
            .find(|p| p.is_file())
    };
    if let Some(bin) = named.filter(|p| p.is_file()).or_else(on_path) {
        println!("cargo::rustc-cfg=openjd");
        println!("cargo::rustc-env=LGH_OPENJD_BIN={}", bin.display());
    }
    println!("cargo::rerun-if-changed={MODELS}");
    if std::path::Path::new(MODELS).is_dir() {
        println!("cargo::rustc-cfg=assimp_models");
    }
}
