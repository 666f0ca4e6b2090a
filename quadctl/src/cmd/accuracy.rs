//! `quadctl accuracy`: seed 000's hardware accuracy metric (§3.3) between target and measured
//! joint angles, and the Cartesian foot error through forward kinematics.

use crate::args;
use kin_core::LegId;
use quad_host::ops::accuracy::{self, Angles, Request};
use std::path::PathBuf;
use std::process::ExitCode;

const LONG_ABOUT: &str = "\
Seed 000's accuracy metric (§3.3) between target angles (what was commanded) and measured angles
(what the leg did), per joint j over the N paired samples i:

  deviation_j = 100 % · (1/N) · Σ_i |measured_ij − target_ij| / |target_ij|   (mean relative deviation)
  RSSE        = √(deviation_abduction² + deviation_hip² + deviation_knee²)      (root sum square)
  accuracy    = 100 % − RSSE

The percentages depend on where each angle's zero is: --angles seed000 first converts both files
to seed 000's θ1, θ2, θ3 (the paper's setting); --angles canonical (the default) uses the angles
as they are. A target angle of exactly zero makes its relative deviation undefined and is
refused, naming the row.

Seed 000 reports 2.59 %, 3.64 % and 20.83 % for its three joints and an RSSE of 21.10 %, i.e.
78.9 % accuracy. Its own per-joint figures give √(2.59² + 3.64² + 20.83²) = 21.30 %, i.e.
78.70 %: the 21.10 is an arithmetic slip (a third figure of 20.63 instead of 20.83 would give
21.11 ≈ 21.1, and 78.9 = 100 − 21.1 follows from it).

With --robot, also the Cartesian foot error: the distance between the feet that forward
kinematics puts at the target and at the measured angles (mean, RMS and maximum, metres).

Inputs: CSV files with a header, one row per sample, paired by order (same number of rows).
Joint columns, radians: either one leg, `abduction_rad,hip_rad,knee_rad` (the leg is --leg), or
the twelve `FL_abduction_rad … RR_knee_rad` of `quadctl motion` (all four legs pooled per joint;
rows whose status is not ok are skipped in both files). Other columns are ignored; `#` lines
are comments.

Output: a table; with --json also one JSON object as the last line. --plot draws target and
measured per joint over the samples (seed 000 Fig. 9-11) for --leg.";

/// Arguments of `quadctl accuracy`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
#[command(
    about = "Seed 000's accuracy metric: per-joint mean deviation %, RSSE, 100 − RSSE; foot error",
    long_about = LONG_ABOUT
)]
pub struct Args {
    /// Target (commanded) angles, CSV.
    #[arg(long, value_name = "A.csv")]
    pub target: PathBuf,
    /// Measured angles, CSV.
    #[arg(long, value_name = "B.csv")]
    pub measured: PathBuf,
    /// The leg of single-leg files, and the leg plotted.
    #[arg(long, default_value = "FL", value_parser = args::parse_leg)]
    pub leg: LegId,
    /// Which angles the percentages are taken of.
    #[arg(long, value_parser = args::angles(), default_value = "canonical")]
    pub angles: Angles,
    /// Robot (preset or TOML file) for the Cartesian foot error.
    #[arg(long, value_name = "PRESET|FILE.toml")]
    pub robot: Option<String>,
    /// Draw target vs measured per joint (.svg or .png).
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
    /// Also print one JSON object as the last line.
    #[arg(long)]
    pub json: bool,
}

/// `quadctl accuracy`.
pub fn run(args: &Args) -> ExitCode {
    let request = Request {
        target: args.target.clone(),
        measured: args.measured.clone(),
        leg: args.leg,
        angles: args.angles,
        robot: args.robot.clone(),
        plot: args.plot.clone(),
    };
    let acc = match accuracy::run(&request) {
        Ok(a) => a,
        Err(e) => return args::fail("quadctl", &e),
    };
    println!(
        "accuracy (seed 000 §3.3): {} paired joint triples, angles {}",
        acc.samples,
        match args.angles {
            Angles::Canonical => "canonical",
            Angles::Seed000 => "seed000 (θ1, θ2, θ3)",
        }
    );
    let d = acc.deviation_pct;
    for (name, d) in args
        .angles
        .joint_names()
        .iter()
        .zip([d.abduction, d.hip, d.knee])
    {
        println!("  {name:<16} mean deviation {d:>8.2} %");
    }
    println!("  RSSE                            {:>8.2} %", acc.rsse_pct);
    println!(
        "  accuracy = 100 − RSSE           {:>8.2} %",
        acc.accuracy_pct
    );
    if let Some(f) = &acc.foot_error {
        println!(
            "  foot error (FK): mean {:.4} m, RMS {:.4} m, max {:.4} m",
            f.mean_m, f.rms_m, f.max_m
        );
    }
    if args.json {
        // Through a `serde_json::Value`, as since the first release: keys sorted at every
        // level.
        match serde_json::to_value(acc).and_then(|v| serde_json::to_string(&v)) {
            Ok(json) => println!("{json}"),
            Err(e) => return args::fail("quadctl", &e),
        }
    }
    ExitCode::from(args::EXIT_OK)
}
