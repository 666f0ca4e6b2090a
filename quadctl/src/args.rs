//! The `quadctl` subcommands, one module each, and what they share: the `--robot`, `--knee` and
//! `--input` arguments, the batch driver and the exit codes.
//!
//! A new subcommand is a module here with an `Args` struct (`clap::Args`) and a `run` function,
//! plus one variant in `main.rs`.

pub mod accuracy;
pub mod calibrate;
pub mod check;
pub mod demo;
pub mod fk;
pub mod ik;
pub mod motion;
pub mod plot;
pub mod pose;
pub mod stream;

use crate::csv_io::{self, Input, Summary};
use crate::robot_file::{self, LoadError};
use kin_core::{KneeBend, Robot, Vec3};
use std::fmt;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Exit status when every record was answered (reachable or not).
pub const EXIT_OK: u8 = 0;
/// Exit status when at least one record was malformed (the others were answered).
pub const EXIT_MALFORMED: u8 = 1;
/// Exit status when nothing or not everything could be processed: bad arguments, unreadable or
/// invalid robot file, unreadable input, a foreign header, or an output error.
pub const EXIT_FATAL: u8 = 2;

/// Help text shared by the batch commands: input rules and exit codes.
pub const BATCH_RULES: &str = "\
Input: CSV, one record per line, fields separated by commas (no quoting), spaces around fields
ignored. Blank lines and lines starting with `#` are skipped. The header row is optional: the
first record is taken as a header when its first field is not a value of the first column; it
must then name exactly the expected columns, or nothing is processed. Leg names are FL, FR, RL,
RR (any case).

Output: CSV on stdout with a header row. Numbers are printed with the shortest decimal that reads
back to the same f32.

Malformed records (wrong number of fields, a field that is not a number or not a leg name) are
reported on stderr as `<input>:<line>: <what is wrong>` and get NO output row; the other records
are still answered, in input order.

Exit status: 0 every record answered (unreachable targets are answers, see `status`); 1 at least
one malformed record; 2 nothing processed or processing stopped (bad arguments, robot file or
input not readable or invalid, foreign header, output error).

Robot files (TOML): d_lat_m, d_ax_m, femur_m, tibia_m, body_length_m, body_width_m (metres,
required); knee_bend = \"backward\" | \"forward\" (optional, default backward); optional
[limits] table with abduction_rad, hip_rad, knee_rad = [min, max] (radians; a joint left out is
limited only to the full turn [-pi, pi]). Unknown keys are refused.";

/// `--robot`.
#[derive(Debug, Clone, PartialEq, Eq, clap::Args)]
pub struct RobotArgs {
    /// Robot: a preset (shahriar2023, fernando2025) or a TOML robot file.
    #[arg(long, value_name = "PRESET|FILE.toml")]
    pub robot: String,
}

impl RobotArgs {
    /// Resolves the preset or file; `knee` overrides the robot's knee bend (mirroring its knee
    /// limits with it, see [`Robot::with_knee_bend`]).
    pub fn load(&self, knee: Option<Knee>) -> Result<Robot, Error> {
        let robot = robot_file::resolve(&self.robot).map_err(Error::Robot)?;
        Ok(match knee {
            Some(k) => robot.with_knee_bend(k.into()),
            None => robot,
        })
    }
}

/// `--input`.
#[derive(Debug, Clone, PartialEq, Eq, clap::Args)]
pub struct InputArgs {
    /// CSV input file, or `-` for standard input.
    #[arg(long, value_name = "FILE|-", default_value = "-")]
    pub input: PathBuf,
}

/// `--knee`: which IK solution the knee takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Knee {
    /// knee <= 0 (the knee joint behind the hip-foot line).
    Backward,
    /// knee >= 0 (the knee joint in front of the hip-foot line).
    Forward,
}

impl From<Knee> for KneeBend {
    fn from(k: Knee) -> KneeBend {
        match k {
            Knee::Backward => KneeBend::Backward,
            Knee::Forward => KneeBend::Forward,
        }
    }
}

/// Lower-case name of a knee bend, as accepted by `--knee`.
pub fn knee_name(bend: KneeBend) -> &'static str {
    match bend {
        KneeBend::Backward => "backward",
        KneeBend::Forward => "forward",
    }
}

/// Errors that stop a batch command.
#[derive(Debug)]
#[non_exhaustive]
pub enum Error {
    /// `--robot` could not be resolved.
    Robot(LoadError),
    /// Input, output or header error.
    Csv(csv_io::Error),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Robot(e) => write!(f, "{e}"),
            Error::Csv(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Robot(e) => Some(e),
            Error::Csv(e) => Some(e),
        }
    }
}

impl From<csv_io::Error> for Error {
    fn from(e: csv_io::Error) -> Self {
        Error::Csv(e)
    }
}

impl Error {
    fn is_broken_pipe(&self) -> bool {
        matches!(self, Error::Csv(csv_io::Error::Io(e)) if e.kind() == io::ErrorKind::BrokenPipe)
    }
}

/// A command-line value that could not be used.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum ArgError {
    /// Not a number.
    NotANumber(String),
    /// A length that must be finite and > 0.
    NotPositive(f32),
    /// Not a finite number.
    NotFinite(String),
    /// Not three comma-separated numbers.
    NotThree(usize),
}

impl fmt::Display for ArgError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ArgError::NotANumber(s) => write!(f, "`{s}` is not a number"),
            ArgError::NotPositive(v) => write!(f, "{v} must be a finite length > 0 (metres)"),
            ArgError::NotFinite(s) => write!(f, "`{s}` is not a finite number"),
            ArgError::NotThree(n) => {
                write!(f, "expected three comma-separated numbers X,Y,Z, found {n}")
            }
        }
    }
}

impl std::error::Error for ArgError {}

fn parse_finite(s: &str) -> Result<f32, ArgError> {
    let v: f32 = s
        .trim()
        .parse()
        .map_err(|_| ArgError::NotANumber(s.trim().to_owned()))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ArgError::NotFinite(s.trim().to_owned()))
    }
}

/// Value parser: a finite length > 0, metres.
pub fn parse_positive_m(s: &str) -> Result<f32, ArgError> {
    let v = parse_finite(s)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(ArgError::NotPositive(v))
    }
}

/// Value parser: `X,Y,Z`, three finite numbers (metres).
pub fn parse_vec3_m(s: &str) -> Result<Vec3, ArgError> {
    let parts: Vec<&str> = s.split(',').collect();
    match parts.as_slice() {
        [x, y, z] => Ok(Vec3::new(
            parse_finite(x)?,
            parse_finite(y)?,
            parse_finite(z)?,
        )),
        other => Err(ArgError::NotThree(other.len())),
    }
}

/// Runs a batch command on `--input` with stdout and stderr, reports its outcome on stderr and
/// turns it into the exit status ([`EXIT_OK`], [`EXIT_MALFORMED`], [`EXIT_FATAL`]).
pub fn run_batch(
    input: &Path,
    body: impl FnOnce(Input, &mut dyn Write, &mut dyn Write) -> Result<Summary, Error>,
) -> ExitCode {
    let stdout = io::stdout();
    let mut out = io::BufWriter::new(stdout.lock());
    let stderr = io::stderr();
    let mut diag = stderr.lock();
    let result = Input::open(input)
        .map_err(Error::Csv)
        .and_then(|input| body(input, &mut out, &mut diag))
        .and_then(|summary| {
            out.flush().map_err(|e| Error::Csv(csv_io::Error::Io(e)))?;
            Ok(summary)
        });
    match result {
        Ok(summary) if summary.malformed == 0 => ExitCode::from(EXIT_OK),
        Ok(summary) => {
            // Nothing useful can be done if stderr itself fails.
            let _ = writeln!(
                diag,
                "quadctl: {} malformed record(s) skipped, {} answered",
                summary.malformed, summary.answered
            );
            ExitCode::from(EXIT_MALFORMED)
        }
        // The reader of stdout went away (e.g. `| head`): stop quietly.
        Err(e) if e.is_broken_pipe() => ExitCode::from(EXIT_OK),
        Err(e) => {
            let _ = out.flush();
            let _ = writeln!(diag, "quadctl: error: {e}");
            ExitCode::from(EXIT_FATAL)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn value_parsers_refuse_what_they_cannot_use() {
        assert_eq!(parse_positive_m("0.9294"), Ok(0.9294));
        assert_eq!(parse_positive_m("0"), Err(ArgError::NotPositive(0.0)));
        assert_eq!(
            parse_positive_m("inf"),
            Err(ArgError::NotFinite("inf".to_owned()))
        );
        assert_eq!(parse_vec3_m("0.1, -0.2,0"), Ok(Vec3::new(0.1, -0.2, 0.0)));
        assert_eq!(parse_vec3_m("1,2"), Err(ArgError::NotThree(2)));
        assert_eq!(
            parse_vec3_m("1,x,2"),
            Err(ArgError::NotANumber("x".to_owned()))
        );
    }
}
