//! `quadctl ik`: leg inverse kinematics, one foot target per record.

use super::{Error, InputArgs, Knee, RobotArgs, BATCH_RULES};
use crate::csv_io::{self, FirstColumn, Input, Num, Schema, Summary};
use kin_core::{leg, ReachPolicy, Vec3};
use std::io::Write;

/// Input columns.
pub const INPUT: Schema = Schema {
    columns: &["leg", "x_m", "y_m", "z_m"],
    first: FirstColumn::Leg,
};

/// Output header under `--policy reject`.
pub const OUTPUT_HEADER: &str = "leg,abduction_rad,hip_rad,knee_rad,status";

/// Output header under `--policy clamp`.
pub const OUTPUT_HEADER_CLAMP: &str = "leg,abduction_rad,hip_rad,knee_rad,status,clamp_distance_m";

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

/// What the IK does with an unreachable target.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Policy {
    /// Report the reason in `status`, leave the angles empty.
    Reject,
    /// Move the target to the nearest reachable point and report the distance moved.
    Clamp,
}

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
    #[arg(long, value_enum)]
    pub knee: Option<Knee>,
    /// What to do with unreachable targets.
    #[arg(long, value_enum, default_value_t = Policy::Reject)]
    pub policy: Policy,
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
    let (policy, header) = match args.policy {
        Policy::Reject => (ReachPolicy::Reject, OUTPUT_HEADER),
        Policy::Clamp => (ReachPolicy::Clamp, OUTPUT_HEADER_CLAMP),
    };
    let clamp = policy == ReachPolicy::Clamp;
    let summary = csv_io::for_each_row(input, INPUT, out, diag, Some(header), |row, out| {
        let leg = row.leg(0)?;
        let foot_in_hip = Vec3::new(row.number(1)?, row.number(2)?, row.number(3)?);
        match leg::Solver::new(&robot).inverse(leg, foot_in_hip, policy) {
            Ok(solution) => {
                let q = solution.angles;
                write!(
                    out,
                    "{leg},{},{},{},",
                    Num(q.abduction_rad),
                    Num(q.hip_rad),
                    Num(q.knee_rad)
                )?;
                match solution.clamped {
                    None if clamp => writeln!(out, "ok,0")?,
                    None => writeln!(out, "ok")?,
                    Some(c) => writeln!(out, "clamped:{},{}", c.kind.code(), Num(c.distance_m))?,
                }
            }
            Err(e) => {
                let tail = if clamp { "," } else { "" };
                writeln!(out, "{leg},,,,{}{tail}", e.kind.code())?;
            }
        }
        Ok(())
    })?;
    Ok(summary)
}
