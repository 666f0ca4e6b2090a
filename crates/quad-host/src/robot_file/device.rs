//! The robot a device holds (protocol 2.4): a `--robot` argument made the description a device
//! holds, and the robot a connected device runs.

use super::{names, parse_file, resolve_description, DeviceTable, Error, Path};
use kin_core::Robot;
use quad_protocol::{DeviceInfo, RobotPreset};

/// Why the robot of a device could not be known.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum DeviceRobotError {
    /// The device runs a robot that is no preset, and no robot file was given.
    #[error(
        "the device runs a robot that is no preset (`custom`): give its robot file with \
         --robot FILE.toml"
    )]
    Custom,
    /// The robot given is not the preset the device runs.
    #[error(
        "the device runs robot {}, the robot given is another: leave --robot out (the device's \
         own robot is used) or give that preset",
        names::robot_preset_name(*device)
    )]
    Mismatch {
        /// The device's preset.
        device: RobotPreset,
    },
    /// The robot given is not the robot the device holds (protocol 2.4).
    #[error(
        "the device holds robot `{device}` (hash {device_hash:#010x}), the robot given is \
         another: leave --robot out (the device's own robot is used), or put yours on the \
         device with `quadctl robot send FILE --save`"
    )]
    Differs {
        /// The name of the device's robot.
        device: String,
        /// The hash of the device's robot description.
        device_hash: u32,
    },
}

/// The robot the device runs: the description it holds (`held`, read with `GetRobot` from a
/// device of protocol 2.4 or later), else the preset its `HelloAck` reports, else `file` (a robot
/// file given on the command line) for an older device whose robot is no preset. A robot given
/// beside a known robot must be that robot's geometry.
///
/// Every operation that plans with the device's own robot (the guided calibration's posture and
/// test poses, the panel's calibration tab) obtains it here.
///
/// # Errors
/// [`DeviceRobotError::Custom`] for an older custom device without `file`,
/// [`DeviceRobotError::Mismatch`] for a preset device and another robot,
/// [`DeviceRobotError::Differs`] for a held description and another robot.
pub fn device_robot(
    info: &DeviceInfo,
    held: Option<&quad_protocol::RobotDescription>,
    file: Option<&Robot>,
) -> Result<Robot, DeviceRobotError> {
    if let Some(held) = held {
        return match file {
            Some(given) if !held.robot.equals(given) => Err(DeviceRobotError::Differs {
                device: held.name_str().unwrap_or("?").to_owned(),
                device_hash: held.hash(),
            }),
            _ => Ok(held.robot),
        };
    }
    match (info.robot.robot(), file) {
        (Some(robot), None) => Ok(robot),
        (Some(robot), Some(given)) if robot.equals(given) => Ok(robot),
        (Some(_), Some(_)) => Err(DeviceRobotError::Mismatch { device: info.robot }),
        (None, Some(given)) => Ok(*given),
        (None, None) => Err(DeviceRobotError::Custom),
    }
}

/// The default stance height of a robot sent to the device without one, m: the hip joint's
/// offset plus 80 % of the stretched femur and tibia (a knee bent about 75° for equal links),
/// what every robot of this leg chain reaches within the usual limits.
pub fn default_stance_height_m(robot: &Robot) -> f32 {
    robot.leg.d_ax_m + 0.8 * (robot.leg.femur_m + robot.leg.tibia_m)
}

/// Why a robot could not be made a device's robot description.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DeviceError {
    /// The robot file or argument was refused.
    #[error(transparent)]
    Robot(#[from] Error),
    /// The `[device]` name is not a valid name (printable ASCII, 1 to 16 bytes).
    #[error("[device] name `{name}`: {source}")]
    Name {
        /// The name given.
        name: String,
        /// What is wrong with it.
        source: quad_protocol::robot::NameError,
    },
    /// The `[device]` rotation order is not one of the six.
    #[error("[device] rotation_order `{0}`: not one of xyz, xzy, yxz, yzx, zxy, zyx")]
    RotationOrder(String),
    /// The description is one the device refuses (`quad_protocol::check_robot`, whose
    /// [`quad_protocol::NackReason::BadRobot`] names the field).
    #[error(
        "the device cannot hold this robot ({reason}{}); not sent",
        hint_text(hint)
    )]
    Refused {
        /// The device's refusal, naming the field.
        reason: quad_protocol::NackReason,
        /// What the field must be for this robot, when there is more to say than its name.
        hint: Option<String>,
    },
}

/// `: hint` when there is one.
fn hint_text(hint: &Option<String>) -> String {
    hint.as_ref().map(|h| format!(": {h}")).unwrap_or_default()
}

/// What a refused field of `d` must be, in the robot's own numbers: the ranges that depend on
/// the robot (the stance height), and the poses the device must reach (the rest pose and the
/// stance). `None` for a field whose range the protocol document lists as it is.
fn refusal_hint(
    reason: &quad_protocol::NackReason,
    d: &quad_protocol::RobotDescription,
) -> Option<String> {
    use quad_protocol::range::{leg_span_m, reach_limit_m, MIN_STANCE_HEIGHT_M};
    use quad_protocol::{NackReason, RobotField};
    let NackReason::BadRobot(field) = reason else {
        return None;
    };
    let r = &d.robot;
    match field {
        RobotField::StanceHeightM => Some(format!(
            "{} m is outside [{MIN_STANCE_HEIGHT_M}, {:.3}] m, twice this leg's span \
             d_lat_m + d_ax_m + femur_m + tibia_m = {:.3} m",
            d.stance_height_m,
            reach_limit_m(r),
            leg_span_m(r)
        )),
        RobotField::Stance(leg) => Some(format!(
            "leg {leg:?} cannot put its foot {} m below its hip (the stance height) at the zero \
             body pose within its joint limits; the leg stretched is {:.3} m: lower \
             stance_height_m or widen the limits",
            d.stance_height_m,
            leg_span_m(r)
        )),
        RobotField::RestPose(joint) => {
            let rest = r.rest_leg();
            Some(format!(
                "the rest pose (abduction {}, hip {}, knee {} rad), where the device's sit, rest \
                 and safe state go, leaves the {joint:?} limits",
                rest.abduction_rad, rest.hip_rad, rest.knee_rad
            ))
        }
        _ => None,
    }
}

/// Resolves a `--robot` argument into the description a device holds (protocol 2.4): a preset
/// name (the preset's own description, `quad_device::Config::description`), a URDF file (its
/// stem as name, the defaults below) or a TOML file (its `[device]` table over the defaults:
/// the file's stem as name, [`default_stance_height_m`], rotation order zyx, the device's
/// default joint-speed limit; for a file with a preset's geometry, the preset's description).
/// Checked as the device checks it.
///
/// # Errors
/// [`DeviceError`].
pub fn device_description(spec: &str) -> Result<quad_protocol::RobotDescription, DeviceError> {
    use quad_protocol::RobotDescription;
    if let Some(preset) = quad_protocol::RobotPreset::from_name(spec.trim()) {
        if let Some(config) = quad_device::Config::for_preset(preset) {
            return Ok(config.description());
        }
    }
    let path = Path::new(spec);
    let stem: String = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let (robot, table) = if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("urdf"))
    {
        (resolve_description(spec)?.robot, DeviceTable::default())
    } else {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Read {
            path: path.to_owned(),
            source,
        })?;
        let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
        let (file, robot) = parse_file(text).map_err(|e| e.in_file(path))?;
        (robot, file.device)
    };
    // A file with a preset's geometry defaults to the preset's description (the robot the
    // device calls by the preset's name).
    let base = [
        quad_protocol::RobotPreset::Shahriar2023,
        quad_protocol::RobotPreset::Fernando2025,
    ]
    .into_iter()
    .filter_map(quad_device::Config::for_preset)
    .map(|c| c.description())
    .find(|d| d.robot == robot);
    let name = match (table.name, &base) {
        (Some(n), _) => n,
        (None, Some(b)) => b.name_str().unwrap_or_default().to_owned(),
        (None, None) => stem.chars().take(16).collect(),
    };
    let name_bytes =
        RobotDescription::name_bytes(&name).map_err(|source| DeviceError::Name { name, source })?;
    let order = match table.rotation_order {
        Some(o) => kin_core::RotationOrder::parse(&o).ok_or(DeviceError::RotationOrder(o))?,
        None => base.map_or(kin_core::RotationOrder::Zyx, |b| b.order),
    };
    let d = RobotDescription {
        name: name_bytes,
        robot,
        stance_height_m: table.stance_height_m.unwrap_or_else(|| {
            base.map_or_else(|| default_stance_height_m(&robot), |b| b.stance_height_m)
        }),
        order,
        joint_speed_limit_rad_s: table.joint_speed_limit_rad_s.unwrap_or_else(|| {
            base.map_or(quad_device::engine::DEFAULT_JOINT_SPEED_LIMIT_RAD_S, |b| {
                b.joint_speed_limit_rad_s
            })
        }),
    };
    quad_protocol::check_robot::<kin_core::DefaultMath>(&d).map_err(|reason| {
        DeviceError::Refused {
            hint: refusal_hint(&reason, &d),
            reason,
        }
    })?;
    Ok(d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot_file::parse;

    const MINIMAL: &str = "d_lat_m = 0.044\nd_ax_m = 0.0\nfemur_m = 0.28\ntibia_m = 0.277\n\
                           body_length_m = 0.6\nbody_width_m = 0.28\n";

    /// The `HelloAck` of a device running `preset`.
    fn info(preset: RobotPreset) -> DeviceInfo {
        let c = quad_device::Config::shahriar2023();
        DeviceInfo {
            version: quad_protocol::PROTOCOL_VERSION,
            firmware: c.firmware,
            robot: preset,
            max_frame_len: 128,
            pose_config: c.pose_config,
            link_timeout: c.link_timeout,
            robot_hash: None,
        }
    }

    #[test]
    fn the_device_robot_is_the_preset_it_reports_or_the_file_given_for_a_custom_one() {
        let fernando = info(RobotPreset::Fernando2025);
        assert_eq!(
            device_robot(&fernando, None, None),
            Ok(Robot::fernando2025())
        );
        assert_eq!(
            device_robot(&fernando, None, Some(&Robot::fernando2025())),
            Ok(Robot::fernando2025())
        );
        assert_eq!(
            device_robot(&fernando, None, Some(&Robot::shahriar2023())),
            Err(DeviceRobotError::Mismatch {
                device: RobotPreset::Fernando2025
            })
        );
        let custom = info(RobotPreset::Custom);
        let e = device_robot(&custom, None, None).unwrap_err();
        assert_eq!(e, DeviceRobotError::Custom);
        assert!(e.to_string().contains("--robot FILE.toml"), "{e}");
        let file = parse(MINIMAL).expect("valid file");
        assert_eq!(device_robot(&custom, None, Some(&file)), Ok(file));
    }

    #[test]
    fn a_held_description_is_the_device_robot_and_another_robot_is_refused_naming_it() {
        // A device of protocol 2.4 reports what it holds: that wins over the hello's preset.
        let file = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/robots/bench-pup.toml"
        );
        let held = device_description(file).expect("the example robot");
        let custom = info(RobotPreset::Custom);
        assert_eq!(device_robot(&custom, Some(&held), None), Ok(held.robot));
        assert_eq!(
            device_robot(&custom, Some(&held), Some(&held.robot)),
            Ok(held.robot)
        );
        let e = device_robot(&custom, Some(&held), Some(&Robot::shahriar2023())).unwrap_err();
        assert_eq!(
            e,
            DeviceRobotError::Differs {
                device: "bench-pup".to_owned(),
                device_hash: held.hash()
            }
        );
        assert!(e.to_string().contains("quadctl robot send"), "{e}");
    }
}
