//! The host end of the device link: handshake, requests retried under one sequence number, and
//! the body-pose stream with its end-to-end readback check.
//!
//! ## Requests
//! [`Client::exchange`] sends one request and waits for the answer carrying its sequence number,
//! at most [`ClientConfig::retries`] more times with the **same** sequence number when
//! - no answer came within the timeout (request or answer lost, or a stall),
//! - a nack without a sequence number came (the device could not read a frame: bad CRC, bad
//!   COBS, oversize) *after* the request could have reached the device — an earlier one is about
//!   older garbage and is ignored,
//! - the answer failed the caller's check (the readback check below): a frame corrupted on the
//!   line can pass a 16-bit CRC (about 1 in 65,536 damaged frames), and a retry tells a
//!   corrupted request or answer from a real disagreement, which persists.
//!
//! Answers with another sequence number (late or duplicated answers to earlier attempts) are
//! dropped. The device answers an exact repeat of the request it answered last with the same
//! answer, without acting again (docs/protocol.md, link rules), so a resend is always safe.
//!
//! ## A window in flight
//! [`PoseStream::submit`] keeps up to [`MAX_WINDOW`] (two) setpoints in flight, as the device
//! allows (docs/protocol.md, link rules): the next request leaves as soon as the oldest is
//! answered, so the device solves it while the previous answer is on the wire. Each setpoint
//! gets the checks and retries above under its own sequence number; an attempt's timeout runs
//! from its sending or from the answer to the one before it, whichever is later (the device
//! answers in order). A resend after a later setpoint was answered leaves the device holding
//! the older one, so [`PoseStream::flush`] then sends the newest once more.
//!
//! The answer timeout of an attempt ([`AnswerWait`]) is, for the ATmega2560 (a real port or
//! the emulated chip), the firmware's measured answer time of that kind of request at the
//! link's line rate with a margin ([`quad_protocol::timing`]); for the simulated device, the
//! wire time of the request and of the longest answer plus its modelled computation.
//!
//! ## Readback check ([`PoseStream`])
//! For every body pose the host runs kin-core itself (`body::Solver::inverse_at_stance` on `DefaultMath`,
//! the device's robot, stance height, rotation order and reject policy) and maps the angles
//! through the device's calibration (read at connection):
//! - a pose the host solves must be acked, with the twelve angles equal to the host's
//!   ([`AngleCheck::Exact`]: the same bits, when both sides run the same math, as the simulated
//!   device does; [`AngleCheck::Within`]: within a bound, e.g. [`AVR_ANGLE_TOLERANCE_RAD`] for
//!   the ATmega2560's avr-libc math) and the twelve pulses equal to the host's calibration
//!   mapping **of the device's angles** (`quad_protocol::servo`, bit-exact on every IEEE-754
//!   f32 implementation), or 0 while the outputs are off;
//! - a pose the host rejects (unreachable, joint limit, non-finite, beyond a servo's travel)
//!   must be nacked with the same reason, leg and kind.

//!
//! ## Files
//! - `exchange.rs`: [`Client`], one request and its answer under one sequence number, retried;
//!   the session requests built on it (handshake, acknowledged requests, calibration reads).
//! - `stream.rs`: [`PoseStream`], body poses, feet or joints streamed and judged.
//! - `checks.rs`: what the host expects of an answer ([`expected`], [`judge`],
//!   [`check_readback`]) and how angles are compared ([`AngleCheck`]).

mod checks;
mod exchange;
mod stream;

pub use checks::{
    check_readback, expected, judge, AngleCheck, Expected, Mismatch, AVR_ANGLE_TOLERANCE_RAD,
};
pub use exchange::{Client, Counters, Exchange, Outcome, Verdict};
pub use stream::{
    PoseResult, PoseStream, Setpoint, Settled, StreamSetup, StreamStats, DEFAULT_WINDOW, MAX_WINDOW,
};

use crate::link;
use quad_protocol::{DeviceToHost, NackReason, Request, RobotPreset, PROTOCOL_VERSION};
use std::time::Duration;

/// Default number of retries of a streamed request (a body pose).
pub const DEFAULT_RETRIES: u32 = 10;

/// Retries of a session request (handshake, configuration, calibration): these must get
/// through even on a poor line, and repeating them is harmless.
pub const SESSION_RETRIES: u32 = 100;

/// Timing and retry policy of a [`Client`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClientConfig {
    /// Resends of a streamed request after its first attempt ([`Client::exchange`]).
    pub retries: u32,
    /// Resends of a session request ([`Client::request`] and what builds on it).
    pub session_retries: u32,
    /// How long an attempt waits for its answer.
    pub answer_wait: AnswerWait,
    /// How long the handshake keeps trying (a Mega resets when its port opens).
    pub hello_patience: Duration,
}

/// How long an attempt of a request waits for its answer before it is resent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AnswerWait {
    /// The ATmega2560 firmware's answer time of the request's kind at the link's line rate,
    /// measured ([`quad_protocol::timing`], docs/protocol.md "Answer times"), with half again
    /// as margin and `host_latency` for the host's side of the line.
    Measured {
        /// A real port's USB frames and scheduling ([`quad_protocol::timing::HOST_LATENCY`]);
        /// next to nothing for the emulated chip.
        host_latency: Duration,
    },
    /// The wire time of the request and of the longest answer, plus `compute`, plus `save`
    /// for `SaveCalibration`: for the simulated device, whose time is modelled.
    Modelled {
        /// The device's time per request.
        compute: Duration,
        /// The extra time of an EEPROM save.
        save: Duration,
    },
}

impl ClientConfig {
    /// For the simulated UART: the modelled device time plus 1 ms.
    pub fn sim(compute: Duration) -> ClientConfig {
        ClientConfig {
            retries: DEFAULT_RETRIES,
            session_retries: SESSION_RETRIES,
            answer_wait: AnswerWait::Modelled {
                compute: compute + Duration::from_millis(1),
                save: Duration::from_secs(1),
            },
            hello_patience: Duration::from_millis(100),
        }
    }

    /// For the firmware in simavr ([`crate::link::emulator`]), in simulated time: 20 ms of
    /// turnaround (one servo period; a body-pose solve takes about 7 ms), 1 s of handshake
    /// patience.
    pub fn emulator() -> ClientConfig {
        ClientConfig {
            retries: DEFAULT_RETRIES,
            session_retries: SESSION_RETRIES,
            answer_wait: AnswerWait::Measured {
                host_latency: Duration::from_millis(2),
            },
            hello_patience: Duration::from_secs(1),
        }
    }

    /// For a real port: 50 ms of turnaround (USB latency and the device's IK), 4 s of
    /// handshake patience.
    pub fn serial() -> ClientConfig {
        ClientConfig {
            retries: DEFAULT_RETRIES,
            session_retries: SESSION_RETRIES,
            answer_wait: AnswerWait::Measured {
                host_latency: quad_protocol::timing::HOST_LATENCY,
            },
            hello_patience: Duration::from_secs(4),
        }
    }

    /// The configuration that suits `target`, with `retries` resends per streamed request.
    pub fn for_target(target: &link::Target, retries: u32) -> ClientConfig {
        let config = match target {
            link::Target::Sim { config, .. } => ClientConfig::sim(config.compute),
            link::Target::Emulator { .. } => ClientConfig::emulator(),
            link::Target::Serial { .. } => ClientConfig::serial(),
        };
        ClientConfig { retries, ..config }
    }
}

/// Why a session request failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The link failed.
    #[error(transparent)]
    Link(#[from] link::Error),
    /// No answer after every attempt.
    #[error("no answer to {request} after every retry")]
    NoAnswer {
        /// The request's name.
        request: &'static str,
    },
    /// The device refused.
    #[error("the device refused {request}: {reason}")]
    Refused {
        /// The request's name.
        request: &'static str,
        /// Why.
        reason: NackReason,
    },
    /// An answer of the wrong kind.
    #[error("unexpected answer to {request}: {}", answer_name(answer))]
    Unexpected {
        /// The request's name.
        request: &'static str,
        /// The answer.
        answer: Box<DeviceToHost>,
    },
    /// The device speaks another major protocol version.
    #[error(
        "the device speaks protocol {}.{}, this host {}.{}",
        device >> 8,
        device & 0xFF,
        PROTOCOL_VERSION >> 8,
        PROTOCOL_VERSION & 0xFF
    )]
    Version {
        /// The device's version.
        device: u16,
    },
    /// A window of requests in flight the device does not take.
    #[error(
        "{window} requests in flight: the device takes 1 to {}",
        stream::MAX_WINDOW
    )]
    Window {
        /// The window asked for.
        window: usize,
    },
    /// The device runs another robot than the host was asked for.
    #[error(
        "the device runs robot {}, the host was given {}",
        crate::names::robot_preset_name(*device),
        crate::names::robot_preset_name(*host)
    )]
    Robot {
        /// The device's robot.
        device: RobotPreset,
        /// The host's.
        host: RobotPreset,
    },
    /// The device holds another robot than the one the host plans with (their hashes differ,
    /// protocol 2.4).
    #[error(
        "the device holds robot {device_name} (hash {device_hash:08x}), the host plans with \
         {host_name} (hash {host_hash:08x}): send the host's robot to the device with \
         `quadctl robot send FILE --save` (with the same --sim/--emulator/--port), or run \
         without --robot to plan with the device's own"
    )]
    RobotMismatch {
        /// The device's robot's name.
        device_name: String,
        /// Its hash.
        device_hash: u32,
        /// The host's robot's name.
        host_name: String,
        /// Its hash.
        host_hash: u32,
    },
    /// The device speaks a protocol older than 2.4: it cannot tell or take its robot.
    #[error(
        "the device speaks protocol {}.{}: it holds a preset robot only (sending or reading \
         the robot needs 2.4)",
        device >> 8,
        device & 0xFF
    )]
    NoRobotRequests {
        /// The device's version.
        device: u16,
    },
}

/// Short name of an answer, for messages.
pub fn answer_name(a: &DeviceToHost) -> &'static str {
    match a {
        DeviceToHost::Nack { .. } => "Nack",
        DeviceToHost::HelloAck { .. } => "HelloAck",
        DeviceToHost::Ack { .. } => "Ack",
        DeviceToHost::Calibration { .. } => "Calibration",
        DeviceToHost::Configured { .. } => "Configured",
        DeviceToHost::MotionAck { .. } => "MotionAck",
        DeviceToHost::Imu { .. } => "Imu",
        DeviceToHost::Robot { .. } => "Robot",
    }
}

/// Short name of a request, for messages.
pub fn request_name(r: &Request) -> &'static str {
    match r {
        Request::Hello { .. } => "Hello",
        Request::GetState => "GetState",
        Request::SetBodyPose(_) => "SetBodyPose",
        Request::SetFeet { .. } => "SetFeet",
        Request::SetJoints { .. } => "SetJoints",
        Request::SetOutputs { .. } => "SetOutputs",
        Request::SetLinkTimeout(_) => "SetLinkTimeout",
        Request::SetCalibration { .. } => "SetCalibration",
        Request::GetCalibration { .. } => "GetCalibration",
        Request::SaveCalibration => "SaveCalibration",
        Request::SetPoseConfig(_) => "SetPoseConfig",
        Request::StartMotion(_) => "StartMotion",
        Request::StopMotion => "StopMotion",
        Request::GetMotion => "GetMotion",
        Request::SetVelocity { .. } => "SetVelocity",
        Request::SetJointSpeedLimit { .. } => "SetJointSpeedLimit",
        Request::SetBalance(_) => "SetBalance",
        Request::GetImu => "GetImu",
        Request::SetRobot(_) => "SetRobot",
        Request::GetRobot => "GetRobot",
        Request::SaveRobot => "SaveRobot",
    }
}
