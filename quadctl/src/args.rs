//! What the commands share: the exit codes, the arguments used by several commands
//! (`--robot`, `--input`, the device target, a law's parameters), the value parsers, the
//! batch driver and the one place where errors become exit codes.

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use kin_core::motion::path::PathKind;
use kin_core::{KneeBend, LegId, ReachPolicy, Robot, RotationOrder, Vec3};
use quad_host::client::DEFAULT_RETRIES;
use quad_host::csv::play::ColumnKind;
use quad_host::csv::{self, Input, Summary};
use quad_host::link::emulator::EmulatorConfig;
use quad_host::link::sim::{SimConfig, DEFAULT_RX_FIFO_LEN};
use quad_host::link::{Faults, Target};
use quad_host::names;
use quad_host::ops::accuracy::Angles;
use quad_host::ops::batch::PoseFormat;
use quad_host::ops::motion::{Law, Params};
use quad_host::ops::session::Session;
use quad_host::robot_file;
use quad_protocol::RobotPreset;
use std::fmt;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

/// Exit status when every record was answered (reachable or not).
pub const EXIT_OK: u8 = 0;
/// Exit status when at least one record was malformed (the others were answered).
pub const EXIT_MALFORMED: u8 = 1;
/// Exit status when nothing or not everything could be processed: bad arguments, unreadable or
/// invalid robot file, unreadable input, a foreign header, or an output error.
pub const EXIT_FATAL: u8 = 2;
/// Exit status when a readback, a nack or a pulse disagreed with the host (`stream`, `demo`).
pub const EXIT_CHECK_FAILED: u8 = 3;
/// Exit status of `stream` and `play` when every check passed but at least one pose or row was
/// refused by the device (nacked) or lost (no answer after every retry); `--allow-refused`
/// turns it back into [`EXIT_OK`].
pub const EXIT_REFUSED: u8 = 4;

/// The one place where an error becomes an exit status: reported on stderr as
/// `<prefix>: error: <message>`, then [`EXIT_FATAL`].
pub fn fail(prefix: &str, e: &dyn std::error::Error) -> ExitCode {
    // Nothing useful can be done if stderr itself fails.
    let _ = writeln!(io::stderr(), "{prefix}: error: {e}");
    ExitCode::from(EXIT_FATAL)
}

/// Writes `summary` to stdout as one JSON line (a command's last line); `Err` carries the
/// [`fail`] status when it cannot be encoded or written.
pub fn print_json_line<T: serde::Serialize>(summary: &T) -> Result<(), ExitCode> {
    let json = serde_json::to_string(summary).map_err(|e| fail("quadctl", &e))?;
    let mut out = io::stdout().lock();
    writeln!(out, "{json}")
        .and_then(|()| out.flush())
        .map_err(|e| fail("quadctl", &e))
}

/// [`EXIT_OK`], or [`fail`] with `quadctl`.
pub fn exit_status<E: std::error::Error>(result: Result<(), E>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::from(EXIT_OK),
        Err(e) => fail("quadctl", &e),
    }
}

/// Help text shared by the batch commands: input rules and exit codes.
pub const BATCH_RULES: &str = "\
Input: CSV in UTF-8 (a byte-order mark at the start is ignored), one record per line, fields
separated by commas (no quoting; a line using `;` or tabs is refused with that hint), spaces
around fields ignored. Blank lines and lines starting with `#` are skipped. The header row is
optional: the first record is taken as a header when its first field is not a value of the
first column; it must then name exactly the expected columns, optionally followed by the columns
another batch command writes (status, clamp_distance_m, line: so `ik | fk` and `fk | ik` pipe),
or nothing is processed. Leg names are FL, FR, RL, RR (any case). An input without any record
is an error.

Output: CSV on stdout with a header row. Numbers are printed with the shortest decimal that reads
back to the same f32. The last column, line, is the input line of the record, so that output
rows can be matched to input rows although malformed records get no row; when the input carries
a line column (piped from another batch command), its value is kept, naming the line of the
first input. A piped record that was not answered (status other than ok or clamped:...) is
passed on with its status and empty cells.

Numbers that are nan, inf or beyond the f32 range (e.g. 1e300) are answered with the status
non_finite and empty cells, the same way by ik, fk and pose.

Malformed records (wrong number of fields, a field that is not a number or not a leg name, a
line that is not UTF-8) are reported on stderr as `<input>:<line>: <what is wrong>` and
get NO output row; the other records are still answered, in input order.

Exit status: 0 every record answered (unreachable targets are answers, see `status`); 1 at least
one malformed record; 2 nothing processed or processing stopped (bad arguments, robot file or
input not readable or invalid, foreign header, no record, output error).

Robot files (TOML): d_lat_m, d_ax_m, femur_m, tibia_m, body_length_m, body_width_m (metres,
required); knee_bend = \"backward\" | \"forward\" (optional, default backward); optional
[limits] table with abduction_rad, hip_rad, knee_rad = [min, max] (radians; a joint left out is
limited only to the full turn [-pi, pi]). Unknown keys are refused.";

/// The text after a batch command's `--help`: its examples, then [`BATCH_RULES`].
pub fn batch_help(examples: &str) -> String {
    format!("{examples}\n\n{BATCH_RULES}")
}

/// `--robot` of a device command: optional, the device's own robot when not given
/// (protocol 2.4).
#[derive(Debug, Clone, PartialEq, Eq, clap::Args)]
pub struct DeviceRobotArgs {
    /// Robot the host plans with: a preset (shahriar2023, fernando2025), a TOML or a URDF robot
    /// file; the device must hold the same (compared by hash; `quadctl robot send` puts it
    /// there). Not given: the robot the device holds. With --sim, a robot file runs on the
    /// simulated device compiled with shahriar2023 (the firmware's) and its --sim-storage.
    #[arg(long, value_name = "PRESET|FILE.toml|FILE.urdf", value_parser = parse_robot)]
    pub robot: Option<String>,
}

impl DeviceRobotArgs {
    /// The preset the simulated device is compiled with: the one named, else the firmware's
    /// (shahriar2023), whose EEPROM may hold another robot.
    pub fn sim_preset(&self) -> RobotPreset {
        self.robot
            .as_deref()
            .and_then(|r| RobotPreset::from_name(r.trim()))
            .unwrap_or(RobotPreset::Shahriar2023)
    }
}

/// `--robot`.
#[derive(Debug, Clone, PartialEq, Eq, clap::Args)]
pub struct RobotArgs {
    /// Robot: a preset (shahriar2023, fernando2025) or a TOML robot file.
    #[arg(long, value_name = "PRESET|FILE.toml", value_parser = parse_robot)]
    pub robot: String,
}

impl RobotArgs {
    /// Resolves the preset or file; `knee` overrides the robot's knee bend (mirroring its knee
    /// limits with it, see [`Robot::with_knee_bend`]).
    pub fn load(&self, knee: Option<KneeBend>) -> Result<Robot, robot_file::Error> {
        let robot = robot_file::resolve(&self.robot)?;
        Ok(match knee {
            Some(k) => robot.with_knee_bend(k),
            None => robot,
        })
    }
}

/// `--input`.
#[derive(Debug, Clone, PartialEq, Eq, clap::Args)]
pub struct InputArgs {
    /// CSV input file, or `-` for standard input.
    #[arg(long, value_name = "FILE|-", default_value = "-")]
    pub input: PathBuf,
}

/// Where the device is: `--sim`, `--emulator` or `--port` (exactly one: the group `target`,
/// so that a missing one is reported with the three choices), and the line (`stream`,
/// `calibrate`).
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(group = clap::ArgGroup::new("target").required(true).multiple(false))]
pub struct TargetArgs {
    /// Run against the device controller behind a simulated UART.
    #[arg(long, group = "target")]
    pub sim: bool,
    /// Run the real firmware in simavr (an emulated ATmega2560; simulated time).
    #[arg(long, group = "target")]
    pub emulator: bool,
    /// Firmware ELF for --emulator; default: built from firmware-avr/ for --baud (115200:
    /// firmware.elf, 1000000: firmware-1mbaud.elf).
    #[arg(long, value_name = "PATH", requires = "emulator")]
    pub elf: Option<PathBuf>,
    /// Serial port of a real device, e.g. /dev/ttyACM0.
    #[arg(long, value_name = "PATH", group = "target")]
    pub port: Option<String>,
    /// Line rate, bit/s (8N1).
    #[arg(long, value_name = "B", default_value_t = 115_200, value_parser = clap::value_parser!(u32).range(300..))]
    pub baud: u32,
    /// Line faults of --sim or --emulator: drop=P,flip=P (per byte), dup=P,trunc=P,stall=P (per
    /// frame), stall_ms=MS.
    #[arg(
        long,
        value_name = "drop=P,flip=P,dup=P,trunc=P",
        conflicts_with = "port"
    )]
    pub faults: Option<Faults>,
    /// Seed of the simulated faults.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub seed: u64,
    /// Modelled device time per answered frame in the simulation, µs (0: wire-limited).
    #[arg(long, value_name = "US", default_value_t = 0.0, value_parser = parse_us, requires = "sim")]
    pub sim_compute_us: f64,
    /// EEPROM image file of the simulated or emulated device (read at power-on; written on
    /// every change with --sim, at the end of the run with --emulator).
    #[arg(long, value_name = "FILE", conflicts_with = "port")]
    pub sim_storage: Option<PathBuf>,
    /// Resends per request after the first attempt.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_RETRIES)]
    pub retries: u32,
}

impl TargetArgs {
    /// The library's target; `preset` is the robot of the simulated device.
    pub fn target(&self, preset: RobotPreset) -> Target {
        let faults = self.faults.unwrap_or(Faults::NONE);
        if let Some(path) = &self.port {
            Target::Serial {
                path: path.clone(),
                baud: self.baud,
            }
        } else if self.emulator {
            Target::Emulator {
                elf: self.elf.clone(),
                config: EmulatorConfig {
                    faults,
                    seed: self.seed,
                    ..EmulatorConfig::new(self.baud)
                },
                storage: self.sim_storage.clone(),
            }
        } else {
            Target::Sim {
                preset,
                config: SimConfig {
                    baud: self.baud,
                    faults,
                    seed: self.seed,
                    compute: Duration::from_secs_f64(self.sim_compute_us * 1e-6),
                    rx_fifo_len: DEFAULT_RX_FIFO_LEN,
                },
                storage: self.sim_storage.clone(),
            }
        }
    }
}

/// The device side of the commands that stream setpoints (`stream`, `play`): robot, device,
/// what is set on it and how its answers are checked.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct SessionArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub robot: DeviceRobotArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub target: TargetArgs,
    /// Stance height H set on the device, metres; default: the device's own.
    #[arg(long, value_name = "H", value_parser = parse_positive_m)]
    pub stance_height_m: Option<f32>,
    /// Rotation order set on the device; default: the input's (`play`: a rotation_order=
    /// comment), else the device's own.
    #[arg(long, value_parser = rotation_order())]
    pub rotation_order: Option<RotationOrder>,
    /// Compare the device's angles within this bound (rad) instead of bit for bit; default:
    /// exact with --sim, 2e-5 rad with --emulator and --port (the AVR's math differs from the
    /// host's).
    #[arg(long, value_name = "RAD")]
    pub angle_tolerance_rad: Option<f32>,
    /// Exit with status 0 even when poses or rows were refused (nacked) or lost, as long as
    /// every answer passed its check (without it: status 4).
    #[arg(long)]
    pub allow_refused: bool,
    /// Send one request and wait for its answer before the next (default: two in flight, the
    /// device solving the next while the answer to the previous one is on the wire).
    #[arg(long)]
    pub one_at_a_time: bool,
}

impl SessionArgs {
    /// The requests kept in flight: 1 with `--one-at-a-time`, else
    /// [`quad_host::client::DEFAULT_WINDOW`].
    pub fn window(&self) -> usize {
        if self.one_at_a_time {
            1
        } else {
            quad_host::client::DEFAULT_WINDOW
        }
    }

    /// The library's session. The simulated device runs the preset given, else the
    /// firmware's (a robot file: what its --sim-storage EEPROM holds; the session compares
    /// the hashes); without --robot the session plans with the device's robot.
    pub fn session(&self) -> Session {
        Session {
            robot: self.robot.robot.clone(),
            target: self.target.target(self.robot.sim_preset()),
            retries: self.target.retries,
            stance_height_m: self.stance_height_m,
            rotation_order: self.rotation_order,
            angle_tolerance_rad: self.angle_tolerance_rad,
        }
    }
}

/// The exit status of a stream that ran to its end (`stream`, `play`): [`EXIT_CHECK_FAILED`]
/// when a check failed, else [`EXIT_REFUSED`] when a pose was nacked or lost (unless
/// `allow_refused`), else [`EXIT_MALFORMED`] when input records were malformed, else
/// [`EXIT_OK`].
pub fn stream_status(
    stream: &quad_host::client::StreamStats,
    check_failed: bool,
    malformed: usize,
    allow_refused: bool,
) -> u8 {
    if check_failed {
        EXIT_CHECK_FAILED
    } else if !allow_refused && stream.nacked + stream.lost > 0 {
        EXIT_REFUSED
    } else if malformed > 0 {
        EXIT_MALFORMED
    } else {
        EXIT_OK
    }
}

/// The law and its parameters, shared by `motion` and `check --motion`. Every parameter is
/// optional; the defaults are the papers' (see `quadctl motion --help`).
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct LawArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub robot: RobotArgs,
    /// Stance height H (m): feet straight below the hips, H below them. Default: the
    /// device's stance for a preset (shahriar2023 0.40 m, fernando2025 seed 001's initial
    /// pose, 0.9294 m), seed 001's initial pose (φ=120°, α=60°, β=0) through forward
    /// kinematics for a robot file; rect-path: 0.2 m (seed 000 Fig. 8).
    #[arg(long, value_name = "M")]
    pub stance_height_m: Option<f32>,
    /// Rotation order of the body pose [default: a preset's device order (fernando2025 zxy,
    /// shahriar2023 zyx, as the firmware runs it); a robot file: zxy for the sways and
    /// yaw-turn (seed 001), zyx otherwise].
    #[arg(long, value_parser = rotation_order())]
    pub rotation_order: Option<RotationOrder>,
    /// Sways: amplitude A, rad [default: 0.2].
    #[arg(long, value_name = "RAD", value_parser = parse_angle_rad)]
    pub amplitude_rad: Option<f32>,
    /// Sways: period T, s [default: 20].
    #[arg(long, value_name = "S")]
    pub period_s: Option<f32>,
    /// yaw-turn, trot, walk: yaw rate, rad/s; positive turns counter-clockwise seen from
    /// above (REP 103; seed 001's ω_z = 0.085 clockwise is −0.085) [default: yaw-turn -0.085,
    /// gaits 0]. `--yaw-rad-s` is the same option (its former name for the gaits).
    #[arg(long, value_name = "RAD_S", alias = "yaw-rad-s")]
    pub yaw_rate_rad_s: Option<f32>,
    /// yaw-turn: step period T1, s [default: 6].
    #[arg(long, value_name = "S")]
    pub step_period_s: Option<f32>,
    /// yaw-turn: lift height h_K, m [default: 0.3].
    #[arg(long, value_name = "M")]
    pub lift_height_m: Option<f32>,
    /// rect-path: path shape [default: rectangle]; trot/walk: swing shape [default: bezier].
    #[arg(long, value_parser = path_kind())]
    pub path: Option<PathKind>,
    /// rect-path: stride length, m [default: 0.1].
    #[arg(long, value_name = "M")]
    pub stride_m: Option<f32>,
    /// rect-path, trot, walk: swing apex above the ground, m [default: rect-path 0.05,
    /// gaits 0.15·H].
    #[arg(long, value_name = "M")]
    pub step_height_m: Option<f32>,
    /// rect-path, trot, walk: stance fraction of the cycle, in (0, 1) [default: rectangle 1/3
    /// (one speed round the loop), other paths 0.5; trot and walk 0.75].
    #[arg(long, value_name = "D")]
    pub duty_factor: Option<f32>,
    /// rect-path, trot, walk: cycle time, s [default: rect-path 3, gaits 1.0].
    #[arg(long, value_name = "S")]
    pub cycle_s: Option<f32>,
    /// trot, walk: forward speed, m/s [default: 0].
    #[arg(long, value_name = "M_S")]
    pub forward_m_s: Option<f32>,
    /// trot, walk: lateral speed (left positive), m/s [default: 0].
    #[arg(long, value_name = "M_S")]
    pub lateral_m_s: Option<f32>,
    /// stable-turn: yaw of one cycle (each leg steps once), rad, counter-clockwise positive,
    /// |Δψ| ≤ π/2 [default: 0.2].
    #[arg(long, value_name = "RAD", value_parser = parse_angle_rad, allow_hyphen_values = true)]
    pub yaw_per_cycle_rad: Option<f32>,
    /// stable-turn: how far the body moves towards the centroid of the three feet that stay
    /// down, in (0, 1] [default: 0.8].
    #[arg(long, value_name = "F")]
    pub shift_fraction: Option<f32>,
}

impl LawArgs {
    /// The library's parameters.
    pub fn params(&self) -> Params {
        Params {
            robot: self.robot.robot.clone(),
            stance_height_m: self.stance_height_m,
            amplitude_rad: self.amplitude_rad,
            period_s: self.period_s,
            yaw_rate_rad_s: self.yaw_rate_rad_s,
            step_period_s: self.step_period_s,
            lift_height_m: self.lift_height_m,
            path: self.path,
            stride_m: self.stride_m,
            step_height_m: self.step_height_m,
            duty_factor: self.duty_factor,
            cycle_s: self.cycle_s,
            forward_m_s: self.forward_m_s,
            lateral_m_s: self.lateral_m_s,
            yaw_rad_s: None,
            yaw_per_cycle_rad: self.yaw_per_cycle_rad,
            shift_fraction: self.shift_fraction,
            rotation_order: self.rotation_order,
        }
    }
}

/// A value parser for one of a fixed set of named values: the names are the library's or
/// kin-core's own (no mirror enums here), listed with `help` as the possible values in
/// `--help`.
pub fn choice<T: Copy + Send + Sync + 'static>(
    all: &'static [T],
    name: fn(T) -> &'static str,
    help: fn(T) -> String,
) -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(
        all.iter()
            .map(|&v| PossibleValue::new(name(v)).help(help(v))),
    )
    .map(move |s| {
        all.iter()
            .copied()
            .find(|&v| name(v) == s)
            .expect("clap accepts only the names listed")
    })
}

/// `--rotation-order`: kin-core's six orders by name, each described by its product read
/// left to right.
pub fn rotation_order() -> impl TypedValueParser<Value = RotationOrder> {
    fn help(o: RotationOrder) -> String {
        let factor = |axis: u8| ["Rx(roll)", "Ry(pitch)", "Rz(yaw)"][usize::from(axis)];
        let product = o.axes().map(factor).join("·");
        match o {
            RotationOrder::Zxy => format!("{product} (seed 001)"),
            RotationOrder::Zyx => format!("{product} (the default)"),
            _ => product,
        }
    }
    choice(&RotationOrder::ALL, RotationOrder::name, help)
}

/// `--knee`.
pub fn knee() -> impl TypedValueParser<Value = KneeBend> {
    fn help(k: KneeBend) -> String {
        match k {
            KneeBend::Backward => "knee <= 0 (the knee joint behind the hip-foot line)",
            KneeBend::Forward => "knee >= 0 (the knee joint in front of the hip-foot line)",
        }
        .to_owned()
    }
    choice(&names::KNEE_BEND_VALUES, names::knee_bend_name, help)
}

/// `--policy`.
pub fn policy() -> impl TypedValueParser<Value = ReachPolicy> {
    fn help(p: ReachPolicy) -> String {
        match p {
            ReachPolicy::Reject => "Report the reason in `status`, leave the angles empty",
            ReachPolicy::Clamp => {
                "Move the target to the nearest reachable point and report the distance moved"
            }
        }
        .to_owned()
    }
    choice(&names::REACH_POLICY_VALUES, names::reach_policy_name, help)
}

/// `--path`: kin-core's foot path shapes by name.
pub fn path_kind() -> impl TypedValueParser<Value = PathKind> {
    fn help(k: PathKind) -> String {
        match k {
            PathKind::Rectangle => "Lift, stride, lower, return (seed 000 Fig. 8)",
            PathKind::Semicircle => "Semicircle of diameter the stride (its height is stride/2)",
            PathKind::Ellipse => "Half ellipse",
            PathKind::Cycloid => "Cycloid (zero velocity at lift-off and touch-down)",
            PathKind::Bezier => "Quintic Bézier, C1 with the stance",
        }
        .to_owned()
    }
    choice(&PathKind::ALL, PathKind::name, help)
}

/// `--send` of `play`: a kind of setpoint columns.
pub fn column_kind() -> impl TypedValueParser<Value = ColumnKind> {
    fn help(k: ColumnKind) -> String {
        match k {
            ColumnKind::Joints => "The joint-angle columns, as SetJoints",
            ColumnKind::Feet => "The foot columns, as SetFeet",
            ColumnKind::Pose => "The body-pose columns, as SetBodyPose",
            _ => "",
        }
        .to_owned()
    }
    choice(&ColumnKind::ALL, ColumnKind::name, help)
}

/// A motion law by name.
pub fn law() -> impl TypedValueParser<Value = Law> {
    choice(&Law::ALL, Law::name, |l| l.summary().to_owned())
}

/// `--angles`.
pub fn angles() -> impl TypedValueParser<Value = Angles> {
    fn help(a: Angles) -> String {
        match a {
            Angles::Canonical => "The canonical angles as they are in the files",
            Angles::Seed000 => "Seed 000's θ1, θ2, θ3 (kin_core::paper::to_seed000)",
        }
        .to_owned()
    }
    choice(&Angles::ALL, Angles::name, help)
}

/// `--format` of `pose`.
pub fn pose_format() -> impl TypedValueParser<Value = PoseFormat> {
    fn help(f: PoseFormat) -> String {
        match f {
            PoseFormat::Csv => "CSV in radians, for programs",
            PoseFormat::Table => "A table per pose in degrees, for people",
        }
        .to_owned()
    }
    choice(&PoseFormat::ALL, PoseFormat::name, help)
}

/// Errors that stop a batch command.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// `--robot` could not be resolved.
    #[error(transparent)]
    Robot(#[from] robot_file::Error),
    /// Input, output or header error.
    #[error(transparent)]
    Csv(#[from] csv::Error),
}

impl Error {
    fn is_broken_pipe(&self) -> bool {
        matches!(self, Error::Csv(csv::Error::Io(e)) if e.kind() == io::ErrorKind::BrokenPipe)
    }
}

/// A command-line value that could not be used.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum ArgError {
    /// Not a number.
    NotANumber(String),
    /// A length that must be finite and > 0.
    NotPositive(f32),
    /// Not a finite number.
    NotFinite(String),
    /// Not three comma-separated numbers.
    NotThree(usize),
    /// Not a time in µs within [0, 1e7].
    OutOfMicrosecondRange(String),
    /// Not a leg name.
    UnknownLeg(String),
    /// Not one speed or three.
    SpeedCount(String),
    /// An angle beyond a full turn: most likely degrees where radians are asked.
    DegreesNotRadians(f32),
    /// Neither a preset nor an existing file, but close to a preset's name.
    MistypedPreset {
        /// What was given.
        given: String,
        /// The preset it is closest to.
        preset: &'static str,
    },
}

impl fmt::Display for ArgError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ArgError::NotANumber(s) => write!(f, "`{s}` is not a number"),
            ArgError::NotPositive(v) => write!(f, "{v} must be a finite length > 0 (metres)"),
            ArgError::NotFinite(s) => write!(f, "`{s}` is not a finite number"),
            ArgError::NotThree(n) => {
                write!(f, "expected three comma-separated numbers X,Y,Z, found {n}")
            }
            ArgError::OutOfMicrosecondRange(s) => {
                write!(f, "`{s}` is not a time in µs within [0, 1e7]")
            }
            ArgError::UnknownLeg(s) => write!(f, "`{s}` is not a leg (FL, FR, RL, RR)"),
            ArgError::SpeedCount(s) => write!(
                f,
                "expected one value or three (abduction,hip,knee), got `{s}`"
            ),
            ArgError::DegreesNotRadians(v) => write!(
                f,
                "{v} rad = {:.0}°; angles are in radians (did you mean {v}° = {:.4} rad?)",
                v.to_degrees(),
                v.to_radians()
            ),
            ArgError::MistypedPreset { given, preset } => write!(
                f,
                "`{given}` is not a preset ({}) nor an existing file: did you mean `{preset}`?",
                Robot::PRESETS.join(", ")
            ),
        }
    }
}

impl std::error::Error for ArgError {}

/// A finite number (no NaN, no infinity).
pub fn parse_finite(s: &str) -> Result<f32, ArgError> {
    let v: f32 = s
        .trim()
        .parse()
        .map_err(|_| ArgError::NotANumber(s.trim().to_owned()))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ArgError::NotFinite(s.trim().to_owned()))
    }
}

/// Value parser: a finite length > 0, metres.
pub fn parse_positive_m(s: &str) -> Result<f32, ArgError> {
    let v = parse_finite(s)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(ArgError::NotPositive(v))
    }
}

/// `Some` hint when `v` (an angle, rad) looks like degrees: beyond a full turn, up to 360
/// ([`quad_host::ops::session::looks_like_degrees`], which says why), so that such a value is
/// refused as degrees with its conversion before anything reports it as merely out of range.
pub fn degrees_hint(v: f32) -> Option<ArgError> {
    quad_host::ops::session::looks_like_degrees(v).then_some(ArgError::DegreesNotRadians(v))
}

/// Value parser: an angle in radians, refused when it looks like degrees ([`degrees_hint`]);
/// any other number (a NaN, a value far out of range) is left to the range checks of its use.
pub fn parse_angle_rad(s: &str) -> Result<f32, ArgError> {
    let v: f32 = s
        .trim()
        .parse()
        .map_err(|_| ArgError::NotANumber(s.trim().to_owned()))?;
    match degrees_hint(v) {
        Some(e) => Err(e),
        None => Ok(v),
    }
}

/// The preset `given` is most likely a misspelling of: within a third of the preset's name in
/// edits (ignoring case), or a prefix of it of at least four characters.
pub fn close_preset(given: &str) -> Option<&'static str> {
    let given = given.trim().to_ascii_lowercase();
    if given.is_empty() {
        return None;
    }
    Robot::PRESETS
        .iter()
        .map(|&p| (edit_distance(&given, p), p))
        .filter(|&(d, p)| {
            d <= (p.len() / 3).max(1) || (given.len() >= 4 && p.starts_with(given.as_str()))
        })
        .min_by_key(|&(d, _)| d)
        .map(|(_, p)| p)
}

/// Levenshtein distance of two strings, in characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let substitute = diagonal + usize::from(ca != cb);
            diagonal = row[j + 1];
            row[j + 1] = substitute.min(row[j] + 1).min(diagonal + 1);
        }
    }
    row[b.len()]
}

/// Value parser of `--robot`: kept as given (a preset or a file, resolved later), except a
/// value that is neither a preset nor an existing file but close to a preset's name, which is
/// refused with "did you mean".
pub fn parse_robot(s: &str) -> Result<String, ArgError> {
    let is_file = Path::new(s).exists();
    match close_preset(s) {
        Some(preset) if !is_file && Robot::preset(s.trim()).is_none() => {
            Err(ArgError::MistypedPreset {
                given: s.to_owned(),
                preset,
            })
        }
        _ => Ok(s.to_owned()),
    }
}

/// Value parser: `X,Y,Z`, three finite numbers (metres).
pub fn parse_vec3_m(s: &str) -> Result<Vec3, ArgError> {
    let parts: Vec<&str> = s.split(',').collect();
    match parts.as_slice() {
        [x, y, z] => Ok(Vec3::new(
            parse_finite(x)?,
            parse_finite(y)?,
            parse_finite(z)?,
        )),
        other => Err(ArgError::NotThree(other.len())),
    }
}

/// Value parser: a time in µs within [0, 1e7].
pub fn parse_us(s: &str) -> Result<f64, ArgError> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && (0.0..=1e7).contains(&v) => Ok(v),
        _ => Err(ArgError::OutOfMicrosecondRange(s.to_owned())),
    }
}

/// Value parser: a leg name (any case).
pub fn parse_leg(s: &str) -> Result<LegId, ArgError> {
    LegId::parse(s).ok_or_else(|| ArgError::UnknownLeg(s.to_owned()))
}

/// Value parser of `--max-joint-speed-rad-s`: one speed for all joints or ABDUCTION,HIP,KNEE,
/// rad/s.
pub fn parse_speed_limits(s: &str) -> Result<[f32; 3], ArgError> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| {
            x.trim()
                .parse::<f32>()
                .map_err(|_| ArgError::NotANumber(x.trim().to_owned()))
        })
        .collect::<Result<_, _>>()?;
    match v.as_slice() {
        [a] => Ok([*a; 3]),
        [a, b, c] => Ok([*a, *b, *c]),
        _ => Err(ArgError::SpeedCount(s.to_owned())),
    }
}

/// Runs a batch command on `--input` with stdout and stderr, reports its outcome on stderr and
/// turns it into the exit status ([`EXIT_OK`], [`EXIT_MALFORMED`], [`EXIT_FATAL`]).
pub fn run_batch(
    input: &Path,
    body: impl FnOnce(Input, &mut dyn Write, &mut dyn Write) -> Result<Summary, Error>,
) -> ExitCode {
    let stdout = io::stdout();
    let mut out = io::BufWriter::new(stdout.lock());
    let stderr = io::stderr();
    let mut diag = stderr.lock();
    let result = Input::open(input)
        .map_err(Error::Csv)
        .and_then(|input| body(input, &mut out, &mut diag))
        .and_then(|summary| {
            out.flush().map_err(|e| Error::Csv(csv::Error::Io(e)))?;
            Ok(summary)
        });
    match result {
        Ok(summary) if summary.malformed == 0 => ExitCode::from(EXIT_OK),
        Ok(summary) => {
            // Nothing useful can be done if stderr itself fails.
            let _ = writeln!(
                diag,
                "quadctl: {} malformed record(s) skipped, {} answered",
                summary.malformed, summary.answered
            );
            ExitCode::from(EXIT_MALFORMED)
        }
        // The reader of stdout went away (e.g. `| head`): stop quietly.
        Err(e) if e.is_broken_pipe() => ExitCode::from(EXIT_OK),
        Err(e) => {
            let _ = out.flush();
            drop(diag);
            fail("quadctl", &e)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use kin_core::preflight::DEFAULT_MAX_JOINT_SPEED_RAD_S;

    #[test]
    fn the_default_speed_limit_is_kin_cores() {
        let default: f32 = "6".parse().unwrap();
        assert_eq!(default, DEFAULT_MAX_JOINT_SPEED_RAD_S);
        assert_eq!(parse_speed_limits("1,2,3").unwrap(), [1.0, 2.0, 3.0]);
        assert_eq!(parse_speed_limits("4").unwrap(), [4.0; 3]);
        assert!(parse_speed_limits("1,2").is_err() && parse_speed_limits("x").is_err());
    }

    #[test]
    fn named_values_parse_to_the_library_values() {
        let cmd = clap::Command::new("t");
        let order = rotation_order();
        let ok = |s: &str| order.parse_ref(&cmd, None, std::ffi::OsStr::new(s)).ok();
        assert_eq!(ok("zxy"), Some(RotationOrder::Zxy));
        assert_eq!(ok("zyy"), None);
        let knees = knee();
        let k = knees
            .parse_ref(&cmd, None, std::ffi::OsStr::new("forward"))
            .ok();
        assert_eq!(k, Some(KneeBend::Forward));
    }

    #[test]
    fn a_refused_or_lost_pose_has_its_own_status() {
        let stats = |nacked, lost| quad_host::client::StreamStats {
            nacked,
            lost,
            ..Default::default()
        };
        assert_eq!(stream_status(&stats(0, 0), false, 0, false), EXIT_OK);
        assert_eq!(stream_status(&stats(1, 0), false, 0, false), EXIT_REFUSED);
        assert_eq!(stream_status(&stats(0, 2), false, 0, false), EXIT_REFUSED);
        assert_eq!(stream_status(&stats(0, 2), false, 0, true), EXIT_OK);
        assert_eq!(stream_status(&stats(1, 1), false, 3, false), EXIT_REFUSED);
        assert_eq!(stream_status(&stats(1, 1), false, 3, true), EXIT_MALFORMED);
        assert_eq!(
            stream_status(&stats(1, 0), true, 3, false),
            EXIT_CHECK_FAILED
        );
    }

    #[test]
    fn presets_are_suggested_for_near_misses_only() {
        assert_eq!(close_preset("shahriar2024"), Some("shahriar2023"));
        assert_eq!(close_preset("FERNANDO"), Some("fernando2025"));
        assert_eq!(close_preset("fern"), Some("fernando2025"));
        assert_eq!(close_preset("robot.toml"), None);
        assert_eq!(close_preset(""), None);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert!(parse_robot("shahriar2023").is_ok());
        assert!(parse_robot("examples/robots/missing.toml").is_ok());
        assert!(parse_robot("shahriar-2023").is_err());
    }

    #[test]
    fn value_parsers_refuse_what_they_cannot_use() {
        assert_eq!(parse_angle_rad("6.2"), Ok(6.2));
        assert_eq!(
            parse_angle_rad("-90"),
            Err(ArgError::DegreesNotRadians(-90.0))
        );
        assert_eq!(parse_positive_m("0.9294"), Ok(0.9294));
        assert_eq!(parse_positive_m("0"), Err(ArgError::NotPositive(0.0)));
        assert_eq!(
            parse_positive_m("inf"),
            Err(ArgError::NotFinite("inf".to_owned()))
        );
        assert_eq!(parse_vec3_m("0.1, -0.2,0"), Ok(Vec3::new(0.1, -0.2, 0.0)));
        assert_eq!(parse_vec3_m("1,2"), Err(ArgError::NotThree(2)));
        assert_eq!(
            parse_vec3_m("1,x,2"),
            Err(ArgError::NotANumber("x".to_owned()))
        );
    }
}
