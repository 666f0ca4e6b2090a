//! The whole chain on an emulated Arduino Mega (or a real one): the firmware built from
//! `firmware-avr/`, booted in simavr, driven with seed 000's body-pose sweeps; every readback
//! checked against the host's own kin-core and every pulse on the twelve servo pins against the
//! readbacks. The operation behind `quadctl demo`.

use crate::client::{
    self, AngleCheck, Client, ClientConfig, Mismatch, PoseResult, PoseStream, StreamSetup,
    AVR_ANGLE_TOLERANCE_RAD, DEFAULT_RETRIES,
};
use crate::emu::{build, elf};
use crate::link::emulator::{EmulatorConfig, PulseStats};
use crate::link::{self, Link, Target};
use kin_core::motion::laws::{Axis, Sway, SwayParams};
use kin_core::motion::Motion;
use kin_core::{DefaultMath, Robot};
use quad_protocol::{DeviceInfo, RobotPreset};
use std::io::{self, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Default poses per sweep.
pub const DEFAULT_POSES_PER_SWEEP: usize = 100;

/// What [`run`] is asked.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// A real Arduino Mega on this serial port instead of the emulator.
    pub port: Option<String>,
    /// Line rate, bit/s: 115200 (firmware.elf) or 1000000 (firmware-1mbaud.elf).
    pub baud: u32,
    /// Firmware ELF for the emulator; `None`: built from firmware-avr/ for `baud`.
    pub elf: Option<PathBuf>,
    /// Poses per sweep (three sweeps).
    pub poses_per_sweep: usize,
    /// After the sweeps, the device's own motions ([`crate::ops::demo_motions`]).
    pub motions: bool,
}

/// Why the demo could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// No pose to send.
    #[error("--poses-per-sweep must be at least 1")]
    NoPoses,
    /// A sweep law refused its parameters (cannot happen for the paper's values).
    #[error("the seed 000 sweep: {0}")]
    Motion(#[from] kin_core::motion::Error),
    /// No firmware is built for this line rate.
    #[error("no firmware is built for {0} baud: use 115200 or 1000000")]
    NoFirmwareForBaud(u32),
    /// The firmware could not be built.
    #[error(transparent)]
    Build(#[from] build::Error),
    /// The firmware's ELF could not be read.
    #[error(transparent)]
    Elf(#[from] elf::Error),
    /// The link could not be opened.
    #[error(transparent)]
    Link(#[from] link::Error),
    /// The handshake or the link failed.
    #[error(transparent)]
    Client(#[from] client::Error),
    /// Writing the log failed.
    #[error("cannot write the output: {0}")]
    Io(#[from] io::Error),
    /// An onboard motion was refused or stopped early.
    #[error("the device's own motions: {0}")]
    Motions(#[from] crate::ops::onboard::Error),
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
    /// Bytes the chip's receive buffer lost (emulator only).
    pub rx_overruns: Option<u64>,
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
            && self.rx_overruns.unwrap_or(0) == 0
    }
}

/// The device the demo runs: the firmware's shahriar2023 configuration.
const DEVICE: quad_device::Config = quad_device::Config::shahriar2023();

/// The demo's poses: seed 000's roll, pitch and yaw sweeps, `n` samples of one period each.
///
/// # Errors
/// A motion that does not validate (cannot happen for the paper's values).
pub fn poses(n: usize) -> Result<Vec<kin_core::Pose>, Error> {
    let mut out = Vec::with_capacity(3 * n);
    for axis in [Axis::Roll, Axis::Pitch, Axis::Yaw] {
        let sway = Sway::new(SwayParams::seed000(axis))?;
        let period = sway.params().period_s;
        for k in 0..n {
            let t = period * k as f32 / n as f32;
            out.push(sway.frame::<DefaultMath>(t)?.pose);
        }
    }
    Ok(out)
}

/// Streams `poses` and checks them (see the module docs); `progress` sees every pose's index
/// and result as it comes.
///
/// # Errors
/// Link failures and handshake errors.
pub fn stream<L: Link>(
    link: L,
    config: ClientConfig,
    poses: &[kin_core::Pose],
    mut progress: impl FnMut(&PoseStream<L>, usize, &PoseResult),
) -> Result<(PoseStream<L>, Summary), client::Error> {
    let setup = StreamSetup {
        robot: Robot::shahriar2023(),
        preset: RobotPreset::Shahriar2023,
        // The firmware's own stance and order (quad_device::Config, the one source).
        stance_height_m: Some(DEVICE.pose_config.stance_height_m),
        order: Some(DEVICE.pose_config.order),
        check: AngleCheck::Within(AVR_ANGLE_TOLERANCE_RAD),
    };
    let mut stream = PoseStream::connect(Client::new(link, config), setup)?;
    let mut latency_sum = Duration::ZERO;
    let mut latency_max = Duration::ZERO;
    for (i, pose) in poses.iter().enumerate() {
        let t0 = stream.client().link().now();
        let result = stream.send(pose)?;
        let dt = stream.client().link().now().saturating_sub(t0);
        latency_sum += dt;
        latency_max = latency_max.max(dt);
        progress(&stream, i, &result);
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

/// The emulated MCU after the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Mcu {
    /// Resets seen (0 unless the watchdog fired).
    pub resets: u32,
    /// Deepest stack, bytes.
    pub stack_peak_bytes: u16,
    /// The longest stretch with interrupts off while bytes were arriving, cycles.
    pub interrupts_off_receiving_cycles: u64,
}

/// What the demo did.
#[derive(Debug, Clone, PartialEq)]
pub struct Demo {
    /// The checks.
    pub summary: Summary,
    /// The device's `HelloAck`.
    pub info: DeviceInfo,
    /// The emulated MCU; `None` on a real board.
    pub mcu: Option<Mcu>,
    /// Wall time of the run.
    pub wall: Duration,
    /// The poses whose readback disagreed with the host: index and what disagreed.
    pub mismatches: Vec<(usize, Mismatch)>,
    /// The onboard motions and their checks, when asked for.
    pub motions: Option<Vec<crate::ops::demo_motions::Leg>>,
}

impl Demo {
    /// True when every check passed, the onboard motions' included.
    pub fn passed(&self) -> bool {
        self.summary.passed()
            && self
                .motions
                .as_ref()
                .is_none_or(|legs| legs.iter().all(|l| l.errors == 0))
    }
}

/// Runs the demo, writing what it sets up (the firmware build, the target) to `log` as it
/// goes.
///
/// # Errors
/// See [`Error`].
pub fn run(args: &Request, log: &mut dyn Write) -> Result<Demo, Error> {
    if args.poses_per_sweep == 0 {
        return Err(Error::NoPoses);
    }
    let poses = poses(args.poses_per_sweep)?;
    let wall = Instant::now();
    let target = if let Some(port) = &args.port {
        writeln!(
            log,
            "quadctl demo: Arduino Mega on {port}, {} baud",
            args.baud
        )?;
        Target::Serial {
            path: port.clone(),
            baud: args.baud,
        }
    } else {
        let elf_path = match &args.elf {
            Some(p) => p.clone(),
            None => {
                let bin = build::firmware_for_baud(args.baud)
                    .ok_or(Error::NoFirmwareForBaud(args.baud))?;
                write!(
                    log,
                    "building the firmware (cd firmware-avr && cargo build --release) ... "
                )?;
                log.flush()?;
                let path = build::firmware_elf(bin)?;
                writeln!(log, "ok")?;
                path
            }
        };
        let sizes = elf::sizes(&elf_path)?;
        writeln!(
            log,
            "quadctl demo: {} ({:.1} KB flash, {} B static SRAM) on an emulated ATmega2560 \
             (simavr, 16 MHz), {} baud",
            elf_path.display(),
            sizes.flash_bytes as f64 / 1024.0,
            sizes.sram_static_bytes,
            args.baud
        )?;
        Target::Emulator {
            elf: Some(elf_path),
            config: EmulatorConfig::new(args.baud),
            storage: None,
        }
    };
    let link = link::open(&target)?;
    let config = ClientConfig::for_target(&target, DEFAULT_RETRIES);
    let mut mismatches = Vec::new();
    let (mut stream, summary) = stream(link, config, &poses, |_, i, result| {
        if let PoseResult::Mismatch(what) = result {
            mismatches.push((i, *what));
        }
    })?;
    let info = *stream.info();
    // The sweeps' pin check: the readbacks explain every pulse of the sweeps. During the
    // onboard motions the device moves its outputs at every frame between answers; their pins
    // are checked against the host's kin-core by the motions' own check.
    let sweep_pins = stream
        .client_mut()
        .link_mut()
        .emulator()
        .map(|link| link.pulse_stats());
    let mut motions = None;
    if args.motions {
        writeln!(log, "quadctl demo: the device's own motions")?;
        let mut session =
            crate::ops::onboard::Session::connect(stream.into_client(), RobotPreset::Shahriar2023)?;
        let legs = crate::ops::demo_motions::run_tour(
            &mut session,
            &Robot::shahriar2023(),
            AngleCheck::Within(AVR_ANGLE_TOLERANCE_RAD),
            crate::ops::demo_motions::full_tour,
            |_| {},
        )?;
        motions = Some(legs);
        return finish(
            session.client_mut(),
            Sweeps {
                summary,
                pins: sweep_pins,
                mismatches,
            },
            info,
            wall,
            motions,
        );
    }
    finish(
        stream.client_mut(),
        Sweeps {
            summary,
            pins: sweep_pins,
            mismatches,
        },
        info,
        wall,
        motions,
    )
}

/// What the pose sweeps gave: the stream's summary, the pin check at their end and the
/// readback mismatches.
struct Sweeps {
    summary: Summary,
    pins: Option<PulseStats>,
    mismatches: Vec<(usize, Mismatch)>,
}

/// The pin statistics and the MCU of an emulated run, and the result.
fn finish<L: Link>(
    client: &mut Client<L>,
    sweeps: Sweeps,
    info: DeviceInfo,
    wall: Instant,
    motions: Option<Vec<crate::ops::demo_motions::Leg>>,
) -> Result<Demo, Error> {
    let Sweeps {
        mut summary,
        pins,
        mismatches,
    } = sweeps;
    if let Some(pulses) = pins {
        summary.pulses_checked = Some(pulses.checked);
        summary.pulse_width_errors = Some(pulses.errors);
        summary.first_pulse_error = pulses.first_error;
    }
    let mcu = client.link_mut().emulator().map(|link| {
        summary.rx_overruns = Some(link.rx_overruns());
        Mcu {
            resets: link.mcu().resets().count,
            stack_peak_bytes: link.mcu().stack_peak_bytes(),
            interrupts_off_receiving_cycles: link.mcu().interrupts_off().longest_receiving_cycles,
        }
    });
    Ok(Demo {
        summary,
        info,
        mcu,
        wall: wall.elapsed(),
        mismatches,
        motions,
    })
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
                    kin_core::motion::laws::SEED000_SWEEP_STANCE_HEIGHT_M,
                    kin_core::ReachPolicy::Reject,
                )
                .expect("every demo pose is reachable");
        }
    }
}
