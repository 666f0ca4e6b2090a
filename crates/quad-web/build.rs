//! Puts the page's generated assets in `OUT_DIR/assets/`, where `src/assets.rs` embeds them:
//!
//! - `kin.wasm`: `crates/kin-wasm` built for `wasm32-unknown-unknown` (release) by a nested
//!   cargo with its own target directory (the outer build holds the lock of the workspace's);
//! - three.js (`three.module.js`, `three.core.js`) and its `OrbitControls.js`, copied from
//!   `web/node_modules/` (`npm ci` in `web/`, run by `scripts/install-deps.sh`).
//!
//! When the wasm target or `web/node_modules` is missing, the build still succeeds with a
//! warning and the page says what to install: the rest of the workspace builds without Node.js.
//! What is missing is passed on as `QUAD_WEB_MISSING` (space-separated `kin.wasm`, `three.js`)
//! for `assets::check` (`quadctl serve --check`, and a test of the CI).

use std::path::{Path, PathBuf};
use std::process::Command;

const THREE_FILES: [(&str, &str); 3] = [
    ("three/build/three.module.js", "three.module.js"),
    ("three/build/three.core.js", "three.core.js"),
    (
        "three/examples/jsm/controls/OrbitControls.js",
        "OrbitControls.js",
    ),
];

fn main() {
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap());
    let root = manifest.join("../..");
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap());
    let assets = out.join("assets");
    std::fs::create_dir_all(&assets).unwrap();

    for dir in ["crates/kin-wasm/src", "crates/kin-core/src"] {
        println!("cargo:rerun-if-changed={}", root.join(dir).display());
    }
    println!(
        "cargo:rerun-if-changed={}",
        root.join("crates/kin-wasm/Cargo.toml").display()
    );
    println!(
        "cargo:rerun-if-changed={}",
        root.join("web/node_modules/three/package.json").display()
    );
    println!(
        "cargo:rerun-if-changed={}",
        root.join("web/package-lock.json").display()
    );

    let mut missing = Vec::new();
    if !build_wasm(&root, &out, &assets.join("kin.wasm")) {
        missing.push("kin.wasm");
    }
    if !copy_three(&root.join("web/node_modules"), &assets) {
        missing.push("three.js");
    }
    println!("cargo:rustc-env=QUAD_WEB_MISSING={}", missing.join(" "));
}

/// True when `kin.wasm` was built.
fn build_wasm(root: &Path, out: &Path, dest: &Path) -> bool {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let target_dir = out.join("wasm-target");
    let mut cmd = Command::new(cargo);
    cmd.current_dir(root)
        .args([
            "build",
            "--quiet",
            "--release",
            "-p",
            "kin-wasm",
            "--lib",
            "--target",
            "wasm32-unknown-unknown",
        ])
        .arg("--target-dir")
        .arg(&target_dir);
    // The nested build is a plain cargo build: none of the outer build's wrappers, flags or
    // jobserver.
    for (key, _) in std::env::vars_os() {
        let k = key.to_string_lossy();
        if k.starts_with("CARGO_") && k != "CARGO_HOME"
            || k.starts_with("RUSTC")
            || k == "RUSTFLAGS"
            || k == "RUSTDOCFLAGS"
            || k == "MAKEFLAGS"
            || k == "MFLAGS"
        {
            cmd.env_remove(&key);
        }
    }
    let built = target_dir.join("wasm32-unknown-unknown/release/kin_wasm.wasm");
    match cmd.status() {
        Ok(s) if s.success() => {
            std::fs::copy(&built, dest).unwrap();
            true
        }
        other => {
            println!(
                "cargo:warning=kin-wasm was not built for wasm32-unknown-unknown ({other:?}); \
                 the page cannot preview poses. Run `rustup target add wasm32-unknown-unknown` \
                 (scripts/install-deps.sh does)."
            );
            std::fs::write(dest, b"").unwrap();
            false
        }
    }
}

/// True when every three.js file was copied.
fn copy_three(node_modules: &Path, assets: &Path) -> bool {
    let mut all = true;
    for (from, to) in THREE_FILES {
        let src = node_modules.join(from);
        let dest = assets.join(to);
        if std::fs::copy(&src, &dest).is_err() {
            println!(
                "cargo:warning={} is missing: the page has no 3D view. Run `npm ci` in web/ \
                 (scripts/install-deps.sh does).",
                src.display()
            );
            std::fs::write(
                &dest,
                "throw new Error('three.js was not found at build time: run `npm ci` in web/ and rebuild');\n",
            )
            .unwrap();
            all = false;
        }
    }
    all
}
