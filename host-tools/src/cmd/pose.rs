//! `quadctl pose`: body pose → the twelve joint angles, feet held at the nominal stance.

use super::{knee_name, Error, InputArgs, Knee, RobotArgs, BATCH_RULES};
use crate::csv_io::{self, FirstColumn, Input, Num, Schema, Summary};
use kin_core::body::{self, BodySolution, Pose};
use kin_core::{BodyConfig, IkError, LegId, ReachPolicy, Robot, RotationOrder, Vec3};
use std::io::{self, Write};

/// Input columns.
pub const INPUT: Schema = Schema {
    columns: &["roll_rad", "pitch_rad", "yaw_rad", "x_m", "y_m", "z_m"],
    first: FirstColumn::Number,
};

/// Output header of the CSV format.
pub const OUTPUT_HEADER: &str = "FL_abduction_rad,FL_hip_rad,FL_knee_rad,\
FR_abduction_rad,FR_hip_rad,FR_knee_rad,\
RL_abduction_rad,RL_hip_rad,RL_knee_rad,\
RR_abduction_rad,RR_hip_rad,RR_knee_rad,status";

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

/// `--rotation-order`: the elementary rotations' product, left to right.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Order {
    /// Rx(roll)·Ry(pitch)·Rz(yaw).
    Xyz,
    /// Rx(roll)·Rz(yaw)·Ry(pitch).
    Xzy,
    /// Ry(pitch)·Rx(roll)·Rz(yaw).
    Yxz,
    /// Ry(pitch)·Rz(yaw)·Rx(roll).
    Yzx,
    /// Rz(yaw)·Rx(roll)·Ry(pitch) (seed 001).
    Zxy,
    /// Rz(yaw)·Ry(pitch)·Rx(roll) (the default).
    Zyx,
}

impl From<Order> for RotationOrder {
    fn from(o: Order) -> RotationOrder {
        match o {
            Order::Xyz => RotationOrder::Xyz,
            Order::Xzy => RotationOrder::Xzy,
            Order::Yxz => RotationOrder::Yxz,
            Order::Yzx => RotationOrder::Yzx,
            Order::Zxy => RotationOrder::Zxy,
            Order::Zyx => RotationOrder::Zyx,
        }
    }
}

/// `--format`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// CSV in radians, for programs.
    Csv,
    /// A table per pose in degrees, for people.
    Table,
}

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
    #[arg(long, value_name = "H", value_parser = super::parse_positive_m)]
    pub stance_height_m: f32,
    /// Order of the body rotation, as a matrix product read left to right.
    #[arg(long, value_enum, default_value_t = Order::Zyx)]
    pub rotation_order: Order,
    /// Pivot of the body rotation in the body frame, metres (default: the body centre).
    #[arg(
        long,
        value_name = "X,Y,Z",
        value_parser = super::parse_vec3_m,
        allow_hyphen_values = true,
        default_value = "0,0,0"
    )]
    pub pivot_m: Vec3,
    /// Knee solution; default: the robot's own (backward for the presets).
    #[arg(long, value_enum)]
    pub knee: Option<Knee>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Csv)]
    pub format: Format,
    /// Same as `--format table`: a human-readable table in degrees.
    #[arg(long, conflicts_with = "format")]
    pub table: bool,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub input: InputArgs,
}

impl Args {
    /// The output format, `--table` included.
    pub fn output_format(&self) -> Format {
        if self.table {
            Format::Table
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
        order: args.rotation_order.into(),
        pivot_m: args.pivot_m,
    };
    let format = args.output_format();
    let header = match format {
        Format::Csv => OUTPUT_HEADER.to_owned(),
        Format::Table => table_preamble(&args.robot.robot, &robot, args.stance_height_m, &config),
    };
    let summary = csv_io::for_each_row(input, INPUT, out, diag, Some(&header), |row, out| {
        let mut v = [0.0f32; 6];
        for (i, slot) in v.iter_mut().enumerate() {
            *slot = row.number(i)?;
        }
        let pose = Pose::from_array(v);
        let result = body::Solver::new(&robot).inverse_at_stance(
            &pose,
            &config,
            args.stance_height_m,
            ReachPolicy::Reject,
        );
        match format {
            Format::Csv => write_csv(out, &result)?,
            Format::Table => write_table(out, row.line, &pose, &result)?,
        }
        Ok(())
    })?;
    Ok(summary)
}

fn write_csv(out: &mut dyn Write, result: &Result<BodySolution, IkError>) -> io::Result<()> {
    match result {
        Ok(solution) => {
            for angle in solution.flat() {
                write!(out, "{},", Num(angle))?;
            }
            writeln!(out, "ok")
        }
        Err(e) => writeln!(out, "{}{}:{}", ",".repeat(12), e.leg, e.kind.code()),
    }
}

fn table_preamble(name: &str, robot: &Robot, stance_height_m: f32, config: &BodyConfig) -> String {
    let p = config.pivot_m;
    format!(
        "quadctl pose: robot {name}, stance height {} m, rotation order {}, pivot ({}, {}, {}) m, \
         knee {}\n\
         Body pose: roll, pitch, yaw in degrees; x, y, z in metres. \
         Joint angles in DEGREES (the CSV output gives radians).",
        Num(stance_height_m),
        config.order,
        Num(p.x),
        Num(p.y),
        Num(p.z),
        knee_name(robot.knee_bend),
    )
}

fn write_table(
    out: &mut dyn Write,
    line: usize,
    pose: &Pose,
    result: &Result<BodySolution, IkError>,
) -> io::Result<()> {
    writeln!(out)?;
    writeln!(
        out,
        "line {line}: roll {}°  pitch {}°  yaw {}°  x {} m  y {} m  z {} m",
        fixed(pose.roll_rad.to_degrees(), 2),
        fixed(pose.pitch_rad.to_degrees(), 2),
        fixed(pose.yaw_rad.to_degrees(), 2),
        fixed(pose.x_m, 4),
        fixed(pose.y_m, 4),
        fixed(pose.z_m, 4),
    )?;
    match result {
        Ok(solution) => {
            writeln!(out, "  leg  abduction_deg   hip_deg  knee_deg")?;
            for leg in LegId::ALL {
                let q = solution.legs[leg.index()].angles;
                writeln!(
                    out,
                    "  {leg}   {:>13} {:>9} {:>9}",
                    fixed(q.abduction_rad.to_degrees(), 2),
                    fixed(q.hip_rad.to_degrees(), 2),
                    fixed(q.knee_rad.to_degrees(), 2),
                )?;
            }
            Ok(())
        }
        Err(e) => writeln!(out, "  unreachable: {e} (no angles)"),
    }
}

/// `v` with `decimals` decimals, without the sign of a value that rounds to zero (`-0.00`).
fn fixed(v: f32, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    match s.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_owned(),
        _ => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_drops_the_sign_of_rounded_zeros_only() {
        assert_eq!(fixed(-1.0e-6, 2), "0.00");
        assert_eq!(fixed(-0.0, 2), "0.00");
        assert_eq!(fixed(-0.006, 2), "-0.01");
        assert_eq!(fixed(30.0, 2), "30.00");
    }
}
