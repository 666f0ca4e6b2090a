//! The robot a device holds (since 2.4): [`RobotDescription`], what [`crate::Request::SetRobot`]
//! sends and [`crate::DeviceToHost::Robot`] answers, its hash ([`RobotDescription::hash`], the
//! one definition host and device compare) and the field a refusal names ([`RobotField`]).
//!
//! ## Wire form
//! The fields in declaration order: the name as 16 bytes (printable ASCII, zero-padded; no
//! length byte), the kin-core [`Robot`] as `d_lat_m`, `d_ax_m`, `femur_m`, `tibia_m`,
//! `body_length_m`, `body_width_m` (six f32), `min_rad`, `max_rad` (three f32 each, abduction,
//! hip, knee) and the knee bend (one varint: 0 backward, 1 forward), then the stance height
//! (f32), the rotation order (one varint, [`crate::wire::rotation_order`]) and the default
//! joint-speed limit (f32): [`RobotDescription::WIRE_LEN`] = 74 bytes, always.
//!
//! The admissible values are checked by [`crate::range::check_robot`], on the host before
//! sending and on the device before anything changes.

use crate::wire::{self, wire_enum};
use core::fmt;
use kin_core::{Joint, LegId, Robot, RotationOrder};
use serde::{Deserialize, Serialize};

/// Bytes of a robot's name ([`RobotDescription::name`]).
pub const NAME_LEN: usize = 16;

/// A robot as a device holds it: the geometry the IK runs on and the defaults that go with it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RobotDescription {
    /// A short name: printable ASCII (0x20‥0x7E), at least one byte, zero-padded to
    /// [`NAME_LEN`] bytes ([`RobotDescription::name_str`]).
    #[serde(with = "wire::array")]
    pub name: [u8; NAME_LEN],
    /// Leg geometry, body size, joint limits and knee bend.
    #[serde(with = "wire::robot")]
    pub robot: Robot,
    /// The stance height `H` the device stands at and solves body poses about, m (the
    /// [`crate::PoseConfig::stance_height_m`] it takes when it adopts the robot).
    pub stance_height_m: f32,
    /// The rotation order of body poses it takes when it adopts the robot.
    #[serde(with = "wire::rotation_order")]
    pub order: RotationOrder,
    /// The joint-speed limit of every output when it adopts the robot, rad/s.
    pub joint_speed_limit_rad_s: f32,
}

/// Why a robot's name was refused ([`RobotDescription::with_name`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum NameError {
    /// Empty.
    Empty,
    /// Longer than [`NAME_LEN`] bytes.
    TooLong,
    /// A character outside printable ASCII.
    NotPrintable,
}

impl fmt::Display for NameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            NameError::Empty => "a robot's name must not be empty",
            NameError::TooLong => "a robot's name has at most 16 bytes",
            NameError::NotPrintable => "a robot's name is printable ASCII",
        })
    }
}

impl core::error::Error for NameError {}

impl RobotDescription {
    /// Bytes of a description on the wire (see the module docs).
    pub const WIRE_LEN: usize = NAME_LEN + 12 * 4 + 1 + 4 + 1 + 4;

    /// The name field of `name`.
    ///
    /// # Errors
    /// [`NameError`] for an empty name, one longer than [`NAME_LEN`] bytes or one with a
    /// character outside printable ASCII.
    pub fn name_bytes(name: &str) -> Result<[u8; NAME_LEN], NameError> {
        if name.is_empty() {
            return Err(NameError::Empty);
        }
        if name.len() > NAME_LEN {
            return Err(NameError::TooLong);
        }
        if !name.bytes().all(|b| (0x20..=0x7E).contains(&b)) {
            return Err(NameError::NotPrintable);
        }
        let mut out = [0u8; NAME_LEN];
        out[..name.len()].copy_from_slice(name.as_bytes());
        Ok(out)
    }

    /// This description with the name `name`.
    ///
    /// # Errors
    /// As [`RobotDescription::name_bytes`].
    pub fn with_name(mut self, name: &str) -> Result<RobotDescription, NameError> {
        self.name = Self::name_bytes(name)?;
        Ok(self)
    }

    /// The length of the name without its padding; `None` when it is not a valid name (see
    /// [`RobotDescription::name`]). Bytes only: no UTF-8 decoding (whose 256-byte table
    /// would be copied into the ATmega2560's SRAM).
    pub fn name_len(&self) -> Option<usize> {
        let len = self.name.iter().position(|&b| b == 0).unwrap_or(NAME_LEN);
        let (text, pad) = self.name.split_at(len);
        let printable = text.iter().all(|b| (0x20..=0x7E).contains(b));
        (len > 0 && printable && pad.iter().all(|&b| b == 0)).then_some(len)
    }

    /// The name without its padding; `None` when it is not a valid name (see
    /// [`RobotDescription::name`]).
    pub fn name_str(&self) -> Option<&str> {
        let len = self.name_len()?;
        core::str::from_utf8(&self.name[..len]).ok()
    }

    /// The wire bytes (module docs): always [`RobotDescription::WIRE_LEN`] of them (every
    /// field has a fixed size; both enums' indices are one-byte varints).
    pub fn to_wire(&self) -> [u8; Self::WIRE_LEN] {
        let mut out = [0u8; Self::WIRE_LEN];
        // Cannot fail: the bytes fit exactly.
        let _ = postcard::to_slice(self, &mut out);
        out
    }

    /// The description of `bytes` (its wire form); `None` when they are not one (an unknown
    /// knee bend or rotation order index).
    pub fn from_wire(bytes: &[u8; Self::WIRE_LEN]) -> Option<RobotDescription> {
        postcard::from_bytes(bytes).ok()
    }

    /// The robot's hash: the CRC-32 ([`crc32`]) of its wire bytes (module docs). The one
    /// definition: a device reports it in [`crate::DeviceInfo::robot_hash`], a host compares it
    /// with the hash of the robot it plans with.
    pub fn hash(&self) -> u32 {
        let mut flavor = Crc32Flavor(CRC32_INIT);
        // Serializing into a CRC cannot fail: no buffer to fill, every value has a wire form.
        let _ = postcard::serialize_with_flavor(self, &mut flavor);
        crc32_finish(flavor.0)
    }
}

/// The CRC-32 register before the first byte.
const CRC32_INIT: u32 = 0xFFFF_FFFF;

/// Feeds one byte into a CRC-32 register (ISO-HDLC: reflected, polynomial `0x04C11DB7`,
/// reversed `0xEDB88320`); bitwise, no table (as [`crate::crc`]).
const fn crc32_update(mut crc: u32, byte: u8) -> u32 {
    crc ^= byte as u32;
    let mut i = 0;
    while i < 8 {
        let mask = (crc & 1).wrapping_neg();
        crc = (crc >> 1) ^ (0xEDB8_8320 & mask);
        i += 1;
    }
    crc
}

const fn crc32_finish(crc: u32) -> u32 {
    crc ^ 0xFFFF_FFFF
}

/// CRC-32/ISO-HDLC (the CRC of zip and Ethernet; check value over `"123456789"`:
/// `0xCBF43926`) of `bytes`.
pub const fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = CRC32_INIT;
    let mut i = 0;
    while i < bytes.len() {
        crc = crc32_update(crc, bytes[i]);
        i += 1;
    }
    crc32_finish(crc)
}

/// A postcard flavor that feeds the bytes into a CRC-32 register instead of storing them.
struct Crc32Flavor(u32);

impl postcard::ser_flavors::Flavor for &mut Crc32Flavor {
    type Output = ();

    fn try_push(&mut self, data: u8) -> postcard::Result<()> {
        self.0 = crc32_update(self.0, data);
        Ok(())
    }

    fn finalize(self) -> postcard::Result<()> {
        Ok(())
    }
}

wire_enum! {
    /// A field of a [`RobotDescription`], as named by [`crate::NackReason::BadRobot`] (since 2.4).
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum RobotField {
        /// The name: empty, not printable ASCII or not zero-padded.
        0 => Name,
        /// `femur_m`.
        1 => FemurM,
        /// `tibia_m`.
        2 => TibiaM,
        /// `d_lat_m`.
        3 => DLatM,
        /// `d_ax_m`.
        4 => DAxM,
        /// `body_length_m`.
        5 => BodyLengthM,
        /// `body_width_m`.
        6 => BodyWidthM,
        /// The limits of one joint: not finite, outside `[−π, π]` or min > max.
        7 => Limit(Joint as wire::joint),
        /// `stance_height_m` outside its range.
        8 => StanceHeightM,
        /// `joint_speed_limit_rad_s` outside its range.
        9 => JointSpeedLimitRadS,
        /// The rest pose (`Robot::rest_leg`) leaves this joint's limits.
        10 => RestPose(Joint as wire::joint),
        /// This leg cannot reach its stance foot at the zero body pose (too far, too close,
        /// or beyond a joint limit).
        11 => Stance(LegId as wire::leg_id),
    }
}

impl fmt::Display for RobotField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RobotField::Name => f.write_str("name"),
            RobotField::FemurM => f.write_str("femur_m"),
            RobotField::TibiaM => f.write_str("tibia_m"),
            RobotField::DLatM => f.write_str("d_lat_m"),
            RobotField::DAxM => f.write_str("d_ax_m"),
            RobotField::BodyLengthM => f.write_str("body_length_m"),
            RobotField::BodyWidthM => f.write_str("body_width_m"),
            RobotField::Limit(j) => write!(f, "limits.{j}_rad"),
            RobotField::StanceHeightM => f.write_str("stance_height_m"),
            RobotField::JointSpeedLimitRadS => f.write_str("joint_speed_limit_rad_s"),
            RobotField::RestPose(j) => write!(f, "rest pose ({j} outside its limits)"),
            RobotField::Stance(leg) => write!(f, "stance ({leg} cannot reach it)"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn the_wire_form_has_a_fixed_length_and_round_trips() {
        let d = RobotDescription {
            name: RobotDescription::name_bytes("x").unwrap(),
            robot: Robot::fernando2025().with_knee_bend(kin_core::KneeBend::Forward),
            stance_height_m: 0.9,
            order: RotationOrder::Zxy,
            joint_speed_limit_rad_s: 2.0,
        };
        let mut buf = [0u8; 128];
        let len = postcard::to_slice(&d, &mut buf).unwrap().len();
        assert_eq!(len, RobotDescription::WIRE_LEN);
        assert_eq!(RobotDescription::from_wire(&d.to_wire()), Some(d));
        assert_eq!(d.hash(), crc32(&d.to_wire()));
        let mut bad = d.to_wire();
        bad[RobotDescription::WIRE_LEN - 5] = 9; // rotation order 9
        assert_eq!(RobotDescription::from_wire(&bad), None);
    }

    #[test]
    fn names() {
        let n = RobotDescription::name_bytes("bench-dog").unwrap();
        assert_eq!(&n[..9], b"bench-dog");
        assert!(n[9..].iter().all(|&b| b == 0));
        assert_eq!(RobotDescription::name_bytes(""), Err(NameError::Empty));
        assert_eq!(
            RobotDescription::name_bytes("seventeen-bytes!!"),
            Err(NameError::TooLong)
        );
        assert_eq!(
            RobotDescription::name_bytes("dog\n"),
            Err(NameError::NotPrintable)
        );
    }
}
