//! `quadctl pose`: body pose → the twelve joint angles, feet held at the nominal stance.

use crate::args::{self, Error, InputArgs, RobotArgs, BATCH_RULES};
use kin_core::{BodyConfig, KneeBend, RotationOrder, Vec3};
use quad_host::csv::{Input, Summary};
use quad_host::ops::batch::{self, PoseFormat, PoseSetup};
use std::io::Write;

const LONG_ABOUT: &str = "\
Full-body IK: body pose -> the 12 joint angles, with the feet held at the nominal stance.

Frames: the world frame coincides with the body frame in the nominal pose; body frame origin at
the body's geometric centre, x forward, y left, z up. The feet stay at the nominal stance of
height H (--stance-height-m): each foot straight below its hip mount at depth H, in the plane of
the zero-abduction leg, i.e. foot_in_world = hip_in_body + (0, s·d_lat, −H), s = +1 left, −1
right.

Input columns: roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m — the body's rotation (RADIANS) and
translation (METRES) relative to the world frame. The rotation is the product of the elementary
rotations in --rotation-order, read left to right: zyx is R = Rz(yaw)·Ry(pitch)·Rx(roll), zxy is
Rz(yaw)·Rx(roll)·Ry(pitch) (seed 001). With --pivot-m c (body frame, metres) the body rotates
about c: foot_in_hip = Rᵀ·(foot_in_world − t − c) + c − hip_in_body.

Output (CSV): FL_abduction_rad,FL_hip_rad,FL_knee_rad, then FR, RL, RR likewise (RADIANS, the
canonical convention: all zero is the leg straight down), then status: `ok`, or `<leg>:<reason>`
for the first leg (in the order FL, FR, RL, RR) that cannot reach, e.g. `FR:too_far`, with all
twelve angle cells empty (all or nothing). Reasons: too_far, too_close, inside_offset,
joint_limit, non_finite (a nan or inf in the pose is reported as FL:non_finite).

Output (--table): a human-readable table per pose, angles in DEGREES (pose angles too), for
reading, not for parsing.";

/// Arguments of `quadctl pose`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Body IK: body pose (rad, m) -> 12 joint angles (rad) at the nominal stance, CSV",
    long_about = LONG_ABOUT,
    after_long_help = BATCH_RULES
)]
pub struct Args {
    #[command(flatten)]
    #[allow(missing_docs)]
    pub robot: RobotArgs,
    /// Stance height H, metres: depth of each foot below its hip mount in the nominal pose.
    #[arg(long, value_name = "H", value_parser = args::parse_positive_m)]
    pub stance_height_m: f32,
    /// Order of the body rotation, as a matrix product read left to right.
    #[arg(long, value_parser = args::rotation_order(), default_value = "zyx")]
    pub rotation_order: RotationOrder,
    /// Pivot of the body rotation in the body frame, metres (default: the body centre).
    #[arg(
        long,
        value_name = "X,Y,Z",
        value_parser = args::parse_vec3_m,
        allow_hyphen_values = true,
        default_value = "0,0,0"
    )]
    pub pivot_m: Vec3,
    /// Knee solution; default: the robot's own (backward for the presets).
    #[arg(long, value_parser = args::knee())]
    pub knee: Option<KneeBend>,
    /// Output format.
    #[arg(long, value_parser = args::pose_format(), default_value = "csv")]
    pub format: PoseFormat,
    /// Same as `--format table`: a human-readable table in degrees.
    #[arg(long, conflicts_with = "format")]
    pub table: bool,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: InputArgs,
}

impl Args {
    /// The output format, `--table` included.
    pub fn output_format(&self) -> PoseFormat {
        if self.table {
            PoseFormat::Table
        } else {
            self.format
        }
    }
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
    let config = BodyConfig {
        order: args.rotation_order,
        pivot_m: args.pivot_m,
    };
    let format = args.output_format();
    let setup = PoseSetup {
        robot: &robot,
        robot_name: &args.robot.robot,
        config,
        stance_height_m: args.stance_height_m,
        format,
    };
    Ok(batch::pose(&setup, input, out, diag)?)
}
