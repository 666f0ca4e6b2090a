//! The batch commands: one answer per CSV record ([`crate::csv::for_each_row`]) — leg IK
//! (`quadctl ik`), leg FK (`fk`) and full-body IK at the nominal stance (`pose`).

use super::stream::POSE_COLUMNS;
use crate::csv::{self, FirstColumn, Input, Num, Schema, Summary};
use crate::names;
use kin_core::body::{self, BodySolution, Pose};
use kin_core::{leg, BodyConfig, IkError, JointAngles, LegId, ReachPolicy, Robot, Vec3};
use std::io::{self, Write};

/// `ik`'s input columns.
pub const IK_INPUT: Schema = Schema {
    columns: &["leg", "x_m", "y_m", "z_m"],
    first: FirstColumn::Leg,
};

/// `ik`'s output header under [`ReachPolicy::Reject`].
pub const IK_OUTPUT_HEADER: &str = "leg,abduction_rad,hip_rad,knee_rad,status,line";

/// `ik`'s output header under [`ReachPolicy::Clamp`].
pub const IK_OUTPUT_HEADER_CLAMP: &str =
    "leg,abduction_rad,hip_rad,knee_rad,status,clamp_distance_m,line";

/// `fk`'s input columns.
pub const FK_INPUT: Schema = Schema {
    columns: &["leg", "abduction_rad", "hip_rad", "knee_rad"],
    first: FirstColumn::Leg,
};

/// `fk`'s output header.
pub const FK_OUTPUT_HEADER: &str = "leg,x_m,y_m,z_m,status,line";

/// `pose`'s input columns: the body pose.
pub const POSE_INPUT: Schema = POSE_COLUMNS;

/// `pose`'s CSV output header.
pub const POSE_OUTPUT_HEADER: &str = "FL_abduction_rad,FL_hip_rad,FL_knee_rad,\
FR_abduction_rad,FR_hip_rad,FR_knee_rad,\
RL_abduction_rad,RL_hip_rad,RL_knee_rad,\
RR_abduction_rad,RR_hip_rad,RR_knee_rad,status,line";

/// Leg IK of every record of `input` (foot in the hip frame → joint angles).
///
/// # Errors
/// [`csv::Error`] when the input cannot be read, its header is foreign, or the output fails.
pub fn ik(
    robot: &Robot,
    policy: ReachPolicy,
    input: Input,
    out: &mut dyn Write,
    diag: &mut dyn Write,
) -> Result<Summary, csv::Error> {
    let clamp = policy == ReachPolicy::Clamp;
    let header = if clamp {
        IK_OUTPUT_HEADER_CLAMP
    } else {
        IK_OUTPUT_HEADER
    };
    let solver = leg::Solver::new(robot);
    csv::for_each_row(input, IK_INPUT, out, diag, Some(header), |row, out| {
        let leg = row.leg(0)?;
        let line = row.source_line()?;
        let tail = if clamp { "," } else { "" };
        if let Some(status) = row.unanswered_status() {
            writeln!(out, "{leg},,,,{status}{tail},{line}")?;
            return Ok(());
        }
        let foot_in_hip = Vec3::new(row.number(1)?, row.number(2)?, row.number(3)?);
        match solver.inverse(leg, foot_in_hip, policy) {
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
                    None if clamp => writeln!(out, "ok,0,{line}")?,
                    None => writeln!(out, "ok,{line}")?,
                    Some(c) => writeln!(
                        out,
                        "clamped:{},{},{line}",
                        c.kind.code(),
                        Num(c.distance_m)
                    )?,
                }
            }
            Err(e) => writeln!(out, "{leg},,,,{}{tail},{line}", e.kind.code())?,
        }
        Ok(())
    })
}

/// Leg FK of every record of `input` (joint angles → foot in the hip frame).
///
/// # Errors
/// As [`ik`].
pub fn fk(
    robot: &Robot,
    input: Input,
    out: &mut dyn Write,
    diag: &mut dyn Write,
) -> Result<Summary, csv::Error> {
    csv::for_each_row(
        input,
        FK_INPUT,
        out,
        diag,
        Some(FK_OUTPUT_HEADER),
        |row, out| {
            let leg = row.leg(0)?;
            let line = row.source_line()?;
            if let Some(status) = row.unanswered_status() {
                writeln!(out, "{leg},,,,{status},{line}")?;
                return Ok(());
            }
            let q = [row.number(1)?, row.number(2)?, row.number(3)?];
            // As `ik` and `pose` answer a non-finite target: a status, no values.
            if q.iter().any(|a| !a.is_finite()) {
                writeln!(
                    out,
                    "{leg},,,,{},{line}",
                    leg::Unreachable::NonFinite.code()
                )?;
                return Ok(());
            }
            let foot = leg::forward(&robot.leg, leg, JointAngles::from_array(q));
            writeln!(
                out,
                "{leg},{},{},{},ok,{line}",
                Num(foot.x),
                Num(foot.y),
                Num(foot.z)
            )?;
            Ok(())
        },
    )
}

/// How `pose` prints.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PoseFormat {
    /// CSV in radians, for programs.
    Csv,
    /// A table per pose in degrees, for people.
    Table,
}

impl PoseFormat {
    /// Both, in the command line's order.
    pub const ALL: [PoseFormat; 2] = [PoseFormat::Csv, PoseFormat::Table];

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            PoseFormat::Csv => "csv",
            PoseFormat::Table => "table",
        }
    }
}

/// What `pose` solves with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseSetup<'a> {
    /// The robot.
    pub robot: &'a Robot,
    /// The robot as given (preset or file), for the table.
    pub robot_name: &'a str,
    /// Rotation order and pivot.
    pub config: BodyConfig,
    /// Stance height H, m: the feet's depth below the hips in the nominal pose.
    pub stance_height_m: f32,
    /// How to print.
    pub format: PoseFormat,
}

/// Full-body IK of every record of `input` (body pose → the 12 joint angles, feet at the
/// nominal stance).
///
/// # Errors
/// As [`ik`].
pub fn pose(
    setup: &PoseSetup<'_>,
    input: Input,
    out: &mut dyn Write,
    diag: &mut dyn Write,
) -> Result<Summary, csv::Error> {
    let PoseSetup {
        robot,
        robot_name,
        config,
        stance_height_m,
        format,
    } = *setup;
    let config = &config;
    let header = match format {
        PoseFormat::Csv => POSE_OUTPUT_HEADER.to_owned(),
        PoseFormat::Table => table_preamble(robot_name, robot, stance_height_m, config),
    };
    let solver = body::Solver::new(robot);
    csv::for_each_row(input, POSE_INPUT, out, diag, Some(&header), |row, out| {
        let line = row.source_line()?;
        if let Some(status) = row.unanswered_status() {
            match format {
                PoseFormat::Csv => writeln!(out, "{}{status},{line}", ",".repeat(12))?,
                PoseFormat::Table => writeln!(out, "\nline {line}: {status} (no pose)")?,
            }
            return Ok(());
        }
        let mut v = [0.0f32; 6];
        for (i, slot) in v.iter_mut().enumerate() {
            *slot = row.number(i)?;
        }
        let pose = Pose::from_array(v);
        let result = solver.inverse_at_stance(&pose, config, stance_height_m, ReachPolicy::Reject);
        match format {
            PoseFormat::Csv => write_csv(out, &result, line)?,
            PoseFormat::Table => write_table(out, line, &pose, &result)?,
        }
        Ok(())
    })
}

fn write_csv(
    out: &mut dyn Write,
    result: &Result<BodySolution, IkError>,
    line: usize,
) -> io::Result<()> {
    match result {
        Ok(solution) => {
            for angle in solution.flat() {
                write!(out, "{},", Num(angle))?;
            }
            writeln!(out, "ok,{line}")
        }
        Err(e) => writeln!(out, "{}{}:{},{line}", ",".repeat(12), e.leg, e.kind.code()),
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
        names::knee_bend_name(robot.knee_bend),
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
                let q = solution.leg(leg).angles;
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
