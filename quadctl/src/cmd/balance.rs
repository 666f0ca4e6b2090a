//! `quadctl status`, `watch` and `balance`: the device's state with its inertial sensor (the
//! health, the attitude, the leveling and a latched fall; protocol 2.3), once or live, and the
//! balance switch.

use crate::args::{self, DeviceRobotArgs, TargetArgs, EXIT_OK};
use clap::ValueEnum;
use quad_host::ops::onboard::{self, Session};
use quad_protocol::{
    BalanceConfig, FallKind, FaultAction, Flags, ImuFaultKind, ImuHealth, ImuReport, Readback,
    Request, SafeState,
};
use serde::Serialize;
use std::io::Write;
use std::process::ExitCode;
use std::time::Duration;

const STATUS_ABOUT: &str = "\
The device's state once: the outputs, the running motion, and its inertial sensor (protocol
2.3) — the health (absent, starting: the gyro bias is being measured in the first still
second, ok, or the fault), roll and pitch (degrees on the human line, rad in the JSON), the
leveling (on/off, active, its correction) and a latched fall.

Output: one human line, then one JSON object as the last line of stdout: outputs_enabled,
fall_detected, motion, imu (the device's report). Exit status: 0; 2 when the link failed or the
device speaks a protocol older than 2.3.";

/// `quadctl status --help`'s examples.
pub const STATUS_EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl status --robot shahriar2023 --sim
  quadctl status --robot shahriar2023 --port /dev/ttyACM0";

/// Arguments of `quadctl status`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(long_about = STATUS_ABOUT, after_help = STATUS_EXAMPLES)]
pub struct StatusArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub robot: DeviceRobotArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub target: TargetArgs,
}

const WATCH_ABOUT: &str = "\
The device's state live: the line of `quadctl status` every --period-ms (link time), --count
times (0: until interrupted). The simulated device (--sim) reads level and still: its sensor
reports starting for its first second, then ok.

Output: one human line per poll, then one JSON object as the last line of stdout: polls and the
last report. Exit status: 0; 2 when the link failed or the device is older than 2.3.";

/// `quadctl watch --help`'s examples.
pub const WATCH_EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl watch --robot shahriar2023 --sim --count 8 --period-ms 250
  quadctl watch --robot shahriar2023 --port /dev/ttyACM0";

/// Arguments of `quadctl watch`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(long_about = WATCH_ABOUT, after_help = WATCH_EXAMPLES)]
pub struct WatchArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub robot: DeviceRobotArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub target: TargetArgs,
    /// Time between two polls, ms.
    #[arg(long, value_name = "MS", default_value_t = 200, value_parser = clap::value_parser!(u64).range(10..))]
    pub period_ms: u64,
    /// Polls before stopping (0: until interrupted).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub count: u64,
}

const BALANCE_ABOUT: &str = "\
Configures the device's balance functions (protocol 2.3), starting from its settings in
effect: only the options given change. Leveling corrects the body's roll and pitch from the
measured attitude while a stance is held or a sway runs (a PI: --kp, --ki-per-s, bounded by
--max-correction-rad); fall detection stops the motion and puts the outputs in the safe state
(rest: the legs folded through the joint-speed limiter; off: no pulses) when |roll| or |pitch|
passes --fall-angle-rad or the robot falls freely, latched until the next motion command;
--on-fault says whether a motion continues open loop or stops when the sensor fails.

The numbers are checked against their ranges (docs/protocol.md, motion field ranges) before
sending. Leveling is refused by a device without a working sensor.

Output: the human line of `quadctl status`'s sensor part, then one JSON object (the device's
report with the settings as applied) as the last line of stdout. Exit status: 0; 2 refused or
the link failed.";

/// `quadctl balance --help`'s examples.
pub const BALANCE_EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl balance --robot shahriar2023 --sim --leveling on --kp 0.3 --ki-per-s 4
  quadctl balance --robot shahriar2023 --sim --fall-angle-rad 0.9 --safe-state off --on-fault stop
  quadctl balance --robot shahriar2023 --port /dev/ttyACM0 --leveling off";

/// On or off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Switch {
    /// Switched on.
    On,
    /// Switched off.
    Off,
}

/// The safe state after a fall.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Safe {
    /// The rest pose, through the joint-speed limiter.
    Rest,
    /// The outputs off.
    Off,
}

/// What a motion does when the sensor fails.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum OnFault {
    /// It continues open loop.
    OpenLoop,
    /// It stops cleanly.
    Stop,
}

/// Arguments of `quadctl balance`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(long_about = BALANCE_ABOUT, after_help = BALANCE_EXAMPLES)]
pub struct BalanceArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub robot: DeviceRobotArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub target: TargetArgs,
    /// Body leveling.
    #[arg(long, value_enum)]
    pub leveling: Option<Switch>,
    /// Leveling's proportional gain, rad per rad, in [0, 0.9].
    #[arg(long, value_name = "K", allow_negative_numbers = true)]
    pub kp: Option<f32>,
    /// Leveling's integral gain, 1/s, in [0, 20].
    #[arg(long, value_name = "K", allow_negative_numbers = true)]
    pub ki_per_s: Option<f32>,
    /// The largest leveling correction, rad, in [0, pi/4].
    #[arg(long, value_name = "RAD", allow_negative_numbers = true, value_parser = crate::args::parse_angle_rad)]
    pub max_correction_rad: Option<f32>,
    /// Fall detection.
    #[arg(long, value_enum)]
    pub fall_detection: Option<Switch>,
    /// |roll| or |pitch| beyond which the robot has fallen, rad, in [0.17, pi].
    #[arg(long, value_name = "RAD", allow_negative_numbers = true, value_parser = crate::args::parse_angle_rad)]
    pub fall_angle_rad: Option<f32>,
    /// Where the outputs go on a fall.
    #[arg(long, value_enum)]
    pub safe_state: Option<Safe>,
    /// What a running motion does when the sensor fails.
    #[arg(long, value_enum)]
    pub on_fault: Option<OnFault>,
}

impl BalanceArgs {
    /// `current` with the options given.
    fn apply(&self, current: BalanceConfig) -> BalanceConfig {
        let on = |s: Switch| s == Switch::On;
        BalanceConfig {
            leveling: self.leveling.map_or(current.leveling, on),
            level_kp: self.kp.unwrap_or(current.level_kp),
            level_ki_per_s: self.ki_per_s.unwrap_or(current.level_ki_per_s),
            max_correction_rad: self
                .max_correction_rad
                .unwrap_or(current.max_correction_rad),
            fall_detection: self.fall_detection.map_or(current.fall_detection, on),
            fall_angle_rad: self.fall_angle_rad.unwrap_or(current.fall_angle_rad),
            safe_state: match self.safe_state {
                Some(Safe::Rest) => SafeState::Rest,
                Some(Safe::Off) => SafeState::Off,
                None => current.safe_state,
            },
            on_fault: match self.on_fault {
                Some(OnFault::OpenLoop) => FaultAction::OpenLoop,
                Some(OnFault::Stop) => FaultAction::Stop,
                None => current.on_fault,
            },
        }
    }
}

/// What `status` (and each poll of `watch`) reports.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Status {
    /// The outputs are driven.
    pub outputs_enabled: bool,
    /// A fall was detected and is latched.
    pub fall_detected: bool,
    /// The motion running (`None` when idle).
    pub motion: Option<&'static str>,
    /// The device's report of its sensor and balance functions.
    pub imu: ImuReport,
}

fn session(
    robot: &DeviceRobotArgs,
    target: &TargetArgs,
) -> Result<Session<Box<dyn quad_host::link::Link>>, onboard::Error> {
    let device = target.target(robot.sim_preset());
    match &robot.robot {
        Some(r) => onboard::open(r, &device, target.retries),
        None => onboard::open_device_robot(&device, target.retries),
    }
}

fn poll<L: quad_host::link::Link>(s: &mut Session<L>) -> Result<Status, onboard::Error> {
    let imu = s.imu(Request::GetImu)?;
    let readback: Readback = s.state()?;
    let motion = s.get()?.status.kind.map(onboard::kind_name);
    Ok(Status {
        outputs_enabled: readback.flags.contains(Flags::OUTPUTS_ENABLED),
        fall_detected: readback.flags.contains(Flags::FALL_DETECTED),
        motion,
        imu,
    })
}

fn health_words(h: ImuHealth) -> String {
    match h {
        ImuHealth::Absent => "absent".to_owned(),
        ImuHealth::Starting => "starting".to_owned(),
        ImuHealth::Ok => "ok".to_owned(),
        ImuHealth::Fault(kind) => format!(
            "fault ({})",
            match kind {
                ImuFaultKind::WrongId => "wrong id",
                ImuFaultKind::Nak => "nak",
                ImuFaultKind::Stuck => "stuck",
                ImuFaultKind::BusHeld => "bus held",
            }
        ),
    }
}

/// The sensor's part of a status line: health, attitude in degrees, leveling, fall.
pub fn imu_line(r: &ImuReport) -> String {
    let leveling = match (r.config.leveling, r.leveling_active) {
        (false, _) => "off".to_owned(),
        (true, false) => "on (waiting)".to_owned(),
        (true, true) => format!(
            "on, correction roll {:+.2}° pitch {:+.2}°{}",
            r.correction_roll_rad.to_degrees(),
            r.correction_pitch_rad.to_degrees(),
            if r.correction_limited {
                " (limited)"
            } else {
                ""
            }
        ),
    };
    let fall = match r.fall {
        None => "none",
        Some(FallKind::Tilt) => "tilt (latched)",
        Some(FallKind::FreeFall) => "free fall (latched)",
    };
    format!(
        "imu {}  roll {:+.2}°  pitch {:+.2}°  leveling {}  fall {}  samples {}",
        health_words(r.health),
        r.roll_rad.to_degrees(),
        r.pitch_rad.to_degrees(),
        leveling,
        fall,
        r.samples
    )
}

fn status_line(s: &Status) -> String {
    format!(
        "{}  motion {}  outputs {}",
        imu_line(&s.imu),
        s.motion.unwrap_or("none"),
        if s.outputs_enabled { "on" } else { "off" }
    )
}

fn print_line(line: &str) -> Result<(), ExitCode> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{line}")
        .and_then(|()| out.flush())
        .map_err(|e| args::fail("quadctl", &e))
}

/// Runs `quadctl status`.
pub fn status(args: &StatusArgs) -> ExitCode {
    let result = session(&args.robot, &args.target).and_then(|mut s| poll(&mut s));
    match result {
        Ok(st) => match print_line(&status_line(&st)).and_then(|()| args::print_json_line(&st)) {
            Ok(()) => ExitCode::from(EXIT_OK),
            Err(code) => code,
        },
        Err(e) => args::fail("quadctl", &e),
    }
}

/// What `watch` reports at its end.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WatchSummary {
    /// Polls made.
    pub polls: u64,
    /// The last one.
    pub last: Status,
}

/// Runs `quadctl watch`.
pub fn watch(args: &WatchArgs) -> ExitCode {
    let mut s = match session(&args.robot, &args.target) {
        Ok(s) => s,
        Err(e) => return args::fail("quadctl", &e),
    };
    let period = Duration::from_millis(args.period_ms);
    let mut polls = 0u64;
    let mut last = None;
    while args.count == 0 || polls < args.count {
        let next = s.now() + period;
        let st = match poll(&mut s) {
            Ok(st) => st,
            Err(e) => return args::fail("quadctl", &e),
        };
        polls += 1;
        let line = format!("t {:>8.2} s  {}", s.now().as_secs_f64(), status_line(&st));
        if let Err(code) = print_line(&line) {
            return code;
        }
        last = Some(st);
        if args.count != 0 && polls >= args.count {
            break;
        }
        if let Err(e) = s.client_mut().idle_until(next) {
            return args::fail("quadctl", &e);
        }
    }
    match last {
        Some(last) => match args::print_json_line(&WatchSummary { polls, last }) {
            Ok(()) => ExitCode::from(EXIT_OK),
            Err(code) => code,
        },
        None => ExitCode::from(EXIT_OK),
    }
}

/// Runs `quadctl balance`.
pub fn balance(args: &BalanceArgs) -> ExitCode {
    let result = session(&args.robot, &args.target).and_then(|mut s| {
        let current = s.imu(Request::GetImu)?.config;
        s.imu(Request::SetBalance(args.apply(current)))
    });
    match result {
        Ok(report) => {
            match print_line(&imu_line(&report)).and_then(|()| args::print_json_line(&report)) {
                Ok(()) => ExitCode::from(EXIT_OK),
                Err(code) => code,
            }
        }
        Err(e) => args::fail("quadctl", &e),
    }
}
