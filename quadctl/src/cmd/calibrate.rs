//! `quadctl calibrate`: read, edit (from a TOML file) and save the device's servo calibration,
//! or walk through it step by step (`guide`).

use crate::args::{self, TargetArgs};
use quad_host::ops::calibrate::{self, to_toml};
use quad_protocol::RobotPreset;
use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;

mod guide;

/// Why `--robot` was refused.
#[derive(Debug, thiserror::Error)]
enum RobotError {
    #[error(
        "--robot {0}: the simulated device (--sim) runs a preset (shahriar2023, fernando2025)"
    )]
    NotAPreset(String),
    #[error("{0}")]
    File(#[from] quad_host::robot_file::Error),
}

const LONG_ABOUT: &str = "\
Reads, edits and saves the servo calibration of the device (--sim or --port).

One calibration per servo, named <LEG>_<joint> (FL_abduction, FL_hip, FL_knee, FR_..., RL_...,
RR_...). The pulse for a joint angle is

  pulse_us = center_us + s * us_per_rad * (angle_rad - zero_rad),  s = -1 if reversed, else +1

valid only within [min_us, max_us] (a target outside is refused, never clamped). Angles in
RADIANS, pulses in MICROSECONDS.

  get            print the 12 calibrations as TOML (the format `set` reads)
  set FILE.toml  send the servos listed in FILE (any subset) to the device's RAM; --save also
                 persists them
  save           persist the calibration in the device's RAM (EEPROM, two banks with a CRC)
  guide          the guided calibration, step by step: the calibration posture, each servo
                 jogged to its mark, test poses (rest, stand, a step in place), save or abort
                 (`quadctl calibrate guide --help`)

TOML: one inline table per servo, every field required, e.g.
  FL_knee = { zero_rad = -1.0472, reversed = false, us_per_rad = 636.62, center_us = 1500, min_us = 500, max_us = 2500 }

The device refuses a calibration whose travel excludes the joint's current angle (move the robot
first). With --sim the simulated device powers on at every run: keep its EEPROM in a file with
--sim-storage FILE to see a save in a later run.

The robot is the device's own (its handshake reports it): --robot names the simulated device's
preset with --sim (required there), and the robot file of a device whose robot is no preset
(`guide` plans its posture and test poses with it).";

/// What to do.
#[derive(Debug, Clone, PartialEq, Eq, clap::Subcommand)]
pub enum Action {
    /// Print the device's 12 calibrations as TOML.
    #[command(after_help = "Example: quadctl calibrate --sim --robot shahriar2023 get > cal.toml")]
    Get,
    /// Send the calibrations of FILE.toml to the device's RAM.
    #[command(
        after_help = "Example: quadctl calibrate --sim --robot shahriar2023 --sim-storage eeprom.bin set cal.toml --save"
    )]
    Set {
        /// TOML file with one table per servo to change.
        file: PathBuf,
        /// Persist them too (as `save`).
        #[arg(long)]
        save: bool,
    },
    /// Persist the calibration held in the device's RAM.
    #[command(
        after_help = "Example: quadctl calibrate --sim --robot shahriar2023 --sim-storage eeprom.bin save"
    )]
    Save,
    /// The guided calibration: posture, jog each servo to its mark, test poses, save or abort.
    #[command(long_about = guide::LONG_ABOUT, after_help = guide::EXAMPLES)]
    Guide(guide::Args),
}

/// `--help`'s examples, run from the repository root (the files of `examples/`).
pub const EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl calibrate --sim --robot shahriar2023 get > cal.toml
  quadctl calibrate --sim --robot shahriar2023 --sim-storage eeprom.bin set cal.toml --save
  quadctl calibrate --sim --robot shahriar2023 guide --script n,+,+,n,t,n,n,n,s
  quadctl calibrate --port /dev/ttyACM0 get";

/// Arguments of `quadctl calibrate`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Read, edit (TOML) and save the device's servo calibration (--sim or --port)",
    long_about = LONG_ABOUT,
    after_help = EXAMPLES
)]
pub struct Args {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub target: TargetArgs,
    /// Robot: the simulated device's preset with --sim (required there); for `guide` on a
    /// device whose robot is no preset, its robot file. Default: the device's own.
    #[arg(long, value_name = "PRESET|FILE.toml", value_parser = crate::args::parse_robot, required_if_eq("sim", "true"))]
    pub robot: Option<String>,
    #[command(subcommand)]
    #[allow(missing_docs)]
    pub action: Action,
}

/// The preset of the simulated device (`--sim`; the others run their own robot).
fn sim_preset(args: &Args) -> Result<RobotPreset, RobotError> {
    match (&args.robot, args.target.sim) {
        (Some(name), true) => {
            RobotPreset::from_name(name.trim()).ok_or_else(|| RobotError::NotAPreset(name.clone()))
        }
        // Not simulated: the preset is not used (clap requires --robot with --sim).
        _ => Ok(RobotPreset::Custom),
    }
}

/// Runs `quadctl calibrate` and returns its exit status.
pub fn main(args: &Args) -> ExitCode {
    let preset = match sim_preset(args) {
        Ok(p) => p,
        Err(e) => return args::fail("quadctl", &e),
    };
    let target = args.target.target(preset);
    let action = match &args.action {
        Action::Get => calibrate::Action::Get,
        Action::Set { file, save } => calibrate::Action::Set {
            file: file.clone(),
            save: *save,
        },
        Action::Save => calibrate::Action::Save,
        Action::Guide(guide) => {
            // A robot file for a device whose robot is no preset; with --sim, --robot is the
            // simulated device's preset, which the device then reports.
            let file = match &args.robot {
                Some(spec) if !args.target.sim => match quad_host::robot_file::resolve(spec) {
                    Ok(r) => Some(r),
                    Err(e) => return args::fail("quadctl", &RobotError::from(e)),
                },
                _ => None,
            };
            return guide::main(guide, &target, args.target.retries, file.as_ref());
        }
    };
    let table = match calibrate::run(&target, args.target.retries, &action) {
        Ok(t) => t,
        Err(e) => return args::fail("quadctl", &e),
    };
    let text = match action {
        calibrate::Action::Save => "# saved\n".to_owned() + &to_toml(&table),
        _ => to_toml(&table),
    };
    let mut out = io::stdout().lock();
    args::exit_status(out.write_all(text.as_bytes()).and_then(|()| out.flush()))
}
