//! Marks the build with `cfg(lgh_scenes)` when `LGH_SCENES` names the folder of the shared
//! test scenes, so that the tests on them are `#[ignore]`d (shown as ignored, not passed)
//! in a build without it.

fn main() {
    println!("cargo::rustc-check-cfg=cfg(lgh_scenes)");
    println!("cargo::rerun-if-env-changed=LGH_SCENES");
    if std::env::var_os("LGH_SCENES").is_some_and(|v| !v.is_empty()) {
        println!("cargo::rustc-cfg=lgh_scenes");
    }
}
