//! [`PoseStream`]: setpoints streamed to the device, each answer judged against the host's own
//! kin-core (see the module docs of [`crate::client`]).

use super::checks::{check_readback, expected, expected_angles, judge};
use super::{AngleCheck, Client, Error, Exchange, Expected, Mismatch, Outcome};
use crate::link::Link;
use kin_core::body::{self, Pose};
use kin_core::{ReachPolicy, Robot, RotationOrder, Vec3};
use quad_protocol::servo::Calibration;
use quad_protocol::{
    DeviceInfo, DeviceToHost, Flags, NackReason, PoseConfig, Readback, Request, RobotPreset,
    ServoId,
};
use serde::Serialize;
use std::time::Duration;

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
        self.finished = self.client.link().now();
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
