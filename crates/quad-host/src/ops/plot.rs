//! Figures of a motion CSV: joint angles over time (seed 001 Fig. 4–6) or the robot in top,
//! side and front views at chosen instants (seed 000 Fig. 6–7). The operation behind
//! `quadctl plot`.

use super::motion::Error;
use crate::csv::motion::MotionCsv;
use crate::plot::{self, Decimator, Snapshot};
use crate::robot_file;
use kin_core::{BodyConfig, JointAngles, RotationOrder, Vec3};
use std::path::PathBuf;

/// What [`run`] is asked to draw.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// The motion CSV (`-`: stdin).
    pub file: PathBuf,
    /// The figure, .svg or .png.
    pub output: PathBuf,
    /// Draw the robot at these times (s) instead of the joint angles.
    pub at_s: Vec<f64>,
    /// Robot (needed with `at_s`): preset or TOML file.
    pub robot: Option<String>,
    /// Rotation order of the poses in the file (overrides the file's own).
    pub rotation_order: Option<RotationOrder>,
    /// Figure title; `None`: the file name.
    pub title: Option<String>,
}

/// Draws the figure.
///
/// # Errors
/// Options that do not go together, the robot, reading the CSV, drawing.
pub fn run(args: &Request) -> Result<(), Error> {
    let title = args
        .title
        .clone()
        .unwrap_or_else(|| args.file.display().to_string());
    if args.at_s.is_empty() {
        if args.robot.is_some() {
            return Err(Error::NotApplicable {
                option: "--robot",
                law: "the joint-angle plot (use it with --at-s)",
            });
        }
        let mut csv = MotionCsv::open(&args.file)?;
        let mut d = Decimator::new();
        while let Some(row) = csv.next_row()? {
            d.push(row.t_s, row.angles);
        }
        return Ok(plot::joint_angles(&args.output, &title, &d.finish())?);
    }
    if let Some(t) = args.at_s.iter().find(|t| !t.is_finite()) {
        return Err(Error::NotFiniteTime(*t));
    }
    let robot_spec = args.robot.as_ref().ok_or(Error::NotApplicable {
        option: "--at-s without --robot",
        law: "the robot views (they need the robot's geometry)",
    })?;
    let robot = robot_file::resolve(robot_spec)?;
    let mut csv = MotionCsv::open(&args.file)?;
    let order: RotationOrder = args
        .rotation_order
        .or(csv.rotation_order)
        .unwrap_or_default();
    let config = BodyConfig {
        order,
        pivot_m: Vec3::ZERO,
    };
    // Nearest reachable sample to each requested time.
    let mut best: Vec<Option<(f64, Snapshot)>> = vec![None; args.at_s.len()];
    while let Some(row) = csv.next_row()? {
        let (Some(a), Some(pose)) = (row.angles, row.pose) else {
            continue;
        };
        for (slot, &want) in best.iter_mut().zip(&args.at_s) {
            let d = (row.t_s - want).abs();
            if slot.as_ref().is_none_or(|(bd, _)| d < *bd) {
                *slot = Some((
                    d,
                    Snapshot {
                        t_s: row.t_s,
                        pose,
                        angles: core::array::from_fn(|l| {
                            JointAngles::new(a[3 * l], a[3 * l + 1], a[3 * l + 2])
                        }),
                    },
                ));
            }
        }
    }
    let snaps: Vec<Snapshot> = best.into_iter().flatten().map(|(_, s)| s).collect();
    Ok(plot::robot_views(
        &args.output,
        &title,
        &robot,
        &config,
        &snaps,
    )?)
}
