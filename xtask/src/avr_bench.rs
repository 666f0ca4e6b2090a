//! `cargo xtask avr-bench`: the firmware's IK benchmark in simavr.
//!
//! Runs `cargo run --release -p integration-tests --bin avr-bench`, which builds the release
//! ELFs of `firmware-avr/` (nightly, via that directory's `rust-toolchain.toml`), runs them in
//! simavr in-process and prints a table per math backend and, as the last line of stdout, the
//! JSON figures `{"leg_ik_cycles":…,"body_pose_cycles":…,"leg_ik_cycles_libm":…,
//! "body_pose_cycles_libm":…,"max_angle_err_deg":…,"flash_bytes":…,"sram_static_bytes":…,
//! "max_stack_bytes":…}`. The simulator lives in the `integration-tests` crate so that this
//! program stays dependency-free.

use std::path::Path;
use std::process::{Command, ExitCode};

/// Runs the benchmark from the workspace root `root`; extra arguments are refused.
pub fn run(root: &Path, args: &[String]) -> ExitCode {
    if let Some(a) = args.first() {
        eprintln!("xtask avr-bench: unexpected argument `{a}` (usage: cargo xtask avr-bench)");
        return ExitCode::from(2);
    }
    let mut cmd = Command::new("cargo");
    cmd.current_dir(root).args([
        "run",
        "--release",
        "--quiet",
        "--package",
        "integration-tests",
        "--bin",
        "avr-bench",
    ]);
    match cmd.status() {
        Ok(s) if s.success() => ExitCode::SUCCESS,
        Ok(s) => {
            eprintln!("xtask avr-bench: the benchmark failed ({s})");
            ExitCode::FAILURE
        }
        Err(e) => {
            eprintln!("xtask avr-bench: cannot start cargo: {e}");
            ExitCode::FAILURE
        }
    }
}
