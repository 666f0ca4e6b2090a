//! `quadctl ik`: leg inverse kinematics, one foot target per record.

use crate::args::{self, Error, InputArgs, RobotArgs, BATCH_RULES};
use kin_core::{KneeBend, ReachPolicy};
use quad_host::csv::{Input, Summary};
use quad_host::ops::batch;
use std::io::Write;

const LONG_ABOUT: &str = "\
Leg inverse kinematics: foot positions in the hip frame -> joint angles.

Input columns: leg,x_m,y_m,z_m — the foot in the HIP FRAME of that leg, metres: origin at the
leg's hip (abduction-axis) mount, axes parallel to the body frame (x forward, y left, z up).

Output columns: leg,abduction_rad,hip_rad,knee_rad,status — joint angles in RADIANS in the
canonical convention (all zero: leg straight down; abduction about x, hip and knee about the
abducted y axis, knee relative to the femur).

status is `ok`, or why the target is unreachable, with the three angle cells left empty:
too_far, too_close, inside_offset (foot within d_lat of the abduction axis), joint_limit,
non_finite (a coordinate is nan or inf).

With --policy clamp an unreachable target is moved to the nearest reachable point (and the
angles clamped to the joint limits): the row then has angles, status `clamped:<reason>` and a
last column clamp_distance_m, the distance in metres between the requested foot and the foot the
angles reach (0 for `ok` rows; empty for non_finite rows, which are still rejected).";

/// Arguments of `quadctl ik`.
#[derive(Debug, Clone, PartialEq, Eq, clap::Args)]
#[command(
    about = "Leg IK: foot in hip frame (m) -> joint angles (rad), CSV",
    long_about = LONG_ABOUT,
    after_long_help = BATCH_RULES
)]
pub struct Args {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub robot: RobotArgs,
    /// Knee solution; default: the robot's own (backward for the presets).
    #[arg(long, value_parser = args::knee())]
    pub knee: Option<KneeBend>,
    /// What to do with unreachable targets.
    #[arg(long, value_parser = args::policy(), default_value = "reject")]
    pub policy: ReachPolicy,
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
    let robot = args.robot.load(args.knee)?;
    Ok(batch::ik(&robot, args.policy, input, out, diag)?)
}
