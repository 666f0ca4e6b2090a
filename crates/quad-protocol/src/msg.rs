//! The messages, named by direction: [`HostToDevice`] (requests) and [`DeviceToHost`]
//! (answers).
//!
//! Every type here is serialized with postcard. The declarations below are the wire format: a
//! struct's fields in declaration order, an enum's variants by the index written beside each
//! (`0 => Hello { .. }`; see [`crate::wire`]), their fields in declaration order. Add variants
//! with new indices and fields only at the end, and only in a new minor version (see
//! `docs/protocol.md`). Leg, joint, rotation-order and reach-policy enums and the body pose are
//! kin-core's own types ([`LegId`], [`Joint`], [`RotationOrder`], [`ReachPolicy`], [`Pose`]),
//! carried through the index tables and field order of [`crate::wire`]; the golden tests pin
//! their encoding.
//!
//! Arrays of twelve joint values are in kin-core's canonical order
//! `[FL_abduction, FL_hip, FL_knee, FR_…, RL_…, RR_…]`; arrays of four feet in leg order
//! FL, FR, RL, RR.

use crate::balance::{BalanceConfig, ImuFaultKind, ImuReport};
use crate::robot::{RobotDescription, RobotField};
use crate::servo;
use crate::wire::{self, wire_enum};
use core::fmt;
use kin_core::motion::gait::Pattern;
use kin_core::motion::laws::Axis;
use kin_core::motion::path::PathKind;
use kin_core::{IkError, Joint, LegId, Pose, ReachPolicy, RotationOrder, Unreachable};
use serde::{Deserialize, Serialize};

/// One request from the host. The device answers every request it can read with exactly one
/// [`DeviceToHost`] carrying the same `seq`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HostToDevice {
    /// Sequence number chosen by the host, echoed by the answer. A retry of the same request
    /// reuses it.
    #[serde(with = "wire::shared")]
    pub seq: u16,
    /// What the host asks.
    pub request: Request,
}

wire_enum! {
    /// What the host asks. The comment on each variant names the answer.
    #[derive(Debug, Clone, Copy, PartialEq)]
    pub enum Request {
        /// Handshake: the host's [`crate::PROTOCOL_VERSION`]. → [`DeviceToHost::HelloAck`], or
        /// [`NackReason::UnknownVersion`] when the major versions differ. Variant index 0 and its
        /// layout are frozen across all versions.
        0 => Hello {
            /// The host's protocol version.
            version: u16 as wire::shared,
        },
        /// Report the current state without moving anything. → [`DeviceToHost::Ack`].
        1 => GetState,
        /// Body pose in the world frame; the device solves full-body IK with the feet held at the
        /// stance of its [`PoseConfig`]. → [`DeviceToHost::Ack`] or a nack (nothing moves).
        2 => SetBodyPose(Pose as wire::pose),
        /// Feet positions in the body frame, m, leg order FL, FR, RL, RR; `[x, y, z]` each.
        /// → [`DeviceToHost::Ack`] or a nack.
        3 => SetFeet {
            /// The four feet in the body frame, m.
            feet_in_body_m: [[f32; 3]; 4] as wire::array,
        },
        /// Twelve joint angles, rad, canonical order; bypasses the IK (joint limits and servo
        /// calibration still apply). → [`DeviceToHost::Ack`] or a nack.
        4 => SetJoints {
            /// The twelve joint angles, rad.
            angles_rad: [f32; 12] as wire::array,
        },
        /// Switch the servo outputs on or off (off at power-on). → [`DeviceToHost::Ack`].
        5 => SetOutputs {
            /// True to drive the outputs.
            enabled: bool,
        },
        /// Configure the link-loss failsafe. → [`DeviceToHost::Ack`].
        6 => SetLinkTimeout(LinkTimeout),
        /// Replace one servo's calibration in RAM (not yet persisted). → [`DeviceToHost::Ack`] or
        /// [`NackReason::BadCalibration`].
        7 => SetCalibration {
            /// Which servo.
            servo: ServoId,
            /// The new calibration.
            calibration: servo::Calibration,
        },
        /// Read one servo's calibration. → [`DeviceToHost::Calibration`].
        8 => GetCalibration {
            /// Which servo.
            servo: ServoId,
        },
        /// Persist all twelve calibrations. → [`DeviceToHost::Ack`] or [`NackReason::Storage`].
        9 => SaveCalibration,
        /// Set how [`Request::SetBodyPose`] is interpreted. → [`DeviceToHost::Ack`] or
        /// [`NackReason::InvalidArgument`].
        10 => SetPoseConfig(PoseConfig),
        /// Start a motion that the device runs by itself, frame by frame (since 2.1). Its
        /// parameters are checked (first against their ranges, [`crate::range`]) and the motion
        /// preflighted first. → [`DeviceToHost::MotionAck`],
        /// or a nack naming the parameter ([`NackReason::InvalidParameter`]), the failing sample
        /// ([`NackReason::Preflight`], [`NackReason::ServoRange`]), [`NackReason::MotionRunning`]
        /// or [`NackReason::OutputsDisabled`] (nothing moves, a running motion keeps running).
        11 => StartMotion(MotionCommand),
        /// Stop the running motion cleanly: a periodic motion at the end of its period, a walk
        /// once its strides are finished, then a ramp to the stance (since 2.1).
        /// → [`DeviceToHost::MotionAck`].
        12 => StopMotion,
        /// Report the motion engine's state (since 2.1). → [`DeviceToHost::MotionAck`].
        13 => GetMotion,
        /// The running walk's velocity command, body frame; it must be refreshed within the
        /// walk's `velocity_timeout_ms` (since 2.1). → [`DeviceToHost::MotionAck`], or
        /// [`NackReason::InvalidParameter`] naming a component outside its range
        /// ([`crate::range`]), [`NackReason::NotWalking`], or [`NackReason::InvalidParameter`]
        /// naming the component beyond the gait's reach.
        14 => SetVelocity {
            /// Forward speed, m/s.
            forward_m_s: f32,
            /// Lateral speed (to the left), m/s.
            lateral_m_s: f32,
            /// Yaw rate, rad/s, counter-clockwise positive (REP 103).
            yaw_rate_rad_s: f32,
        },
        /// The joint-speed limit of every output, rad/s, within
        /// [`crate::range::JOINT_SPEED_LIMIT_RAD_S`] (since 1.1).
        /// → [`DeviceToHost::Ack`] or [`NackReason::InvalidParameter`].
        15 => SetJointSpeedLimit {
            /// The limit, rad/s.
            joint_speed_limit_rad_s: f32,
        },
        /// Configure the balance functions: leveling, fall detection, the safe state, the
        /// action on a sensor fault (since 2.3). Its numbers are checked against their ranges
        /// ([`crate::range`]) first. → [`DeviceToHost::Imu`] with the settings as applied, or
        /// [`NackReason::InvalidParameter`] naming the field, [`NackReason::ImuAbsent`] or
        /// [`NackReason::ImuFault`] when leveling is asked of a device without a working
        /// sensor (nothing changes then).
        16 => SetBalance(BalanceConfig),
        /// Report the sensor, the attitude and the balance functions (since 2.3).
        /// → [`DeviceToHost::Imu`].
        17 => GetImu,
        /// Replace the robot the device holds in RAM (since 2.4; not stored until
        /// [`Request::SaveRobot`]): its geometry, stance, rotation order and joint-speed limit
        /// take effect at once, and the device holds the new stance. Checked first
        /// ([`crate::range::check_robot`]); refused while the outputs are on (a geometry change
        /// must never move powered servos). → [`DeviceToHost::Robot`] echoing the robot as
        /// held, or [`NackReason::BadRobot`] naming the field, [`NackReason::OutputsEnabled`]
        /// (nothing changes then).
        18 => SetRobot(RobotDescription),
        /// Report the robot the device holds (since 2.4). → [`DeviceToHost::Robot`].
        19 => GetRobot,
        /// Store the robot held in RAM in the device's non-volatile storage, the one it
        /// adopts at power-on (since 2.4). → [`DeviceToHost::Ack`] once written, or
        /// [`NackReason::Storage`].
        20 => SaveRobot,
    }
}

wire_enum! {
    /// A motion the device runs by itself ([`Request::StartMotion`]). Durations are rounded
    /// up to whole periods; `None` runs until [`Request::StopMotion`].
    #[derive(Debug, Clone, Copy, PartialEq)]
    pub enum MotionCommand {
        /// Outputs on at the rest pose (when off), then a ramp to the stance.
        0 => StandUp,
        /// A ramp to the rest pose, held.
        1 => Sit,
        /// A ramp to the rest pose, then the outputs off.
        2 => Rest,
        /// Seed 001's sway about `axis`, `angle = A·sin(2πt/T)`, feet fixed.
        3 => Sway {
            /// Roll, pitch or yaw.
            axis: Axis as wire::sway_axis,
            /// Amplitude `A`, rad.
            amplitude_rad: f32,
            /// Period `T`, s.
            period_s: f32,
            /// Duration, s; `None`: until stopped.
            duration_s: Option<f32>,
        },
        /// Seed 001's crossed-pair yaw turn about the body centre.
        4 => YawTurn {
            /// Turn rate, rad/s, counter-clockwise positive (REP 103).
            yaw_rate_rad_s: f32,
            /// Step period `T1`, s.
            step_period_s: f32,
            /// Lift `h_K`, m.
            lift_height_m: f32,
            /// Duration, s; `None`: until stopped.
            duration_s: Option<f32>,
        },
        /// A seed 000 foot path around the stance point of one leg or all four, body held.
        5 => FootPath {
            /// The path's shape.
            path: PathKind as wire::path_kind,
            /// The legs that follow it.
            legs: LegSet,
            /// Stride (length along x), m.
            stride_m: f32,
            /// Lift, m.
            step_height_m: f32,
            /// Stance fraction of the loop, in (0, 1).
            duty_factor: f32,
            /// One loop, s.
            cycle_s: f32,
            /// Duration, s; `None`: until stopped.
            duration_s: Option<f32>,
        },
        /// Trot or walk from a velocity command ([`Request::SetVelocity`]), zero at the start.
        6 => Walk {
            /// Trot or walk.
            gait: Pattern as wire::gait_pattern,
            /// Body height (hip plane above the ground), m.
            body_height_m: f32,
            /// Swing apex above the ground, m.
            step_height_m: f32,
            /// Gait cycle, s.
            cycle_s: f32,
            /// Timeout of the velocity command, ms (> 0): a command not refreshed within it
            /// stops the walk as [`Request::StopMotion`] does.
            velocity_timeout_ms: u16 as wire::shared,
        },
        /// A statically stable yaw turn on the spot about the body centre (kin-core's
        /// `StableTurn`): one leg at a time, the body first shifted towards the centroid of
        /// the other three feet (since 2.3).
        7 => StableTurn {
            /// Yaw of one cycle (each leg steps once), rad, counter-clockwise positive (REP 103).
            yaw_per_cycle_rad: f32,
            /// One cycle, s.
            cycle_s: f32,
            /// Swing apex above the ground, m.
            lift_height_m: f32,
            /// How far the body moves towards the centroid of its support triangle, in (0, 1].
            shift_fraction: f32,
            /// Duration, s; `None`: until stopped.
            duration_s: Option<f32>,
        },
    }
}

/// Default timeout of a walk's velocity command, ms: five missed commands at the 10 Hz a
/// teleoperating host sends.
pub const DEFAULT_VELOCITY_TIMEOUT_MS: u16 = 500;

impl MotionCommand {
    /// Seed 000 Fig. 8's rectangle (stride 0.1 m, lift 0.05 m, 3 s per loop, duty 1/3) on
    /// `legs` for `duration_s`.
    pub fn seed000_rectangle(legs: LegSet, duration_s: Option<f32>) -> MotionCommand {
        let s = kin_core::motion::path::Rectangle::seed000().stride();
        MotionCommand::FootPath {
            path: PathKind::Rectangle,
            legs,
            stride_m: s.length_m(),
            step_height_m: s.height_m(),
            duty_factor: s.duty_factor(),
            cycle_s: 3.0,
            duration_s,
        }
    }

    /// Seed 001's sway about `axis` (A = 0.2 rad, T = 20 s) for `duration_s`.
    pub fn seed001_sway(axis: Axis, duration_s: Option<f32>) -> MotionCommand {
        let p = kin_core::motion::laws::SwayParams::seed001(axis);
        MotionCommand::Sway {
            axis,
            amplitude_rad: p.amplitude_rad,
            period_s: p.period_s,
            duration_s,
        }
    }

    /// Seed 001's yaw turn (ω_z = 0.085 rad/s clockwise, T1 = 6 s, h_K = 0.3 m) for
    /// `duration_s`.
    pub fn seed001_yaw_turn(duration_s: Option<f32>) -> MotionCommand {
        let p = kin_core::motion::laws::YawTurnParams::seed001();
        MotionCommand::YawTurn {
            yaw_rate_rad_s: p.yaw_rate_rad_s,
            step_period_s: p.step_period_s,
            lift_height_m: p.lift_height_m,
            duration_s,
        }
    }

    /// kin-core's statically stable yaw turn with its defaults (0.2 rad per 20 s cycle, a
    /// shift of 0.8) and a lift of 0.15 × `body_height_m`, for `duration_s`.
    pub fn stable_turn(body_height_m: f32, duration_s: Option<f32>) -> MotionCommand {
        use kin_core::motion::laws::StableTurnParams as P;
        MotionCommand::StableTurn {
            yaw_per_cycle_rad: P::DEFAULT_YAW_PER_CYCLE_RAD,
            cycle_s: P::DEFAULT_CYCLE_S,
            lift_height_m: P::DEFAULT_LIFT_FRACTION * body_height_m,
            shift_fraction: P::DEFAULT_SHIFT_FRACTION,
            duration_s,
        }
    }

    /// A walk with `gait` at `body_height_m` with kin-core's default cycle and step height
    /// ([`kin_core::motion::gait::GaitParams::new`]) and [`DEFAULT_VELOCITY_TIMEOUT_MS`].
    pub fn walk(gait: Pattern, body_height_m: f32) -> MotionCommand {
        use kin_core::motion::gait::GaitParams;
        MotionCommand::Walk {
            gait,
            body_height_m,
            step_height_m: GaitParams::DEFAULT_STEP_HEIGHT_FRACTION * body_height_m,
            cycle_s: GaitParams::DEFAULT_CYCLE_S,
            velocity_timeout_ms: DEFAULT_VELOCITY_TIMEOUT_MS,
        }
    }

    /// What kind of motion this is.
    pub const fn kind(&self) -> MotionKind {
        match self {
            MotionCommand::StandUp => MotionKind::StandUp,
            MotionCommand::Sit => MotionKind::Sit,
            MotionCommand::Rest => MotionKind::Rest,
            MotionCommand::Sway { .. } => MotionKind::Sway,
            MotionCommand::YawTurn { .. } => MotionKind::YawTurn,
            MotionCommand::FootPath { .. } => MotionKind::FootPath,
            MotionCommand::Walk { .. } => MotionKind::Walk,
            MotionCommand::StableTurn { .. } => MotionKind::StableTurn,
        }
    }
}

wire_enum! {
    /// The legs a foot path moves.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum LegSet {
        /// All four, in phase.
        0 => All,
        /// One leg; the others stay at their stance points.
        1 => One(LegId as wire::leg_id),
    }
}

wire_enum! {
    /// The kinds of motion ([`MotionStatus::kind`]).
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum MotionKind {
        /// [`MotionCommand::StandUp`].
        0 => StandUp,
        /// [`MotionCommand::Sit`].
        1 => Sit,
        /// [`MotionCommand::Rest`].
        2 => Rest,
        /// [`MotionCommand::Sway`].
        3 => Sway,
        /// [`MotionCommand::YawTurn`].
        4 => YawTurn,
        /// [`MotionCommand::FootPath`].
        5 => FootPath,
        /// [`MotionCommand::Walk`].
        6 => Walk,
        /// [`MotionCommand::StableTurn`] (since 2.3).
        7 => StableTurn,
    }
}

wire_enum! {
    /// Where a motion is ([`MotionStatus::stage`]).
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum MotionStage {
        /// Ramping from the outputs to the motion's first setpoint.
        0 => Approach,
        /// Running.
        1 => Run,
        /// Stop requested: running to the end of the period (or of the strides).
        2 => Stopping,
        /// Ramping to the stance (or the rest pose).
        3 => Leave,
        /// No motion runs ([`MotionStatus::kind`] is `None`; since 2.2). A device sends it only
        /// to a host of minor 2 or later; an older host gets [`MotionStage::Run`] with `t_s`
        /// and `phase` 0 when idle ([`MotionStatus::for_minor`]).
        4 => Idle,
    }
}

/// The motion engine's state, in [`DeviceToHost::MotionAck`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MotionStatus {
    /// The motion running; `None` when idle.
    pub kind: Option<MotionKind>,
    /// Its stage: [`MotionStage::Idle`] when idle (to a host of minor 2 or later; `Run` to an
    /// older one).
    pub stage: MotionStage,
    /// Motion time since the run began, s; 0 when idle.
    pub t_s: f32,
    /// Phase within the motion's period (the walk's gait phase), in `[0, 1)`; 0 when idle.
    pub phase: f32,
    /// Why the last motion stopped early (a run-time sample failed), if it did.
    pub fault: Option<NackReason>,
}

impl MotionStatus {
    /// This status as a peer of protocol minor `minor` may receive it: unchanged for minor 2
    /// or later; for minor 0 or 1, which do not know [`MotionStage::Idle`], an idle status is
    /// reported as stage [`MotionStage::Run`] (what 2.1 devices sent) with `t_s` and `phase` 0.
    #[must_use]
    ///
    /// A host of minor 0 to 2 does not know [`MotionKind::StableTurn`] (2.3): a stable turn
    /// that another host started is reported to it as [`MotionKind::YawTurn`], the turn on the
    /// spot it knows.
    pub const fn for_minor(self, minor: u8) -> MotionStatus {
        let status = match self.kind {
            Some(MotionKind::StableTurn) if minor < 3 => MotionStatus {
                kind: Some(MotionKind::YawTurn),
                ..self
            },
            _ => self,
        };
        match status.stage {
            MotionStage::Idle if minor < 2 => MotionStatus {
                stage: MotionStage::Run,
                t_s: 0.0,
                phase: 0.0,
                ..status
            },
            _ => status,
        }
    }
}

/// The frame numbers of a motion (since 2.3, at the end of [`DeviceToHost::MotionAck`] to a
/// peer of minor 3 or later): with the request and the [`MotionStatus`], what a host needs to
/// recompute every frame of the motion (docs/motion.md, "Replaying a motion").
///
/// A frame is one 20 ms servo frame. The run's frames are counted from 0 at the start of stage
/// [`MotionStage::Run`] (frame `n` is the setpoint at motion time `n · 20 ms`; `t_s` reports
/// the same count in seconds); a ramp's frames are its steps. Each number is sent modulo
/// [`MotionFrames::MODULUS`] (16,384 frames, 5 min 27.68 s), so that it takes at most two
/// bytes and the answer stays within the largest answer of 2.2.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct MotionFrames {
    /// Frames of the current stage when the answer was made: the steps taken along the ramp
    /// in [`MotionStage::Approach`] and [`MotionStage::Leave`], the run frame in
    /// [`MotionStage::Run`] and [`MotionStage::Stopping`]; 0 when idle. In the answer to a
    /// [`Request::SetVelocity`] in stage `Run` this is the run frame from which the velocity
    /// applies (the walker's step from this frame to the next is the first with it); one
    /// answered in stage `Approach` applies from run frame 0.
    pub frame: u16,
    /// The run frame at which the stop took effect ([`Request::StopMotion`], the walk's
    /// velocity timeout or the link-loss failsafe; the first of them): the run's step from this
    /// frame on is the first of the stopping motion. `None` while no stop took effect in the
    /// run (a stop asked for in the approach turns the ramp back at once, without a run).
    pub stop_frame: Option<u16>,
}

impl MotionFrames {
    /// The frame numbers are sent modulo this (2^14: a varint of at most two bytes).
    pub const MODULUS: u32 = 1 << 14;

    /// `frame` modulo [`MotionFrames::MODULUS`], as sent.
    pub const fn wrap(frame: u32) -> u16 {
        (frame % Self::MODULUS) as u16
    }
}

wire_enum! {
    /// A parameter of a motion request ([`NackReason::InvalidParameter`]).
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum MotionParam {
        /// A sway's amplitude.
        0 => AmplitudeRad,
        /// A sway's period.
        1 => PeriodS,
        /// A duration.
        2 => DurationS,
        /// A yaw turn's or a velocity command's yaw rate.
        3 => YawRateRadS,
        /// A yaw turn's step period.
        4 => StepPeriodS,
        /// A yaw turn's lift.
        5 => LiftHeightM,
        /// A foot path's stride.
        6 => StrideM,
        /// A foot path's or a walk's step height.
        7 => StepHeightM,
        /// A foot path's duty factor.
        8 => DutyFactor,
        /// A foot path's or a walk's cycle.
        9 => CycleS,
        /// A foot path's shape (out of reach at some phase).
        10 => Path,
        /// A walk's body height.
        11 => BodyHeightM,
        /// A walk's velocity timeout.
        12 => VelocityTimeoutMs,
        /// A velocity command's forward speed.
        13 => ForwardMS,
        /// A velocity command's lateral speed.
        14 => LateralMS,
        /// A velocity command's combination of components.
        15 => Velocity,
        /// The joint-speed limit.
        16 => JointSpeedLimitRadS,
        /// The stance the motion starts from (the device's stance height).
        17 => Stance,
        /// A walk's stride disc (reach radius, set from the body height).
        18 => ReachRadiusM,
        /// A parameter this protocol version has no code for.
        19 => Other,
        /// The leveling's proportional gain ([`BalanceConfig::level_kp`]; since 2.3).
        20 => LevelKp,
        /// The leveling's integral gain ([`BalanceConfig::level_ki_per_s`]; since 2.3).
        21 => LevelKiPerS,
        /// The leveling's bound ([`BalanceConfig::max_correction_rad`]; since 2.3).
        22 => MaxCorrectionRad,
        /// The fall angle ([`BalanceConfig::fall_angle_rad`]; since 2.3).
        23 => FallAngleRad,
        /// A stable turn's yaw per cycle (since 2.3).
        24 => YawPerCycleRad,
        /// A stable turn's shift fraction (since 2.3).
        25 => ShiftFraction,
    }
}

wire_enum! {
    /// What is wrong with a [`MotionParam`].
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum ParamProblem {
        /// NaN or infinite.
        0 => NonFinite,
        /// Zero or negative where it must be > 0.
        1 => NotPositive,
        /// Negative where it must be ≥ 0.
        2 => Negative,
        /// Outside its admissible range.
        3 => OutOfRange,
        /// It puts a foot out of reach.
        4 => BeyondReach,
    }
}

wire_enum! {
    /// Why a preflight sample of a motion fails ([`NackReason::Preflight`]).
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum PreflightFault {
        /// The foot cannot be reached.
        0 => Reach(ReachFault),
        /// A joint leaves the robot's joint limits.
        1 => JointLimit(Joint as wire::joint),
        /// The leg comes too close to a singular configuration.
        2 => Singular,
        /// A sample is NaN or infinite.
        3 => NonFinite,
        /// A reason this protocol version has no code for.
        4 => Other,
    }
}

/// One servo: a leg and one of its joints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct ServoId {
    /// The leg.
    #[serde(with = "wire::leg_id")]
    pub leg: LegId,
    /// The joint of that leg.
    #[serde(with = "wire::joint")]
    pub joint: Joint,
}

impl ServoId {
    /// All twelve servos in canonical order.
    pub const ALL: [ServoId; 12] = {
        let mut out = [ServoId {
            leg: LegId::FL,
            joint: Joint::Abduction,
        }; 12];
        let mut i = 0;
        while i < 12 {
            out[i] = ServoId {
                leg: LegId::ALL[i / 3],
                joint: Joint::ALL[i % 3],
            };
            i += 1;
        }
        out
    };

    /// Index in the canonical twelve-value order: `3·leg + joint`.
    #[inline]
    pub const fn index(self) -> usize {
        3 * self.leg.index() + self.joint as usize
    }

    /// The servo at `index` in the canonical order.
    #[inline]
    pub const fn from_index(index: usize) -> Option<ServoId> {
        if index < 12 {
            Some(ServoId::ALL[index])
        } else {
            None
        }
    }
}

impl fmt::Display for ServoId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{}", self.leg, self.joint)
    }
}

wire_enum! {
    /// What the device does when no valid frame arrived for `timeout_ms`.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
    pub enum LinkLossAction {
        /// Keep the last pulses on the outputs (the default).
        #[default]
        0 => Hold,
        /// Stop the pulses (hobby servos then go limp).
        1 => Disable,
    }
}

/// Link-loss failsafe settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct LinkTimeout {
    /// Time without a valid frame before the failsafe acts, ms; 0 = never.
    #[serde(with = "wire::shared")]
    pub timeout_ms: u16,
    /// What the failsafe does.
    pub action: LinkLossAction,
}

/// How the device interprets [`Request::SetBodyPose`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PoseConfig {
    /// Stance height `H`: the feet are held at `hip_in_body + (0, s·d_lat, −H)`, m (> 0).
    pub stance_height_m: f32,
    /// Rotation order of roll, pitch and yaw.
    #[serde(with = "wire::rotation_order")]
    pub order: RotationOrder,
    /// Reject unreachable targets, or clamp them and report [`Flags::CLAMPED`].
    #[serde(with = "wire::reach_policy")]
    pub policy: ReachPolicy,
}

wire_enum! {
    /// Robot geometry the firmware was built for.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum RobotPreset {
        /// [`kin_core::Robot::shahriar2023`] (seed 000).
        0 => Shahriar2023,
        /// [`kin_core::Robot::fernando2025`] (seed 001).
        1 => Fernando2025,
        /// A geometry that is none of the presets.
        2 => Custom,
    }
}

impl RobotPreset {
    /// The kin-core robot of a preset; `None` for [`RobotPreset::Custom`].
    pub const fn robot(self) -> Option<kin_core::Robot> {
        match self {
            RobotPreset::Shahriar2023 => Some(kin_core::Robot::shahriar2023()),
            RobotPreset::Fernando2025 => Some(kin_core::Robot::fernando2025()),
            RobotPreset::Custom => None,
        }
    }

    /// The preset of kin-core's name (`shahriar2023`, `fernando2025`).
    pub fn from_name(name: &str) -> Option<RobotPreset> {
        match name {
            "shahriar2023" => Some(RobotPreset::Shahriar2023),
            "fernando2025" => Some(RobotPreset::Fernando2025),
            _ => None,
        }
    }
}

/// Firmware release, semantic-version style.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct FirmwareVersion {
    /// Major.
    pub major: u8,
    /// Minor.
    pub minor: u8,
    /// Patch.
    pub patch: u8,
}

/// What the device tells about itself in [`DeviceToHost::HelloAck`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DeviceInfo {
    /// The device's [`crate::PROTOCOL_VERSION`].
    #[serde(with = "wire::shared")]
    pub version: u16,
    /// Firmware release.
    pub firmware: FirmwareVersion,
    /// The preset the robot the device holds is ([`RobotPreset::Custom`] when it is none of
    /// them; since 2.4 the robot may be sent and stored, [`Request::SetRobot`]).
    pub robot: RobotPreset,
    /// Largest decoded frame (postcard bytes + CRC) the device accepts, bytes.
    #[serde(with = "wire::shared")]
    pub max_frame_len: u16,
    /// Current pose interpretation.
    pub pose_config: PoseConfig,
    /// Current link-loss failsafe.
    pub link_timeout: LinkTimeout,
    /// The [`RobotDescription::hash`] of the robot the device holds (since 2.4): present
    /// exactly when the negotiated minor is 4 or later, absent (no byte) otherwise
    /// ([`wire::trailing`]).
    #[serde(with = "wire::trailing")]
    pub robot_hash: Option<u32>,
}

impl DeviceInfo {
    /// The device's answer to [`Request::Hello`] with sequence number `seq` from a host of
    /// version `host_version`: [`DeviceToHost::HelloAck`] when the majors agree, else
    /// [`NackReason::UnknownVersion`] carrying this device's version.
    ///
    /// A host of minor < 4 gets no [`DeviceInfo::robot_hash`] (2.3's bytes exactly).
    pub const fn answer_hello(&self, seq: u16, host_version: u16) -> DeviceToHost {
        if crate::version_major(host_version) == crate::version_major(self.version) {
            let mut info = *self;
            if crate::negotiated_minor(host_version, self.version) < 4 {
                info.robot_hash = None;
            }
            DeviceToHost::HelloAck { seq, info }
        } else {
            DeviceToHost::Nack {
                seq: Some(seq),
                reason: NackReason::UnknownVersion {
                    supported: self.version,
                },
            }
        }
    }
}

/// Status bits of a [`Readback`], one byte on the wire. Unknown bits are reserved: senders
/// write 0, receivers ignore them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
pub struct Flags(pub u8);

impl Flags {
    /// The last target was moved by [`ReachPolicy::Clamp`] (the angles are not those asked).
    pub const CLAMPED: u8 = 1 << 0;
    /// A joint or servo limit acted on the last target.
    pub const LIMITED: u8 = 1 << 1;
    /// The servo outputs are driven.
    pub const OUTPUTS_ENABLED: u8 = 1 << 2;
    /// The link-loss failsafe has acted since the last valid frame.
    pub const FAILSAFE_ACTIVE: u8 = 1 << 3;
    /// A calibration in RAM differs from the stored one.
    pub const CALIBRATION_UNSAVED: u8 = 1 << 4;
    /// No valid stored calibration was found at power-on: defaults are in use.
    pub const CALIBRATION_DEFAULT: u8 = 1 << 5;
    /// The device's last reset was the watchdog's (since 2.2): set from boot, latched until an
    /// answer carrying the flags has reported it to a host of minor 2 or later.
    pub const WATCHDOG_RESET: u8 = 1 << 6;
    /// A fall was detected and the outputs went to their safe state (since 2.3): latched until
    /// an explicit motion request, sent only to a host of minor 3 or later.
    pub const FALL_DETECTED: u8 = 1 << 7;

    /// No bit set.
    pub const EMPTY: Flags = Flags(0);

    /// True when every bit of `mask` is set.
    #[inline]
    pub const fn contains(self, mask: u8) -> bool {
        self.0 & mask == mask
    }

    /// These flags with the bits of `mask` set to `on`.
    #[inline]
    #[must_use]
    pub const fn with(self, mask: u8, on: bool) -> Flags {
        if on {
            Flags(self.0 | mask)
        } else {
            Flags(self.0 & !mask)
        }
    }
}

/// What the device did: the state after the request, for the host's readback check.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Readback {
    /// The twelve joint angles the device holds (computed by its IK, or as set), rad;
    /// canonical order. Always finite.
    #[serde(with = "wire::array")]
    pub angles_rad: [f32; 12],
    /// The twelve pulse widths on the outputs, half-µs (one 0.5 µs timer tick each; 3000 =
    /// 1500 µs); 0 = that output is off. Canonical order.
    #[serde(with = "wire::array")]
    pub pulses_half_us: [u16; 12],
    /// Status bits.
    pub flags: Flags,
    /// Frames received with a good CRC since power-on (wrapping).
    #[serde(with = "wire::shared")]
    pub frames_ok: u32,
    /// Frames dropped for a bad CRC, bad encoding or oversize since power-on (wrapping).
    #[serde(with = "wire::shared")]
    pub frames_bad: u32,
}

wire_enum! {
    /// One answer from the device.
    #[derive(Debug, Clone, Copy, PartialEq)]
    pub enum DeviceToHost {
        /// The request was refused; nothing moved. Variant index 0 and its layout are frozen.
        0 => Nack {
            /// The request's sequence number; `None` when the frame could not be read
            /// ([`NackReason::BadCrc`], [`NackReason::BadFrame`], [`NackReason::Oversize`]).
            seq: Option<u16>,
            /// Why.
            reason: NackReason,
        },
        /// Answer to [`Request::Hello`] with a compatible version.
        1 => HelloAck {
            /// The request's sequence number.
            seq: u16,
            /// The device.
            info: DeviceInfo,
        },
        /// The request was carried out (or, for [`Request::GetState`], the state is reported).
        2 => Ack {
            /// The request's sequence number.
            seq: u16,
            /// The state after the request.
            readback: Readback,
        },
        /// Answer to [`Request::GetCalibration`].
        3 => Calibration {
            /// The request's sequence number.
            seq: u16,
            /// Which servo.
            servo: ServoId,
            /// Its calibration in RAM.
            calibration: servo::Calibration,
        },
        /// Answer to a configuration request ([`Request::SetLinkTimeout`],
        /// [`Request::SetPoseConfig`], [`Request::SetCalibration`]) that was carried out: the
        /// setting as the device now holds it, so that a request corrupted into another valid
        /// one does not go unnoticed, and the state after it.
        4 => Configured {
            /// The request's sequence number.
            seq: u16,
            /// The setting as applied.
            setting: Setting,
            /// The state after the request.
            readback: Readback,
        },
        /// Answer to [`Request::StartMotion`], [`Request::StopMotion`], [`Request::GetMotion`]
        /// and [`Request::SetVelocity`] (since 2.1).
        5 => MotionAck {
            /// The request's sequence number.
            seq: u16,
            /// The motion engine after the request.
            status: MotionStatus,
            /// The state after the request, as [`DeviceToHost::Ack`] reports it.
            readback: Readback,
            /// When the motion's frames ran and its commands took effect (since 2.3): present
            /// exactly when the negotiated minor is 3 or later, absent (no byte) otherwise
            /// ([`wire::trailing`]).
            frames: Option<MotionFrames> as wire::trailing,
        },
        /// Answer to [`Request::SetBalance`] and [`Request::GetImu`] (since 2.3).
        6 => Imu {
            /// The request's sequence number.
            seq: u16,
            /// The sensor, the attitude and the balance functions after the request.
            report: ImuReport,
        },
        /// Answer to [`Request::SetRobot`] and [`Request::GetRobot`] (since 2.4).
        7 => Robot {
            /// The request's sequence number.
            seq: u16,
            /// The robot the device holds after the request.
            robot: RobotDescription,
        },
    }
}

wire_enum! {
    /// A configuration setting as the device holds it (the echo of [`DeviceToHost::Configured`]).
    #[derive(Debug, Clone, Copy, PartialEq)]
    pub enum Setting {
        /// The link-loss failsafe.
        0 => LinkTimeout(LinkTimeout),
        /// How body poses are interpreted.
        1 => PoseConfig(PoseConfig),
        /// One servo's calibration in RAM.
        2 => Calibration {
            /// Which servo.
            servo: ServoId,
            /// Its calibration.
            calibration: servo::Calibration,
        },
    }
}

impl Setting {
    /// The setting `request` asks for; `None` for a request that is not a configuration.
    pub const fn of_request(request: &Request) -> Option<Setting> {
        match *request {
            Request::SetLinkTimeout(t) => Some(Setting::LinkTimeout(t)),
            Request::SetPoseConfig(p) => Some(Setting::PoseConfig(p)),
            Request::SetCalibration { servo, calibration } => {
                Some(Setting::Calibration { servo, calibration })
            }
            _ => None,
        }
    }
}

impl DeviceToHost {
    /// The echoed sequence number; `None` for a nack of an unreadable frame.
    pub const fn seq(&self) -> Option<u16> {
        match self {
            DeviceToHost::Nack { seq, .. } => *seq,
            DeviceToHost::HelloAck { seq, .. }
            | DeviceToHost::Ack { seq, .. }
            | DeviceToHost::Calibration { seq, .. }
            | DeviceToHost::Configured { seq, .. }
            | DeviceToHost::MotionAck { seq, .. }
            | DeviceToHost::Imu { seq, .. }
            | DeviceToHost::Robot { seq, .. } => Some(*seq),
        }
    }

    /// The readback an answer carries (`Ack`, `Configured`, `MotionAck`); `None` for the others.
    pub const fn readback(&self) -> Option<&Readback> {
        match self {
            DeviceToHost::Ack { readback, .. }
            | DeviceToHost::Configured { readback, .. }
            | DeviceToHost::MotionAck { readback, .. } => Some(readback),
            DeviceToHost::Nack { .. }
            | DeviceToHost::HelloAck { .. }
            | DeviceToHost::Calibration { .. }
            | DeviceToHost::Imu { .. }
            | DeviceToHost::Robot { .. } => None,
        }
    }
}

wire_enum! {
    /// Why a foot target cannot be reached (kin-core's [`Unreachable`] without the joint-limit and
    /// non-finite cases, which have their own [`NackReason`]s).
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum ReachFault {
        /// Farther than femur + tibia.
        0 => TooFar,
        /// Closer than |femur − tibia|.
        1 => TooClose,
        /// Within `d_lat` of the abduction axis.
        2 => InsideOffset,
        /// A reason this protocol version has no code for.
        3 => Other,
    }
}

wire_enum! {
    /// Why a request was refused.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    #[non_exhaustive]
    pub enum NackReason {
        /// The host's major version differs from the device's. Variant index 0 is frozen.
        0 => UnknownVersion {
            /// The device's own [`crate::PROTOCOL_VERSION`].
            supported: u16 as wire::shared,
        },
        /// A frame arrived whose CRC did not match.
        1 => BadCrc,
        /// A frame arrived that is not valid COBS or not a valid message.
        2 => BadFrame,
        /// A frame arrived that exceeds the device's buffer.
        3 => Oversize,
        /// A motion or configuration request arrived before a successful [`Request::Hello`].
        4 => HelloRequired,
        /// A foot cannot reach its target.
        5 => Unreachable {
            /// The first leg (in order FL, FR, RL, RR) that cannot reach.
            leg: LegId as wire::leg_id,
            /// Why.
            fault: ReachFault,
        },
        /// A joint angle would leave the robot's joint limits.
        6 => JointLimit {
            /// The leg.
            leg: LegId as wire::leg_id,
            /// The joint.
            joint: Joint as wire::joint,
        },
        /// A joint angle maps to a pulse outside that servo's calibrated `[min_us, max_us]`.
        7 => ServoRange {
            /// The leg.
            leg: LegId as wire::leg_id,
            /// The joint.
            joint: Joint as wire::joint,
            /// Below min or above max.
            fault: servo::Error,
        },
        /// A value in the request is NaN or infinite.
        8 => NonFinite,
        /// A calibration was refused.
        9 => BadCalibration(servo::Error),
        /// The device cannot take the request now (e.g. a save is in progress).
        10 => Busy,
        /// A motion request arrived while the outputs are disabled.
        11 => OutputsDisabled,
        /// The calibration storage failed.
        12 => Storage,
        /// A configuration value is out of its admissible range.
        13 => InvalidArgument,
        /// A finite value outside its field's admissible range ([`crate::range`]).
        14 => OutOfRange {
            /// The field.
            field: Field,
        },
        /// A motion parameter is invalid (since 2.1).
        15 => InvalidParameter {
            /// The parameter.
            param: MotionParam,
            /// What is wrong with it.
            problem: ParamProblem,
        },
        /// A preflight sample of the motion fails (since 2.1).
        16 => Preflight {
            /// The first leg that fails.
            leg: LegId as wire::leg_id,
            /// Why.
            fault: PreflightFault,
        },
        /// A motion runs: stop it first (since 2.1).
        17 => MotionRunning,
        /// A velocity command arrived while no walk runs (since 2.1).
        18 => NotWalking,
        /// Leveling was asked of a device without a sensor (since 2.3).
        19 => ImuAbsent,
        /// Leveling was asked while the sensor fails (since 2.3).
        20 => ImuFault(ImuFaultKind),
        /// A motion was refused because the body is not upright (since 2.3; to a host of
        /// minor < 3 the device sends [`NackReason::Busy`] instead,
        /// [`NackReason::for_minor`]).
        21 => NotUpright,
        /// A robot description was refused (since 2.4): the first field that fails
        /// [`crate::range::check_robot`].
        22 => BadRobot(RobotField),
        /// The request needs the outputs off (since 2.4: [`Request::SetRobot`]).
        23 => OutputsEnabled,
    }
}

impl NackReason {
    /// This reason as a peer of protocol minor `minor` may receive it: unchanged for minor 3
    /// or later; the reasons of 2.3 that a request of an older minor can meet
    /// ([`NackReason::NotUpright`]) become [`NackReason::Busy`] ("cannot take it now") for an
    /// older peer. Those of 2.4 (which only its own requests meet) likewise:
    /// [`NackReason::BadRobot`] becomes [`NackReason::InvalidArgument`] and
    /// [`NackReason::OutputsEnabled`] [`NackReason::Busy`] for a peer of minor < 4.
    #[must_use]
    pub const fn for_minor(self, minor: u8) -> NackReason {
        match self {
            NackReason::NotUpright | NackReason::ImuAbsent | NackReason::ImuFault(_)
                if minor < 3 =>
            {
                NackReason::Busy
            }
            NackReason::BadRobot(_) if minor < 4 => NackReason::InvalidArgument,
            NackReason::OutputsEnabled if minor < 4 => NackReason::Busy,
            other => other,
        }
    }
}

wire_enum! {
    /// A field of a request, as named by [`NackReason::OutOfRange`].
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum Field {
        /// `Pose::roll_rad`.
        0 => BodyRoll,
        /// `Pose::pitch_rad`.
        1 => BodyPitch,
        /// `Pose::yaw_rad`.
        2 => BodyYaw,
        /// `Pose::x_m`.
        3 => BodyX,
        /// `Pose::y_m`.
        4 => BodyY,
        /// `Pose::z_m`.
        5 => BodyZ,
        /// One foot of `SetFeet` (any of its coordinates).
        6 => Foot(LegId as wire::leg_id),
        /// One angle of `SetJoints`.
        7 => JointAngle {
            /// The leg.
            leg: LegId as wire::leg_id,
            /// The joint.
            joint: Joint as wire::joint,
        },
        /// `PoseConfig::stance_height_m`.
        8 => StanceHeight,
    }
}

impl fmt::Display for Field {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Field::BodyRoll => f.write_str("roll_rad"),
            Field::BodyPitch => f.write_str("pitch_rad"),
            Field::BodyYaw => f.write_str("yaw_rad"),
            Field::BodyX => f.write_str("x_m"),
            Field::BodyY => f.write_str("y_m"),
            Field::BodyZ => f.write_str("z_m"),
            Field::Foot(leg) => write!(f, "foot {leg}"),
            Field::JointAngle { leg, joint } => write!(f, "angle {leg}.{joint}"),
            Field::StanceHeight => f.write_str("stance_height_m"),
        }
    }
}

impl From<IkError> for NackReason {
    fn from(e: IkError) -> Self {
        let fault = match e.kind {
            Unreachable::JointLimit(joint) => return NackReason::JointLimit { leg: e.leg, joint },
            Unreachable::NonFinite => return NackReason::NonFinite,
            Unreachable::TooFar => ReachFault::TooFar,
            Unreachable::TooClose => ReachFault::TooClose,
            Unreachable::InsideOffset => ReachFault::InsideOffset,
            _ => ReachFault::Other,
        };
        NackReason::Unreachable { leg: e.leg, fault }
    }
}

impl fmt::Display for ReachFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ReachFault::TooFar => "too_far",
            ReachFault::TooClose => "too_close",
            ReachFault::InsideOffset => "inside_offset",
            ReachFault::Other => "other",
        })
    }
}

impl fmt::Display for NackReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NackReason::UnknownVersion { supported } => write!(
                f,
                "unknown version (device speaks {}.{})",
                crate::version_major(*supported),
                crate::version_minor(*supported)
            ),
            NackReason::BadCrc => f.write_str("bad CRC"),
            NackReason::BadFrame => f.write_str("bad frame"),
            NackReason::Oversize => f.write_str("oversize frame"),
            NackReason::HelloRequired => f.write_str("hello required first"),
            NackReason::Unreachable { leg, fault } => write!(f, "unreachable: {leg} {fault}"),
            NackReason::JointLimit { leg, joint } => write!(f, "joint limit: {leg}.{joint}"),
            NackReason::ServoRange { leg, joint, fault } => {
                write!(f, "servo range: {leg}.{joint}: {fault}")
            }
            NackReason::NonFinite => f.write_str("non-finite value"),
            NackReason::BadCalibration(e) => write!(f, "bad calibration: {e}"),
            NackReason::Busy => f.write_str("busy"),
            NackReason::OutputsDisabled => f.write_str("outputs disabled"),
            NackReason::Storage => f.write_str("storage error"),
            NackReason::InvalidArgument => f.write_str("invalid argument"),
            NackReason::OutOfRange { field } => write!(f, "out of range: {field}"),
            NackReason::InvalidParameter { param, problem } => {
                write!(f, "invalid parameter {param:?}: {problem:?}")
            }
            NackReason::Preflight { leg, fault } => write!(f, "preflight: {leg} {fault:?}"),
            NackReason::MotionRunning => f.write_str("a motion is running (stop it first)"),
            NackReason::NotWalking => f.write_str("no walk is running"),
            NackReason::ImuAbsent => f.write_str("no inertial sensor"),
            NackReason::ImuFault(kind) => write!(f, "inertial sensor fault: {kind:?}"),
            NackReason::NotUpright => f.write_str("the body is not upright"),
            NackReason::BadRobot(field) => write!(f, "robot refused: {field}"),
            NackReason::OutputsEnabled => f.write_str("the outputs are on (switch them off first)"),
        }
    }
}

impl core::error::Error for NackReason {}
