//! `quadctl plot`: figures of a motion CSV — joint angles over time (seed 001 Fig. 4–6) or the
//! robot in top, side and front views at chosen instants (seed 000 Fig. 6–7).

use crate::args;
use kin_core::RotationOrder;
use quad_host::ops::plot::{self, Request};
use std::path::PathBuf;
use std::process::ExitCode;

const LONG_ABOUT: &str = "\
Draw a motion CSV written by `quadctl motion` (FILE, `-` for stdin) to an SVG or PNG file (by
the extension of --output).

Without --at-s: the twelve joint angles over time, one panel per joint (abduction, hip, knee),
one curve per leg, in degrees (seed 001 Fig. 4-6). Unreachable samples leave gaps. Long files
are decimated to a few thousand points per curve.

With --at-s T1,T2,...: the robot at the samples nearest to those times, one row per time, in
three views on one equal-aspect scale: top (x forward, y left), side (x, z up), front (y, z),
body outline in black, legs coloured FL blue, FR red, RL green, RR purple (seed 000 Fig. 6-7).
Needs --robot; the rotation order is read from the file's `# quadctl motion` line, else
--rotation-order, else zyx.

Text needs a TrueType font, read at run time: $QUADCTL_FONT or a system font (DejaVu Sans,
Liberation Sans, FreeSans; Debian: apt-get install fonts-dejavu-core).";

/// Arguments of `quadctl plot`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Draw a motion CSV: joint angles over time, or the robot in three views (SVG/PNG)",
    long_about = LONG_ABOUT
)]
pub struct Args {
    /// Motion CSV written by `quadctl motion` (`-` for stdin).
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    /// Output figure: .svg or .png.
    #[arg(long, value_name = "OUT.svg")]
    pub output: PathBuf,
    /// Draw the robot at these times (s), comma-separated, instead of the joint angles.
    #[arg(
        long,
        value_name = "T1,T2,…",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    pub at_s: Vec<f64>,
    /// Robot (needed with --at-s): preset or TOML file.
    #[arg(long, value_name = "PRESET|FILE.toml")]
    pub robot: Option<String>,
    /// Rotation order of the poses in the file (overrides the file's own).
    #[arg(long, value_parser = args::rotation_order())]
    pub rotation_order: Option<RotationOrder>,
    /// Figure title [default: the file name].
    #[arg(long)]
    pub title: Option<String>,
}

/// `quadctl plot`.
pub fn run(args: &Args) -> ExitCode {
    args::exit_status(plot::run(&Request {
        file: args.file.clone(),
        output: args.output.clone(),
        at_s: args.at_s.clone(),
        robot: args.robot.clone(),
        rotation_order: args.rotation_order,
        title: args.title.clone(),
    }))
}
