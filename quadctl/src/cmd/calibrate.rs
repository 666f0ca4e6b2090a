//! `quadctl calibrate`: read, edit (from a TOML file) and save the device's servo calibration.

use crate::args::{self, TargetArgs};
use quad_host::ops::calibrate::{self, to_toml};
use quad_protocol::RobotPreset;
use std::io::{self, Write};
use std::path::PathBuf;
use std::process::ExitCode;

/// Why `--robot` was refused.
#[derive(Debug, thiserror::Error)]
#[error("--robot {0}: not a preset (shahriar2023, fernando2025)")]
struct NotAPreset(String);

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

TOML: one inline table per servo, every field required, e.g.
  FL_knee = { zero_rad = -1.0472, reversed = false, us_per_rad = 636.62, center_us = 1500, min_us = 500, max_us = 2500 }

The device refuses a calibration whose travel excludes the joint's current angle (move the robot
first). With --sim the simulated device powers on at every run: keep its EEPROM in a file with
--sim-storage FILE to see a save in a later run.";

/// What to do.
#[derive(Debug, Clone, PartialEq, Eq, clap::Subcommand)]
pub enum Action {
    /// Print the device's 12 calibrations as TOML.
    #[command(after_help = "Example: quadctl calibrate --sim get > cal.toml")]
    Get,
    /// Send the calibrations of FILE.toml to the device's RAM.
    #[command(
        after_help = "Example: quadctl calibrate --sim --sim-storage eeprom.bin set cal.toml --save"
    )]
    Set {
        /// TOML file with one table per servo to change.
        file: PathBuf,
        /// Persist them too (as `save`).
        #[arg(long)]
        save: bool,
    },
    /// Persist the calibration held in the device's RAM.
    #[command(after_help = "Example: quadctl calibrate --sim --sim-storage eeprom.bin save")]
    Save,
}

/// `--help`'s examples, run from the repository root (the files of `examples/`).
pub const EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl calibrate --sim get > cal.toml
  quadctl calibrate --sim --sim-storage eeprom.bin set cal.toml --save
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
    /// Robot of the simulated device.
    #[arg(long, value_name = "PRESET", default_value = "fernando2025", value_parser = crate::args::parse_robot)]
    pub robot: String,
    #[command(subcommand)]
    #[allow(missing_docs)]
    pub action: Action,
}

/// Runs `quadctl calibrate` and returns its exit status.
pub fn main(args: &Args) -> ExitCode {
    let Some(preset) = RobotPreset::from_name(args.robot.trim()) else {
        return args::fail("quadctl", &NotAPreset(args.robot.clone()));
    };
    let action = match &args.action {
        Action::Get => calibrate::Action::Get,
        Action::Set { file, save } => calibrate::Action::Set {
            file: file.clone(),
            save: *save,
        },
        Action::Save => calibrate::Action::Save,
    };
    let target = args.target.target(preset);
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
