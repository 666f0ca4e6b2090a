//! [`Client`]: one request and its answer under one sequence number, retried (see the module
//! docs of [`crate::client`]), and the session requests built on it.

use super::{request_name, AnswerWait, ClientConfig, Error};
use crate::link::{self, byte_time, Link};
use quad_protocol::servo::Calibration;
use quad_protocol::timing;
use quad_protocol::{
    encode_frame, frame, Accumulator, DeviceInfo, DeviceToHost, Feed, HostToDevice, NackReason,
    Readback, Request, RobotDescription, ServoId, DEVICE_TO_HOST_MAX_LEN, MAX_DECODED_LEN,
    MAX_FRAME_LEN, PROTOCOL_VERSION,
};
use serde::Serialize;
use std::time::Duration;

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

enum Wait {
    Answer(DeviceToHost),
    LinkNack,
    Timeout,
}

/// What [`Client::wait_any`] saw first.
pub(super) enum Waited {
    /// The answer to one of the sequence numbers waited for.
    Answer(u16, DeviceToHost),
    /// A nack without a sequence number, or an unreadable frame.
    LinkNack,
    /// The deadline passed.
    Timeout,
}

/// A request framed under its sequence number: the same bytes on every attempt.
#[derive(Debug, Clone)]
pub(super) struct Framed {
    /// Its sequence number.
    pub seq: u16,
    /// The frame on the wire.
    pub bytes: Vec<u8>,
    /// How long an attempt waits for the answer ([`Client::attempt_timeout`]).
    pub timeout: Duration,
    /// The frame's time on the wire.
    pub on_wire: Duration,
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

    /// Timeout of one attempt of a request whose frame has `wire_len` bytes
    /// ([`ClientConfig::answer_wait`]).
    pub fn attempt_timeout(&self, wire_len: usize, request: &Request) -> Duration {
        match self.config.answer_wait {
            AnswerWait::Measured { host_latency } => {
                timing::Kind::of(request).timeout_with(self.link.baud(), host_latency)
            }
            AnswerWait::Modelled { compute, save } => {
                let answer_len = frame::encoded_len_max(DEVICE_TO_HOST_MAX_LEN);
                let mut t = byte_time(self.link.baud()) * (wire_len + answer_len) as u32 + compute;
                if matches!(request, Request::SaveCalibration | Request::SaveRobot) {
                    t += save;
                }
                t
            }
        }
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
        Ok(match self.wait_any(&[seq], deadline, nack_from)? {
            Waited::Answer(_, answer) => Wait::Answer(answer),
            Waited::LinkNack => Wait::LinkNack,
            Waited::Timeout => Wait::Timeout,
        })
    }

    /// Frames `request` under the next sequence number, for [`Client::send_framed`] (the
    /// requests of a window in flight, [`super::PoseStream`]).
    pub(super) fn frame_next(&mut self, request: Request) -> Framed {
        self.seq = self.seq.wrapping_add(1);
        let seq = self.seq;
        let mut buf = [0u8; MAX_FRAME_LEN];
        let bytes = encode_frame(&HostToDevice { seq, request }, &mut buf)
            .map(<[u8]>::to_vec)
            .unwrap_or_default();
        let timeout = self.attempt_timeout(bytes.len(), &request);
        let on_wire = byte_time(self.link.baud()) * bytes.len() as u32;
        Framed {
            seq,
            bytes,
            timeout,
            on_wire,
        }
    }

    /// Sends `framed` (a first attempt, or a resend with `retry`); returns the link's time
    /// when it was handed to the line.
    ///
    /// # Errors
    /// Link failures.
    pub(super) fn send_framed(
        &mut self,
        framed: &Framed,
        retry: bool,
    ) -> Result<Duration, link::Error> {
        let sent_at = self.link.now();
        self.link.send(&framed.bytes)?;
        self.counters.frames_sent += 1;
        if retry {
            self.counters.retries += 1;
        }
        Ok(sent_at)
    }

    /// The counters, to count what a caller of [`Client::wait_any`] decides.
    pub(super) fn counters_mut(&mut self) -> &mut Counters {
        &mut self.counters
    }

    /// Waits until `deadline` for an answer to one of `seqs`; a nack without a sequence number
    /// counts only from `nack_from` on. Answers to other sequence numbers are dropped as stale.
    ///
    /// # Errors
    /// Link failures.
    pub(super) fn wait_any(
        &mut self,
        seqs: &[u16],
        deadline: Duration,
        nack_from: Duration,
    ) -> Result<Waited, link::Error> {
        let mut buf = [0u8; 256];
        loop {
            let input = std::mem::take(&mut self.pending);
            let mut rest: &[u8] = &input;
            loop {
                match self.acc.feed::<DeviceToHost>(rest) {
                    Feed::NeedMore => break,
                    Feed::Frame { msg, remaining } => {
                        rest = remaining;
                        if let Some(seq) = msg.seq().filter(|s| seqs.contains(s)) {
                            self.pending = rest.to_vec();
                            return Ok(Waited::Answer(seq, msg));
                        }
                        if msg.seq().is_none() && self.link.now() >= nack_from {
                            self.pending = rest.to_vec();
                            return Ok(Waited::LinkNack);
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
                            return Ok(Waited::LinkNack);
                        }
                    }
                }
            }
            let now = self.link.now();
            if now >= deadline {
                return Ok(Waited::Timeout);
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

    /// The robot the device holds (protocol 2.4).
    ///
    /// # Errors
    /// As [`Client::request`], or [`Error::Unexpected`].
    pub fn get_robot(&mut self) -> Result<RobotDescription, Error> {
        match self.request(Request::GetRobot)? {
            DeviceToHost::Robot { robot, .. } => Ok(robot),
            other => Err(Error::Unexpected {
                request: "GetRobot",
                answer: Box::new(other),
            }),
        }
    }

    /// Sends `robot` to the device (protocol 2.4; held in RAM until [`Client::save_robot`]).
    /// The host's own check ([`quad_protocol::check_robot`]) runs first: a robot the device
    /// would refuse is not sent.
    ///
    /// # Errors
    /// [`Error::Refused`] with [`NackReason::BadRobot`] naming the field (by the host's check
    /// or the device's), [`NackReason::OutputsEnabled`], as [`Client::request`], or
    /// [`Error::Unexpected`] (an echo that differs from the robot sent included).
    pub fn set_robot(&mut self, robot: &RobotDescription) -> Result<(), Error> {
        quad_protocol::check_robot::<kin_core::DefaultMath>(robot).map_err(|reason| {
            Error::Refused {
                request: "SetRobot (not sent)",
                reason,
            }
        })?;
        match self.request(Request::SetRobot(*robot))? {
            DeviceToHost::Robot { robot: held, .. } if held == *robot => Ok(()),
            other => Err(Error::Unexpected {
                request: "SetRobot",
                answer: Box::new(other),
            }),
        }
    }

    /// Stores the robot the device holds in its EEPROM (protocol 2.4).
    ///
    /// # Errors
    /// As [`Client::ack`] ([`NackReason::Storage`] when the write failed).
    pub fn save_robot(&mut self) -> Result<(), Error> {
        self.ack(Request::SaveRobot).map(|_| ())
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
