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
//! dropped. The device acts on every copy of a request it reads; a body pose is idempotent, so
//! a duplicate only costs line time, and the latest pose wins.
//!
//! The answer timeout of an attempt is the wire time of the request and of the longest answer at
//! the link's baud rate plus [`ClientConfig::turnaround`] (device computation and, on a real
//! port, USB latency).
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

use crate::link::{self, byte_time, Link};
use kin_core::body::{self, Pose};
use kin_core::{BodyConfig, ReachPolicy, Robot, RotationOrder, Vec3};
use quad_protocol::servo::Calibration;
use quad_protocol::{
    encode_frame, frame, Accumulator, DeviceInfo, DeviceToHost, Feed, Flags, HostToDevice,
    NackReason, PoseConfig, Readback, Request, RobotPreset, ServoId, DEVICE_TO_HOST_MAX_LEN,
    MAX_DECODED_LEN, MAX_FRAME_LEN, PROTOCOL_VERSION,
};
use serde::Serialize;
use std::time::Duration;

/// Bound on |device angle − host angle| for the ATmega2560 firmware, whose math backend
/// (`avr_libc_math::AvrFast`: avr-libc `sqrt`, kin-core's fixed-point `atan2` and `sin_cos`
/// kernels) differs from the host's, rad: the backend's documented worst case (about 4e-6 rad
/// per angle) with margin. Measured in the emulator tests (`tests/tests/avr_firmware.rs`,
/// `angle_tolerance_bounds_the_firmware_against_the_host`): 4.8e-6 rad over 100 seeded poses.
/// 2e-5 rad is 0.001°, far below a servo's resolution (about 0.1° per 0.5 µs tick).
pub const AVR_ANGLE_TOLERANCE_RAD: f32 = 2e-5;

/// Default number of retries of a streamed request (a body pose).
pub const DEFAULT_RETRIES: u32 = 10;

/// Retries of a session request (handshake, configuration, calibration): these must get
/// through even on a poor line, and repeating them is harmless.
pub const SESSION_RETRIES: u32 = 100;

/// How the device's angles are compared with the host's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AngleCheck {
    /// The same bits (both sides run the same kin-core math backend).
    Exact,
    /// |device − host| ≤ the bound, rad.
    Within(f32),
}

/// Timing and retry policy of a [`Client`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClientConfig {
    /// Resends of a streamed request after its first attempt ([`Client::exchange`]).
    pub retries: u32,
    /// Resends of a session request ([`Client::request`] and what builds on it).
    pub session_retries: u32,
    /// Added to the wire time of request + answer to make an attempt's timeout.
    pub turnaround: Duration,
    /// Extra time allowed for `SaveCalibration` (an EEPROM write of ~200 bytes at 3.4 ms each).
    pub save_time: Duration,
    /// How long the handshake keeps trying (a Mega resets when its port opens).
    pub hello_patience: Duration,
}

impl ClientConfig {
    /// For the simulated UART: the modelled device time plus 1 ms.
    pub fn sim(compute: Duration) -> ClientConfig {
        ClientConfig {
            retries: DEFAULT_RETRIES,
            session_retries: SESSION_RETRIES,
            turnaround: compute + Duration::from_millis(1),
            save_time: Duration::from_secs(1),
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
            turnaround: Duration::from_millis(20),
            save_time: Duration::from_secs(1),
            hello_patience: Duration::from_secs(1),
        }
    }

    /// For a real port: 50 ms of turnaround (USB latency and the device's IK), 4 s of
    /// handshake patience.
    pub fn serial() -> ClientConfig {
        ClientConfig {
            retries: DEFAULT_RETRIES,
            session_retries: SESSION_RETRIES,
            turnaround: Duration::from_millis(50),
            save_time: Duration::from_secs(1),
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

impl AngleCheck {
    /// The check that suits `target`: the same bits for the simulated controller (the host's
    /// math), [`AVR_ANGLE_TOLERANCE_RAD`] for the ATmega2560's.
    pub fn for_target(target: &link::Target) -> AngleCheck {
        if target.runs_host_math() {
            AngleCheck::Exact
        } else {
            AngleCheck::Within(AVR_ANGLE_TOLERANCE_RAD)
        }
    }
}

/// What the client saw on the link.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Counters {
    /// Request frames sent (first attempts and retries).
    pub frames_sent: u64,
    /// Resends.
    pub retries: u64,
    /// Attempts that timed out.
    pub timeouts: u64,
    /// Attempts ended early by a nack without a sequence number or an unreadable frame.
    pub link_nacks: u64,
    /// Answers the caller's check refused.
    pub rejected: u64,
    /// Answers to other sequence numbers (late or duplicated), dropped.
    pub stale: u64,
    /// Received frames that did not decode (bad CRC, COBS, oversize).
    pub bad_frames: u64,
}

/// The caller's judgement of an answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Take it.
    Accept,
    /// Not believable: retry.
    Reject,
}

/// How an exchange ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outcome {
    /// An answer the check accepted.
    Accepted(DeviceToHost),
    /// Answers came, but the check refused the last one after every attempt.
    Rejected(DeviceToHost),
    /// No answer after every attempt.
    Lost,
}

/// One request and what came of it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Exchange {
    /// The result.
    pub outcome: Outcome,
    /// Attempts made (1 + retries).
    pub attempts: u32,
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
}

/// The host's mapping of a pulse, for messages.
fn host_pulse(half_us: &Option<u16>) -> String {
    match half_us {
        Some(p) => format!("{p} half-µs"),
        None => "beyond the servo's travel".to_owned(),
    }
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
    }
}

/// Why a pose's answer disagreed with the host (see [`PoseStream::send`]).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Mismatch {
    /// A readback angle differs from the host's beyond the [`AngleCheck`].
    #[error("{servo}: device angle {device_rad} rad, host {host_rad} rad")]
    Angle {
        /// The joint.
        servo: ServoId,
        /// The device's angle, rad.
        device_rad: f32,
        /// The host's, rad.
        host_rad: f32,
    },
    /// A readback pulse differs from the calibration's mapping of the device's angle.
    #[error(
        "{servo}: device pulse {device_half_us} half-µs, host mapping {}",
        host_pulse(host_half_us)
    )]
    Pulse {
        /// The joint.
        servo: ServoId,
        /// The device's pulse, half-µs.
        device_half_us: u16,
        /// The host's mapping, half-µs (`None`: beyond the servo's travel).
        host_half_us: Option<u16>,
    },
    /// The device acked a pose the host rejects.
    #[error("device acked, host rejects: {0}")]
    AckedHostRejects(NackReason),
    /// The device nacked a pose the host solves.
    #[error("device nacked ({0}), host solves")]
    NackedHostSolves(NackReason),
    /// Both nacked, for different reasons.
    #[error("device nacked ({device}), host rejects with {host}")]
    Reasons {
        /// The device's reason.
        device: NackReason,
        /// The host's.
        host: NackReason,
    },
    /// An answer of another kind than an ack or a nack.
    #[error("unexpected answer {}", answer_name(.0))]
    Unexpected(DeviceToHost),
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
    }
}

enum Wait {
    Answer(DeviceToHost),
    LinkNack,
    Timeout,
}

/// Requests over a [`Link`] (see the module docs).
pub struct Client<L> {
    link: L,
    config: ClientConfig,
    seq: u16,
    acc: Accumulator<MAX_DECODED_LEN>,
    /// Received bytes not yet fed to the accumulator.
    pending: Vec<u8>,
    counters: Counters,
}

impl<L: Link> Client<L> {
    /// A client on `link`.
    pub fn new(link: L, config: ClientConfig) -> Client<L> {
        Client {
            link,
            config,
            seq: 0,
            acc: Accumulator::new(),
            pending: Vec::new(),
            counters: Counters::default(),
        }
    }

    /// The link.
    pub fn link(&self) -> &L {
        &self.link
    }

    /// The link, mutable (e.g. to let time pass or reset a simulated device).
    pub fn link_mut(&mut self) -> &mut L {
        &mut self.link
    }

    /// What the client saw so far.
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// The configuration.
    pub fn config(&self) -> &ClientConfig {
        &self.config
    }

    /// Timeout of one attempt of a request whose frame has `wire_len` bytes.
    pub fn attempt_timeout(&self, wire_len: usize, request: &Request) -> Duration {
        let answer_len = frame::encoded_len_max(DEVICE_TO_HOST_MAX_LEN);
        let mut t =
            byte_time(self.link.baud()) * (wire_len + answer_len) as u32 + self.config.turnaround;
        if matches!(request, Request::SaveCalibration) {
            t += self.config.save_time;
        }
        t
    }

    /// Sends `request` and waits for its answer, retrying under the same sequence number (see
    /// the module docs); `check` judges each answer.
    ///
    /// # Errors
    /// Only link failures; a lost request is [`Outcome::Lost`].
    pub fn exchange(
        &mut self,
        request: Request,
        check: impl FnMut(&DeviceToHost) -> Verdict,
    ) -> Result<Exchange, link::Error> {
        self.exchange_with(request, self.config.retries, check)
    }

    /// [`Client::exchange`] with `retries` resends at most.
    ///
    /// # Errors
    /// Only link failures; a lost request is [`Outcome::Lost`].
    pub fn exchange_with(
        &mut self,
        request: Request,
        retries: u32,
        mut check: impl FnMut(&DeviceToHost) -> Verdict,
    ) -> Result<Exchange, link::Error> {
        self.seq = self.seq.wrapping_add(1);
        let seq = self.seq;
        let mut buf = [0u8; MAX_FRAME_LEN];
        let wire_len = encode_frame(&HostToDevice { seq, request }, &mut buf)
            .map(<[u8]>::len)
            .unwrap_or(0);
        let frame = &buf[..wire_len];
        let timeout = self.attempt_timeout(wire_len, &request);
        let on_wire = byte_time(self.link.baud()) * wire_len as u32;
        let mut rejected = None;
        let mut attempts = 0;
        while attempts <= retries {
            if attempts > 0 {
                self.counters.retries += 1;
            }
            attempts += 1;
            let sent_at = self.link.now();
            self.link.send(frame)?;
            self.counters.frames_sent += 1;
            match self.wait(seq, sent_at + timeout, sent_at + on_wire)? {
                Wait::Answer(answer) => match check(&answer) {
                    Verdict::Accept => {
                        return Ok(Exchange {
                            outcome: Outcome::Accepted(answer),
                            attempts,
                        })
                    }
                    Verdict::Reject => {
                        self.counters.rejected += 1;
                        rejected = Some(answer);
                    }
                },
                Wait::LinkNack => self.counters.link_nacks += 1,
                Wait::Timeout => self.counters.timeouts += 1,
            }
        }
        Ok(Exchange {
            outcome: rejected.map_or(Outcome::Lost, Outcome::Rejected),
            attempts,
        })
    }

    /// Waits for the answer to `seq` until `deadline`; a nack without a sequence number counts
    /// only from `nack_from` on.
    fn wait(
        &mut self,
        seq: u16,
        deadline: Duration,
        nack_from: Duration,
    ) -> Result<Wait, link::Error> {
        let mut buf = [0u8; 256];
        loop {
            let input = std::mem::take(&mut self.pending);
            let mut rest: &[u8] = &input;
            loop {
                match self.acc.feed::<DeviceToHost>(rest) {
                    Feed::NeedMore => break,
                    Feed::Frame { msg, remaining } => {
                        rest = remaining;
                        if msg.seq() == Some(seq) {
                            self.pending = rest.to_vec();
                            return Ok(Wait::Answer(msg));
                        }
                        if msg.seq().is_none() && self.link.now() >= nack_from {
                            self.pending = rest.to_vec();
                            return Ok(Wait::LinkNack);
                        }
                        self.counters.stale += 1;
                    }
                    other => {
                        self.counters.bad_frames += 1;
                        rest = other.remaining();
                        // Most likely the answer, damaged on the line: retry now rather than
                        // at the timeout.
                        if self.link.now() >= nack_from {
                            self.pending = rest.to_vec();
                            return Ok(Wait::LinkNack);
                        }
                    }
                }
            }
            let now = self.link.now();
            if now >= deadline {
                return Ok(Wait::Timeout);
            }
            let n = self.link.recv(&mut buf, deadline - now)?;
            self.pending.extend_from_slice(&buf[..n]);
        }
    }

    /// Lets the link's time run until `deadline` (virtual time on a simulated or emulated link,
    /// wall time on a port), keeping what arrives meanwhile for the next exchange (which drops
    /// it as stale unless it answers that exchange).
    ///
    /// # Errors
    /// Link failures.
    pub fn idle_until(&mut self, deadline: Duration) -> Result<(), link::Error> {
        let mut buf = [0u8; 256];
        loop {
            let now = self.link.now();
            if now >= deadline {
                return Ok(());
            }
            let n = self.link.recv(&mut buf, deadline - now)?;
            self.pending.extend_from_slice(&buf[..n]);
        }
    }

    /// [`Client::exchange`] with [`ClientConfig::session_retries`], accepting any answer; a nack
    /// of the request is an error.
    ///
    /// # Errors
    /// [`Error::NoAnswer`], [`Error::Refused`], or the link's error.
    pub fn request(&mut self, request: Request) -> Result<DeviceToHost, Error> {
        let name = request_name(&request);
        let retries = self.config.session_retries;
        match self
            .exchange_with(request, retries, |_| Verdict::Accept)?
            .outcome
        {
            Outcome::Accepted(DeviceToHost::Nack { reason, .. }) => Err(Error::Refused {
                request: name,
                reason,
            }),
            Outcome::Accepted(answer) | Outcome::Rejected(answer) => Ok(answer),
            Outcome::Lost => Err(Error::NoAnswer { request: name }),
        }
    }

    /// A request answered by an `Ack`, or a configuration request answered by a `Configured`
    /// that echoes exactly the setting sent; returns its readback.
    ///
    /// # Errors
    /// As [`Client::request`], or [`Error::Unexpected`] (an echo that differs included).
    pub fn ack(&mut self, request: Request) -> Result<Readback, Error> {
        let name = request_name(&request);
        let sent = quad_protocol::Setting::of_request(&request);
        match self.request(request)? {
            DeviceToHost::Ack { readback, .. } => Ok(readback),
            DeviceToHost::Configured {
                setting, readback, ..
            } if Some(setting) == sent => Ok(readback),
            other => Err(Error::Unexpected {
                request: name,
                answer: Box::new(other),
            }),
        }
    }

    /// The handshake, repeated for up to [`ClientConfig::hello_patience`].
    ///
    /// # Errors
    /// [`Error::Version`] for another major version, [`Error::NoAnswer`] when
    /// nothing answered in time, or the link's error.
    pub fn hello(&mut self) -> Result<DeviceInfo, Error> {
        let until = self.link.now() + self.config.hello_patience;
        loop {
            let request = Request::Hello {
                version: PROTOCOL_VERSION,
            };
            let retries = self.config.session_retries;
            match self
                .exchange_with(request, retries, |_| Verdict::Accept)?
                .outcome
            {
                Outcome::Accepted(DeviceToHost::HelloAck { info, .. }) => return Ok(info),
                Outcome::Accepted(DeviceToHost::Nack {
                    reason: NackReason::UnknownVersion { supported },
                    ..
                }) => return Err(Error::Version { device: supported }),
                Outcome::Accepted(other) => {
                    return Err(Error::Unexpected {
                        request: "Hello",
                        answer: Box::new(other),
                    })
                }
                Outcome::Rejected(_) | Outcome::Lost if self.link.now() < until => {}
                Outcome::Rejected(_) | Outcome::Lost => {
                    return Err(Error::NoAnswer { request: "Hello" })
                }
            }
        }
    }

    /// One servo's calibration.
    ///
    /// # Errors
    /// As [`Client::request`], or [`Error::Unexpected`].
    pub fn calibration(&mut self, servo: ServoId) -> Result<Calibration, Error> {
        match self.request(Request::GetCalibration { servo })? {
            DeviceToHost::Calibration {
                servo: s,
                calibration,
                ..
            } if s == servo => Ok(calibration),
            other => Err(Error::Unexpected {
                request: "GetCalibration",
                answer: Box::new(other),
            }),
        }
    }

    /// All twelve calibrations, canonical order.
    ///
    /// # Errors
    /// As [`Client::calibration`].
    pub fn calibrations(&mut self) -> Result<[Calibration; 12], Error> {
        let mut table = [Calibration::STANDARD; 12];
        for s in ServoId::ALL {
            table[s.index()] = self.calibration(s)?;
        }
        Ok(table)
    }
}

/// What the host asks of a pose stream.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StreamSetup {
    /// The host's robot (must be the device's).
    pub robot: Robot,
    /// Its preset.
    pub preset: RobotPreset,
    /// Stance height to set on the device; `None` keeps the device's.
    pub stance_height_m: Option<f32>,
    /// Rotation order to set on the device; `None` keeps the device's.
    pub order: Option<RotationOrder>,
    /// How angles are compared.
    pub check: AngleCheck,
}

/// The summary of a stream, printed by `quadctl stream` as its last line.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct StreamStats {
    /// Poses sent.
    pub sent: u64,
    /// Poses acked with a readback that passed the check.
    pub acked: u64,
    /// Poses nacked with the reason the host's own kin-core gives.
    pub nacked: u64,
    /// Resends, all poses together.
    pub retries: u64,
    /// Poses without an answer after every retry.
    pub lost: u64,
    /// Poses whose answer still disagreed with the host after every retry.
    pub readback_mismatches: u64,
    /// Largest |device angle − host angle| over the acked poses, rad.
    pub max_angle_err_rad: f32,
    /// Pulses in final readbacks outside their servo's calibrated travel.
    pub pulses_out_of_range: u64,
    /// Answered poses (acked + nacked) per second of link time.
    pub poses_per_s: f64,
    /// Answers refused by the check and then corrected by a retry (line corruption that passed
    /// the CRC).
    pub transient_mismatches: u64,
    /// Attempts that timed out.
    pub timeouts: u64,
    /// Link time from the first pose sent to the last answer, s.
    pub elapsed_s: f64,
    /// Times the outputs were found off (link-loss failsafe) and enabled again.
    pub reenabled: u64,
}

/// The host's expectation for one pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Expected {
    /// An ack with these angles.
    Angles([f32; 12]),
    /// A nack with this reason.
    Nack(NackReason),
}

/// A setpoint of the stream: what one request asks the device to hold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Setpoint {
    /// A body pose, feet at the stance ([`Request::SetBodyPose`]).
    Pose(Pose),
    /// The four feet in the body frame, m ([`Request::SetFeet`]).
    Feet([Vec3; 4]),
    /// The twelve joint angles, rad, canonical order ([`Request::SetJoints`]).
    Joints([f32; 12]),
}

impl Setpoint {
    /// The request that sends it.
    pub fn request(&self) -> Request {
        match *self {
            Setpoint::Pose(pose) => Request::SetBodyPose(pose),
            Setpoint::Feet(feet) => Request::SetFeet {
                feet_in_body_m: feet.map(|f| [f.x, f.y, f.z]),
            },
            Setpoint::Joints(angles_rad) => Request::SetJoints { angles_rad },
        }
    }
}

/// How one pose ended.
#[derive(Debug, Clone, PartialEq)]
pub enum PoseResult {
    /// Acked; the readback passed the check.
    Acked {
        /// Largest angle difference to the host, rad.
        max_err_rad: f32,
    },
    /// Nacked with the host's own reason.
    Nacked(NackReason),
    /// No answer.
    Lost,
    /// The answer disagreed with the host after every retry.
    Mismatch(Mismatch),
}

/// Body poses streamed to the device, each checked against the host's own kin-core.
pub struct PoseStream<L> {
    client: Client<L>,
    setup: StreamSetup,
    info: DeviceInfo,
    pose_config: PoseConfig,
    calibration: [Calibration; 12],
    stats: StreamStats,
    started: Option<Duration>,
    finished: Duration,
}

impl<L: Link> PoseStream<L> {
    /// Handshake, robot check, pose configuration, calibration read-back, outputs on.
    ///
    /// # Errors
    /// Any [`Error`] of these steps.
    pub fn connect(client: Client<L>, setup: StreamSetup) -> Result<PoseStream<L>, Error> {
        let mut s = PoseStream {
            client,
            setup,
            info: DeviceInfo {
                version: 0,
                firmware: Default::default(),
                robot: RobotPreset::Custom,
                max_frame_len: 0,
                pose_config: PoseConfig {
                    stance_height_m: 1.0,
                    order: RotationOrder::Zyx,
                    policy: ReachPolicy::Reject,
                },
                link_timeout: Default::default(),
            },
            pose_config: PoseConfig {
                stance_height_m: 1.0,
                order: RotationOrder::Zyx,
                policy: ReachPolicy::Reject,
            },
            calibration: [Calibration::STANDARD; 12],
            stats: StreamStats::default(),
            started: None,
            finished: Duration::ZERO,
        };
        s.setup()?;
        Ok(s)
    }

    fn setup(&mut self) -> Result<(), Error> {
        let info = self.client.hello()?;
        if info.robot != self.setup.preset {
            return Err(Error::Robot {
                device: info.robot,
                host: self.setup.preset,
            });
        }
        self.info = info;
        self.pose_config = PoseConfig {
            stance_height_m: self
                .setup
                .stance_height_m
                .unwrap_or(info.pose_config.stance_height_m),
            order: self.setup.order.unwrap_or(info.pose_config.order),
            policy: ReachPolicy::Reject,
        };
        self.client.ack(Request::SetPoseConfig(self.pose_config))?;
        self.calibration = self.client.calibrations()?;
        let rb = self.client.ack(Request::SetOutputs { enabled: true })?;
        if !rb.flags.contains(Flags::OUTPUTS_ENABLED) {
            return Err(Error::Unexpected {
                request: "SetOutputs",
                answer: Box::new(DeviceToHost::Ack {
                    seq: 0,
                    readback: rb,
                }),
            });
        }
        Ok(())
    }

    /// The device's `HelloAck`.
    pub fn info(&self) -> &DeviceInfo {
        &self.info
    }

    /// What the host asked of the stream.
    pub fn stream_setup(&self) -> &StreamSetup {
        &self.setup
    }

    /// The pose configuration in force.
    pub fn pose_config(&self) -> &PoseConfig {
        &self.pose_config
    }

    /// The device's calibration as read at connection.
    pub fn calibration(&self) -> &[Calibration; 12] {
        &self.calibration
    }

    /// The client.
    pub fn client(&self) -> &Client<L> {
        &self.client
    }

    /// The client, the stream done.
    pub fn into_client(self) -> Client<L> {
        self.client
    }

    /// The client, e.g. to send other requests between poses.
    pub fn client_mut(&mut self) -> &mut Client<L> {
        &mut self.client
    }

    /// What the host's range check, kin-core and calibration make of `pose` ([`expected`]).
    pub fn expected(&self, pose: &Pose) -> Expected {
        expected(
            &self.setup.robot,
            &self.pose_config,
            &self.calibration,
            pose,
        )
    }

    /// What the host's kin-core, joint limits and calibration make of `setpoint`: the device's
    /// own steps (the body IK about the body centre in the pose configuration's order for a
    /// pose, the legs' IK of each foot less its hip mount for feet, the joint limits for joint
    /// angles; then the calibration of all twelve joints).
    pub fn expected_for(&self, setpoint: &Setpoint) -> Expected {
        let angles = match setpoint {
            Setpoint::Pose(pose) => return self.expected(pose),
            Setpoint::Feet(feet) => {
                match body::Solver::new(&self.setup.robot)
                    .inverse_feet_in_body(feet, ReachPolicy::Reject)
                {
                    Err(e) => return Expected::Nack(e.into()),
                    Ok(solution) => solution.flat(),
                }
            }
            Setpoint::Joints(angles) => {
                for s in ServoId::ALL {
                    let a = angles[s.index()];
                    if !a.is_finite() {
                        return Expected::Nack(NackReason::NonFinite);
                    }
                    if !self.setup.robot.limits.admits(s.joint, a) {
                        return Expected::Nack(NackReason::JointLimit {
                            leg: s.leg,
                            joint: s.joint,
                        });
                    }
                }
                *angles
            }
        };
        self.expected_angles(angles)
    }

    /// `angles` through the device's calibration: the angles, or the first servo out of its
    /// travel.
    fn expected_angles(&self, angles: [f32; 12]) -> Expected {
        expected_angles(&self.calibration, angles)
    }

    /// Compares a readback with the expected angles (see [`check_readback`]).
    ///
    /// # Errors
    /// What disagrees.
    pub fn check_readback(&self, rb: &Readback, want: &[f32; 12]) -> Result<f32, Mismatch> {
        check_readback(self.setup.check, &self.calibration, rb, want)
    }

    fn count_out_of_range(&mut self, rb: &Readback) {
        if rb.flags.contains(Flags::OUTPUTS_ENABLED) {
            for (c, &p) in self.calibration.iter().zip(&rb.pulses_half_us) {
                if p < c.min_half_us() || p > c.max_half_us() {
                    self.stats.pulses_out_of_range += 1;
                }
            }
        }
    }

    /// Sends one pose, checks its answer, updates the statistics.
    ///
    /// # Errors
    /// Link failures, and the errors of a new handshake after a device reset.
    pub fn send(&mut self, pose: &Pose) -> Result<PoseResult, Error> {
        self.send_setpoint(&Setpoint::Pose(*pose))
    }

    /// Sends one setpoint (a pose, feet or joint angles), checks its answer against
    /// [`PoseStream::expected_for`], updates the statistics.
    ///
    /// # Errors
    /// Link failures, and the errors of a new handshake after a device reset.
    pub fn send_setpoint(&mut self, setpoint: &Setpoint) -> Result<PoseResult, Error> {
        let expected = self.expected_for(setpoint);
        if self.started.is_none() {
            self.started = Some(self.client.link.now());
        }
        self.stats.sent += 1;
        let mut exchange = self.exchange_pose(setpoint, expected)?;
        if let Outcome::Accepted(DeviceToHost::Nack {
            reason: NackReason::HelloRequired,
            ..
        }) = exchange.outcome
        {
            // The device was reset: set the session up again and send the pose once more.
            self.setup()?;
            self.stats.retries += u64::from(exchange.attempts);
            exchange = self.exchange_pose(setpoint, expected)?;
        }
        self.stats.retries += u64::from(exchange.attempts - 1);
        self.finished = self.client.link.now();
        let result = match (exchange.outcome, expected) {
            // The check accepts an ack only when the host expects angles.
            (Outcome::Accepted(DeviceToHost::Ack { readback, .. }), Expected::Angles(want)) => {
                self.count_out_of_range(&readback);
                let max_err_rad = self
                    .check_readback(&readback, &want)
                    .unwrap_or(f32::INFINITY);
                self.stats.max_angle_err_rad = self.stats.max_angle_err_rad.max(max_err_rad);
                self.stats.acked += 1;
                if !readback.flags.contains(Flags::OUTPUTS_ENABLED) {
                    self.client.ack(Request::SetOutputs { enabled: true })?;
                    self.stats.reenabled += 1;
                }
                PoseResult::Acked { max_err_rad }
            }
            (Outcome::Accepted(DeviceToHost::Nack { reason, .. }), _) => {
                self.stats.nacked += 1;
                PoseResult::Nacked(reason)
            }
            (Outcome::Accepted(other), _) => {
                self.stats.readback_mismatches += 1;
                PoseResult::Mismatch(Mismatch::Unexpected(other))
            }
            (Outcome::Rejected(answer), _) => {
                self.stats.readback_mismatches += 1;
                if let DeviceToHost::Ack { readback, .. } = &answer {
                    self.count_out_of_range(readback);
                }
                PoseResult::Mismatch(self.describe_mismatch(&answer, &expected))
            }
            (Outcome::Lost, _) => {
                self.stats.lost += 1;
                PoseResult::Lost
            }
        };
        Ok(result)
    }

    fn exchange_pose(
        &mut self,
        setpoint: &Setpoint,
        expected: Expected,
    ) -> Result<Exchange, Error> {
        let rejected_before = self.client.counters.rejected;
        let (check, calibration) = (self.setup.check, self.calibration);
        let exchange = self.client.exchange(setpoint.request(), |answer| {
            judge(check, &calibration, answer, &expected)
        })?;
        let rejected = self.client.counters.rejected - rejected_before;
        if matches!(exchange.outcome, Outcome::Accepted(_)) {
            self.stats.transient_mismatches += rejected;
        }
        Ok(exchange)
    }

    fn describe_mismatch(&self, answer: &DeviceToHost, expected: &Expected) -> Mismatch {
        match (answer, expected) {
            (DeviceToHost::Ack { readback, .. }, Expected::Angles(want)) => {
                match self.check_readback(readback, want) {
                    Err(m) => m,
                    // The check refused it on an earlier attempt; this copy passes.
                    Ok(_) => Mismatch::Unexpected(*answer),
                }
            }
            (DeviceToHost::Ack { .. }, Expected::Nack(reason)) => {
                Mismatch::AckedHostRejects(*reason)
            }
            (DeviceToHost::Nack { reason, .. }, Expected::Angles(_)) => {
                Mismatch::NackedHostSolves(*reason)
            }
            (DeviceToHost::Nack { reason, .. }, Expected::Nack(want)) => Mismatch::Reasons {
                device: *reason,
                host: *want,
            },
            (other, _) => Mismatch::Unexpected(*other),
        }
    }

    /// The statistics so far, with the rate over the link time from the first pose to the last
    /// answer and the client's timeout count.
    pub fn stats(&self) -> StreamStats {
        let mut s = self.stats;
        let elapsed = self
            .started
            .map_or(Duration::ZERO, |t| self.finished.saturating_sub(t));
        s.elapsed_s = elapsed.as_secs_f64();
        s.poses_per_s = if elapsed.is_zero() {
            0.0
        } else {
            (s.acked + s.nacked) as f64 / s.elapsed_s
        };
        s.timeouts = self.client.counters.timeouts;
        s
    }
}

/// What the host makes of `pose` on a device with `pose_config` and `calibration`: after the
/// range check the device runs too (`quad_protocol::range`), the angles of kin-core's
/// `inverse_at_stance` (reject policy) when every one maps to a pulse within its servo's
/// travel, else the nack the device must answer. The check every body pose of the host passes
/// before it is sent.
pub fn expected(
    robot: &Robot,
    pose_config: &PoseConfig,
    calibration: &[Calibration; 12],
    pose: &Pose,
) -> Expected {
    if let Err(reason) = quad_protocol::range::check_pose(pose, robot) {
        return Expected::Nack(reason);
    }
    let config = BodyConfig {
        order: pose_config.order,
        pivot_m: Vec3::ZERO,
    };
    match body::Solver::new(robot).inverse_at_stance(
        pose,
        &config,
        pose_config.stance_height_m,
        ReachPolicy::Reject,
    ) {
        Err(e) => Expected::Nack(e.into()),
        Ok(solution) => expected_angles(calibration, solution.flat()),
    }
}

/// `angles` through `calibration`: the angles, or the first servo out of its travel.
fn expected_angles(calibration: &[Calibration; 12], angles: [f32; 12]) -> Expected {
    for s in ServoId::ALL {
        if let Err(fault) = calibration[s.index()].pulse_half_us(angles[s.index()]) {
            return Expected::Nack(NackReason::ServoRange {
                leg: s.leg,
                joint: s.joint,
                fault,
            });
        }
    }
    Expected::Angles(angles)
}

/// The readback check of one answer against the host's expectation: a nack must carry the
/// host's reason; an ack must pass [`check_readback`]. A `HelloRequired` nack (the device was
/// reset) is accepted so that the stream can set the session up again.
pub fn judge(
    check: AngleCheck,
    calibration: &[Calibration; 12],
    answer: &DeviceToHost,
    expected: &Expected,
) -> Verdict {
    match (answer, expected) {
        (
            DeviceToHost::Nack {
                reason: NackReason::HelloRequired,
                ..
            },
            _,
        ) => Verdict::Accept,
        (DeviceToHost::Nack { reason, .. }, Expected::Nack(want)) if reason == want => {
            Verdict::Accept
        }
        (DeviceToHost::Ack { readback, .. }, Expected::Angles(want))
            if check_readback(check, calibration, readback, want).is_ok() =>
        {
            Verdict::Accept
        }
        _ => Verdict::Reject,
    }
}

/// Compares a readback with the host's angles `want`: each angle by `check`, each pulse equal
/// to `calibration`'s mapping of the **device's** angle (0 while the outputs are off). Returns
/// the largest angle difference, rad.
///
/// # Errors
/// A description of the first disagreement.
pub fn check_readback(
    check: AngleCheck,
    calibration: &[Calibration; 12],
    rb: &Readback,
    want: &[f32; 12],
) -> Result<f32, Mismatch> {
    let mut max_err = 0.0f32;
    for (i, (&got, &w)) in rb.angles_rad.iter().zip(want).enumerate() {
        let err = (got - w).abs();
        let ok = match check {
            AngleCheck::Exact => got.to_bits() == w.to_bits(),
            AngleCheck::Within(tol) => err <= tol,
        };
        if !ok {
            return Err(Mismatch::Angle {
                servo: ServoId::ALL[i],
                device_rad: got,
                host_rad: w,
            });
        }
        max_err = max_err.max(err);
    }
    let enabled = rb.flags.contains(Flags::OUTPUTS_ENABLED);
    for (i, &p) in rb.pulses_half_us.iter().enumerate() {
        let want = if enabled {
            calibration[i].pulse_half_us(rb.angles_rad[i]).ok()
        } else {
            Some(0)
        };
        if want != Some(p) {
            return Err(Mismatch::Pulse {
                servo: ServoId::ALL[i],
                device_half_us: p,
                host_half_us: want,
            });
        }
    }
    Ok(max_err)
}
