//! What the device is built for: the robot, how body poses are read, the link-loss failsafe,
//! where the calibration is stored, and the default servo calibration.

use crate::engine::Limiter;
use crate::store::Table;
use core::fmt;
use kin_core::body;
use kin_core::robot::RobotError;
use kin_core::{BodyConfig, LegId, Math, ReachPolicy, Robot, RotationOrder};
use quad_protocol::robot::NAME_LEN;
use quad_protocol::servo::{Calibration, STANDARD_US_PER_RAD};
use quad_protocol::{
    FirmwareVersion, LinkTimeout, PoseConfig, Ranges, RobotDescription, RobotPreset,
};

/// The preset `robot` is: [`RobotPreset::Custom`] unless it equals a preset's
/// [`Config::description`] in every field, its name included.
pub fn preset_of(robot: &RobotDescription) -> RobotPreset {
    for preset in [RobotPreset::Shahriar2023, RobotPreset::Fernando2025] {
        if let Some(c) = Config::for_preset(preset) {
            if c.description() == *robot {
                return preset;
            }
        }
    }
    RobotPreset::Custom
}

/// Default stance height of [`Robot::fernando2025`]: seed 001's initial pose (eq. 5, α = 60°,
/// φ = 120°), `H = l0 + (l1 + l2)·sin 60°`, m.
pub const FERNANDO2025_STANCE_HEIGHT_M: f32 = 0.9294;

/// Default stance height of [`Robot::shahriar2023`]: the height of seed 000's pose sweeps
/// (`kin_core::motion::laws::SEED000_SWEEP_STANCE_HEIGHT_M`), m.
pub const SHAHRIAR2023_STANCE_HEIGHT_M: f32 = kin_core::motion::laws::SEED000_SWEEP_STANCE_HEIGHT_M;

/// Default servo travel on either side of the centre pulse, µs: 500–2500 µs, about ±90° at the
/// standard gain.
pub const DEFAULT_TRAVEL_US: u16 = 1000;

/// Default centre pulse, µs.
pub const DEFAULT_CENTER_US: u16 = 1500;

/// Everything the controller is constructed with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Config {
    /// The preset reported in `HelloAck` ([`RobotPreset::Custom`] for another geometry).
    pub preset: RobotPreset,
    /// The geometry the IK runs on.
    pub robot: Robot,
    /// How body poses are read at power-on (changed by `SetPoseConfig`, not persisted).
    pub pose_config: PoseConfig,
    /// Link-loss failsafe at power-on (changed by `SetLinkTimeout`, not persisted).
    pub link_timeout: LinkTimeout,
    /// Firmware release reported in `HelloAck`.
    pub firmware: FirmwareVersion,
    /// Storage address of calibration bank A; [`crate::store::USED_LEN`] bytes are used (the
    /// calibration's banks, then the robot's, [`crate::store`]).
    pub storage_base: u16,
    /// Joint-speed limit of every output at power-on, rad/s (within the range that
    /// `SetJointSpeedLimit` admits, [`quad_protocol::range::JOINT_SPEED_LIMIT_RAD_S`]; see
    /// [`crate::engine::DEFAULT_JOINT_SPEED_LIMIT_RAD_S`]).
    pub joint_speed_limit_rad_s: f32,
}

/// Why a [`Config`] or a pose configuration was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ConfigError {
    /// The robot description is invalid.
    Robot(RobotError),
    /// The stance height is not a finite length > 0.
    StanceHeight,
    /// The preset names a robot other than [`Config::robot`].
    PresetMismatch,
    /// The storage banks (calibration and robot) do not fit below address 65536.
    StorageBase,
    /// The joint-speed limit is outside the range `SetJointSpeedLimit` admits
    /// ([`quad_protocol::range::JOINT_SPEED_LIMIT_RAD_S`]).
    JointSpeedLimit,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConfigError::Robot(e) => write!(f, "robot: {e}"),
            ConfigError::StanceHeight => f.write_str("stance height must be a finite length > 0"),
            ConfigError::PresetMismatch => f.write_str("preset and robot geometry differ"),
            ConfigError::StorageBase => f.write_str("the storage exceeds 64 KiB"),
            ConfigError::JointSpeedLimit => f.write_str(
                "joint speed limit must be within SetJointSpeedLimit's range, [0.1, 157.08] rad/s",
            ),
        }
    }
}

impl core::error::Error for ConfigError {}

/// Checks a pose configuration: the stance height must be finite and > 0.
pub const fn validate_pose_config(p: &PoseConfig) -> Result<(), ConfigError> {
    if p.stance_height_m.is_finite() && p.stance_height_m > 0.0 {
        Ok(())
    } else {
        Err(ConfigError::StanceHeight)
    }
}

impl Config {
    /// [`Robot::fernando2025`] at [`FERNANDO2025_STANCE_HEIGHT_M`], seed 001's rotation order
    /// `zxy`, unreachable poses rejected, no link-loss timeout, the default joint-speed limit.
    /// The stance height and rotation order here are the robot's one default: the motion
    /// engine's stance, stand-up and motions use them.
    pub const fn fernando2025() -> Config {
        Config {
            preset: RobotPreset::Fernando2025,
            robot: Robot::fernando2025(),
            pose_config: PoseConfig {
                stance_height_m: FERNANDO2025_STANCE_HEIGHT_M,
                order: RotationOrder::Zxy,
                policy: ReachPolicy::Reject,
            },
            link_timeout: LinkTimeout {
                timeout_ms: 0,
                action: quad_protocol::LinkLossAction::Hold,
            },
            firmware: FirmwareVersion {
                major: 0,
                minor: 1,
                patch: 0,
            },
            storage_base: 0,
            joint_speed_limit_rad_s: crate::engine::DEFAULT_JOINT_SPEED_LIMIT_RAD_S,
        }
    }

    /// [`Robot::shahriar2023`] at [`SHAHRIAR2023_STANCE_HEIGHT_M`], rotation order `zyx`,
    /// unreachable poses rejected, no link-loss timeout.
    pub const fn shahriar2023() -> Config {
        let mut c = Config::fernando2025();
        c.preset = RobotPreset::Shahriar2023;
        c.robot = Robot::shahriar2023();
        c.pose_config.stance_height_m = SHAHRIAR2023_STANCE_HEIGHT_M;
        c.pose_config.order = RotationOrder::Zyx;
        c
    }

    /// The configuration of a preset; `None` for [`RobotPreset::Custom`].
    pub const fn for_preset(preset: RobotPreset) -> Option<Config> {
        match preset {
            RobotPreset::Fernando2025 => Some(Config::fernando2025()),
            RobotPreset::Shahriar2023 => Some(Config::shahriar2023()),
            RobotPreset::Custom => None,
        }
    }

    /// The robot this configuration describes, as protocol 2.4 sends and stores it: named
    /// after the preset (`shahriar2023`, `fernando2025`, `custom`), with the stance height and
    /// rotation order of [`Config::pose_config`] and [`Config::joint_speed_limit_rad_s`]. The
    /// one definition of a preset's description: the host compares its hash with the device's.
    pub const fn description(&self) -> RobotDescription {
        let name: &[u8] = match self.preset {
            RobotPreset::Shahriar2023 => b"shahriar2023",
            RobotPreset::Fernando2025 => b"fernando2025",
            RobotPreset::Custom => b"custom",
        };
        let mut bytes = [0u8; NAME_LEN];
        let mut i = 0;
        while i < name.len() {
            bytes[i] = name[i];
            i += 1;
        }
        RobotDescription {
            name: bytes,
            robot: self.robot,
            stance_height_m: self.pose_config.stance_height_m,
            order: self.pose_config.order,
            joint_speed_limit_rad_s: self.joint_speed_limit_rad_s,
        }
    }

    /// Checks the robot, the pose configuration, that a named preset matches the robot, and
    /// that the storage fits. A `const fn`: a firmware's constant configuration is checked at
    /// compile time ([`ValidConfig::checked`]).
    pub const fn validate(&self) -> Result<(), ConfigError> {
        if let Err(e) = self.robot.validate() {
            return Err(ConfigError::Robot(e));
        }
        if let Err(e) = validate_pose_config(&self.pose_config) {
            return Err(e);
        }
        if let Some(r) = self.preset.robot() {
            if !r.equals(&self.robot) {
                return Err(ConfigError::PresetMismatch);
            }
        }
        if self.storage_base as u32 + crate::store::USED_LEN as u32 > 0x1_0000 {
            return Err(ConfigError::StorageBase);
        }
        // The range the wire admits (`SetJointSpeedLimit`), then the limiter's own check.
        if quad_protocol::range::JOINT_SPEED_LIMIT_RAD_S
            .check(self.joint_speed_limit_rad_s)
            .is_err()
            || crate::engine::Limiter::new(self.joint_speed_limit_rad_s).is_err()
        {
            return Err(ConfigError::JointSpeedLimit);
        }
        Ok(())
    }
}

/// A [`Config`] that passed [`Config::validate`], with the limiter of its joint-speed limit
/// and the request ranges of its robot:
/// what [`crate::Device::stopped_valid`] builds a controller from without checking again. A
/// constant one (`const C: ValidConfig = ValidConfig::checked(…)`) is checked at compile
/// time, so that a firmware carries no validation code for it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ValidConfig {
    config: Config,
    limiter: Limiter,
    ranges: Ranges,
}

impl ValidConfig {
    /// `config` once [`Config::validate`] accepts it.
    ///
    /// # Errors
    /// [`Config::validate`]'s error.
    pub const fn new(config: Config) -> Result<ValidConfig, ConfigError> {
        if let Err(e) = config.validate() {
            return Err(e);
        }
        match Limiter::new(config.joint_speed_limit_rad_s) {
            Ok(limiter) => Ok(ValidConfig {
                config,
                limiter,
                ranges: Ranges::of(&config.robot),
            }),
            Err(_) => Err(ConfigError::JointSpeedLimit),
        }
    }

    /// [`ValidConfig::new`] for a constant: in a `const` item, an invalid `config` fails the
    /// build.
    ///
    /// # Panics
    /// When `config` is invalid (at compile time in a `const` item).
    pub const fn checked(config: Config) -> ValidConfig {
        match ValidConfig::new(config) {
            Ok(c) => c,
            Err(_) => panic!("invalid device configuration"),
        }
    }

    /// The configuration.
    pub const fn config(&self) -> &Config {
        &self.config
    }

    /// The limiter of [`Config::joint_speed_limit_rad_s`].
    pub const fn limiter(&self) -> &Limiter {
        &self.limiter
    }

    /// The request ranges of [`Config::robot`].
    pub const fn ranges(&self) -> &Ranges {
        &self.ranges
    }
}

/// The calibration a controller holds from [`crate::Device::stopped`] until
/// [`crate::Device::boot`]: all zeros, an empty travel (0 µs) that no angle maps into. Zeros so
/// that it costs a memset, not a table copied into SRAM at reset.
pub(crate) const UNBOOTED_CALIBRATION: Table = [Calibration {
    zero_rad: 0.0,
    reversed: false,
    us_per_rad: 0.0,
    center_us: 0,
    min_us: 0,
    max_us: 0,
}; 12];

/// The calibration used when the storage holds none: each servo centred (1500 µs) on the
/// joint's angle in the nominal stance of `pose_config`, standard gain
/// ([`STANDARD_US_PER_RAD`]), travel 500–2500 µs, hip and knee servos of the right legs
/// reversed (mounted mirrored). When the stance is unreachable the centres sit at angle 0.
pub fn default_calibration<M: Math>(robot: &Robot, pose_config: &PoseConfig) -> Table {
    let mut table = UNBOOTED_CALIBRATION;
    write_default_calibration(
        &body::Solver::<M>::with_math(robot),
        pose_config,
        &mut table,
    );
    table
}

/// [`default_calibration`] written in place (no table-sized temporary on the stack), with the
/// body solver of the robot (a device's own, built once).
pub(crate) fn write_default_calibration<M: Math>(
    solver: &body::Solver<M>,
    pose_config: &PoseConfig,
    table: &mut Table,
) {
    let stance = solver.inverse_at_stance(
        &body::Pose::default(),
        &BodyConfig::about_centre(pose_config.order),
        pose_config.stance_height_m,
        ReachPolicy::Reject,
    );
    // Indexed loops over the legs and joints, read from the solution in place: no copy of
    // the twelve angles, no table of servo ids.
    for (leg, calibrations) in table.chunks_exact_mut(3).enumerate() {
        for (joint, c) in calibrations.iter_mut().enumerate() {
            let zero_rad = match &stance {
                Ok(s) => s.angles_rad[3 * leg + joint],
                Err(_) => 0.0,
            };
            let right = matches!(LegId::from_index(leg), Some(LegId::FR | LegId::RR));
            *c = Calibration {
                zero_rad,
                reversed: right && joint != kin_core::Joint::Abduction as usize,
                us_per_rad: STANDARD_US_PER_RAD,
                center_us: DEFAULT_CENTER_US,
                min_us: DEFAULT_CENTER_US - DEFAULT_TRAVEL_US,
                max_us: DEFAULT_CENTER_US + DEFAULT_TRAVEL_US,
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use kin_core::DefaultMath;

    #[test]
    fn presets_validate() {
        for p in [RobotPreset::Fernando2025, RobotPreset::Shahriar2023] {
            let c = Config::for_preset(p).unwrap();
            assert_eq!(c.validate(), Ok(()));
            assert_eq!(c.preset, p);
        }
        assert!(Config::for_preset(RobotPreset::Custom).is_none());
        let mut c = Config::fernando2025();
        c.robot = Robot::shahriar2023();
        assert_eq!(c.validate(), Err(ConfigError::PresetMismatch));
        c = Config::fernando2025();
        c.pose_config.stance_height_m = f32::NAN;
        assert_eq!(c.validate(), Err(ConfigError::StanceHeight));
    }

    /// Both presets pass the check at compile time (a failing one would fail the build).
    const CHECKED: [ValidConfig; 2] = [
        ValidConfig::checked(Config::fernando2025()),
        ValidConfig::checked(Config::shahriar2023()),
    ];

    #[test]
    fn valid_config_is_the_validated_config_with_its_limiter() {
        for (v, c) in CHECKED
            .iter()
            .zip([Config::fernando2025(), Config::shahriar2023()])
        {
            assert_eq!(*v.config(), c);
            assert_eq!(
                *v.limiter(),
                Limiter::new(c.joint_speed_limit_rad_s).unwrap()
            );
        }
        let mut c = Config::fernando2025();
        c.robot = Robot::shahriar2023();
        assert_eq!(ValidConfig::new(c), Err(ConfigError::PresetMismatch));
        c = Config::fernando2025();
        c.joint_speed_limit_rad_s = 0.0;
        assert_eq!(ValidConfig::new(c), Err(ConfigError::JointSpeedLimit));
    }

    /// The limit at power-on is held to the range `SetJointSpeedLimit` admits: a subnormal one
    /// ("finite and > 0") would move no output ever.
    #[test]
    fn the_boot_joint_speed_limit_is_within_the_wire_range() {
        let mut c = Config::shahriar2023();
        for bad in [1e-45, 0.099, 158.0, f32::INFINITY] {
            c.joint_speed_limit_rad_s = bad;
            assert_eq!(c.validate(), Err(ConfigError::JointSpeedLimit), "{bad}");
        }
        for good in [0.1, 3.0, 100.0] {
            c.joint_speed_limit_rad_s = good;
            assert_eq!(c.validate(), Ok(()), "{good}");
        }
    }

    #[test]
    fn default_calibration_centres_the_stance() {
        for c in [Config::fernando2025(), Config::shahriar2023()] {
            let table = default_calibration::<DefaultMath>(&c.robot, &c.pose_config);
            for cal in &table {
                assert_eq!(cal.validate(), Ok(()));
                assert_eq!(cal.pulse_half_us(cal.zero_rad), Ok(2 * DEFAULT_CENTER_US));
            }
            // The stance knee is bent, so its centre is not at angle 0.
            assert!(table[2].zero_rad < -0.1);
            assert!(table[5].reversed && !table[3].reversed && !table[2].reversed);
        }
    }
}
