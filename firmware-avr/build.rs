//! Links avr-libc's own `sqrt` into the benchmark and test harness firmwares (`bench`,
//! `harness`) under the name `avr_libc_sqrt`: the firmware defines `sqrt` itself
//! (`avr_libc_math::sqrt`), so `libm.a`'s `sqrt.o` is never linked as it stands; the emulator
//! tests `avr_sqrt` and `avr_kernel_edges` compare the two bit for bit. The member is taken from the `libm.a` that avr-gcc links and renamed with
//! `avr-objcopy`; the other binaries are left alone. Links every binary with the linker's
//! relaxation (`--relax`).

use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs `program` with `args`; its standard output. Panics (the build fails) when it cannot.
fn run(program: &str, args: &[&str]) -> Vec<u8> {
    let out = Command::new(program)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("{program} does not run ({e}): install gcc-avr, binutils-avr"));
    assert!(
        out.status.success(),
        "{program} {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    if !std::env::var("TARGET").is_ok_and(|t| t.starts_with("avr")) {
        return;
    }
    // Every binary: the linker's relaxation turns each `call`/`jmp` whose target lies within
    // ±4 KB into `rcall`/`rjmp` (2 bytes and a cycle fewer; measured in
    // `docs/benchmark-journal.md`).
    // Safe with LLVM's objects: every branch, local ones included, carries a relocation, which
    // the linker moves with the code it shortens.
    println!("cargo:rustc-link-arg=-Wl,--relax");
    let out_dir = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let libm = run("avr-gcc", &["-mmcu=atmega2560", "-print-file-name=libm.a"]);
    let libm = String::from_utf8(libm).expect("a UTF-8 path");
    let libm = Path::new(libm.trim());
    assert!(
        libm.is_file(),
        "avr-libc's libm.a not found ({})",
        libm.display()
    );
    let member = out_dir.join("sqrt.o");
    std::fs::write(
        &member,
        run("avr-ar", &["p", &libm.to_string_lossy(), "sqrt.o"]),
    )
    .expect("OUT_DIR is writable");
    let renamed = out_dir.join("avr_libc_sqrt.o");
    run(
        "avr-objcopy",
        &[
            "--redefine-sym",
            "sqrt=avr_libc_sqrt",
            "--redefine-sym",
            "sqrtf=avr_libc_sqrtf",
            &member.to_string_lossy(),
            &renamed.to_string_lossy(),
        ],
    );
    for bin in ["bench", "harness"] {
        println!("cargo:rustc-link-arg-bin={bin}={}", renamed.display());
        // Its helpers (`__fp_splitA`, `__fp_norm2`, …) from `libm.a`, after it on the command
        // line.
        println!("cargo:rustc-link-arg-bin={bin}=-lm");
    }
}
