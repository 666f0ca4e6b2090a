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
//!
//! An optional `[physical]` table gives the physics twin what the kinematics does not need
//! ([`quad_model::Physical`]; SI units); every key is optional and defaults to the physical
//! preset `preset` (the values and their reasoning: `docs/twin.md`):
//!
//! ```toml
//! [physical]
//! preset = "shahriar2023"       # defaults; omitted: the preset of the same geometry, else shahriar2023
//! servo = "ds3235"              # a servo preset: mg996r, ds3235, qdd17, qdd33
//! body_mass_kg = 1.8            # body with frame, battery, electronics, abduction servos
//! body_height_m = 0.06          # thickness of the body box
//! abduction_link_mass_kg = 0.085
//! femur_mass_kg = 0.06          # without the knee servo
//! tibia_mass_kg = 0.05          # with the foot
//! knee_servo_offset_m = 0.04    # knee servo below the hip joint, along the femur
//! foot_radius_m = 0.015
//! foot_friction = 0.8
//! link_radius_m = 0.012
//! ```
//!
//! A non-positive or non-finite value, an unknown servo or physical preset is refused naming the
//! key and its line ([`Error::Physical`]; unknown presets list the known ones).
//!
//! An optional `[device]` table gives what the device holds besides the geometry when the robot
//! is sent to it (protocol 2.4, `quadctl robot send`; [`device_description`]); every key is
//! optional:
//!
//! ```toml
//! [device]
//! name = "bench-pup"              # printable ASCII, at most 16 bytes; default: the file's stem
//! stance_height_m = 0.32          # default: see `default_stance_height_m`
//! rotation_order = "zyx"          # of body poses; default zyx
//! joint_speed_limit_rad_s = 3.0   # default: the device's default limit
//! ```
//!
//! A key left out of a file with a preset's geometry takes the preset's value (its name, stance
//! height, rotation order and joint-speed limit). The device checks what it is sent (`quad_protocol::check_robot`, which the host runs first):
//! the lengths and limits within their ranges, the stance reachable by every leg, the rest pose
//! within the limits.

use crate::names;
use kin_core::robot::RobotError;
use kin_core::{JointLimits, KneeBend, LegGeometry, Robot};
use quad_model::{Model, Physical, ServoModel};

use serde::{Deserialize, Deserializer};
use std::io;
use std::path::{Path, PathBuf};
use toml::Spanned;

mod device;
mod write;

pub use device::{
    default_stance_height_m, device_description, device_robot, DeviceError, DeviceRobotError,
};
pub use write::to_toml;

/// `knee_bend = "backward" | "forward"`, through [`names::knee_bend`].
fn knee_bend<'de, D: Deserializer<'de>>(d: D) -> Result<KneeBend, D::Error> {
    let name = String::deserialize(d)?;
    names::knee_bend(&name)
        .ok_or_else(|| serde::de::Error::unknown_variant(&name, &names::KNEE_BEND_NAMES))
}

/// The `[limits]` table: `[min, max]` per joint, rad.
#[derive(Debug, Clone, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct LimitsTable {
    abduction_rad: Option<Spanned<[f32; 2]>>,
    hip_rad: Option<Spanned<[f32; 2]>>,
    knee_rad: Option<Spanned<[f32; 2]>>,
}

/// The `[physical]` table: every key optional (see the module docs), kept with its place in
/// the text so that a refused value can be reported with its line.
#[derive(Debug, Clone, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct PhysicalTable {
    preset: Option<Spanned<String>>,
    servo: Option<Spanned<String>>,
    body_mass_kg: Option<Spanned<f32>>,
    body_height_m: Option<Spanned<f32>>,
    abduction_link_mass_kg: Option<Spanned<f32>>,
    femur_mass_kg: Option<Spanned<f32>>,
    tibia_mass_kg: Option<Spanned<f32>>,
    knee_servo_offset_m: Option<Spanned<f32>>,
    foot_radius_m: Option<Spanned<f32>>,
    foot_friction: Option<Spanned<f32>>,
    link_radius_m: Option<Spanned<f32>>,
}

impl PhysicalTable {
    /// The numeric keys: name, value, and where in the file to put it.
    fn numbers(&self) -> [(&'static str, Option<&Spanned<f32>>); 9] {
        [
            ("body_mass_kg", self.body_mass_kg.as_ref()),
            ("body_height_m", self.body_height_m.as_ref()),
            (
                "abduction_link_mass_kg",
                self.abduction_link_mass_kg.as_ref(),
            ),
            ("femur_mass_kg", self.femur_mass_kg.as_ref()),
            ("tibia_mass_kg", self.tibia_mass_kg.as_ref()),
            ("knee_servo_offset_m", self.knee_servo_offset_m.as_ref()),
            ("foot_radius_m", self.foot_radius_m.as_ref()),
            ("foot_friction", self.foot_friction.as_ref()),
            ("link_radius_m", self.link_radius_m.as_ref()),
        ]
    }

    /// The line of key `field` in `text`, when the file gives it.
    fn line(&self, field: &str, text: &str) -> Option<usize> {
        let span = match field {
            "preset" => self.preset.as_ref().map(Spanned::span),
            "servo" => self.servo.as_ref().map(Spanned::span),
            _ => self
                .numbers()
                .into_iter()
                .find(|(name, _)| *name == field)
                .and_then(|(_, v)| v.map(Spanned::span)),
        }?;
        Some(line_of(text, span.start))
    }

    /// The physical properties of `robot`: the preset's, with the file's values over them.
    fn physical(&self, robot: &Robot, text: &str) -> Result<Physical, Error> {
        let refused = |field: &str, source| Error::Physical {
            path: None,
            line: self.line(field, text),
            source,
        };
        let base = match &self.preset {
            Some(name) => Physical::preset(name.get_ref()).map_err(|e| refused("preset", e))?,
            None => default_physical(robot),
        };
        let mut p = base;
        if let Some(name) = &self.servo {
            p.servo = ServoModel::preset(name.get_ref())
                .map_err(|e| refused("servo", quad_model::Error::UnknownServo(e)))?;
        }
        let set = |slot: &mut f32, v: Option<&Spanned<f32>>| {
            if let Some(v) = v {
                *slot = *v.get_ref();
            }
        };
        set(&mut p.body_mass_kg, self.body_mass_kg.as_ref());
        set(&mut p.body_height_m, self.body_height_m.as_ref());
        set(
            &mut p.abduction_link_mass_kg,
            self.abduction_link_mass_kg.as_ref(),
        );
        set(&mut p.femur_mass_kg, self.femur_mass_kg.as_ref());
        set(&mut p.tibia_mass_kg, self.tibia_mass_kg.as_ref());
        set(
            &mut p.knee_servo_offset_m,
            self.knee_servo_offset_m.as_ref(),
        );
        set(&mut p.foot_radius_m, self.foot_radius_m.as_ref());
        set(&mut p.foot_friction, self.foot_friction.as_ref());
        set(&mut p.link_radius_m, self.link_radius_m.as_ref());
        // quad-model validates (one definition of a valid body); the key it names gets its line.
        match Model::new(*robot, p) {
            Ok(_) => Ok(p),
            Err(e) => {
                let field = match &e {
                    quad_model::Error::NonPositive { field }
                    | quad_model::Error::Negative { field } => *field,
                    quad_model::Error::KneeServoBeyondFemur => "knee_servo_offset_m",
                    _ => "",
                };
                Err(refused(field, e))
            }
        }
    }
}

/// The physical preset of a robot without a `[physical]` preset: the preset of the same
/// geometry, else seed 000's hobby-servo robot.
pub fn default_physical(robot: &Robot) -> Physical {
    Physical::PRESETS
        .into_iter()
        .find(|name| Robot::preset(name).as_ref() == Some(robot))
        .and_then(|name| Physical::preset(name).ok())
        .unwrap_or(Physical::shahriar2023())
}

/// The whole file; every value with its place in the text, for messages.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct RobotFile {
    d_lat_m: Spanned<f32>,
    d_ax_m: Spanned<f32>,
    femur_m: Spanned<f32>,
    tibia_m: Spanned<f32>,
    body_length_m: Spanned<f32>,
    body_width_m: Spanned<f32>,
    #[serde(default, deserialize_with = "knee_bend")]
    knee_bend: KneeBend,
    #[serde(default)]
    limits: LimitsTable,
    #[serde(default)]
    physical: PhysicalTable,
    #[serde(default)]
    device: DeviceTable,
}

/// The `[device]` table (module docs): every key optional.
#[derive(Debug, Clone, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct DeviceTable {
    name: Option<String>,
    stance_height_m: Option<f32>,
    rotation_order: Option<String>,
    joint_speed_limit_rad_s: Option<f32>,
}

/// The longest link or body dimension a robot file may give, m. Any longer is taken for a value
/// in the wrong unit (millimetres for metres), not a robot.
pub const MAX_DIMENSION_M: f32 = 10.0;

impl RobotFile {
    /// The lengths by key.
    fn lengths(&self) -> [(&'static str, &Spanned<f32>); 6] {
        [
            ("d_lat_m", &self.d_lat_m),
            ("d_ax_m", &self.d_ax_m),
            ("femur_m", &self.femur_m),
            ("tibia_m", &self.tibia_m),
            ("body_length_m", &self.body_length_m),
            ("body_width_m", &self.body_width_m),
        ]
    }

    /// The byte offset of the value kin-core names when it refuses one (a length's key or a
    /// joint's name).
    fn span_of(&self, key: &str) -> Option<usize> {
        if let Some((_, v)) = self.lengths().into_iter().find(|(k, _)| *k == key) {
            return Some(v.span().start);
        }
        let limit = match key {
            "abduction" => &self.limits.abduction_rad,
            "hip" => &self.limits.hip_rad,
            "knee" => &self.limits.knee_rad,
            _ => return None,
        };
        limit.as_ref().map(|l| l.span().start)
    }

    fn into_robot(self) -> Robot {
        let full = JointLimits::FULL_TURN;
        let pick = |entry: Option<Spanned<[f32; 2]>>, j: usize| {
            entry.map_or([full.min_rad[j], full.max_rad[j]], Spanned::into_inner)
        };
        let entries = [
            pick(self.limits.abduction_rad, 0),
            pick(self.limits.hip_rad, 1),
            pick(self.limits.knee_rad, 2),
        ];
        Robot {
            leg: LegGeometry {
                d_lat_m: *self.d_lat_m.get_ref(),
                d_ax_m: *self.d_ax_m.get_ref(),
                femur_m: *self.femur_m.get_ref(),
                tibia_m: *self.tibia_m.get_ref(),
            },
            body_length_m: *self.body_length_m.get_ref(),
            body_width_m: *self.body_width_m.get_ref(),
            limits: JointLimits {
                min_rad: entries.map(|e| e[0]),
                max_rad: entries.map(|e| e[1]),
            },
            knee_bend: self.knee_bend,
        }
    }
}

/// 1-based line of byte `offset` in `text`.
fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
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
    #[error("{}{}", place(path, *line), source.message().trim_end())]
    Toml {
        /// The file, when the text came from one.
        path: Option<PathBuf>,
        /// 1-based line of the error, when it has one (a missing key has none).
        line: Option<usize>,
        /// The TOML error (its message names the key); boxed, it is large.
        source: Box<toml::de::Error>,
    },
    /// The values were read but [`Robot::validate`] refused them.
    #[error("{}{source}", place(path, *line))]
    Invalid {
        /// The file, when the text came from one.
        path: Option<PathBuf>,
        /// 1-based line of the refused value.
        line: Option<usize>,
        /// kin-core's reason, naming the key.
        source: RobotError,
    },
    /// A length beyond [`MAX_DIMENSION_M`]: a value in another unit than metres.
    #[error(
        "{}`{key}` = {value_m} m is implausible (more than {MAX_DIMENSION_M} m): values are in \
         metres, e.g. 0.28 for 280 mm",
        place(path, Some(*line))
    )]
    Implausible {
        /// The file, when the text came from one.
        path: Option<PathBuf>,
        /// 1-based line of the value.
        line: usize,
        /// The key.
        key: &'static str,
        /// The value given.
        value_m: f32,
    },
    /// A `[physical]` value was refused: not finite and > 0, an unknown servo or physical preset
    /// (the message lists the known ones), a knee servo beyond the femur.
    #[error("{}[physical] {source}", place(path, *line))]
    Physical {
        /// The file, when the text came from one.
        path: Option<PathBuf>,
        /// Line of the refused key in the file (from 1), when the file gives it.
        line: Option<usize>,
        /// quad-model's reason, naming the key.
        source: quad_model::Error,
    },
    /// A URDF file is not a robot with this project's leg chain (or cannot be read).
    #[error("URDF `{}`: {source}", path.display())]
    Urdf {
        /// The file.
        path: PathBuf,
        /// What differs.
        source: quad_model::urdf::ReadError,
    },
    /// The description could not be written as TOML.
    #[error("the robot cannot be written as TOML: {0}")]
    Write(String),
}

/// The `robot file `PATH`:LINE: ` prefix of a message (parts left out when unknown).
fn place(path: &Option<PathBuf>, line: Option<usize>) -> String {
    match (path, line) {
        (Some(p), Some(l)) => format!("robot file `{}`:{l}: ", p.display()),
        (Some(p), None) => format!("robot file `{}`: ", p.display()),
        (None, Some(l)) => format!("line {l}: "),
        (None, None) => String::new(),
    }
}

impl Error {
    fn in_file(self, file: &Path) -> Error {
        let path = Some(file.to_owned());
        match self {
            Error::Toml { line, source, .. } => Error::Toml { path, line, source },
            Error::Invalid { line, source, .. } => Error::Invalid { path, line, source },
            Error::Implausible {
                line, key, value_m, ..
            } => Error::Implausible {
                path,
                line,
                key,
                value_m,
            },
            Error::Physical { line, source, .. } => Error::Physical { path, line, source },
            other => other,
        }
    }
}

/// Parses and validates the text of a robot file (see the module docs for the keys).
///
/// # Errors
/// [`Error::Toml`], [`Error::Invalid`] or [`Error::Implausible`], with the line of the value at
/// fault when there is one.
pub fn parse(text: &str) -> Result<Robot, Error> {
    parse_file(text).map(|(_, robot)| robot)
}

/// The file with the places of its values, and its validated robot.
fn parse_file(text: &str) -> Result<(RobotFile, Robot), Error> {
    let file: RobotFile = toml::from_str(text).map_err(|source| {
        // A missing key is reported on an empty span at the start (or on the whole document):
        // it has no line of its own, and line 1 would point at whatever is there.
        let line = source
            .span()
            .filter(|s| s.start > 0 || (s.end > 0 && s.end < text.trim_end().len()))
            .map(|s| line_of(text, s.start));
        Error::Toml {
            path: None,
            line,
            source: Box::new(source),
        }
    })?;
    if let Some((key, v)) = file
        .lengths()
        .into_iter()
        .find(|(_, v)| v.get_ref().abs() > MAX_DIMENSION_M)
    {
        return Err(Error::Implausible {
            path: None,
            line: line_of(text, v.span().start),
            key,
            value_m: *v.get_ref(),
        });
    }
    let spans = file.clone();
    let robot = file.into_robot();
    robot.validate().map_err(|source| {
        let key = match &source {
            RobotError::BadLength(name) => Some(*name),
            RobotError::BadLimit(joint) => Some(joint.name()),
            _ => None,
        };
        Error::Invalid {
            path: None,
            line: key.and_then(|k| spans.span_of(k)).map(|o| line_of(text, o)),
            source,
        }
    })?;
    Ok((spans, robot))
}

/// A robot with its physical properties, for the physics twin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Description {
    /// The kinematic description.
    pub robot: Robot,
    /// Masses, sizes, feet and servo (the file's `[physical]` over its preset).
    pub physical: Physical,
}

/// Parses and validates the text of a robot file with its `[physical]` table.
pub fn parse_description(text: &str) -> Result<Description, Error> {
    let (file, robot) = parse_file(text)?;
    let physical = file.physical.physical(&robot, text)?;
    Ok(Description { robot, physical })
}

/// Resolves a `--robot` argument with its physical properties: a preset name (its physical
/// preset), a URDF file (`.urdf`, legs with this project's chain, [`quad_model::urdf`]; the
/// physical preset of [`default_physical`]) or else a TOML file path (see
/// [`parse_description`]).
pub fn resolve_description(spec: &str) -> Result<Description, Error> {
    if let Some(robot) = Robot::preset(spec) {
        return Ok(Description {
            robot,
            physical: default_physical(&robot),
        });
    }
    let path = Path::new(spec);
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("urdf"))
    {
        let robot = quad_model::urdf::read_file(path).map_err(|source| Error::Urdf {
            path: path.to_owned(),
            source,
        })?;
        return Ok(Description {
            robot,
            physical: default_physical(&robot),
        });
    }
    let text = std::fs::read_to_string(path).map_err(|source| Error::Read {
        path: path.to_owned(),
        source,
    })?;
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    parse_description(text).map_err(|e| e.in_file(path))
}

/// Reads and validates a robot file.
pub fn load_file(path: &Path) -> Result<Robot, Error> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Read {
        path: path.to_owned(),
        source,
    })?;
    // Editors on Windows may start the file with a byte-order mark; TOML does not allow one.
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    parse(text).map_err(|e| e.in_file(path))
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
                line: Some(3),
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
    fn physical_defaults_follow_the_preset_of_the_geometry() {
        let d = parse_description(MINIMAL).expect("valid file");
        assert_eq!(d.physical, Physical::shahriar2023());
        for name in Robot::PRESETS {
            let d = resolve_description(name).expect("preset");
            assert_eq!(Some(d.physical), Physical::preset(name).ok());
        }
        let text = format!(
            "{MINIMAL}[physical]\npreset = \"fernando2025\"\nservo = \"mg996r\"\nbody_mass_kg = 2.5\n"
        );
        let d = parse_description(&text).expect("valid file");
        assert_eq!(d.physical.body_mass_kg, 2.5);
        assert_eq!(d.physical.servo, ServoModel::MG996R);
        assert_eq!(
            d.physical.tibia_mass_kg,
            Physical::fernando2025().tibia_mass_kg
        );
        // The kinematics alone ignore the table.
        assert_eq!(parse(&text).ok(), Some(d.robot));
    }

    #[test]
    fn bad_physical_values_are_named_with_their_line() {
        let text = format!("{MINIMAL}[physical]\nfemur_mass_kg = 0.06\nbody_mass_kg = -1.8\n");
        let err = parse_description(&text).expect_err("negative mass");
        assert!(
            matches!(
                err,
                Error::Physical {
                    line: Some(9),
                    source: quad_model::Error::NonPositive {
                        field: "body_mass_kg"
                    },
                    ..
                }
            ),
            "{err:?}"
        );
        assert!(err.to_string().contains("line 9"), "{err}");
        assert!(err.to_string().contains("`body_mass_kg`"), "{err}");
        // The kinematics alone still read.
        assert!(parse(&text).is_ok());

        let text = format!("{MINIMAL}[physical]\nservo = \"sg90\"\n");
        let err = parse_description(&text)
            .expect_err("unknown servo")
            .to_string();
        assert!(err.contains("line 8") && err.contains("`sg90`"), "{err}");
        for known in ServoModel::PRESETS {
            assert!(err.contains(known), "{err}");
        }
        let text = format!("{MINIMAL}[physical]\npreset = \"spot\"\n");
        let err = parse_description(&text)
            .expect_err("unknown preset")
            .to_string();
        assert!(
            err.contains("`spot`") && err.contains("shahriar2023"),
            "{err}"
        );
        let text = format!("{MINIMAL}[physical]\nknee_servo_offset_m = 0.5\n");
        let err = parse_description(&text)
            .expect_err("beyond the femur")
            .to_string();
        assert!(
            err.contains("line 8") && err.contains("knee_servo_offset_m"),
            "{err}"
        );
        let text = format!("{MINIMAL}[physical]\nbody_mass = 1.0\n");
        let err = parse_description(&text)
            .expect_err("unknown key")
            .to_string();
        assert!(err.contains("unknown field `body_mass`"), "{err}");
    }

    #[test]
    fn presets_resolve_without_touching_the_file_system() {
        for name in Robot::PRESETS {
            assert_eq!(resolve(name).ok(), Robot::preset(name));
        }
    }
}
