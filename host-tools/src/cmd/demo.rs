//! `quadctl demo`: the whole chain on an emulated Arduino Mega (or a real one): the firmware
//! built from `firmware-avr/`, booted in simavr, driven with seed 000's body-pose sweeps; every
//! readback checked against the host's own kin-core and every pulse on the twelve servo pins
//! against the readbacks; a short human summary.

use super::EXIT_FATAL;
use crate::client::{
    AngleCheck, Client, ClientConfig, PoseResult, PoseStream, StreamSetup, AVR_ANGLE_TOLERANCE_RAD,
    DEFAULT_RETRIES,
};
use crate::emu::{build, elf};
use crate::link::emulator::{EmulatorConfig, EmulatorLink};
use crate::link::serial::SerialLink;
use crate::link::Link;
use kin_core::motion::laws::{Axis, Sway, SwayParams, SEED000_SWEEP_STANCE_HEIGHT_M};
use kin_core::motion::Motion;
use kin_core::{Robot, RotationOrder};
use quad_protocol::RobotPreset;
use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// Exit status when a readback, a nack or a pulse disagreed with the host.
pub const EXIT_CHECK_FAILED: u8 = 3;

/// Default poses per sweep.
pub const DEFAULT_POSES_PER_SWEEP: usize = 100;

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
at --poses-per-sweep poses and streamed as fast as the link allows.

Checks: every pose is acked with the 12 angles of the host's own kin-core (within 5e-5 rad: the
AVR's math differs) and the 12 pulses of the device calibration's mapping of those angles; on the
emulator every pulse measured on the 12 servo pins (Timer1/3/4/5, port L included) must match
the readback in force within one 0.5 us timer tick. Times are simulated time on the emulator.

Exit status: 0 every check passed; 2 the firmware could not be built or the link failed; 3 a
check failed.";

/// Arguments of `quadctl demo`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Demo: body-pose sweeps on the firmware in an emulated Mega (or --port), all checked",
    long_about = LONG_ABOUT
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
    #[arg(long, value_name = "N", default_value_t = DEFAULT_POSES_PER_SWEEP, value_parser = clap::value_parser!(usize))]
    pub poses_per_sweep: usize,
}

/// What the demo measured.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Summary {
    /// Poses sent.
    pub sent: u64,
    /// Poses acked with a readback that passed the check.
    pub acked: u64,
    /// Poses nacked (with the host's own reason).
    pub nacked: u64,
    /// Poses without an answer.
    pub lost: u64,
    /// Readbacks that disagreed with the host.
    pub mismatches: u64,
    /// Largest |device − host| angle, rad.
    pub max_angle_err_rad: f32,
    /// Pulses measured on the pins (emulator only).
    pub pulses_checked: Option<u64>,
    /// Pulses whose width matched no readback in force (emulator only).
    pub pulse_width_errors: Option<u64>,
    /// The first pulse error, described.
    pub first_pulse_error: Option<String>,
    /// Answered poses per second of link time.
    pub poses_per_s: f64,
    /// Mean command → readback time, link time.
    pub latency_mean: Duration,
    /// Longest command → readback time, link time.
    pub latency_max: Duration,
    /// Resends.
    pub retries: u64,
}

impl Summary {
    /// True when every check passed.
    pub fn passed(&self) -> bool {
        self.acked + self.nacked == self.sent
            && self.nacked == 0
            && self.lost == 0
            && self.mismatches == 0
            && self.pulse_width_errors.unwrap_or(0) == 0
            && self.pulses_checked != Some(0)
    }
}

/// The demo's poses: seed 000's roll, pitch and yaw sweeps, `n` samples of one period each.
///
/// # Errors
/// A motion that does not validate (cannot happen for the paper's values).
pub fn poses(n: usize) -> Result<Vec<kin_core::Pose>, String> {
    let mut out = Vec::with_capacity(3 * n);
    for axis in [Axis::Roll, Axis::Pitch, Axis::Yaw] {
        let sway = Sway::new(SwayParams::seed000(axis)).map_err(|e| e.to_string())?;
        let period = sway.params().period_s;
        for k in 0..n {
            let t = period * k as f32 / n as f32;
            out.push(sway.frame(t).map_err(|e| e.to_string())?.pose);
        }
    }
    Ok(out)
}

/// Streams `poses` and checks them (see the module docs).
///
/// # Errors
/// Link failures and handshake errors, as messages.
pub fn stream<L: Link>(
    link: L,
    config: ClientConfig,
    poses: &[kin_core::Pose],
    mut progress: impl FnMut(&PoseStream<L>, usize),
) -> Result<(PoseStream<L>, Summary), String> {
    let setup = StreamSetup {
        robot: Robot::shahriar2023(),
        preset: RobotPreset::Shahriar2023,
        stance_height_m: Some(SEED000_SWEEP_STANCE_HEIGHT_M),
        order: Some(RotationOrder::Zyx),
        check: AngleCheck::Within(AVR_ANGLE_TOLERANCE_RAD),
    };
    let mut stream =
        PoseStream::connect(Client::new(link, config), setup).map_err(|e| e.to_string())?;
    let mut latency_sum = Duration::ZERO;
    let mut latency_max = Duration::ZERO;
    for (i, pose) in poses.iter().enumerate() {
        let t0 = stream.client().link().now();
        let result = stream.send(pose).map_err(|e| e.to_string())?;
        let dt = stream.client().link().now().saturating_sub(t0);
        latency_sum += dt;
        latency_max = latency_max.max(dt);
        if let PoseResult::Mismatch(what) = &result {
            eprintln!("  pose {i}: READBACK MISMATCH: {what}");
        }
        progress(&stream, i + 1);
    }
    let s = stream.stats();
    let summary = Summary {
        sent: s.sent,
        acked: s.acked,
        nacked: s.nacked,
        lost: s.lost,
        mismatches: s.readback_mismatches,
        max_angle_err_rad: s.max_angle_err_rad,
        poses_per_s: s.poses_per_s,
        latency_mean: latency_sum / poses.len().max(1) as u32,
        latency_max,
        retries: s.retries,
        ..Summary::default()
    };
    Ok((stream, summary))
}

/// Runs `quadctl demo`.
pub fn main(args: &Args) -> ExitCode {
    let stdout = io::stdout();
    let mut out = stdout.lock();
    match run(args, &mut out) {
        Ok(summary) if summary.passed() => ExitCode::SUCCESS,
        Ok(_) => ExitCode::from(EXIT_CHECK_FAILED),
        Err(message) => {
            let _ = out.flush();
            eprintln!("quadctl demo: error: {message}");
            ExitCode::from(EXIT_FATAL)
        }
    }
}

/// Runs the demo, printing the summary to `out`.
///
/// # Errors
/// A message when the firmware cannot be built or booted, or the link fails.
pub fn run(args: &Args, out: &mut dyn Write) -> Result<Summary, String> {
    let io_err = |e: io::Error| e.to_string();
    if args.poses_per_sweep == 0 {
        return Err("--poses-per-sweep must be at least 1".into());
    }
    let poses = poses(args.poses_per_sweep)?;
    let wall = Instant::now();
    let (summary, target) = if let Some(port) = &args.port {
        writeln!(
            out,
            "quadctl demo: Arduino Mega on {port}, {} baud",
            args.baud
        )
        .map_err(io_err)?;
        let link = SerialLink::open(port, args.baud).map_err(|e| e.to_string())?;
        let config = ClientConfig {
            retries: DEFAULT_RETRIES,
            ..ClientConfig::serial()
        };
        let (stream, summary) = stream(link, config, &poses, |_, _| {})?;
        let info = *stream.info();
        (summary, describe_info(&info))
    } else {
        let elf_path = match &args.elf {
            Some(p) => p.clone(),
            None => {
                let bin = build::firmware_for_baud(args.baud).ok_or_else(|| {
                    format!(
                        "no firmware is built for {} baud: use 115200 or 1000000",
                        args.baud
                    )
                })?;
                write!(
                    out,
                    "building the firmware (cd firmware-avr && cargo build --release) ... "
                )
                .map_err(io_err)?;
                out.flush().map_err(io_err)?;
                let path = build::firmware_elf(bin).map_err(|e| e.to_string())?;
                writeln!(out, "ok").map_err(io_err)?;
                path
            }
        };
        let sizes = elf::sizes(&elf_path).map_err(|e| e.to_string())?;
        writeln!(
            out,
            "quadctl demo: {} ({:.1} KB flash, {} B static SRAM) on an emulated ATmega2560 \
             (simavr, 16 MHz), {} baud",
            elf_path.display(),
            sizes.flash_bytes as f64 / 1024.0,
            sizes.sram_static_bytes,
            args.baud
        )
        .map_err(io_err)?;
        let link = EmulatorLink::boot(&elf_path, EmulatorConfig::new(args.baud))
            .map_err(|e| e.to_string())?;
        let (mut stream, mut summary) = stream(link, ClientConfig::emulator(), &poses, |_, _| {})?;
        let info = *stream.info();
        let link = stream.client_mut().link_mut();
        let pulses = link.pulse_stats();
        summary.pulses_checked = Some(pulses.checked);
        summary.pulse_width_errors = Some(pulses.errors);
        summary.first_pulse_error = pulses.first_error;
        let resets = link.mcu().resets().count;
        let mut target = describe_info(&info);
        target.push_str(&format!(
            "\n  MCU: {resets} resets, stack peak {} B",
            link.mcu().stack_peak_bytes()
        ));
        (summary, target)
    };
    print_summary(out, &summary, &target, args.poses_per_sweep, wall.elapsed()).map_err(io_err)?;
    Ok(summary)
}

fn describe_info(info: &quad_protocol::DeviceInfo) -> String {
    format!(
        "  device: protocol {}.{}, firmware {}.{}.{}, robot {:?}",
        info.version >> 8,
        info.version & 0xFF,
        info.firmware.major,
        info.firmware.minor,
        info.firmware.patch,
        info.robot
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sweeps_cover_the_papers_ranges_and_solve() {
        let p = poses(40).unwrap();
        assert_eq!(p.len(), 120);
        let max = |f: fn(&kin_core::Pose) -> f32| p.iter().map(f).fold(0.0f32, f32::max);
        assert!((max(|q| q.roll_rad).to_degrees() - 28.0).abs() < 0.5);
        assert!((max(|q| q.pitch_rad).to_degrees() - 21.0).abs() < 0.5);
        assert!((max(|q| q.yaw_rad).to_degrees() - 21.0).abs() < 0.5);
        let robot = Robot::shahriar2023();
        for q in &p {
            kin_core::body::Solver::new(&robot)
                .inverse_at_stance(
                    q,
                    &kin_core::BodyConfig::default(),
                    SEED000_SWEEP_STANCE_HEIGHT_M,
                    kin_core::ReachPolicy::Reject,
                )
                .expect("every demo pose is reachable");
        }
    }
}
