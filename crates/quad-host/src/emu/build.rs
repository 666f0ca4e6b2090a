//! Building the firmware's release ELFs: `cd firmware-avr && cargo build --release`, the way a
//! developer does (the directory's `rust-toolchain.toml` selects nightly with `rust-src`, its
//! `.cargo/config.toml` the `avr-none` target and `build-std`).
//!
//! Needs the Debian packages and toolchain components that `scripts/install-deps.sh` installs;
//! without them the build fails and [`firmware_elf`] returns its output as the error.

use std::io;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus};
use std::sync::{Arc, OnceLock};

/// The firmware at 115,200 baud.
pub const FIRMWARE: &str = "firmware";
/// The firmware at 1,000,000 baud.
pub const FIRMWARE_1MBAUD: &str = "firmware-1mbaud";
/// The cycle benchmark on avr-libc's float routines.
pub const BENCH: &str = "bench";
/// The cycle benchmark of the straightforward build (Rust libm, soft-float).
pub const BENCH_LIBM: &str = "bench-libm";
/// The test harness: the firmware's kernels and IK over batches in SRAM
/// (`firmware_avr::harness`).
pub const HARNESS: &str = "harness";

/// Test only, defective on purpose: the 1 Mbaud firmware whose receive path keeps interrupts
/// off too long (`firmware-avr/src/bin/firmware_1mbaud_cli_hold.rs`); the emulator tests show
/// that the emulated USART catches it.
pub const FIRMWARE_1MBAUD_CLI_HOLD: &str = "firmware-1mbaud-cli-hold";

/// The firmware binary that runs at `baud`, if there is one.
pub fn firmware_for_baud(baud: u32) -> Option<&'static str> {
    match baud {
        115_200 => Some(FIRMWARE),
        1_000_000 => Some(FIRMWARE_1MBAUD),
        _ => None,
    }
}

/// The hint every build error ends with.
const PREREQUISITES: &str = "(install the prerequisites with scripts/install-deps.sh)";

/// Why the firmware could not be built.
#[derive(Debug, Clone, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// `cargo build --release` ran and failed.
    #[error(
        "`cd {} && cargo build --release` failed ({status}):\n{stdout}{stderr}\n{PREREQUISITES}",
        dir.display()
    )]
    Failed {
        /// The firmware workspace.
        dir: PathBuf,
        /// How cargo exited.
        status: ExitStatus,
        /// Its standard output.
        stdout: String,
        /// Its standard error (the compiler's messages).
        stderr: String,
    },
    /// cargo could not be started.
    #[error("cannot run cargo in {}: {source}\n{PREREQUISITES}", dir.display())]
    Spawn {
        /// The firmware workspace.
        dir: PathBuf,
        /// Why (shared: the build runs once per process and its result is cloned).
        source: Arc<io::Error>,
    },
    /// The build passed but did not produce this ELF.
    #[error("{} was not produced\n{PREREQUISITES}", .0.display())]
    Missing(PathBuf),
}

/// The firmware workspace, `firmware-avr/` at the root of the workspace that holds this
/// crate (`crates/quad-host`).
pub fn firmware_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .ancestors()
        .nth(2)
        .map_or_else(|| PathBuf::from("firmware-avr"), |p| p.join("firmware-avr"))
}

/// Where `cargo build --release` puts the ELF of binary `bin`.
pub fn elf_path(bin: &str) -> PathBuf {
    firmware_dir()
        .join("target/avr-none/release")
        .join(format!("{bin}.elf"))
}

/// Environment variables that a cargo running this program sets for its children and that
/// would make the inner build use the outer toolchain, target directory or flags.
fn leaks_from_outer_cargo(key: &str) -> bool {
    (key.starts_with("CARGO_") && key != "CARGO_HOME")
        || key.starts_with("RUSTC")
        || key.starts_with("RUSTDOC")
        || key == "RUSTFLAGS"
        || key == "RUSTUP_TOOLCHAIN"
        || key == "CARGO"
        || key == "__CARGO_FIX_PLZ"
}

/// The rustup `cargo` proxy, which honours `firmware-avr/rust-toolchain.toml`.
fn cargo_proxy() -> PathBuf {
    let home = std::env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cargo")));
    if let Some(p) = home.map(|h| h.join("bin").join("cargo")) {
        if p.is_file() {
            return p;
        }
    }
    PathBuf::from("cargo")
}

/// Runs the build once per process (all binaries at once; cargo does nothing when they are up
/// to date) and returns the result of that one run.
fn build_once() -> &'static Result<(), Error> {
    static BUILT: OnceLock<Result<(), Error>> = OnceLock::new();
    BUILT.get_or_init(|| {
        let dir = firmware_dir();
        let mut cmd = Command::new(cargo_proxy());
        cmd.current_dir(&dir).args(["build", "--release"]);
        for (key, _) in std::env::vars_os() {
            if let Some(k) = key.to_str() {
                if leaks_from_outer_cargo(k) {
                    cmd.env_remove(k);
                }
            }
        }
        match cmd.output() {
            Ok(out) if out.status.success() => Ok(()),
            Ok(out) => Err(Error::Failed {
                dir,
                status: out.status,
                stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
                stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
            }),
            Err(e) => Err(Error::Spawn {
                dir,
                source: Arc::new(e),
            }),
        }
    })
}

/// Builds the firmware workspace (once per process) and returns the path of the release ELF
/// of binary `bin` ([`FIRMWARE`], [`FIRMWARE_1MBAUD`], [`BENCH`], [`BENCH_LIBM`] or
/// [`HARNESS`]).
///
/// # Errors
/// The build's output when it fails, or [`Error::Missing`] when the ELF was not produced.
pub fn firmware_elf(bin: &str) -> Result<PathBuf, Error> {
    build_once().clone()?;
    let elf = elf_path(bin);
    if elf.is_file() {
        Ok(elf)
    } else {
        Err(Error::Missing(elf))
    }
}
