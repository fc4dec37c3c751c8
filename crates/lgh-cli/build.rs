//! Marks the build with `cfg(assimp_models)` when Debian's assimp-testmodels are installed
//! and `cfg(xvfb)` when Debian's xvfb is (`.ci/run` installs both), so that the tests that
//! need them are `#[ignore]`d, shown as ignored rather than passed, in a build without them.

const MODELS: &str = "/usr/share/assimp/models";
const XVFB_RUN: &str = "/usr/bin/xvfb-run";

fn main() {
    println!("cargo::rustc-check-cfg=cfg(assimp_models)");
    println!("cargo::rustc-check-cfg=cfg(xvfb)");
    println!("cargo::rerun-if-changed={XVFB_RUN}");
    if std::path::Path::new(XVFB_RUN).is_file() {
        println!("cargo::rustc-cfg=xvfb");
    }
    println!("cargo::rerun-if-changed={MODELS}");
    if std::path::Path::new(MODELS).is_dir() {
        println!("cargo::rustc-cfg=assimp_models");
    }
}
