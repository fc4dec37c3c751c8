//! Finds libembree3: `EMBREE_DIR` (a folder holding `lib/` and `include/`), then the usual
//! system folders. It also reads the library's `rtcore_config.h` and accepts only the
//! configuration whose struct layouts `src/sys.rs` declares (Embree 3, one instance level, no
//! minimum curve width): a library built otherwise would be called with wrongly laid out
//! structs. When an acceptable library is found, the crate links it and is compiled with
//! `cfg(embree)`; when not, it compiles to a stub (`Scene::new` returns `Error::NotBuilt`),
//! unless the `required` feature asks for it, in which case the build fails with one line
//! saying what to install.

use std::path::{Path, PathBuf};

fn has_lib(dir: &Path) -> bool {
    ["libembree3.so", "libembree3.dylib", "embree3.lib"]
        .iter()
        .any(|f| dir.join(f).exists())
}

/// The library's folder and its `rtcore_config.h`.
fn find() -> Option<(PathBuf, PathBuf)> {
    let candidates: Vec<(PathBuf, PathBuf)> = match std::env::var_os("EMBREE_DIR") {
        Some(root) => {
            let root = PathBuf::from(root);
            let inc = root.join("include");
            ["lib", "lib64", "."]
                .iter()
                .map(|l| (root.join(l), inc.clone()))
                .collect()
        }
        None => [
            ("/usr/lib/x86_64-linux-gnu", "/usr/include"),
            ("/usr/lib/aarch64-linux-gnu", "/usr/include"),
            ("/usr/lib64", "/usr/include"),
            ("/usr/lib", "/usr/include"),
            ("/usr/local/lib", "/usr/local/include"),
            ("/opt/homebrew/lib", "/opt/homebrew/include"),
        ]
        .iter()
        .map(|(l, i)| (PathBuf::from(l), PathBuf::from(i)))
        .collect(),
    };
    candidates
        .into_iter()
        .find(|(lib, _)| has_lib(lib))
        .map(|(lib, inc)| (lib, inc.join("embree3").join("rtcore_config.h")))
}

/// The value of `#define NAME value` in a header's text.
fn define<'a>(header: &'a str, name: &str) -> Option<&'a str> {
    header.lines().find_map(|l| {
        let mut w = l.split_whitespace();
        (w.next() == Some("#define") && w.next() == Some(name)).then(|| w.next().unwrap_or(""))
    })
}

/// Why the configuration in `header` does not match `src/sys.rs`, if it does not.
fn layout_mismatch(header: &str) -> Option<String> {
    let want = [
        ("RTC_VERSION_MAJOR", "3"),
        ("RTC_MAX_INSTANCE_LEVEL_COUNT", "1"),
        ("EMBREE_MIN_WIDTH", "0"),
    ];
    for (name, value) in want {
        let got = define(header, name);
        if got != Some(value) {
            return Some(format!("{name} is {got:?}, lgh-embree needs {value}"));
        }
    }
    header
        .lines()
        .any(|l| l.contains("#define EMBREE_API_NAMESPACE"))
        .then(|| "the library is built with an API namespace".to_owned())
}

fn main() {
    println!("cargo::rustc-check-cfg=cfg(embree)");
    println!("cargo::rerun-if-env-changed=EMBREE_DIR");
    let problem = match find() {
        None => Some("Embree 3 not found".to_owned()),
        Some((lib, config)) => match std::fs::read_to_string(&config) {
            Err(_) => Some(format!("Embree 3's header {} not found", config.display())),
            Ok(h) => match layout_mismatch(&h) {
                Some(why) => Some(format!("Embree 3 at {}: {why}", lib.display())),
                None => {
                    println!("cargo::rerun-if-changed={}", config.display());
                    println!("cargo::rustc-link-search=native={}", lib.display());
                    println!("cargo::rustc-link-lib=dylib=embree3");
                    println!("cargo::rustc-cfg=embree");
                    None
                }
            },
        },
    };
    // Without `required`, silently a stub: the default build must not need Embree.
    if let Some(why) = problem
        && std::env::var_os("CARGO_FEATURE_REQUIRED").is_some()
    {
        println!(
            "cargo::error={why}: install it (Debian: apt-get install libembree-dev) or set EMBREE_DIR to its folder"
        );
    }
}
