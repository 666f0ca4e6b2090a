//! `quadctl port`: the simulated device or the emulated firmware on a virtual serial port
//! (a pseudo-terminal), kept alive across commands.

use crate::args::{self, TargetArgs};
use quad_host::client::DEFAULT_RETRIES;
use quad_host::link::pty::{PortStats, VirtualPort};
use quad_host::link::{self, Faults};
use quad_protocol::RobotPreset;
use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

const LONG_ABOUT: &str = "\
Serves the simulated device (--sim) or the real firmware in simavr (--emulator) on a virtual
serial port, a pseudo-terminal, until interrupted (Ctrl-C, SIGTERM). The first line of stdout
is its path (e.g. /dev/pts/3); every command then talks to it with `--port PATH` exactly as to a
board, one after the other, and the device keeps its state between them (`stand` leaves it
standing for `run`; `sit` and `rest` find it standing), as a board does. The panel
(`serve --port PATH`) and any program that opens a serial port (a terminal, pyserial) do too,
one at a time (a program holds the port while it is open, as a board's port).

The device's clock follows the wall clock: motions take their real time, and the bytes cross
the device's line at --baud whatever rate a program sets. The emulated firmware runs at about
two thirds of the chip's speed, so it answers more slowly than a board (never sooner); the
summary's behind_max_ms says by how much its clock fell behind.

In the background: start it with `&` and --link FILE (a symbolic link to the port, made before
the path is printed and removed at the end), then use `--port FILE`; stop it with `kill %1` (or
its process id): SIGTERM ends it cleanly, writing the emulator's --sim-storage image.

Output: the port's path on the first line of stdout; at the end one JSON line: h2d_bytes,
d2h_bytes, d2h_dropped (device bytes nobody read), behind_max_ms.
Exit status: 0 after an interrupt; 2 when the port or the device could not be set up or the
link failed.";

/// `--help`'s examples (then, in another terminal: `quadctl stand --robot shahriar2023 --port
/// /tmp/quad-port`).
pub const EXAMPLES: &str = "\
Examples:
  quadctl port --sim --robot shahriar2023
  quadctl port --emulator --link /tmp/quad-port";

/// Arguments of `quadctl port`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Serve the simulated device or the emulated firmware on a virtual serial port",
    long_about = LONG_ABOUT,
    after_help = EXAMPLES
)]
#[command(group = clap::ArgGroup::new("device").required(true).multiple(false))]
pub struct Args {
    /// Serve the device controller behind a simulated UART.
    #[arg(long, group = "device", requires = "robot")]
    pub sim: bool,
    /// Serve the real firmware in simavr (an emulated ATmega2560).
    #[arg(long, group = "device")]
    pub emulator: bool,
    /// Robot of the simulated device (a preset).
    #[arg(long, value_name = "PRESET", value_parser = crate::args::parse_robot, requires = "sim")]
    pub robot: Option<String>,
    /// Firmware ELF for --emulator; default: built from firmware-avr/ for --baud.
    #[arg(long, value_name = "PATH", requires = "emulator")]
    pub elf: Option<PathBuf>,
    /// The device's line rate, bit/s (8N1).
    #[arg(long, value_name = "B", default_value_t = 115_200, value_parser = clap::value_parser!(u32).range(300..))]
    pub baud: u32,
    /// Line faults: drop=P,flip=P (per byte), dup=P,trunc=P,stall=P (per frame), stall_ms=MS.
    #[arg(long, value_name = "drop=P,flip=P,dup=P,trunc=P")]
    pub faults: Option<Faults>,
    /// Seed of the simulated faults.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub seed: u64,
    /// EEPROM image file of the device (read at power-on; written on every change with --sim,
    /// at the end with --emulator).
    #[arg(long, value_name = "FILE")]
    pub sim_storage: Option<PathBuf>,
    /// Also make FILE a symbolic link to the port (removed at the end).
    #[arg(long, value_name = "FILE")]
    pub link: Option<PathBuf>,
}

/// Why the port could not be served.
#[derive(Debug, thiserror::Error)]
enum Error {
    #[error("--robot {0}: not a preset (shahriar2023, fernando2025)")]
    NotAPreset(String),
    #[error(transparent)]
    Link(#[from] link::Error),
    #[error("--link {}: {source}", path.display())]
    Symlink { path: PathBuf, source: io::Error },
    #[error("cannot catch SIGINT and SIGTERM: {0}")]
    Signals(String),
    #[error("stdout: {0}")]
    Stdout(io::Error),
}

/// A flag that SIGINT and SIGTERM set.
fn catch_signals() -> Result<Arc<AtomicBool>, Error> {
    let stop = Arc::new(AtomicBool::new(false));
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register(signal, stop.clone())
            .map_err(|e| Error::Signals(e.to_string()))?;
    }
    Ok(stop)
}

/// Runs `quadctl port` and returns its exit status.
pub fn main(args: &Args) -> ExitCode {
    match serve(args) {
        Ok(stats) => match args::print_json_line(&stats) {
            Ok(()) => ExitCode::from(args::EXIT_OK),
            Err(status) => status,
        },
        Err(e) => args::fail("quadctl", &e),
    }
}

fn serve(args: &Args) -> Result<PortStats, Error> {
    let preset = match &args.robot {
        Some(name) => {
            RobotPreset::from_name(name.trim()).ok_or_else(|| Error::NotAPreset(name.clone()))?
        }
        None => RobotPreset::Custom,
    };
    let target = TargetArgs {
        sim: args.sim,
        emulator: args.emulator,
        elf: args.elf.clone(),
        port: None,
        baud: args.baud,
        faults: args.faults,
        seed: args.seed,
        sim_compute_us: 0.0,
        sim_storage: args.sim_storage.clone(),
        retries: DEFAULT_RETRIES,
    }
    .target(preset);
    let stop = catch_signals()?;
    let mut device = link::open(&target)?;
    let mut port = VirtualPort::open()?;
    if let Some(path) = &args.link {
        let symlink = |path: &PathBuf| {
            if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
                std::fs::remove_file(path)?;
            }
            std::os::unix::fs::symlink(port.path(), path)
        };
        symlink(path).map_err(|source| Error::Symlink {
            path: path.clone(),
            source,
        })?;
    }
    {
        let mut out = io::stdout().lock();
        writeln!(out, "{}", port.path().display())
            .and_then(|()| out.flush())
            .map_err(Error::Stdout)?;
    }
    let served = port.serve(&mut *device, &stop);
    if let Some(path) = &args.link {
        let _ = std::fs::remove_file(path);
    }
    // The emulator's EEPROM image is written when its link is dropped.
    drop(device);
    Ok(served?)
}
