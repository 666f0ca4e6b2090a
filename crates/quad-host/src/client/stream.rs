//! [`PoseStream`]: setpoints streamed to the device, each answer judged against the host's own
//! kin-core (see the module docs of [`crate::client`]).

use super::checks::{check_readback, expected, expected_angles, judge};
use super::exchange::{Framed, Waited};
use super::{AngleCheck, Client, Error, Exchange, Expected, Mismatch, Outcome, Verdict};
use crate::link::Link;
use kin_core::body::{self, Pose};
use kin_core::{ReachPolicy, Robot, RotationOrder, Vec3};
use quad_protocol::servo::Calibration;
use quad_protocol::{
    DeviceInfo, DeviceToHost, Flags, NackReason, PoseConfig, Readback, Request, RobotPreset,
    ServoId,
};
use serde::Serialize;
use std::collections::VecDeque;
use std::time::Duration;

/// Requests [`PoseStream::submit`] keeps in flight by default: the device solves the next
/// while the answer to the previous one is on the wire (docs/protocol.md, link rules).
pub const DEFAULT_WINDOW: usize = 2;

/// The most requests the device takes in flight: one being solved, one waiting in its receive
/// buffer (docs/protocol.md, link rules).
pub const MAX_WINDOW: usize = 2;

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
    window: usize,
    in_flight: VecDeque<InFlight>,
    /// The setpoint of the request the device answered last, and whether it is the newest
    /// one submitted: a resend after a later request leaves the device holding an older one.
    held_newest: bool,
    /// When the last setpoint taken out of the window was answered (or given up).
    settled_at: Duration,
}

/// How a setpoint of [`PoseStream::submit`] ended.
#[derive(Debug, Clone, PartialEq)]
pub struct Settled {
    /// The tag it was submitted with.
    pub tag: u64,
    /// Its result.
    pub result: PoseResult,
    /// The link's time of its first attempt.
    pub sent_at: Duration,
    /// The link's time its answer was taken (or it was given up).
    pub answered_at: Duration,
}

/// A setpoint of [`PoseStream::submit`] on its way: its request framed once, its attempts.
struct InFlight {
    tag: u64,
    first_sent_at: Duration,
    answered_at: Duration,
    setpoint: Setpoint,
    expected: Expected,
    framed: Framed,
    sent_at: Duration,
    attempts: u32,
    /// The last answer the check refused.
    rejected: Option<DeviceToHost>,
    /// Answers the check refused.
    rejections: u64,
    /// How it ended, once it has.
    done: Option<Outcome>,
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
                robot_hash: None,
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
            window: DEFAULT_WINDOW,
            in_flight: VecDeque::new(),
            held_newest: true,
            settled_at: Duration::ZERO,
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
            self.started = Some(self.client.link().now());
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
        self.conclude(exchange.outcome, expected)
    }

    /// The result of a setpoint whose exchange ended with `outcome`, counted in the statistics.
    fn conclude(&mut self, outcome: Outcome, expected: Expected) -> Result<PoseResult, Error> {
        self.finished = self.client.link().now();
        let result = match (outcome, expected) {
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

    /// The requests [`PoseStream::submit`] keeps in flight.
    pub fn window(&self) -> usize {
        self.window
    }

    /// Sets how many requests [`PoseStream::submit`] keeps in flight: 1 is one at a time (as
    /// [`PoseStream::send_setpoint`]), at most [`MAX_WINDOW`]. Setpoints still in flight are
    /// finished first and their results returned.
    ///
    /// # Errors
    /// [`Error::Window`] for 0 or more than [`MAX_WINDOW`]; the errors of [`PoseStream::flush`].
    pub fn set_window(&mut self, window: usize) -> Result<Vec<Settled>, Error> {
        if !(1..=MAX_WINDOW).contains(&window) {
            return Err(Error::Window { window });
        }
        let done = self.flush()?;
        self.window = window;
        Ok(done)
    }

    /// Sends `setpoint` with up to [`PoseStream::window`] requests in flight: it leaves as soon
    /// as an earlier one has been answered, and each answer gets the checks and retries of
    /// [`PoseStream::send_setpoint`] (a resend keeps its sequence number; the others stay in
    /// flight meanwhile). Returns the setpoints that ended meanwhile, in the order they were
    /// submitted, each with the `tag` it was submitted with.
    ///
    /// # Errors
    /// Link failures, and the errors of a new handshake after a device reset.
    pub fn submit(&mut self, setpoint: &Setpoint, tag: u64) -> Result<Vec<Settled>, Error> {
        let mut done = Vec::new();
        while self.in_flight.len() >= self.window {
            self.settle_oldest(&mut done)?;
        }
        let expected = self.expected_for(setpoint);
        if self.started.is_none() {
            self.started = Some(self.client.link().now());
        }
        self.stats.sent += 1;
        let framed = self.client.frame_next(setpoint.request());
        let sent_at = self.client.send_framed(&framed, false)?;
        self.held_newest = false;
        self.in_flight.push_back(InFlight {
            tag,
            first_sent_at: sent_at,
            answered_at: sent_at,
            setpoint: *setpoint,
            expected,
            framed,
            sent_at,
            attempts: 1,
            rejected: None,
            rejections: 0,
            done: None,
        });
        Ok(done)
    }

    /// Waits for every setpoint still in flight and returns their results in submission order
    /// (see [`PoseStream::submit`]). When a resend left the device holding an older setpoint
    /// than the newest one, the newest is sent once more (one at a time, counted as a retry):
    /// the device ends holding the last setpoint, as one request at a time would leave it.
    ///
    /// # Errors
    /// As [`PoseStream::submit`].
    pub fn flush(&mut self) -> Result<Vec<Settled>, Error> {
        let mut done = Vec::new();
        let newest = self.in_flight.back().map(|f| (f.setpoint, f.expected));
        while !self.in_flight.is_empty() {
            self.settle_oldest(&mut done)?;
        }
        if let (false, Some((setpoint, expected))) = (self.held_newest, newest) {
            let exchange = self.exchange_pose(&setpoint, expected)?;
            self.stats.retries += u64::from(exchange.attempts);
            self.held_newest = true;
        }
        Ok(done)
    }

    /// Waits until the oldest setpoint in flight has ended, handling every answer, nack and
    /// timeout of the window meanwhile; moves the ended setpoints at the front to `done`.
    fn settle_oldest(&mut self, done: &mut Vec<Settled>) -> Result<(), Error> {
        while self.in_flight.front().is_some_and(|f| f.done.is_none()) {
            self.step(None)?;
        }
        while let Some(front) = self.in_flight.front() {
            let Some(outcome) = front.done else { break };
            let Some(f) = self.in_flight.pop_front() else {
                break;
            };
            if matches!(outcome, Outcome::Accepted(_)) {
                self.stats.transient_mismatches += f.rejections;
            }
            self.settled_at = f.answered_at;
            self.stats.retries += u64::from(f.attempts - 1);
            let result = self.conclude(outcome, f.expected)?;
            done.push(Settled {
                tag: f.tag,
                result,
                sent_at: f.first_sent_at,
                answered_at: f.answered_at,
            });
        }
        Ok(())
    }

    /// Lets the link's time run until `until` while the setpoints in flight are answered,
    /// resent or given up; returns those that ended, as [`PoseStream::submit`] does.
    ///
    /// # Errors
    /// As [`PoseStream::submit`].
    pub fn idle_until(&mut self, until: Duration) -> Result<Vec<Settled>, Error> {
        let mut done = Vec::new();
        while self.client.link().now() < until {
            if self.in_flight.iter().all(|f| f.done.is_some()) {
                self.client.idle_until(until)?;
                break;
            }
            self.step(Some(until))?;
        }
        if self.in_flight.front().is_some_and(|f| f.done.is_some()) {
            self.settle_oldest(&mut done)?;
        }
        Ok(done)
    }

    /// One event of the window: an answer, a nack of an unreadable frame, or the earliest
    /// deadline passing (or `until`, which ends the step without a resend).
    fn step(&mut self, until: Option<Duration>) -> Result<(), Error> {
        let open: Vec<usize> = (0..self.in_flight.len())
            .filter(|&i| self.in_flight[i].done.is_none())
            .collect();
        let Some(&first) = open.first() else {
            return Ok(());
        };
        let seqs: Vec<u16> = open.iter().map(|&i| self.in_flight[i].framed.seq).collect();
        let (latest, deadline) = self
            .deadlines()
            .into_iter()
            .min_by_key(|&(_, d)| d)
            .unwrap_or((first, Duration::ZERO));
        let nack_from = self.in_flight[first].sent_at + self.in_flight[first].framed.on_wire;
        let wait_until = until.map_or(deadline, |u| u.min(deadline));
        match self.client.wait_any(&seqs, wait_until, nack_from)? {
            Waited::Answer(seq, answer) => {
                let Some(i) = open
                    .iter()
                    .copied()
                    .find(|&i| self.in_flight[i].framed.seq == seq)
                else {
                    return Ok(());
                };
                self.held_newest = i + 1 == self.in_flight.len();
                if let DeviceToHost::Nack {
                    reason: NackReason::HelloRequired,
                    ..
                } = answer
                {
                    // The device was reset: set the session up again and send every setpoint
                    // without an answer once more.
                    self.setup()?;
                    for i in open {
                        self.resend(i)?;
                    }
                    return Ok(());
                }
                self.in_flight[i].answered_at = self.client.link().now();
                let f = &self.in_flight[i];
                match judge(self.setup.check, &self.calibration, &answer, &f.expected) {
                    Verdict::Accept => self.in_flight[i].done = Some(Outcome::Accepted(answer)),
                    Verdict::Reject => {
                        self.client.counters_mut().rejected += 1;
                        let f = &mut self.in_flight[i];
                        f.rejections += 1;
                        f.rejected = Some(answer);
                        self.retry(i)?;
                    }
                }
            }
            Waited::LinkNack => {
                // Most likely the oldest request or its answer, damaged on the line.
                self.client.counters_mut().link_nacks += 1;
                self.retry(first)?;
            }
            Waited::Timeout if wait_until < deadline => {}
            Waited::Timeout => {
                self.client.counters_mut().timeouts += 1;
                self.retry(latest)?;
            }
        }
        Ok(())
    }

    /// The answer deadline of each setpoint in flight without an answer: its timeout from its
    /// last attempt, or from when the one before it was answered (or timed out) when that is
    /// later: the device answers in order, so a request waits for the one before it.
    fn deadlines(&self) -> Vec<(usize, Duration)> {
        let mut out = Vec::new();
        let mut before = self.settled_at;
        for (i, f) in self.in_flight.iter().enumerate() {
            let start = f.sent_at.max(before);
            let deadline = start + f.framed.timeout;
            if f.done.is_none() {
                out.push((i, deadline));
                before = deadline;
            } else {
                before = f.answered_at;
            }
        }
        out
    }

    /// Resends the `i`-th setpoint in flight, or ends it (rejected or lost) when it has had
    /// every attempt.
    fn retry(&mut self, i: usize) -> Result<(), Error> {
        let retries = self.client.config().retries;
        let now = self.client.link().now();
        let f = &mut self.in_flight[i];
        if f.attempts > retries {
            f.answered_at = now;
            f.done = Some(f.rejected.map_or(Outcome::Lost, Outcome::Rejected));
            return Ok(());
        }
        self.resend(i)
    }

    /// Sends the `i`-th setpoint in flight again, the same bytes under the same sequence
    /// number.
    fn resend(&mut self, i: usize) -> Result<(), Error> {
        let sent_at = self.client.send_framed(&self.in_flight[i].framed, true)?;
        let f = &mut self.in_flight[i];
        f.sent_at = sent_at;
        f.attempts += 1;
        Ok(())
    }

    fn exchange_pose(
        &mut self,
        setpoint: &Setpoint,
        expected: Expected,
    ) -> Result<Exchange, Error> {
        let rejected_before = self.client.counters().rejected;
        let (check, calibration) = (self.setup.check, self.calibration);
        let exchange = self.client.exchange(setpoint.request(), |answer| {
            judge(check, &calibration, answer, &expected)
        })?;
        let rejected = self.client.counters().rejected - rejected_before;
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
        s.timeouts = self.client.counters().timeouts;
        s
    }
}
