//! `quadctl stand`, `sit`, `rest` and `run <motion>`: the motions the device runs by itself,
//! started and followed to their end; a JSON summary as the last line of stdout.

use crate::args::{self, parse_leg, path_kind, DeviceRobotArgs, TargetArgs, EXIT_OK};
use clap::ValueEnum;
use kin_core::motion::gait::Pattern;
use kin_core::motion::laws::Axis;
use kin_core::motion::path::PathKind;
use kin_core::LegId;
use quad_host::ops::onboard::{self, Session, VelocityStep};
use quad_protocol::{LegSet, MotionCommand};
use std::process::ExitCode;
use std::time::Duration;

/// Longest a command waits for its motion to end, link time.
const WAIT_LIMIT: Duration = Duration::from_secs(600);

const POSTURE_ABOUT: &str = "\
The device ramps its joints at its joint-speed limit (3 rad/s by default) and reports when it
is done. stand: outputs on at the rest pose (legs folded, as a robot lying on the ground),
then up to the stance; sit: down to the rest pose, held; rest: down to the rest pose, then the
outputs off. With the outputs off, sit and rest have nothing to do (motion none).

Output: the last line of stdout is one JSON object: motion, stood_up_first, motion_s, polls,
velocity_commands, elapsed_s, outputs_enabled. motion_s is the time of a motion's run stage,
so 0 for these postures, which are ramps only; elapsed_s is how long the ramp took. Exit
status: 0 done; 2 refused (the device's reason in words) or the link failed.";

/// `--help`'s examples of `stand`, `sit` and `rest` (run from the repository root).
pub const STAND_EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl stand --robot shahriar2023 --sim
  quadctl stand --robot shahriar2023 --port /dev/ttyACM0";

/// `quadctl sit --help`'s examples.
pub const SIT_EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl sit --robot shahriar2023 --sim
  quadctl sit --robot shahriar2023 --port /dev/ttyACM0";

/// `quadctl rest --help`'s examples.
pub const REST_EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl rest --robot shahriar2023 --sim
  quadctl rest --robot shahriar2023 --port /dev/ttyACM0";

/// Arguments of `quadctl stand`, `sit` and `rest`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(long_about = POSTURE_ABOUT)]
pub struct PostureArgs {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub robot: DeviceRobotArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub target: TargetArgs,
}

/// The onboard motions of `quadctl run`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Motion {
    /// Seed 001 eq. 6: roll = A·sin(2πt/T), feet fixed.
    SwayRoll,
    /// Seed 001 eq. 8: pitch = A·sin(2πt/T), feet fixed.
    SwayPitch,
    /// Seed 001 eq. 9-11 (corrected): the crossed pairs step round the body centre.
    YawTurn,
    /// Seed 000's foot paths (rectangle by default) on one leg or all four.
    FootPath,
    /// Trot: diagonal pairs, from a velocity command.
    Trot,
    /// Walk: one leg at a time, from a velocity command.
    Walk,
    /// A statically stable yaw turn: one leg at a time, the body shifted into the support
    /// triangle first.
    StableTurn,
}

const RUN_ABOUT: &str = "\
Runs one of the device's own motions and waits for its end. When the device's outputs are off
(a freshly started board), it stands up first.

Parameters (units in the names; every one optional, the defaults are the device's):
  sway-roll, sway-pitch  --amplitude-rad (0.2) --period-s (20) --duration-s (one period)
  yaw-turn   --yaw-rate-rad-s (0.085 clockwise = -0.085; counter-clockwise positive, REP 103)
             --step-period-s (6) --lift-height-m (0.3) --duration-s (one step period)
  foot-path  --path (rectangle) --leg (all) --stride-m (0.1) --step-height-m (0.05)
             --duty-factor (1/3) --cycle-s (3) --duration-s (one cycle)
  trot, walk --stance-height-m (the device's) --step-height-m (0.15 x height)
             --cycle-s (0.8) --velocity-timeout-ms (500) and the velocity --forward-m-s,
             --lateral-m-s, --yaw-rate-rad-s (0) held for --duration-s (5), then a stop (the
             strides finish, the feet park on the stance).
  stable-turn --yaw-per-cycle-rad (0.2; counter-clockwise positive) --cycle-s (20)
             --lift-height-m (0.15 x the device's stance height) --shift-fraction (0.8)
             --duration-s (one cycle)
Durations are rounded up to whole periods by the device.

Bad values are refused before anything moves, the option named: a value outside its range
(docs/protocol.md, motion field ranges: NaN, zero or negative periods and durations, an
amplitude beyond 90 degrees, ...) by the host before sending, with the device's own reason and
the range; amplitudes or heights beyond reach and velocities beyond what the gait reaches by
the device. Exit status: 0 done; 2 refused, stopped early or the link failed.";

/// `quadctl run --help`'s examples (run from the repository root).
pub const RUN_EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl run sway-roll --robot shahriar2023 --sim --amplitude-rad 0.1 --period-s 2
  quadctl run yaw-turn --robot shahriar2023 --sim --yaw-rate-rad-s 0.1 --step-period-s 2 --lift-height-m 0.03
  quadctl run trot --robot shahriar2023 --sim --forward-m-s 0.02 --duration-s 2
  quadctl run sway-pitch --robot shahriar2023 --port /dev/ttyACM0";

/// Arguments of `quadctl run`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(long_about = RUN_ABOUT, after_help = RUN_EXAMPLES)]
pub struct RunArgs {
    /// The motion.
    #[arg(value_enum)]
    pub motion: Motion,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub robot: DeviceRobotArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub target: TargetArgs,
    /// Sways: amplitude A, rad.
    #[arg(long, value_name = "RAD", allow_negative_numbers = true, value_parser = crate::args::parse_angle_rad)]
    pub amplitude_rad: Option<f32>,
    /// Sways: period T, s.
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub period_s: Option<f32>,
    /// How long, s (sways, yaw-turn, foot-path: rounded up to whole periods; trot, walk: how
    /// long the velocity is held).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub duration_s: Option<f32>,
    /// yaw-turn, trot, walk: yaw rate, rad/s, counter-clockwise positive.
    #[arg(long, value_name = "RAD_S", allow_negative_numbers = true)]
    pub yaw_rate_rad_s: Option<f32>,
    /// yaw-turn: step period T1, s.
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub step_period_s: Option<f32>,
    /// yaw-turn: lift h_K, m.
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    pub lift_height_m: Option<f32>,
    /// foot-path: the path's shape.
    #[arg(long, value_parser = path_kind())]
    pub path: Option<PathKind>,
    /// foot-path: one leg (FL, FR, RL, RR); default all four.
    #[arg(long, value_parser = parse_leg)]
    pub leg: Option<LegId>,
    /// foot-path: stride, m.
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    pub stride_m: Option<f32>,
    /// foot-path, trot, walk: step height, m.
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    pub step_height_m: Option<f32>,
    /// foot-path: stance fraction of the loop, in (0, 1).
    #[arg(long, value_name = "D", allow_negative_numbers = true)]
    pub duty_factor: Option<f32>,
    /// stable-turn: yaw of one cycle, rad, counter-clockwise positive.
    #[arg(long, value_name = "RAD", allow_negative_numbers = true, value_parser = crate::args::parse_angle_rad)]
    pub yaw_per_cycle_rad: Option<f32>,
    /// stable-turn: how far the body moves towards the centroid of its support triangle, in
    /// (0, 1].
    #[arg(long, value_name = "F", allow_negative_numbers = true)]
    pub shift_fraction: Option<f32>,
    /// foot-path, trot, walk, stable-turn: one loop or gait cycle, s.
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub cycle_s: Option<f32>,
    /// trot, walk: stance height (the body's height above the feet), m, as `motion`'s
    /// --stance-height-m; `--body-height-m` is the same option (its former name).
    #[arg(
        long = "stance-height-m",
        alias = "body-height-m",
        value_name = "M",
        allow_negative_numbers = true
    )]
    pub body_height_m: Option<f32>,
    /// trot, walk: timeout of the velocity command, ms.
    #[arg(long, value_name = "MS")]
    pub velocity_timeout_ms: Option<u16>,
    /// trot, walk: forward speed, m/s.
    #[arg(long, value_name = "M_S", allow_negative_numbers = true)]
    pub forward_m_s: Option<f32>,
    /// trot, walk: lateral speed (left positive), m/s.
    #[arg(long, value_name = "M_S", allow_negative_numbers = true)]
    pub lateral_m_s: Option<f32>,
}

/// Which options each motion takes.
fn applies(motion: Motion, option: &str) -> bool {
    let sway = matches!(motion, Motion::SwayRoll | Motion::SwayPitch);
    let gait = matches!(motion, Motion::Trot | Motion::Walk);
    match option {
        "--amplitude-rad" | "--period-s" => sway,
        "--duration-s" => true,
        "--yaw-rate-rad-s" => motion == Motion::YawTurn || gait,
        "--step-period-s" => motion == Motion::YawTurn,
        "--lift-height-m" => matches!(motion, Motion::YawTurn | Motion::StableTurn),
        "--yaw-per-cycle-rad" | "--shift-fraction" => motion == Motion::StableTurn,
        "--path" | "--leg" | "--stride-m" | "--duty-factor" => motion == Motion::FootPath,
        "--step-height-m" => motion == Motion::FootPath || gait,
        "--cycle-s" => matches!(motion, Motion::FootPath | Motion::StableTurn) || gait,
        _ => gait,
    }
}

/// An option given that the motion does not take.
#[derive(Debug, thiserror::Error)]
#[error("{option} does not apply to {motion}")]
struct NotApplicable {
    option: &'static str,
    motion: String,
}

impl RunArgs {
    fn given(&self) -> Vec<&'static str> {
        [
            ("--amplitude-rad", self.amplitude_rad.is_some()),
            ("--period-s", self.period_s.is_some()),
            ("--yaw-rate-rad-s", self.yaw_rate_rad_s.is_some()),
            ("--step-period-s", self.step_period_s.is_some()),
            ("--lift-height-m", self.lift_height_m.is_some()),
            ("--path", self.path.is_some()),
            ("--leg", self.leg.is_some()),
            ("--stride-m", self.stride_m.is_some()),
            ("--step-height-m", self.step_height_m.is_some()),
            ("--duty-factor", self.duty_factor.is_some()),
            ("--cycle-s", self.cycle_s.is_some()),
            ("--stance-height-m", self.body_height_m.is_some()),
            ("--velocity-timeout-ms", self.velocity_timeout_ms.is_some()),
            ("--forward-m-s", self.forward_m_s.is_some()),
            ("--lateral-m-s", self.lateral_m_s.is_some()),
            ("--yaw-per-cycle-rad", self.yaw_per_cycle_rad.is_some()),
            ("--shift-fraction", self.shift_fraction.is_some()),
        ]
        .into_iter()
        .filter_map(|(o, g)| g.then_some(o))
        .collect()
    }

    /// The device's request with the protocol's named defaults
    /// ([`MotionCommand::seed001_sway`], ...) and the options given; `stance_height_m` is the
    /// device's (the walk's default body height).
    fn request(&self, stance_height_m: f32) -> (MotionCommand, Vec<VelocityStep>) {
        let d = self.duration_s;
        let request = match self.motion {
            Motion::SwayRoll | Motion::SwayPitch => {
                let axis = if self.motion == Motion::SwayRoll {
                    Axis::Roll
                } else {
                    Axis::Pitch
                };
                let MotionCommand::Sway {
                    amplitude_rad,
                    period_s,
                    ..
                } = MotionCommand::seed001_sway(axis, None)
                else {
                    unreachable!("seed001_sway is a sway")
                };
                let period_s = self.period_s.unwrap_or(period_s);
                MotionCommand::Sway {
                    axis,
                    amplitude_rad: self.amplitude_rad.unwrap_or(amplitude_rad),
                    period_s,
                    duration_s: Some(d.unwrap_or(one(period_s))),
                }
            }
            Motion::YawTurn => {
                let MotionCommand::YawTurn {
                    yaw_rate_rad_s,
                    step_period_s,
                    lift_height_m,
                    ..
                } = MotionCommand::seed001_yaw_turn(None)
                else {
                    unreachable!("seed001_yaw_turn is a yaw turn")
                };
                let step_period_s = self.step_period_s.unwrap_or(step_period_s);
                MotionCommand::YawTurn {
                    yaw_rate_rad_s: self.yaw_rate_rad_s.unwrap_or(yaw_rate_rad_s),
                    step_period_s,
                    lift_height_m: self.lift_height_m.unwrap_or(lift_height_m),
                    duration_s: Some(d.unwrap_or(one(step_period_s))),
                }
            }
            Motion::FootPath => {
                let legs = self.leg.map_or(LegSet::All, LegSet::One);
                let MotionCommand::FootPath {
                    path,
                    stride_m,
                    step_height_m,
                    duty_factor,
                    cycle_s,
                    ..
                } = MotionCommand::seed000_rectangle(legs, None)
                else {
                    unreachable!("seed000_rectangle is a foot path")
                };
                let cycle_s = self.cycle_s.unwrap_or(cycle_s);
                MotionCommand::FootPath {
                    path: self.path.unwrap_or(path),
                    legs,
                    stride_m: self.stride_m.unwrap_or(stride_m),
                    step_height_m: self.step_height_m.unwrap_or(step_height_m),
                    duty_factor: self.duty_factor.unwrap_or(duty_factor),
                    cycle_s,
                    duration_s: Some(d.unwrap_or(one(cycle_s))),
                }
            }
            Motion::StableTurn => {
                let MotionCommand::StableTurn {
                    yaw_per_cycle_rad,
                    cycle_s,
                    lift_height_m,
                    shift_fraction,
                    ..
                } = MotionCommand::stable_turn(stance_height_m, None)
                else {
                    unreachable!("stable_turn is a stable turn")
                };
                let cycle_s = self.cycle_s.unwrap_or(cycle_s);
                MotionCommand::StableTurn {
                    yaw_per_cycle_rad: self.yaw_per_cycle_rad.unwrap_or(yaw_per_cycle_rad),
                    cycle_s,
                    lift_height_m: self.lift_height_m.unwrap_or(lift_height_m),
                    shift_fraction: self.shift_fraction.unwrap_or(shift_fraction),
                    duration_s: Some(d.unwrap_or(one(cycle_s))),
                }
            }
            Motion::Trot | Motion::Walk => {
                let gait = if self.motion == Motion::Trot {
                    Pattern::Trot
                } else {
                    Pattern::Walk
                };
                let body_height_m = self.body_height_m.unwrap_or(stance_height_m);
                let MotionCommand::Walk {
                    step_height_m,
                    cycle_s,
                    velocity_timeout_ms,
                    ..
                } = MotionCommand::walk(gait, body_height_m)
                else {
                    unreachable!("walk is a walk")
                };
                let step = VelocityStep {
                    forward_m_s: self.forward_m_s.unwrap_or(0.0),
                    lateral_m_s: self.lateral_m_s.unwrap_or(0.0),
                    yaw_rate_rad_s: self.yaw_rate_rad_s.unwrap_or(0.0),
                    duration_s: d.unwrap_or(5.0),
                };
                let walk = MotionCommand::Walk {
                    gait,
                    body_height_m,
                    step_height_m: self.step_height_m.unwrap_or(step_height_m),
                    cycle_s: self.cycle_s.unwrap_or(cycle_s),
                    velocity_timeout_ms: self.velocity_timeout_ms.unwrap_or(velocity_timeout_ms),
                };
                return (walk, vec![step]);
            }
        };
        (request, Vec::new())
    }
}

/// The default duration of a periodic motion: one `period_s`, or 1 s when the period itself
/// is invalid (so that the device's refusal names the period, not the duration).
fn one(period_s: f32) -> f32 {
    if period_s.is_finite() && period_s > 0.0 {
        period_s
    } else {
        1.0
    }
}

fn finish<L: quad_host::link::Link>(
    session: &mut Session<L>,
    request: &MotionCommand,
    walk: &[VelocityStep],
) -> ExitCode {
    let summary = match onboard::run(session, request, walk, WAIT_LIMIT, |_| {}) {
        Ok(s) => s,
        Err(e) => return args::fail("quadctl", &e),
    };
    match args::print_json_line(&summary) {
        Ok(()) => ExitCode::from(EXIT_OK),
        Err(status) => status,
    }
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

/// Runs `quadctl stand`, `sit` or `rest` (`request`) and returns its exit status.
pub fn posture(args: &PostureArgs, request: MotionCommand) -> ExitCode {
    match session(&args.robot, &args.target) {
        Ok(mut s) => finish(&mut s, &request, &[]),
        Err(e) => args::fail("quadctl", &e),
    }
}

/// Runs `quadctl run` and returns its exit status.
pub fn run(args: &RunArgs) -> ExitCode {
    let name = args
        .motion
        .to_possible_value()
        .map_or_else(String::new, |v| v.get_name().to_owned());
    if let Some(option) = args.given().into_iter().find(|o| !applies(args.motion, o)) {
        return args::fail(
            "quadctl",
            &NotApplicable {
                option,
                motion: name,
            },
        );
    }
    let mut s = match session(&args.robot, &args.target) {
        Ok(s) => s,
        Err(e) => return args::fail("quadctl", &e),
    };
    let (request, walk) = args.request(s.info().pose_config.stance_height_m);
    finish(&mut s, &request, &walk)
}
