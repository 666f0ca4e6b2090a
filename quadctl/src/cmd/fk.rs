//! `quadctl fk`: leg forward kinematics, one set of joint angles per record.

use crate::args::{Error, InputArgs, RobotArgs, BATCH_RULES};
use quad_host::csv::{Input, Summary};
use quad_host::ops::batch;
use std::io::Write;

const LONG_ABOUT: &str = "\
Leg forward kinematics: joint angles -> foot position in the hip frame.

Input columns: leg,abduction_rad,hip_rad,knee_rad — joint angles in RADIANS in the canonical
convention (all zero: leg straight down; abduction about x, hip and knee about the abducted y
axis, knee relative to the femur). Angles must be finite (nan or inf make the record
malformed). Joint limits are NOT checked: any finite angles give the foot they put it at.

Output columns: leg,x_m,y_m,z_m — the foot in the HIP FRAME of that leg, metres: origin at the
leg's hip (abduction-axis) mount, axes parallel to the body frame (x forward, y left, z up):

  foot = Rx(abduction)·([0, s·d_lat, −d_ax] + Ry(hip)·[0,0,−femur] + Ry(hip+knee)·[0,0,−tibia])

with s = +1 for the left legs (FL, RL) and −1 for the right legs (FR, RR).";

/// Arguments of `quadctl fk`.
#[derive(Debug, Clone, PartialEq, Eq, clap::Args)]
#[command(
    about = "Leg FK: joint angles (rad) -> foot in hip frame (m), CSV",
    long_about = LONG_ABOUT,
    after_long_help = BATCH_RULES
)]
pub struct Args {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub robot: RobotArgs,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: InputArgs,
}

/// Runs the batch: reads `input`, writes the answers to `out`, reports malformed records on
/// `diag`.
pub fn run(
    args: &Args,
    input: Input,
    out: &mut dyn Write,
    diag: &mut dyn Write,
) -> Result<Summary, Error> {
    let robot = args.robot.load(None)?;
    Ok(batch::fk(&robot, input, out, diag)?)
}
