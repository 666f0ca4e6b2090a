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

use crate::names;
use kin_core::robot::RobotError;
use kin_core::{JointLimits, KneeBend, LegGeometry, Robot};
use serde::{Deserialize, Deserializer};
use std::io;
use std::path::{Path, PathBuf};

/// `knee_bend = "backward" | "forward"`, through [`names::knee_bend`].
fn knee_bend<'de, D: Deserializer<'de>>(d: D) -> Result<KneeBend, D::Error> {
    let name = String::deserialize(d)?;
    names::knee_bend(&name)
        .ok_or_else(|| serde::de::Error::unknown_variant(&name, &names::KNEE_BEND_NAMES))
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
    #[serde(default, deserialize_with = "knee_bend")]
    knee_bend: KneeBend,
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
            knee_bend: self.knee_bend,
        }
    }
}

/// Why a robot file or a `--robot` argument was refused.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Not a preset name, and the file could not be read.
    #[error(
        "`{}` is not a preset ({}) and cannot be read as a robot file: {source}",
        path.display(),
        Robot::PRESETS.join(", ")
    )]
    Read {
        /// The path tried.
        path: PathBuf,
        /// The I/O error.
        source: io::Error,
    },
    /// Not valid TOML, or a key is missing, unknown or of the wrong type.
    #[error("{}{}", file(path), source.to_string().trim_end())]
    Toml {
        /// The file, when the text came from one.
        path: Option<PathBuf>,
        /// The TOML error (it names the key and the line).
        source: toml::de::Error,
    },
    /// The values were read but [`Robot::validate`] refused them.
    #[error("{}{source}", file(path))]
    Invalid {
        /// The file, when the text came from one.
        path: Option<PathBuf>,
        /// kin-core's reason, naming the key.
        source: RobotError,
    },
}

/// The `robot file `PATH`: ` prefix of a message, when there is a file.
fn file(path: &Option<PathBuf>) -> String {
    path.as_ref()
        .map(|p| format!("robot file `{}`: ", p.display()))
        .unwrap_or_default()
}

impl Error {
    fn in_file(self, file: &Path) -> Error {
        match self {
            Error::Toml { source, .. } => Error::Toml {
                path: Some(file.to_owned()),
                source,
            },
            Error::Invalid { source, .. } => Error::Invalid {
                path: Some(file.to_owned()),
                source,
            },
            other => other,
        }
    }
}

/// Parses and validates the text of a robot file (see the module docs for the keys).
pub fn parse(text: &str) -> Result<Robot, Error> {
    let file: RobotFile =
        toml::from_str(text).map_err(|source| Error::Toml { path: None, source })?;
    let robot = file.into_robot();
    robot
        .validate()
        .map_err(|source| Error::Invalid { path: None, source })?;
    Ok(robot)
}

/// Reads and validates a robot file.
pub fn load_file(path: &Path) -> Result<Robot, Error> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Read {
        path: path.to_owned(),
        source,
    })?;
    parse(&text).map_err(|e| e.in_file(path))
}

/// Resolves a `--robot` argument: a preset name ([`Robot::PRESETS`]) or else a TOML file path.
pub fn resolve(spec: &str) -> Result<Robot, Error> {
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
            Error::Invalid {
                source: RobotError::BadLength("femur_m"),
                ..
            }
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
            Error::Invalid {
                source: RobotError::BadLimit(kin_core::Joint::Hip),
                ..
            }
        ));
    }

    #[test]
    fn presets_resolve_without_touching_the_file_system() {
        for name in Robot::PRESETS {
            assert_eq!(resolve(name).ok(), Robot::preset(name));
        }
    }
}
