//! # quad-protocol — the host ↔ ATmega2560 wire protocol, `no_std`, no allocation
//!
//! One crate shared by the firmware and the host tools, so both sides build and read the same
//! bytes and map angles to servo pulses with the same code:
//!
//! - [`msg`]: the messages, named by direction — [`HostToDevice`] (a sequence number and a
//!   [`Request`]) and [`DeviceToHost`] (an answer echoing that sequence number: `HelloAck`,
//!   `Ack` with the [`Readback`], `Calibration`, or `Nack` with a typed [`NackReason`]).
//! - [`frame`]: `COBS(postcard(message) ‖ CRC-16) ‖ 0x00` — [`encode_frame`] and the
//!   bounded [`Accumulator`] for split, concatenated, oversize and garbled input.
//! - [`crc`]: CRC-16/GENIBUS (CCITT-FALSE with a final XOR), a byte at a time, no table.
//! - [`range`]: the admissible range of every request field, one check for host and device.
//! - [`servo`]: per-joint [`servo::Calibration`] and the angle ↔ pulse mapping.
//! - [`balance`]: the inertial sensor's report and the balance functions' settings (2.3).
//! - [`robot`]: the robot a device holds, its hash and the fields a refusal names (2.4).
//! - [`wire`]: the explicit wire index of every enum variant, and the tables of the kin-core
//!   types the messages carry.
//!
//! The byte-level specification with an example frame per message is `docs/protocol.md`.
//!
//! ## Versions
//! [`PROTOCOL_VERSION`] is `major << 8 | minor`. The host opens with [`Request::Hello`]; a
//! device whose major differs answers [`NackReason::UnknownVersion`] carrying its own version.
//! Within one major, a minor only appends enum variants, flag bits and nothing else, and a
//! peer sends nothing newer than the lower of the two minors.
//!
//! ## Sizes
//! Every decoded frame (postcard bytes + CRC) of this version fits in [`MAX_DECODED_LEN`]
//! (128 bytes); on the wire that is at most [`MAX_FRAME_LEN`] (131 bytes). f32 only; no f64.

#![no_std]
#![forbid(unsafe_code)]

pub mod balance;
pub mod crc;
pub mod frame;
pub mod msg;
pub mod range;
pub mod robot;
pub mod schema;
pub mod servo;
pub mod timing;
pub mod wire;

pub use balance::{
    BalanceConfig, FallKind, FaultAction, ImuFaultKind, ImuHealth, ImuReport, SafeState,
};
pub use frame::{
    decode_payload, encode_frame, encode_frame_in_pieces, Accumulator, Feed, DELIMITER,
    MAX_DECODED_LEN, MAX_FRAME_LEN,
};
pub use msg::{
    DeviceInfo, DeviceToHost, Field, FirmwareVersion, Flags, HostToDevice, LegSet, LinkLossAction,
    LinkTimeout, MotionCommand, MotionFrames, MotionKind, MotionParam, MotionStage, MotionStatus,
    NackReason, ParamProblem, PoseConfig, PreflightFault, ReachFault, Readback, Request,
    RobotPreset, ServoId, Setting, DEFAULT_VELOCITY_TIMEOUT_MS,
};
pub use range::{check_request, check_request_in, check_robot, Ranges};
pub use robot::{RobotDescription, RobotField};

/// This crate's protocol version: `major << 8 | minor` (2.1: the onboard motions; 2.2: the idle
/// motion stage and the watchdog-reset flag; 2.3: the inertial sensor and the balance
/// functions, [`balance`], the motion's frame numbers, [`MotionFrames`], and the statically
/// stable yaw turn; 2.4: the robot sent, read and stored on the device, [`robot`], and its
/// hash in the hello).
pub const PROTOCOL_VERSION: u16 = 0x0204;

/// Major part of a protocol version.
#[inline]
pub const fn version_major(version: u16) -> u8 {
    (version >> 8) as u8
}

/// Minor part of a protocol version.
#[inline]
pub const fn version_minor(version: u16) -> u8 {
    (version & 0xFF) as u8
}

/// True when a peer announcing `peer_version` can talk to this crate (same major).
#[inline]
pub const fn is_compatible(peer_version: u16) -> bool {
    version_major(peer_version) == version_major(PROTOCOL_VERSION)
}

/// The minor version both peers use after the handshake: the lower of the two (meaningful only
/// when the majors agree).
#[inline]
pub const fn negotiated_minor(a: u16, b: u16) -> u8 {
    let (x, y) = (version_minor(a), version_minor(b));
    if x < y {
        x
    } else {
        y
    }
}

/// Largest decoded frame of a setpoint request (postcard bytes + CRC), bytes: seq (≤ 3) +
/// variant (1) + `SetFeet`/`SetJoints` (48) + CRC (2) — the largest [`HostToDevice`] frame up
/// to 2.3; since 2.4 a [`Request::SetRobot`] frame is larger, [`SET_ROBOT_MAX_LEN`].
pub const HOST_TO_DEVICE_MAX_LEN: usize = 3 + 1 + 48 + frame::CRC_LEN;

/// Largest decoded [`Request::SetRobot`] frame (postcard bytes + CRC), bytes, the largest
/// [`HostToDevice`] frame of 2.4: seq (≤ 3) + variant (1) + the description
/// ([`RobotDescription::WIRE_LEN`], 74) + CRC (2).
pub const SET_ROBOT_MAX_LEN: usize = 3 + 1 + RobotDescription::WIRE_LEN + frame::CRC_LEN;

/// Largest [`Readback`] in postcard bytes: angles (48) + pulses (12 × ≤ 3) + flags (1) + two
/// counters (2 × ≤ 5).
pub const READBACK_MAX_LEN: usize = 48 + 12 * 3 + 1 + 2 * 5;

/// Largest [`DeviceToHost::Configured`] frame (postcard bytes + CRC), bytes: echoing a
/// calibration — variant (1) + seq (≤ 3) + setting (variant 1 + servo 2 + calibration ≤ 18) +
/// [`READBACK_MAX_LEN`] + CRC (2).
const CONFIGURED_MAX_LEN: usize = 1 + 3 + (1 + 2 + 18) + READBACK_MAX_LEN + frame::CRC_LEN;

/// Largest [`DeviceToHost::MotionAck`] frame (postcard bytes + CRC), bytes: variant (1) + seq
/// (≤ 3) + [`MotionStatus`] (kind ≤ 2, stage 1, time and phase 2 × 4, fault ≤ 1 + 4) +
/// [`READBACK_MAX_LEN`] + [`MotionFrames`] (since 2.3: two frame numbers below 2^14, ≤ 2 each,
/// one of them an option, + 1) + CRC (2).
const MOTION_ACK_MAX_LEN: usize =
    1 + 3 + (2 + 1 + 2 * 4 + 5) + READBACK_MAX_LEN + (2 + 1 + 2) + frame::CRC_LEN;

/// Largest decoded [`DeviceToHost`] frame of this version (postcard bytes + CRC), bytes: the
/// larger of a [`DeviceToHost::Configured`] echoing a calibration and a
/// [`DeviceToHost::MotionAck`].
pub const DEVICE_TO_HOST_MAX_LEN: usize = if CONFIGURED_MAX_LEN > MOTION_ACK_MAX_LEN {
    CONFIGURED_MAX_LEN
} else {
    MOTION_ACK_MAX_LEN
};

const _: () = assert!(HOST_TO_DEVICE_MAX_LEN <= MAX_DECODED_LEN);
const _: () = assert!(DEVICE_TO_HOST_MAX_LEN <= MAX_DECODED_LEN);
// The `Imu` answer (variant, seq, report, CRC) is shorter than the largest answer.
const _: () =
    assert!(1 + 3 + balance::IMU_REPORT_MAX_LEN + frame::CRC_LEN <= DEVICE_TO_HOST_MAX_LEN);
const _: () = assert!(SET_ROBOT_MAX_LEN <= MAX_DECODED_LEN);
// The robot answer (variant, seq, description, CRC) is shorter than the largest answer.
const _: () =
    assert!(1 + 3 + robot::RobotDescription::WIRE_LEN + frame::CRC_LEN <= DEVICE_TO_HOST_MAX_LEN);
// The frame numbers of 2.3 keep the motion ack within 2.2's largest answer.
const _: () = assert!(MOTION_ACK_MAX_LEN <= CONFIGURED_MAX_LEN);
