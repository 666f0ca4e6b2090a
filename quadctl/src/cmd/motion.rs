//! `quadctl motion`: sample a motion law (seed 001's sways and yaw turn, seed 000's foot path,
//! trot / walk) into a CSV of joint angles, feet and body pose; optional plot.

use crate::args::{self, LawArgs, EXIT_MALFORMED, EXIT_OK};
use crate::progress::Bar;
use quad_host::ops::motion::{self, Law, Request};
use std::path::PathBuf;
use std::process::ExitCode;

/// `--help`'s examples, run from the repository root (the files of `examples/`).
pub const EXAMPLES: &str = "\
Examples (from the repository root):
  quadctl motion roll-sway --robot fernando2025 --duration-s 20 --rate-hz 50 --output roll.csv
  quadctl motion trot --robot shahriar2023 --forward-m-s 0.1 --duration-s 4 --rate-hz 100 --output trot.csv --plot trot.svg";

/// Arguments of `quadctl motion`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Sample a motion law into CSV: t, 12 joint angles, 4 feet, body pose, status",
    long_about = LONG_ABOUT,
    allow_negative_numbers = true,
    after_help = EXAMPLES
)]
pub struct Args {
    /// The motion law.
    #[arg(value_parser = args::law())]
    pub law: Law,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub law_args: LawArgs,
    /// Duration, s (samples at 0, 1/F, …, up to T).
    #[arg(long, value_name = "T")]
    pub duration_s: f32,
    /// Sampling rate, Hz.
    #[arg(long, value_name = "F")]
    pub rate_hz: f32,
    /// Output CSV file (written to a temporary file and renamed when complete); default stdout.
    #[arg(long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Also draw the joint angles over time (.svg or .png).
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
    /// Also print the motion's minimum static stability margin (m) and when it happens, on
    /// stderr: the centre of mass (the robot's masses) against the support polygon of the feet
    /// in stance; ≤ 0 when it leaves it.
    #[arg(long)]
    pub stability: bool,
}

const LONG_ABOUT: &str = "\
Sample a motion law at a fixed rate and write one CSV row per sample.

Laws (defaults are the papers' values; seed 001's laws with --robot fernando2025 reproduce its
Fig. 4-6):
  roll-sway   seed 001 eq. 6: roll(t) = A·sin(2πt/T), feet fixed on the ground (eq. 7)
  pitch-sway  seed 001 eq. 8: pitch(t) = A·sin(2πt/T), feet fixed
  yaw-sway    yaw(t) = A·sin(2πt/T), feet fixed
              (A = 0.2 rad, T = 20 s, body centre fixed, rotation order: the device's)
  yaw-turn    seed 001 eq. 9-11, corrected (docs/papers.md): yaw(t) = −ω_z·t; the crossed pairs
              (FL, RR) and (FR, RL) step alternately along the circles of their feet with a
              half-wave sine lift (ω_z = 0.085 rad/s, T1 = 6 s, h_K = 0.3 m)
  rect-path   seed 000 §3.2 Fig. 8: each foot runs a closed path under a held body (rectangle:
              stride 0.1 m, lift 0.05 m at stance height 0.2 m, 3 s per loop)
  trot, walk  gait driven by --forward-m-s, --lateral-m-s, --yaw-rate-rad-s (stance feet fixed in
              the world, Bezier swing by default)

Frames and units: world frame = body frame of the nominal pose (x forward, y left, z up, origin
at the body centre); the ground is z = −H. Metres, radians, seconds.

Output columns: t_s; FL_abduction_rad, FL_hip_rad, FL_knee_rad, then FR, RL, RR likewise (the
canonical convention, all zero = leg straight down); FL_x_m, FL_y_m, FL_z_m, … RR_z_m (feet in
the world frame); roll_rad, pitch_rad, yaw_rad, x_m, y_m, z_m (body pose, feed to `quadctl
stream`); status: `ok`, or `<leg>:<reason>` for the first leg that cannot reach (its angle cells
are then all empty).

Bad parameters (negative durations or periods, zero rates, NaN, a step or lift height beyond
reach, options that do not apply to the law) are refused before anything is written, naming the
option; exit status 2. With --output, the file appears only when complete. Exit status 1 when
some samples are unreachable (the file is complete and says which).";

/// `quadctl motion`.
pub fn run(args: &Args) -> ExitCode {
    let request = Request {
        law: args.law,
        params: args.law_args.params(),
        duration_s: args.duration_s,
        rate_hz: args.rate_hz,
        output: args.output.clone(),
        plot: args.plot.clone(),
    };
    let mut bar = Bar::new(args.law.name());
    let result = motion::run(&request, &mut |p| bar.update(p));
    if args.stability && result.is_ok() {
        match motion::static_margin(&request.params, args.law, args.duration_s, args.rate_hz) {
            Ok(Some(m)) => eprintln!(
                "quadctl: static stability margin (min) {:.4} m at t = {:.3} s",
                m.value, m.t_s
            ),
            Ok(None) => eprintln!("quadctl: static stability margin: no sample solves"),
            Err(e) => return args::fail("quadctl", &e),
        }
    }
    match result {
        Ok(w) if w.unreachable == 0 => ExitCode::from(EXIT_OK),
        Ok(w) => {
            if let Some((t, e)) = w.first_unreachable {
                eprintln!(
                    "quadctl: {} of {} samples unreachable (first at t = {t} s: {e})",
                    w.unreachable, w.samples
                );
            }
            ExitCode::from(EXIT_MALFORMED)
        }
        Err(e) => args::fail("quadctl", &e),
    }
}
