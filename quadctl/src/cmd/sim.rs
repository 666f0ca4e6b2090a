//! `quadctl sim`: a motion of the physics twin's catalogue in MuJoCo, driven by the device
//! controller or by the firmware in simavr.

use crate::args;
use quad_twin::command::{self, Sim};
use quad_twin::scenario::{Scenario, SlopeAxis};
use quad_twin::{Driver, MotionKind, RunOptions};
use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

const LONG_ABOUT: &str = "\
Run MOTION on the robot in the physics twin (MuJoCo: a body, gravity, foot contacts, servos
with stall torque and speed limits) and print its metrics: fell or not, yaw and distance
reached against the commanded ones, foot slip in stance, peak and RMS torque per joint against
the servo's stall torque, body roll/pitch tracking. docs/twin.md explains the model and the
thresholds.

The servo frames (50 Hz) come from the device's own code: --sim (the default) steps the device
controller in-process, a host sending the motion's feet as SetFeet every frame; --emulator runs
the firmware ELF in simavr and measures the pulses on its twelve servo pins (seed 000's robot
only, the firmware's). The pulses map back to joint angles through the device's calibration.
With --onboard the device runs the motion itself: its motion engine gets the motion once
(StartMotion; the trots are its walker with the velocity command sent every frame), and the
host only watches (all but stand).

The world: --slope-deg D inclines the floor by D degrees about --slope-axis (roll, the default:
positive raises the floor on the robot's left; pitch: positive lowers it ahead), the robot
placed on it; --tilt-floor tilts the floor by 10° more about that axis over 1 s from 2.5 s into
the motion; --push-n-s I pushes the body sideways with an impulse of I N·s (a 0.1 s force pulse
at its centre of mass along the world's +y, the robot's left; negative: to the right) at 2.5 s.
A tilt or a push makes the run last 3 s past it; the report adds the body's largest |roll| and
|pitch| from the disturbance, their settled values and the settling time. Every run reports the
IMU's samples (200 Hz: accelerometer, gyroscope and the true attitude, in trace.npz), which the
device receives at their times (--emulator: the firmware reads them from its emulated MPU-6050
over its TWI driver).

--balance switches the device's balance functions on (SetBalance with the protocol's default
gains: leveling the body while it stands or sways, fall detection at 60° with the rest pose as
the safe state), sent once its sensor has given a reading (the device then measures the gyro
bias for 1 s before it levels). The report adds the device's attitude estimate against the
true attitude (in-process always; --emulator with --balance, a GetImu every frame).

--render FILE writes an animation of the run (GIF; a strip of frames when FILE ends in .png);
--out-dir DIR keeps the model, summary.json, plots.png, and with --render, motion.gif and
strip.png. Needs the twin's Python environment (scripts/install-deps.sh creates .venv-twin).

Robots: a preset, a TOML robot file (its optional [physical] table: masses, servo preset), or a
URDF with this project's leg chain.

Exit status: 0 the run finished (a fall is a result, reported); 2 a bad argument, robot or
value, or the twin could not run (no output file is left behind).";

/// `--help`'s examples, run from the repository root.
pub const EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl sim stand --robot fernando2025
  quadctl sim trot --robot shahriar2023 --out-dir trot
  quadctl sim stand --emulator --out-dir stand --render stand.gif
  quadctl sim trot --onboard
  quadctl sim stand --slope-deg 10 --render target/twin/slope.png
  quadctl sim stand --slope-deg 10 --balance --render target/twin/slope-balance.png
  quadctl sim stand --tilt-floor --slope-axis pitch
  quadctl sim stand --push-n-s 2";

/// Arguments of `quadctl sim`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Run a motion in the physics twin (MuJoCo) and print its metrics",
    long_about = LONG_ABOUT,
    after_help = EXAMPLES
)]
pub struct Args {
    /// The motion.
    #[arg(value_parser = motion())]
    pub motion: MotionKind,
    /// Robot: a preset (shahriar2023, fernando2025), a TOML robot file or a URDF.
    #[arg(long, value_name = "PRESET|FILE", default_value = "shahriar2023", value_parser = crate::args::parse_robot)]
    pub robot: String,
    /// The device controller in-process (the simulated link's device); the default.
    #[arg(long, conflicts_with = "emulator")]
    pub sim: bool,
    /// The firmware in simavr (an emulated ATmega2560), its pin pulses measured.
    #[arg(long)]
    pub emulator: bool,
    /// Firmware ELF for --emulator [default: firmware.elf built from firmware-avr/].
    #[arg(long, value_name = "PATH", requires = "emulator")]
    pub elf: Option<PathBuf>,
    /// The device runs the motion itself (its motion engine: started once, a trot's velocity
    /// sent every frame) instead of getting every frame's feet from the host.
    #[arg(long)]
    pub onboard: bool,
    /// Write an animation of the run to FILE (.gif; .png: a strip of frames).
    #[arg(long, value_name = "FILE")]
    pub render: Option<PathBuf>,
    /// Keep the model, summary.json and plots.png (and the pictures with --render) here.
    #[arg(long, value_name = "DIR")]
    pub out_dir: Option<PathBuf>,
    /// Another servo preset on every joint: mg996r, ds3235, qdd17, qdd33.
    #[arg(long, value_name = "NAME")]
    pub servo: Option<String>,
    /// Another stance height than the device's default, m.
    #[arg(long, value_name = "M", value_parser = args::parse_positive_m)]
    pub stance_height_m: Option<f32>,
    /// Incline the floor by D degrees about --slope-axis (at most ±30°).
    #[arg(long, value_name = "D", default_value_t = 0.0, allow_negative_numbers = true, value_parser = args::parse_finite)]
    pub slope_deg: f32,
    /// The axis of --slope-deg and --tilt-floor.
    #[arg(long, value_name = "AXIS", default_value = "roll", value_parser = slope_axis())]
    pub slope_axis: SlopeAxis,
    /// Tilt the floor by 10° more about --slope-axis over 1 s, from 2.5 s into the motion.
    #[arg(long)]
    pub tilt_floor: bool,
    /// Push the body sideways with an impulse of I N·s at 2.5 s (along +y, the robot's left).
    #[arg(long, value_name = "I", allow_negative_numbers = true, value_parser = args::parse_finite)]
    pub push_n_s: Option<f32>,
    /// Switch the device's balance functions on: leveling and fall detection with the
    /// protocol's default settings.
    #[arg(long)]
    pub balance: bool,
}

/// `--slope-axis`: roll or pitch.
fn slope_axis() -> impl clap::builder::TypedValueParser<Value = SlopeAxis> {
    args::choice(&SlopeAxis::ALL, SlopeAxis::name, |a| {
        match a {
            SlopeAxis::Roll => "about the robot's forward axis: it rolls with the floor",
            SlopeAxis::Pitch => "about the robot's left axis: it pitches with the floor",
        }
        .to_owned()
    })
}

/// `--motion`: the twin's catalogue by name.
fn motion() -> impl clap::builder::TypedValueParser<Value = MotionKind> {
    args::choice(&MotionKind::ALL, MotionKind::name, |m| {
        m.summary().to_owned()
    })
}

/// `quadctl sim`.
pub fn run(args: &Args) -> ExitCode {
    let scenario = match Scenario::new(
        args.slope_axis,
        args.slope_deg,
        args.tilt_floor,
        args.push_n_s,
    ) {
        Ok(s) => s,
        Err(e) => return args::fail("quadctl sim", &e),
    };
    let request = Sim {
        robot: args.robot.clone(),
        motion: args.motion,
        servo: args.servo.clone(),
        stance_height_m: args.stance_height_m,
        options: RunOptions {
            out_dir: args.out_dir.clone(),
            render: args.render.is_some(),
            picture: args.render.clone(),
            driver: if args.emulator {
                Driver::Emulator {
                    elf: args.elf.clone(),
                }
            } else {
                Driver::Device
            },
            onboard: args.onboard,
            scenario,
            balance: args.balance.then_some(quad_protocol::BalanceConfig {
                leveling: true,
                fall_detection: true,
                ..quad_protocol::BalanceConfig::DEFAULT
            }),
        },
    };
    match command::sim(&request) {
        Ok(run) => {
            // Nothing useful can be done if stdout itself fails.
            let _ = write!(std::io::stdout(), "{run}");
            ExitCode::from(args::EXIT_OK)
        }
        Err(e) => args::fail("quadctl sim", &e),
    }
}
