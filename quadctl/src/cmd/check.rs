//! `quadctl check`: the preflight report of a motion CSV or of a motion law
//! (`kin_core::preflight`).

use crate::args::{self, LawArgs, EXIT_MALFORMED, EXIT_OK};
use crate::progress::Bar;
use quad_host::ops::check::{self, Request, Source};
use quad_host::ops::defaults;
use quad_host::ops::motion::Law;
use std::path::PathBuf;
use std::process::ExitCode;

const LONG_ABOUT: &str = "\
Preflight report of a motion: sweeps it and reports, per leg and overall,
  - reachability: samples the IK refuses, and the first one (time, leg, reason);
  - minimum workspace margin (m): distance of the foot target to the nearest workspace boundary,
    min(L1 + L2 − r, r − |L1 − L2|, r_yz − d_lat), r the hip-joint-to-foot distance in the leg
    plane, r_yz the foot's distance from the abduction axis; negative = out of reach;
  - minimum joint-limit margin (rad): distance of the tightest joint to its limit;
  - minimum singularity measure: inverse condition number σmin/σmax of the leg Jacobian
    (1 = isotropic, 0 = singular), failing below 0.05;
  - maximum joint speed (rad/s), finite differences between samples, against
    --max-joint-speed-rad-s (default: the device's joint-speed limiter, 3 rad/s, which slows
    every output that would move faster);
  - with --motion, the minimum static stability margin (m): the centre of mass (the robot's
    masses) against the support polygon of the feet in stance, positive inside, ≤ 0 outside or
    with two feet down (reported, not a failure; a motion file has no stance column).

Source: a CSV written by `quadctl motion` (FILE, `-` for stdin; rows with feet and pose are
solved again, rows with angles only are checked as they are; the rotation order is read from the
file's `# quadctl motion … rotation_order=…` line, else --rotation-order, else zyx), or
--motion LAW with the same options as `quadctl motion`.

Output: a table (angles in rad with degrees in brackets); with --json, also one JSON object as
the last line (SI units). Exit status: 0 all samples pass, 1 some fail, 2 bad input.";

/// `--help`'s examples, run from the repository root (the files of `examples/`).
pub const EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl motion yaw-turn --robot fernando2025 --duration-s 12 --rate-hz 50 --output yaw.csv
  quadctl check --robot fernando2025 yaw.csv
  quadctl check --motion pitch-sway --robot fernando2025 --amplitude-rad -0.1 --json";

/// Arguments of `quadctl check`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Preflight report of a motion (file or law): reach, margins, singularity, joint speed",
    long_about = LONG_ABOUT,
    allow_negative_numbers = true,
    after_help = EXAMPLES
)]
pub struct Args {
    /// Motion CSV written by `quadctl motion` (`-` for stdin).
    #[arg(
        value_name = "FILE",
        required_unless_present = "motion",
        conflicts_with = "motion"
    )]
    pub file: Option<PathBuf>,
    /// Check this law instead of a file.
    #[arg(long, value_parser = args::law(), value_name = "LAW")]
    pub motion: Option<Law>,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub law_args: LawArgs,
    /// With --motion: duration, s [default: one period of the law, or 10 s].
    #[arg(long, value_name = "T")]
    pub duration_s: Option<f32>,
    /// With --motion: sampling rate, Hz [default: 100].
    #[arg(long, value_name = "F")]
    pub rate_hz: Option<f32>,
    /// Joint speed limit, rad/s: one value for all joints or ABDUCTION,HIP,KNEE [default: the
    /// device's joint-speed limiter, 3 rad/s: a motion faster than it is slowed on the device].
    #[arg(long, value_name = "RAD_S", value_parser = args::parse_speed_limits)]
    pub max_joint_speed_rad_s: Option<[f32; 3]>,
    /// Also print the report as one JSON object on the last line.
    #[arg(long)]
    pub json: bool,
}

/// `quadctl check`.
pub fn run(args: &Args) -> ExitCode {
    let source = match (&args.file, args.motion) {
        (_, Some(law)) => Source::Law(law),
        (Some(file), None) => Source::File(file.clone()),
        // clap requires one of them.
        (None, None) => unreachable!("FILE or --motion is required"),
    };
    let request = Request {
        source,
        params: args.law_args.params(),
        duration_s: args.duration_s,
        rate_hz: args.rate_hz,
        max_joint_speed_rad_s: args
            .max_joint_speed_rad_s
            .unwrap_or([defaults::joint_speed_limit_rad_s(&args.law_args.robot.robot); 3]),
    };
    let mut bar = Bar::new("check");
    match check::run(&request, &mut |p| bar.update(p)) {
        Ok(checked) => {
            print!("{}", check::table(&checked));
            if args.json {
                // Through a `serde_json::Value`, as since the first release: keys sorted at every
                // level and f32 figures widened to f64.
                match serde_json::to_value(checked.summary())
                    .and_then(|v| serde_json::to_string(&v))
                {
                    Ok(json) => println!("{json}"),
                    Err(e) => return args::fail("quadctl", &e),
                }
            }
            ExitCode::from(if checked.report.ok() {
                EXIT_OK
            } else {
                EXIT_MALFORMED
            })
        }
        Err(e) => args::fail("quadctl", &e),
    }
}
