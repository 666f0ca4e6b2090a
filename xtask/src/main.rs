//! Project automation, dependency-free so that it compiles in seconds.
//!
//! `cargo xtask ci` runs every check of the project, in order, stopping at the first failure:
//!
//! | step           | what                                                                  |
//! |----------------|-----------------------------------------------------------------------|
//! | `deps`         | `scripts/install-deps.sh`: Debian packages and rustup components      |
//! | `fmt`          | `cargo fmt --all --check`                                             |
//! | `clippy`       | `cargo clippy --workspace --all-targets -- -D warnings`               |
//! | `avr-kin-core` | no_std build of kin-core, quad-protocol and quad-device for `avr-none` (atmega2560), nightly + build-std=core |
//! | `firmware-fmt` | `cargo +stable fmt --check` in `firmware-avr/` (when that directory exists) |
//! | `firmware`     | `cargo build --release` in `firmware-avr/` (when that directory exists) |
//! | `budget`       | the firmware's flash ≤ 128 KB and SRAM (static + worst stack in simavr) ≤ 6 KB: figures and margins; tables read with `lpm` in the lowest 64 KB (`integration_tests::budget`) |
//! | `test`         | `cargo test --workspace`                                              |
//! | `python`       | pytest of the Python package `quadkin` (crates/kin-py/tests, examples/python) in `.venv-py`, where the `deps` step installed it |
//! | `doc`          | `cargo doc --workspace --no-deps` with `RUSTDOCFLAGS=-D warnings`     |
//!
//! `cargo xtask ci --list` prints the steps; `cargo xtask ci STEP...` runs only those.
//!
//! `cargo xtask kernel-campaign [ARGS...]` runs the long campaign of the AVR kernels against
//! their twins (the `deps` step, then `integration-tests`' `kernel-campaign`).
//!
//! `cargo xtask demo [ARGS...]` is the main job on a fresh machine: the same `deps` step, then
//! `cargo run --release -p quadctl -- demo ARGS...`.
//!
//! Child processes do not inherit the toolchain selection of the cargo that started this
//! program (`RUSTUP_TOOLCHAIN`): each directory's `rust-toolchain.toml` decides, as it does for
//! a developer typing the same command.

mod avr_bench;

use std::env;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::time::{Duration, Instant};

/// `cargo xtask kernel-campaign [ARGS...]`: the long campaign of the AVR kernels against their
/// twins (`integration_tests` binary `kernel-campaign`; its docs list the arguments), after the
/// `deps` step.
fn kernel_campaign(args: &[String]) -> ExitCode {
    let steps = [
        deps_step(),
        Step::new(
            "kernel-campaign",
            &[
                "cargo",
                "run",
                "--release",
                "-p",
                "integration-tests",
                "--bin",
                "kernel-campaign",
                "--",
            ],
        )
        .with_args(args),
    ];
    run_steps(
        &workspace_root(),
        &steps.iter().collect::<Vec<_>>(),
        "kernel-campaign",
    )
}

/// Target CPU of the robot's controller board (Arduino Mega 2560).
const AVR_TARGET_CPU: &str = "atmega2560";

/// One check: a program run with arguments and extra environment in a directory.
struct Step {
    /// Short name, used by `cargo xtask ci STEP`.
    name: &'static str,
    /// Directory relative to the workspace root.
    dir: &'static str,
    /// Program and arguments.
    argv: Vec<String>,
    /// Extra environment variables.
    env: Vec<(&'static str, String)>,
    /// Environment variables removed for this step (besides the common ones).
    env_remove: Vec<&'static str>,
}

impl Step {
    fn new(name: &'static str, argv: &[&'static str]) -> Step {
        Step {
            name,
            dir: ".",
            argv: argv.iter().map(|a| (*a).to_owned()).collect(),
            env: Vec::new(),
            env_remove: Vec::new(),
        }
    }

    /// Appends arguments given at run time (e.g. passed through from the command line).
    fn with_args(mut self, args: &[String]) -> Step {
        self.argv.extend(args.iter().cloned());
        self
    }

    fn in_dir(mut self, dir: &'static str) -> Step {
        self.dir = dir;
        self
    }

    fn with_env(mut self, key: &'static str, value: impl Into<String>) -> Step {
        self.env.push((key, value.into()));
        self
    }

    fn without_env(mut self, key: &'static str) -> Step {
        self.env_remove.push(key);
        self
    }

    /// The command as a developer would type it from the workspace root.
    fn display(&self) -> String {
        let mut s = String::new();
        if self.dir != "." {
            s.push_str(&format!("(cd {} && ", self.dir));
        }
        for (k, v) in &self.env {
            s.push_str(&format!("{k}=\"{v}\" "));
        }
        s.push_str(&self.argv.join(" "));
        if self.dir != "." {
            s.push(')');
        }
        s
    }
}

/// `scripts/install-deps.sh`: installs what is missing (saying what), does nothing otherwise.
/// The first step of both `cargo xtask ci` and `cargo xtask demo`.
fn deps_step() -> Step {
    Step::new("deps", &["bash", "scripts/install-deps.sh"])
}

/// The steps of `cargo xtask demo ARGS...`: the install step of `cargo xtask ci`, then the demo
/// with `ARGS` passed through (`cargo xtask demo --port /dev/ttyACM0` drives a real board).
fn demo_steps(args: &[String]) -> Vec<Step> {
    vec![
        deps_step(),
        Step::new(
            "demo",
            &["cargo", "run", "--release", "-p", "quadctl", "--", "demo"],
        )
        .with_args(args),
    ]
}

/// The checks run by `cargo xtask ci`, in order. Add new checks here.
fn ci_steps(root: &Path) -> Vec<Step> {
    let mut steps = vec![
        deps_step(),
        Step::new("fmt", &["cargo", "fmt", "--all", "--check"]),
        Step::new(
            "clippy",
            &[
                "cargo",
                "clippy",
                "--workspace",
                "--all-targets",
                "--",
                "-D",
                "warnings",
            ],
        ),
        // kin-core must stay no_std and build for the firmware's target. `[unstable] build-std`
        // cannot live in the root .cargo/config.toml (it breaks host builds), hence the flags;
        // a separate target dir keeps the host artifacts valid.
        Step::new(
            "avr-kin-core",
            &[
                "cargo",
                "+nightly",
                "build",
                "-p",
                "kin-core",
                "-p",
                "quad-protocol",
                "-p",
                "quad-device",
                "--release",
                "--target",
                "avr-none",
                "-Z",
                "build-std=core",
                "--target-dir",
                "target/avr",
            ],
        )
        .with_env("RUSTFLAGS", format!("-C target-cpu={AVR_TARGET_CPU}"))
        .without_env("CARGO_ENCODED_RUSTFLAGS"),
    ];
    // The firmware is its own workspace with its own toolchain and .cargo/config.toml, which
    // cargo and rustup only read from the current directory.
    if root.join("firmware-avr/Cargo.toml").is_file() {
        // The firmware's format, by the stable toolchain's rustfmt (its nightly is minimal).
        steps.push(
            Step::new("firmware-fmt", &["cargo", "+stable", "fmt", "--check"])
                .in_dir("firmware-avr"),
        );
        steps.push(
            Step::new("firmware", &["cargo", "build", "--release"])
                .in_dir("firmware-avr")
                .without_env("RUSTFLAGS")
                .without_env("CARGO_ENCODED_RUSTFLAGS"),
        );
        // Flash and static SRAM from the ELF, the worst stack in simavr after every request
        // type; fails over budget. A debug build of the runner, as the test step's.
        steps.push(Step::new(
            "budget",
            &[
                "cargo",
                "run",
                "--quiet",
                "--package",
                "integration-tests",
                "--bin",
                "firmware-budget",
            ],
        ));
    }
    // Every test binary runs even after one fails: one failure must not hide the others.
    steps.push(Step::new(
        "test",
        &["cargo", "test", "--workspace", "--no-fail-fast"],
    ));
    // The Python package: its wheel was built and installed into .venv-py by the deps step;
    // the tests compare with `quadctl` (built by the test step) and run the examples.
    steps.push(Step::new(
        "python",
        &[
            ".venv-py/bin/python",
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "crates/kin-py/tests",
        ],
    ));
    steps.push(
        Step::new("doc", &["cargo", "doc", "--workspace", "--no-deps"])
            .with_env("RUSTDOCFLAGS", "-D warnings"),
    );
    steps
}

/// Variables set by the cargo/rustup that started this program, which would otherwise leak
/// into the checks (e.g. `RUSTUP_TOOLCHAIN` would override `firmware-avr/rust-toolchain.toml`).
fn is_inherited_cargo_var(key: &str) -> bool {
    matches!(
        key,
        "RUSTUP_TOOLCHAIN"
            | "RUSTUP_TOOLCHAIN_SOURCE"
            | "RUST_RECURSION_COUNT"
            | "CARGO"
            | "CARGO_MANIFEST_DIR"
            | "CARGO_MANIFEST_PATH"
            | "CARGO_PRIMARY_PACKAGE"
            | "CARGO_CRATE_NAME"
            | "CARGO_BIN_NAME"
    ) || key.starts_with("CARGO_PKG_")
}

fn run_step(root: &Path, step: &Step) -> Result<(), String> {
    let (program, args) = step
        .argv
        .split_first()
        .ok_or_else(|| format!("step {} has no command", step.name))?;
    let mut cmd = Command::new(program);
    cmd.args(args).current_dir(root.join(step.dir));
    for (key, _) in env::vars_os() {
        if key.to_str().is_some_and(is_inherited_cargo_var) {
            cmd.env_remove(&key);
        }
    }
    for key in &step.env_remove {
        cmd.env_remove(key);
    }
    for (key, value) in &step.env {
        cmd.env(key, value);
    }
    let status = cmd
        .status()
        .map_err(|e| format!("cannot start `{program}`: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("`{}` failed ({status})", step.display()))
    }
}

fn workspace_root() -> PathBuf {
    let xtask_dir = env::var_os("CARGO_MANIFEST_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")));
    xtask_dir
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or(xtask_dir)
}

fn fmt_duration(d: Duration) -> String {
    let s = d.as_secs_f64();
    if s < 60.0 {
        format!("{s:.1} s")
    } else {
        format!("{}m{:04.1}s", (s / 60.0).floor() as u64, s % 60.0)
    }
}

fn ci(args: &[String]) -> ExitCode {
    let root = workspace_root();
    let all = ci_steps(&root);
    if args.iter().any(|a| a == "--list") {
        for step in &all {
            println!("{:<14} {}", step.name, step.display());
        }
        return ExitCode::SUCCESS;
    }
    if let Some(unknown) = args
        .iter()
        .find(|a| !all.iter().any(|s| s.name == a.as_str()))
    {
        eprintln!("xtask ci: unknown step `{unknown}`; `cargo xtask ci --list` shows the steps");
        return ExitCode::from(2);
    }
    let steps: Vec<&Step> = all
        .iter()
        .filter(|s| args.is_empty() || args.iter().any(|a| a == s.name))
        .collect();

    run_steps(&root, &steps, "ci")
}

/// Runs `steps` in order from the workspace root, stopping at the first failure; prints each
/// command before it runs and a table of times at the end. `what` names the task in messages.
fn run_steps(root: &Path, steps: &[&Step], what: &str) -> ExitCode {
    let start = Instant::now();
    let mut done: Vec<(&str, Duration)> = Vec::new();
    for step in steps {
        println!("\n==> [{}] {}", step.name, step.display());
        let t = Instant::now();
        let result = run_step(root, step);
        let took = t.elapsed();
        done.push((step.name, took));
        match result {
            Ok(()) => println!("<== [{}] ok in {}", step.name, fmt_duration(took)),
            Err(e) => {
                eprintln!("<== [{}] FAILED in {}: {e}", step.name, fmt_duration(took));
                eprintln!(
                    "xtask {what}: FAILED at step `{}` after {}",
                    step.name,
                    fmt_duration(start.elapsed())
                );
                return ExitCode::FAILURE;
            }
        }
    }
    println!("\nxtask {what}: all steps passed");
    for (name, took) in &done {
        println!("  {name:<14} {:>10}", fmt_duration(*took));
    }
    println!("  {:<14} {:>10}", "total", fmt_duration(start.elapsed()));
    ExitCode::SUCCESS
}

/// `cargo xtask demo ARGS...`: installs what the demo needs, then runs it.
fn demo(args: &[String]) -> ExitCode {
    let steps = demo_steps(args);
    println!(
        "xtask demo: first installing what the demo needs, as `cargo xtask ci` does \
         (scripts/install-deps.sh: the AVR toolchain, simavr and the libraries its bindings \
         build against, nightly rust-src; it names what it installs and does nothing when all \
         is present), then building and running the demo"
    );
    run_steps(&workspace_root(), &steps.iter().collect::<Vec<_>>(), "demo")
}

const USAGE: &str =
    "usage: cargo xtask ci [--list | STEP...] | cargo xtask demo [DEMO ARGS...] | cargo xtask avr-bench | cargo xtask kernel-campaign [ARGS...]";

fn main() -> ExitCode {
    let args: Vec<String> = env::args().skip(1).collect();
    match args.split_first() {
        Some((cmd, rest)) if cmd == "ci" => ci(rest),
        Some((cmd, rest)) if cmd == "demo" => demo(rest),
        Some((cmd, rest)) if cmd == "avr-bench" => avr_bench::run(&workspace_root(), rest),
        Some((cmd, rest)) if cmd == "kernel-campaign" => kernel_campaign(rest),
        Some((cmd, _)) if cmd == "-h" || cmd == "--help" => {
            println!("{USAGE}");
            ExitCode::SUCCESS
        }
        _ => {
            eprintln!("{USAGE}");
            ExitCode::from(2)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(steps: &[Step]) -> Vec<&'static str> {
        steps.iter().map(|s| s.name).collect()
    }

    #[test]
    fn step_names_are_unique_and_cover_the_required_checks() {
        let steps = ci_steps(&workspace_root());
        let mut n = names(&steps);
        for required in [
            "deps",
            "fmt",
            "clippy",
            "avr-kin-core",
            "test",
            "python",
            "doc",
        ] {
            assert!(n.contains(&required), "missing step {required}");
        }
        n.sort_unstable();
        let len = n.len();
        n.dedup();
        assert_eq!(n.len(), len, "duplicate step names");
    }

    #[test]
    fn deps_run_first_and_firmware_builds_before_tests() {
        let root = env::temp_dir().join(format!("xtask-test-{}", std::process::id()));
        std::fs::create_dir_all(root.join("firmware-avr")).unwrap();
        assert!(!names(&ci_steps(&root)).contains(&"firmware"));
        std::fs::write(root.join("firmware-avr/Cargo.toml"), "").unwrap();
        let n = names(&ci_steps(&root));
        std::fs::remove_dir_all(&root).unwrap();
        assert_eq!(n[0], "deps");
        let pos = |name| n.iter().position(|s| *s == name).unwrap();
        assert!(pos("firmware") < pos("test"));
        assert!(
            pos("test") < pos("python"),
            "the Python tests use the test step's quadctl"
        );
        assert_eq!(
            pos("budget"),
            pos("firmware") + 1,
            "the budget follows the firmware build"
        );
    }

    #[test]
    fn the_demo_installs_its_dependencies_first_as_ci_does() {
        let args = ["--port".to_owned(), "/dev/ttyACM0".to_owned()];
        let demo = demo_steps(&args);
        let ci = ci_steps(&workspace_root());
        assert_eq!(names(&demo), ["deps", "demo"]);
        assert_eq!(
            demo[0].display(),
            ci[0].display(),
            "the same install step as ci"
        );
        assert_eq!(demo[0].display(), "bash scripts/install-deps.sh");
        assert_eq!(
            demo[1].display(),
            "cargo run --release -p quadctl -- demo --port /dev/ttyACM0"
        );
    }

    #[test]
    fn toolchain_selection_of_the_parent_cargo_is_not_inherited() {
        for key in [
            "RUSTUP_TOOLCHAIN",
            "CARGO",
            "CARGO_MANIFEST_DIR",
            "CARGO_PKG_NAME",
        ] {
            assert!(is_inherited_cargo_var(key), "{key}");
        }
        for key in ["CARGO_HOME", "RUSTUP_HOME", "CARGO_TARGET_DIR", "PATH"] {
            assert!(!is_inherited_cargo_var(key), "{key}");
        }
    }

    #[test]
    fn avr_step_builds_kin_core_for_the_board() {
        let steps = ci_steps(&workspace_root());
        let avr = steps.iter().find(|s| s.name == "avr-kin-core").unwrap();
        assert_eq!(
            avr.display(),
            "RUSTFLAGS=\"-C target-cpu=atmega2560\" cargo +nightly build -p kin-core -p quad-protocol -p quad-device --release \
             --target avr-none -Z build-std=core --target-dir target/avr"
        );
    }
}
