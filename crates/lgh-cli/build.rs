//! Marks the build with `cfg(assimp_models)` when Debian's assimp-testmodels are installed
//! (`.ci/run` installs them), so that the test over them is `#[ignore]`d, shown as ignored
//! rather than passed, in a build without them.

const MODELS: &str = "/usr/share/assimp/models";

fn main() {
    println!("cargo::rustc-check-cfg=cfg(assimp_models)");
    println!("cargo::rerun-if-changed={MODELS}");
    if std::path::Path::new(MODELS).is_dir() {
        println!("cargo::rustc-cfg=assimp_models");
    }
}
