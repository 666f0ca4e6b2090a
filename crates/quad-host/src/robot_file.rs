//! Robot descriptions: the presets of `kin-core` and TOML robot files.
//!
//! A robot file lists the leg geometry and the body size in metres, and optionally the knee bend
//! and the joint limits in radians:
//!
//! ```toml
//! d_lat_m = 0.044        # lateral offset of the leg plane from the abduction axis (seed 000 La)
//! d_ax_m = 0.0           # hip joint below the abduction axis, in the leg plane (seed 001 l0)
//! femur_m = 0.28         # hip to knee
//! tibia_m = 0.277        # knee to foot
//! body_length_m = 0.6    # front to rear hip mounts, along x
//! body_width_m = 0.28    # left to right hip mounts, along y
//! knee_bend = "backward" # optional: "backward" (knee ≤ 0, the default) or "forward" (knee ≥ 0)
//!
//! [limits]               # optional; each entry is [min, max] in rad
//! abduction_rad = [-3.1415927, 3.1415927]
//! hip_rad = [-3.1415927, 3.1415927]
//! knee_rad = [-2.8, -0.05]
//! ```
//!
//! A missing `[limits]` table, or a joint missing from it, means the full turn `[−π, π]`
//! ([`JointLimits::FULL_TURN`]): no limit beyond the IK's own range. Limits are expressed for the
//! file's `knee_bend`. Unknown keys, missing lengths, negative or non-finite lengths and limits
//! with `min > max` are refused with a message naming the key.

use kin_core::robot::RobotError;
use kin_core::{JointLimits, KneeBend, LegGeometry, Robot};
use serde::Deserialize;
use std::fmt;
use std::io;
use std::path::{Path, PathBuf};

/// The knee bend as written in a robot file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
enum KneeBendName {
    /// knee ≤ 0.
    #[default]
    Backward,
    /// knee ≥ 0.
    Forward,
}

/// The `[limits]` table: `[min, max]` per joint, rad.
#[derive(Debug, Clone, Copy, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct LimitsTable {
    abduction_rad: Option<[f32; 2]>,
    hip_rad: Option<[f32; 2]>,
    knee_rad: Option<[f32; 2]>,
}

/// The whole file.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct RobotFile {
    d_lat_m: f32,
    d_ax_m: f32,
    femur_m: f32,
    tibia_m: f32,
    body_length_m: f32,
    body_width_m: f32,
    #[serde(default)]
    knee_bend: KneeBendName,
    #[serde(default)]
    limits: LimitsTable,
}

impl RobotFile {
    fn into_robot(self) -> Robot {
        let full = JointLimits::FULL_TURN;
        let pick =
            |entry: Option<[f32; 2]>, j: usize| entry.unwrap_or([full.min_rad[j], full.max_rad[j]]);
        let entries = [
            pick(self.limits.abduction_rad, 0),
            pick(self.limits.hip_rad, 1),
            pick(self.limits.knee_rad, 2),
        ];
        Robot {
            leg: LegGeometry {
                d_lat_m: self.d_lat_m,
                d_ax_m: self.d_ax_m,
                femur_m: self.femur_m,
                tibia_m: self.tibia_m,
            },
            body_length_m: self.body_length_m,
            body_width_m: self.body_width_m,
            limits: JointLimits {
                min_rad: entries.map(|e| e[0]),
                max_rad: entries.map(|e| e[1]),
            },
            knee_bend: match self.knee_bend {
                KneeBendName::Backward => KneeBend::Backward,
                KneeBendName::Forward => KneeBend::Forward,
            },
        }
    }
}

/// Why the text of a robot file was refused.
#[derive(Debug)]
#[non_exhaustive]
pub enum ParseError {
    /// Not valid TOML, or a key is missing, unknown or of the wrong type.
    Toml(toml::de::Error),
    /// The values were read but [`Robot::validate`] refused them.
    Invalid(RobotError),
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParseError::Toml(e) => write!(f, "{}", e.to_string().trim_end()),
            ParseError::Invalid(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for ParseError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            ParseError::Toml(e) => Some(e),
            ParseError::Invalid(e) => Some(e),
        }
    }
}

/// Parses and validates the text of a robot file (see the module docs for the keys).
pub fn parse(text: &str) -> Result<Robot, ParseError> {
    let file: RobotFile = toml::from_str(text).map_err(ParseError::Toml)?;
    let robot = file.into_robot();
    robot.validate().map_err(ParseError::Invalid)?;
    Ok(robot)
}

/// Why `--robot` could not be resolved.
#[derive(Debug)]
#[non_exhaustive]
pub enum LoadError {
    /// Not a preset name, and the file could not be read.
    Read {
        /// The path tried.
        path: PathBuf,
        /// The I/O error.
        source: io::Error,
    },
    /// The file was read but its content was refused.
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong in it.
        source: ParseError,
    },
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LoadError::Read { path, source } => write!(
                f,
                "`{}` is not a preset ({}) and cannot be read as a robot file: {source}",
                path.display(),
                Robot::PRESETS.join(", ")
            ),
            LoadError::Parse { path, source } => {
                write!(f, "robot file `{}`: {source}", path.display())
            }
        }
    }
}

impl std::error::Error for LoadError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            LoadError::Read { source, .. } => Some(source),
            LoadError::Parse { source, .. } => Some(source),
        }
    }
}

/// Reads and validates a robot file.
pub fn load_file(path: &Path) -> Result<Robot, LoadError> {
    let text = std::fs::read_to_string(path).map_err(|source| LoadError::Read {
        path: path.to_owned(),
        source,
    })?;
    parse(&text).map_err(|source| LoadError::Parse {
        path: path.to_owned(),
        source,
    })
}

/// Resolves a `--robot` argument: a preset name ([`Robot::PRESETS`]) or else a TOML file path.
pub fn resolve(spec: &str) -> Result<Robot, LoadError> {
    match Robot::preset(spec) {
        Some(robot) => Ok(robot),
        None => load_file(Path::new(spec)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = "d_lat_m = 0.044\nd_ax_m = 0.0\nfemur_m = 0.28\ntibia_m = 0.277\n\
                           body_length_m = 0.6\nbody_width_m = 0.28\n";

    #[test]
    fn limits_default_to_the_full_turn_and_knee_to_backward() {
        let robot = parse(MINIMAL).expect("valid file");
        assert_eq!(robot.limits, JointLimits::FULL_TURN);
        assert_eq!(robot.knee_bend, KneeBend::Backward);
        assert_eq!(robot.leg.tibia_m, 0.277);
    }

    #[test]
    fn partial_limits_keep_the_full_turn_elsewhere() {
        let text = format!("{MINIMAL}knee_bend = \"forward\"\n[limits]\nknee_rad = [0.1, 2.5]\n");
        let robot = parse(&text).expect("valid file");
        assert_eq!(robot.knee_bend, KneeBend::Forward);
        assert_eq!(
            robot.limits.min_rad,
            [-core::f32::consts::PI, -core::f32::consts::PI, 0.1]
        );
        assert_eq!(
            robot.limits.max_rad,
            [core::f32::consts::PI, core::f32::consts::PI, 2.5]
        );
    }

    #[test]
    fn negative_length_is_refused_by_name() {
        let text = MINIMAL.replace("femur_m = 0.28", "femur_m = -0.28");
        let err = parse(&text).expect_err("negative femur");
        assert!(matches!(
            err,
            ParseError::Invalid(RobotError::BadLength("femur_m"))
        ));
        assert!(err.to_string().contains("femur_m"), "{err}");
    }

    #[test]
    fn missing_and_unknown_keys_are_named() {
        let missing = MINIMAL.replace("tibia_m = 0.277\n", "");
        let err = parse(&missing).expect_err("missing tibia");
        assert!(err.to_string().contains("missing field `tibia_m`"), "{err}");
        let unknown = format!("{MINIMAL}tibia_length = 0.3\n");
        let err = parse(&unknown).expect_err("unknown key");
        assert!(
            err.to_string().contains("unknown field `tibia_length`"),
            "{err}"
        );
    }

    #[test]
    fn inverted_limit_is_refused() {
        let text = format!("{MINIMAL}[limits]\nhip_rad = [1.0, -1.0]\n");
        let err = parse(&text).expect_err("min > max");
        assert!(matches!(
            err,
            ParseError::Invalid(RobotError::BadLimit(kin_core::Joint::Hip))
        ));
    }

    #[test]
    fn presets_resolve_without_touching_the_file_system() {
        for name in Robot::PRESETS {
            assert_eq!(resolve(name).ok(), Robot::preset(name));
        }
    }
}
