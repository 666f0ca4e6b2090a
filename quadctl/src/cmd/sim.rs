//! `quadctl sim`: a motion of the physics twin's catalogue in MuJoCo, driven by the device
//! controller or by the firmware in simavr.

use crate::args;
use quad_twin::command::{self, Sim};
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
  quadctl sim trot --onboard";

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
}

/// `--motion`: the twin's catalogue by name.
fn motion() -> impl clap::builder::TypedValueParser<Value = MotionKind> {
    args::choice(&MotionKind::ALL, MotionKind::name, |m| {
        m.summary().to_owned()
    })
}

/// `quadctl sim`.
pub fn run(args: &Args) -> ExitCode {
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
