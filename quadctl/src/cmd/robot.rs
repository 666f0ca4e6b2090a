//! `quadctl robot`: show, send (from a preset, a TOML or a URDF file) and store the robot the
//! device holds (protocol 2.4).

use crate::args::{self, TargetArgs};
use quad_host::ops::robot::{self, to_toml};
use quad_protocol::RobotPreset;
use std::io::{self, Write};
use std::process::ExitCode;

/// Why `--sim-preset` was refused.
#[derive(Debug, thiserror::Error)]
#[error("--sim-preset {0}: not a preset (shahriar2023, fernando2025)")]
struct NotAPreset(String);

const LONG_ABOUT: &str = "\
Shows, sends and stores the robot the device holds (--sim, --emulator or --port; protocol 2.4).

The device runs its kinematics on one robot: the leg geometry, the body size, the joint limits
and the knee bend (the keys of a robot file), with the stance height, the rotation order of
body poses and the joint-speed limit it stands and moves with (the file's [device] table). At
power-on it takes the robot stored in its EEPROM (two banks with a CRC, written only by a save),
else the robot compiled into the firmware. Lengths in METRES, angles in RADIANS.

  show              print the device's robot as a robot file (the format `send` reads), with
                    its hash, the one the device reports in its hello
  send ROBOT        send a preset (shahriar2023, fernando2025), a TOML or a URDF robot file to
                    the device's RAM; --save also stores it
  save              store the robot in the device's RAM

The host checks the robot first, as the device does (lengths and limits within their ranges,
the stance reachable by every leg, the rest pose within the limits): a robot the device cannot
hold is refused naming the field, and nothing is sent. The device refuses a new robot while
its outputs are on (`quadctl rest` first). Every device command checks that the device holds
the robot it is given with --robot, by the hash.

Exit status: 0 done; 2 refused (bad arguments or robot file, the device's refusal, a link
error).";

/// What to do.
#[derive(Debug, Clone, PartialEq, Eq, clap::Subcommand)]
pub enum Action {
    /// Print the device's robot as a robot file.
    #[command(after_help = "Example: quadctl robot --sim show > robot.toml")]
    Show,
    /// Send a robot (a preset, FILE.toml or FILE.urdf) to the device's RAM.
    #[command(
        after_help = "Example: quadctl robot --sim --sim-storage eeprom.bin send examples/robots/bench-pup.toml --save"
    )]
    Send {
        /// A preset (shahriar2023, fernando2025), a TOML or a URDF robot file.
        #[arg(value_name = "PRESET|FILE.toml|FILE.urdf")]
        robot: String,
        /// Store it too (as `save`).
        #[arg(long)]
        save: bool,
    },
    /// Store the robot held in the device's RAM.
    #[command(after_help = "Example: quadctl robot --sim --sim-storage eeprom.bin save")]
    Save,
}

/// `--help`'s examples, run from the repository root (the files of `examples/`).
pub const EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl robot --sim show
  quadctl robot --sim --sim-storage eeprom.bin send examples/robots/bench-pup.toml --save
  quadctl robot --port /dev/ttyACM0 show";

/// Arguments of `quadctl robot`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Show, send (preset, TOML or URDF) and store the robot the device holds",
    long_about = LONG_ABOUT,
    after_help = EXAMPLES
)]
pub struct Args {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub target: TargetArgs,
    /// The robot compiled into the simulated device (--sim; its EEPROM may hold another). The
    /// default is the firmware's, as for every other device command.
    #[arg(long, value_name = "PRESET", default_value = "shahriar2023", value_parser = crate::args::parse_robot)]
    pub sim_preset: String,
    #[command(subcommand)]
    #[allow(missing_docs)]
    pub action: Action,
}

/// Runs `quadctl robot` and returns its exit status.
pub fn main(args: &Args) -> ExitCode {
    let Some(preset) = RobotPreset::from_name(args.sim_preset.trim()) else {
        return args::fail("quadctl", &NotAPreset(args.sim_preset.clone()));
    };
    let action = match &args.action {
        Action::Show => robot::Action::Show,
        Action::Send { robot, save } => robot::Action::Send {
            robot: robot.clone(),
            save: *save,
        },
        Action::Save => robot::Action::Save,
    };
    let target = args.target.target(preset);
    let held = match robot::run(&target, args.target.retries, &action) {
        Ok(r) => r,
        Err(e) => return args::fail("quadctl", &e),
    };
    let text = match action {
        robot::Action::Save | robot::Action::Send { save: true, .. } => {
            "# saved\n".to_owned() + &to_toml(&held)
        }
        _ => to_toml(&held),
    };
    let mut out = io::stdout().lock();
    args::exit_status(out.write_all(text.as_bytes()).and_then(|()| out.flush()))
}
