//! `quadctl export`: the robot as a MuJoCo MJCF model, a URDF or a TOML robot file.

use crate::args;
use quad_twin::command::{self, Format};
use std::path::PathBuf;
use std::process::ExitCode;

const LONG_ABOUT: &str = "\
Write the robot as a MuJoCo MJCF model, a URDF (for RViz, PyBullet) or a TOML robot file (every
key explicit, for editing; `--robot` reads each of them back): the body box, the leg
chain of the README's convention (abduction about x, hip and knee about y), spherical feet with
friction, masses and inertias from the robot's physical preset or its TOML [physical] table,
the servos as position actuators (MJCF). docs/twin.md lists the assumptions.

Exit status: 0 written; 2 a bad robot or value, or the file could not be written (nothing is
left at --output).";

/// `--help`'s examples, run from the repository root (the files of `examples/`).
pub const EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl export --format mjcf --output robot.xml
  quadctl export --format urdf --robot examples/robots/shahriar2023.toml --output shahriar2023.urdf
  quadctl export --format toml --robot shahriar2023.urdf --output my-robot.toml";

/// Arguments of `quadctl export`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Write the robot as a MuJoCo MJCF model, a URDF or a TOML robot file",
    long_about = LONG_ABOUT,
    after_help = EXAMPLES
)]
pub struct Args {
    /// Description format.
    #[arg(long, value_parser = format())]
    pub format: Format,
    /// Robot: a preset (shahriar2023, fernando2025), a TOML robot file or a URDF.
    #[arg(long, value_name = "PRESET|FILE", default_value = "shahriar2023", value_parser = crate::args::parse_robot)]
    pub robot: String,
    /// Another servo preset on every joint: mg996r, ds3235, qdd17, qdd33.
    #[arg(long, value_name = "NAME")]
    pub servo: Option<String>,
    /// Output file [default: stdout].
    #[arg(long, value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `--format`.
fn format() -> impl clap::builder::TypedValueParser<Value = Format> {
    fn help(f: Format) -> String {
        match f {
            Format::Mjcf => "MuJoCo MJCF (XML), with the servos as actuators",
            Format::Urdf => "URDF (XML)",
            Format::Toml => {
                "this project's TOML robot file (every key explicit; --robot reads it back)"
            }
        }
        .to_owned()
    }
    args::choice(&Format::ALL, Format::name, help)
}

/// `quadctl export`.
pub fn run(args: &Args) -> ExitCode {
    match command::export(
        &args.robot,
        args.servo.as_deref(),
        args.format,
        args.output.as_ref(),
    ) {
        Ok(()) => ExitCode::from(args::EXIT_OK),
        Err(e) => args::fail("quadctl export", &e),
    }
}
