//! `quadctl plot`: figures of a motion CSV — joint angles over time (seed 001 Fig. 4–6) or the
//! robot in top, side and front views at chosen instants (seed 000 Fig. 6–7).

use super::motion::{Error, MotionCsv};
use super::pose::Order;
use crate::plot::{self, Decimator, Snapshot};
use kin_core::{BodyConfig, JointAngles, RotationOrder, Vec3};
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
    #[arg(long, value_enum)]
    pub rotation_order: Option<Order>,
    /// Figure title [default: the file name].
    #[arg(long)]
    pub title: Option<String>,
}

/// `quadctl plot`.
pub fn run(args: &Args) -> ExitCode {
    super::motion::exit_status(run_inner(args))
}

fn run_inner(args: &Args) -> Result<(), Error> {
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
        return Err(Error::Csv {
            at: "--at-s".to_owned(),
            message: format!("{t} is not a finite time"),
        });
    }
    let robot_spec = args.robot.as_ref().ok_or(Error::NotApplicable {
        option: "--at-s without --robot",
        law: "the robot views (they need the robot's geometry)",
    })?;
    let robot = crate::robot_file::resolve(robot_spec).map_err(Error::Robot)?;
    let mut csv = MotionCsv::open(&args.file)?;
    let order: RotationOrder = args
        .rotation_order
        .map(Order::into)
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
