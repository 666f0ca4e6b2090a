//! `quadctl demo`: the whole chain on an emulated Arduino Mega (or a real one): the firmware
//! built from `firmware-avr/`, booted in simavr, driven with seed 000's body-pose sweeps; every
//! readback checked against the host's own kin-core and every pulse on the twelve servo pins
//! against the readbacks; then the device's own motions (stand-up, seed 001's sways and yaw
//! turn, a trot with a changing velocity, sit), checked against the host's kin-core; a short
//! human summary.

use crate::args::{self, EXIT_CHECK_FAILED};
use quad_host::client::AVR_ANGLE_TOLERANCE_RAD;
use quad_host::ops::demo::{self, Request, Summary};
use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

const LONG_ABOUT: &str = "\
Runs the whole chain and prints a short summary: the host streams body poses, the ATmega2560
firmware solves the full-body IK onboard and drives 12 servo outputs, and the host checks every
answer.

Default target: the real firmware (built from firmware-avr/ if needed: nightly toolchain with
rust-src, gcc-avr, avr-libc; scripts/install-deps.sh installs them) running in simavr in-process
at 16 MHz, no hardware needed. --port PATH drives an Arduino Mega 2560 flashed with the firmware
(scripts/flash.sh) instead.

Motion: seed 000's pose sweeps on its robot (shahriar2023) at the stance height 0.40 m, rotation
order zyx — roll +-28 deg, then pitch +-21 deg, then yaw +-21 deg, one sine period each, sampled
at --poses-per-sweep poses and streamed as fast as the link allows. Then the device's own
motions (--sweeps-only leaves them out): stand-up, seed 001's roll and pitch sways and yaw turn
(counter-clockwise), a trot and a walk whose velocity commands change, sit.

Checks: every pose is acked with the 12 angles of the host's own kin-core (within 2e-5 rad: the
AVR's math differs) and the 12 pulses of the device calibration's mapping of those angles; on the
emulator every pulse measured on the 12 servo pins (Timer1/3/4/5, port L included) must match
the readback in force within one 0.5 us timer tick (or lie on the joint-speed limiter's way to
it). The onboard motions: every answer's pulses and (sways, yaw turn) angles against the host's
kin-core law at the device's motion time, the stance and rest poses at the ends, and on the
emulator the pins against the host's calibration mapping; stand-up, the trot, the walk and sit
replayed frame by frame by the host (the device's engine on the host's kin-core, fed with the
frames at which the device reports each velocity command and the stop took effect): every
answer's angles and every PWM period on the pins. Times are simulated time on the emulator.

Exit status: 0 every check passed; 2 the firmware could not be built or the link failed; 3 a
check failed.";

/// `--help`'s examples, run from the repository root (the files of `examples/`).
pub const EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl demo
  quadctl demo --poses-per-sweep 20 --baud 1000000
  quadctl demo --port /dev/ttyACM0";

/// Arguments of `quadctl demo`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Demo: body-pose sweeps and the onboard motions on the firmware in an emulated Mega (or --port), all checked",
    long_about = LONG_ABOUT,
    after_help = EXAMPLES
)]
pub struct Args {
    /// Drive a real Arduino Mega on this serial port instead of the emulator.
    #[arg(long, value_name = "PATH")]
    pub port: Option<String>,
    /// Line rate, bit/s: 115200 (firmware.elf) or 1000000 (firmware-1mbaud.elf).
    #[arg(long, value_name = "B", default_value_t = 115_200)]
    pub baud: u32,
    /// Firmware ELF for the emulator; default: built from firmware-avr/ for --baud.
    #[arg(long, value_name = "PATH", conflicts_with = "port")]
    pub elf: Option<PathBuf>,
    /// Poses per sweep (three sweeps).
    #[arg(long, value_name = "N", default_value_t = demo::DEFAULT_POSES_PER_SWEEP, value_parser = clap::value_parser!(usize))]
    pub poses_per_sweep: usize,
    /// Only the pose sweeps: leave out the device's own motions that follow them (stand-up,
    /// seed 001's roll and pitch sways, the yaw turn, a trot with a changing velocity and sit,
    /// every answer and, on the emulator, pin checked against the host's kin-core).
    #[arg(long)]
    pub sweeps_only: bool,
}

/// Runs `quadctl demo`.
pub fn main(args: &Args) -> ExitCode {
    let stdout = io::stdout();
    let mut out = stdout.lock();
    let request = Request {
        port: args.port.clone(),
        baud: args.baud,
        elf: args.elf.clone(),
        poses_per_sweep: args.poses_per_sweep,
        motions: !args.sweeps_only,
    };
    let run = match demo::run(&request, &mut out) {
        Ok(run) => run,
        Err(e) => {
            let _ = out.flush();
            return args::fail("quadctl demo", &e);
        }
    };
    for (i, what) in &run.mismatches {
        eprintln!("  pose {i}: READBACK MISMATCH: {what}");
    }
    let mut target = describe_info(&run.info);
    if let Some(mcu) = run.mcu {
        target.push_str(&format!(
            "\n  MCU: {} resets, stack peak {} B, longest interrupts-off stretch while receiving \
             {} cycles",
            mcu.resets, mcu.stack_peak_bytes, mcu.interrupts_off_receiving_cycles
        ));
    }
    if let Err(e) = print_summary(
        &mut out,
        &run.summary,
        &target,
        args.poses_per_sweep,
        run.wall,
    ) {
        return args::fail("quadctl demo", &e);
    }
    if let Some(legs) = &run.motions {
        for l in legs {
            let line = format!(
                "  onboard {}: {} answers, {} angle checks (largest |device − host| {:.1e} rad), \
                 {} pins, {} frames replayed, {} errors, {:.1} s of motion",
                l.motion,
                l.answers,
                l.angles_checked,
                l.max_angle_err_rad,
                l.pins_checked,
                l.frames_checked,
                l.errors,
                l.motion_s
            );
            if let Err(e) = writeln!(out, "{line}") {
                return args::fail("quadctl demo", &e);
            }
            if let Some(first) = &l.first_error {
                eprintln!("    first: {first}");
            }
        }
        let verdict = if run.passed() { "PASS" } else { "FAIL" };
        if let Err(e) = writeln!(out, "  onboard result: {verdict}") {
            return args::fail("quadctl demo", &e);
        }
    }
    if run.passed() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(EXIT_CHECK_FAILED)
    }
}

fn describe_info(info: &quad_protocol::DeviceInfo) -> String {
    format!(
        "  device: protocol {}.{}, firmware {}.{}.{}, robot {}",
        info.version >> 8,
        info.version & 0xFF,
        info.firmware.major,
        info.firmware.minor,
        info.firmware.patch,
        quad_host::names::robot_preset_name(info.robot)
    )
}

fn print_summary(
    out: &mut dyn Write,
    s: &Summary,
    target: &str,
    per_sweep: usize,
    wall: Duration,
) -> io::Result<()> {
    writeln!(out, "{target}")?;
    writeln!(
        out,
        "  motion: seed 000 pose sweeps (roll ±28°, pitch ±21°, yaw ±21°), {per_sweep} poses \
         each, stance 0.40 m, order zyx"
    )?;
    writeln!(
        out,
        "  poses: {} sent, {} acked, {} nacked, {} lost, {} readback mismatches, {} retries",
        s.sent, s.acked, s.nacked, s.lost, s.mismatches, s.retries
    )?;
    writeln!(
        out,
        "  angles: largest |device − host| {:.1e} rad ({:.4}°; bound {:.0e} rad)",
        s.max_angle_err_rad,
        s.max_angle_err_rad.to_degrees(),
        AVR_ANGLE_TOLERANCE_RAD
    )?;
    match (s.pulses_checked, s.pulse_width_errors) {
        (Some(c), Some(e)) => {
            writeln!(
                out,
                "  pins: {c} pulses measured on the 12 servo outputs, {e} off their readback by \
                 more than 0.5 µs"
            )?;
            if let Some(first) = &s.first_pulse_error {
                writeln!(out, "    first: {first}")?;
            }
        }
        _ => writeln!(out, "  pins: not measured (real board)")?,
    }
    if let Some(n) = s.rx_overruns {
        writeln!(
            out,
            "  receive: {n} bytes lost by the chip's two-byte receive buffer (data overruns)"
        )?;
    }
    writeln!(
        out,
        "  timing ({}): {:.1} poses/s, command → readback {:.1} ms mean, {:.1} ms max",
        if s.pulses_checked.is_some() {
            "simulated"
        } else {
            "wall clock"
        },
        s.poses_per_s,
        s.latency_mean.as_secs_f64() * 1e3,
        s.latency_max.as_secs_f64() * 1e3
    )?;
    writeln!(
        out,
        "  result: {} (in {:.1} s)",
        if s.passed() { "PASS" } else { "FAIL" },
        wall.as_secs_f64()
    )
}
