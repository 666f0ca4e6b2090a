//! Motion generation: foot paths, body-motion laws and gaits, all evaluable at any time `t`.
//!
//! Every motion is a pure function of time and its (validated) parameters — no hidden state —
//! so the same code runs on the host and on the device. A [`Motion`] yields a [`Frame`] at time
//! `t`: the body [`Pose`] and the four feet in the world frame; [`solve`] turns a frame into the
//! twelve joint angles through [`crate::body::Solver::inverse`].
//!
//! - [`path`]: foot paths with one interface, [`path::FootPath`] (phase → foot offset + contact):
//!   seed 000's rectangle, semicircle, ellipse, cycloid, Bézier swing.
//! - [`laws`]: seed 001's body-motion laws — roll and pitch sways (eq. 6–8) and the yaw turn
//!   with the crossed-pair leg transfer (eq. 9–11, corrected; see `docs/papers.md`) — plus the
//!   feet following a path under a fixed body (seed 000 §3.2) and a statically stable yaw turn
//!   (one leg at a time, the body shifted into the support triangle first).
//! - [`gait`]: trot / walk generator driven by a body velocity command.
//! - [`walker`]: the same gaits as a stateful stepper, for a velocity command that changes
//!   while walking (footholds planned at lift-off, a stop that ends at the stance).
//!
//! ## Frames
//! The world frame coincides with the body frame in the nominal pose (see the crate docs): the
//! ground under a stance of height `H` is the plane `z = −H`. Seed 001 puts the ground at
//! `z = 0` and the body centre at `z = H`; its feet's `z_K` map to ours as `z = z_K − H`.
//!
//! ## Time
//! `t` is an `f32` in seconds. Laws accept any finite `t` (negative too); a non-finite `t` is
//! [`Error::NonFinite`]. f32 has 24 bits: at `t` = 3600 s the time step resolution is 0.24 ms.

use crate::body::{self, BodyConfig, BodySolution, Pose};
use crate::leg::{IkError, Unreachable};
use crate::math::Math;
use crate::robot::{LegId, Robot, RobotError};
use crate::vec::Vec3;
use crate::ReachPolicy;
use core::fmt;

pub mod gait;
pub mod laws;
pub mod path;
pub mod walker;

/// A motion parameter, as [`Error`] names it: an enum, not a string, so that a target that
/// never formats an error holds no parameter names (on the AVR every string literal takes
/// SRAM as well as flash). [`Param::name`] is the name used in messages and on the command
/// line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Param {
    /// `t_s`: The time of a sample, s.
    TS,
    /// `dt_s`: A time step, s.
    DtS,
    /// `phase`: A phase, cycles.
    Phase,
    /// `velocity`: The velocity command as a whole.
    Velocity,
    /// `forward_m_s`: The forward velocity, m/s.
    ForwardMS,
    /// `lateral_m_s`: The lateral velocity, m/s.
    LateralMS,
    /// `yaw_rad_s`: The yaw rate of a velocity command, rad/s (counter-clockwise positive).
    YawRadS,
    /// `step_height_m`: The step (swing apex) height, m.
    StepHeightM,
    /// `stance_feet`: The feet of the stance, m.
    StanceFeet,
    /// `feet_in_world`: The feet in the world frame, m.
    FeetInWorld,
    /// `lift_height_m`: The lift height h_K of a yaw turn, m.
    LiftHeightM,
    /// `yaw0_rad`: The initial yaw, rad.
    Yaw0Rad,
    /// `roll0_rad`: The initial roll, rad.
    Roll0Rad,
    /// `pitch0_rad`: The initial pitch, rad.
    Pitch0Rad,
    /// `stride_m`: The stride length, m.
    StrideM,
    /// `stance_height_m`: The stance (body) height, m.
    StanceHeightM,
    /// `phase_offsets`: The legs' phase offsets, cycles.
    PhaseOffsets,
    /// `duty_factor`: The duty factor.
    DutyFactor,
    /// `duration_s`: A duration, s.
    DurationS,
    /// `cycle_s`: A gait or path cycle, s.
    CycleS,
    /// `step_period_s`: The step period T1 of a yaw turn, s.
    StepPeriodS,
    /// `period_s`: A sway period, s.
    PeriodS,
    /// `amplitude_rad`: A sway amplitude, rad.
    AmplitudeRad,
    /// `start_s`: A sweep's start time, s.
    StartS,
    /// `rate_hz`: A sweep's sample rate, Hz.
    RateHz,
    /// `reach_radius_m`: The walker's stride-disc radius, m.
    ReachRadiusM,
    /// `path`: A foot path.
    Path,
    /// `parked`: A parked foot (a stopped walker).
    Parked,
    /// `max_joint_speed_rad_s`: The highest joint speed of a sweep, rad/s.
    MaxJointSpeedRadS,
    /// `yaw_rate_rad_s`: The yaw rate of a yaw turn, rad/s (counter-clockwise positive).
    YawRateRadS,
    /// `velocity_timeout_ms`: A walk's velocity command timeout, ms.
    VelocityTimeoutMs,
    /// `joint_speed_limit_rad_s`: A joint-speed limit, rad/s.
    JointSpeedLimitRadS,
    /// `yaw_per_cycle_rad`: The yaw of one cycle of a statically stable turn, rad
    /// (counter-clockwise positive).
    YawPerCycleRad,
    /// `shift_fraction`: How far a statically stable turn moves the body towards the centroid
    /// of its support triangle.
    ShiftFraction,
}

impl Param {
    /// The parameter's name (`snake_case`, with its unit).
    pub const fn name(self) -> &'static str {
        match self {
            Param::TS => "t_s",
            Param::DtS => "dt_s",
            Param::Phase => "phase",
            Param::Velocity => "velocity",
            Param::ForwardMS => "forward_m_s",
            Param::LateralMS => "lateral_m_s",
            Param::YawRadS => "yaw_rad_s",
            Param::StepHeightM => "step_height_m",
            Param::StanceFeet => "stance_feet",
            Param::FeetInWorld => "feet_in_world",
            Param::LiftHeightM => "lift_height_m",
            Param::Yaw0Rad => "yaw0_rad",
            Param::Roll0Rad => "roll0_rad",
            Param::Pitch0Rad => "pitch0_rad",
            Param::StrideM => "stride_m",
            Param::StanceHeightM => "stance_height_m",
            Param::PhaseOffsets => "phase_offsets",
            Param::DutyFactor => "duty_factor",
            Param::DurationS => "duration_s",
            Param::CycleS => "cycle_s",
            Param::StepPeriodS => "step_period_s",
            Param::PeriodS => "period_s",
            Param::AmplitudeRad => "amplitude_rad",
            Param::StartS => "start_s",
            Param::RateHz => "rate_hz",
            Param::ReachRadiusM => "reach_radius_m",
            Param::Path => "path",
            Param::Parked => "parked",
            Param::MaxJointSpeedRadS => "max_joint_speed_rad_s",
            Param::YawRateRadS => "yaw_rate_rad_s",
            Param::VelocityTimeoutMs => "velocity_timeout_ms",
            Param::JointSpeedLimitRadS => "joint_speed_limit_rad_s",
            Param::YawPerCycleRad => "yaw_per_cycle_rad",
            Param::ShiftFraction => "shift_fraction",
        }
    }
}

impl fmt::Display for Param {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The admissible range an [`Error::OutOfRange`] names (an enum for the reason [`Param`] is).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Expected {
    /// In the open interval (0, 1).
    OpenUnitInterval,
    /// Below the stance height: a lifted foot stays below the hips.
    BelowStanceHeight,
    /// At most half a turn per stance (`|ω|·d·T ≤ π`).
    HalfTurnPerStance,
    /// Within the gait's reach: footholds inside the stride disc.
    WithinGaitReach,
    /// At most 2^24 samples (`duration_s × rate_hz`).
    SweepSamples,
    /// In the half-open interval (0, 1].
    UnitIntervalOpenBelow,
    /// At most a quarter turn per cycle (`|Δψ| ≤ π/2`).
    QuarterTurnPerCycle,
}

impl fmt::Display for Expected {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Expected::OpenUnitInterval => "in (0, 1)",
            Expected::BelowStanceHeight => {
                "below the stance height (a lifted foot stays below the hips)"
            }
            Expected::HalfTurnPerStance => "at most half a turn per stance (|ω|·d·T ≤ π)",
            Expected::WithinGaitReach => {
                "within the gait's reach (footholds inside the stride disc)"
            }
            Expected::SweepSamples => "at most 2^24 samples (duration_s × rate_hz)",
            Expected::UnitIntervalOpenBelow => "in (0, 1]",
            Expected::QuarterTurnPerCycle => "at most a quarter turn per cycle (|Δψ| ≤ π/2)",
        })
    }
}

/// Why a motion parameter or a motion sample was refused. Every variant names the parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Error {
    /// The named parameter is NaN or infinite.
    NonFinite(Param),
    /// The named duration, period or rate is zero or negative.
    NotPositive(Param),
    /// The named length or height is negative.
    Negative(Param),
    /// The named parameter is outside its admissible range (`expected` says which).
    OutOfRange {
        /// The parameter.
        parameter: Param,
        /// The admissible range.
        expected: Expected,
    },
    /// The named parameter puts a foot of `leg` out of its reach.
    BeyondReach {
        /// The parameter responsible.
        parameter: Param,
        /// The leg that cannot reach.
        leg: LegId,
        /// Why it cannot.
        kind: Unreachable,
    },
    /// The robot description is invalid.
    Robot(RobotError),
    /// A sample of the motion cannot be reached (inverse kinematics refused it).
    Ik(IkError),
    /// The mass model is invalid.
    Mass(crate::stability::MassError),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::NonFinite(p) => write!(f, "`{p}` must be a finite number"),
            Error::NotPositive(p) => write!(f, "`{p}` must be greater than zero"),
            Error::Negative(p) => write!(f, "`{p}` must not be negative"),
            Error::OutOfRange {
                parameter,
                expected,
            } => write!(f, "`{parameter}` must be {expected}"),
            Error::BeyondReach {
                parameter,
                leg,
                kind,
            } => write!(f, "`{parameter}` puts the {leg} foot out of reach ({kind})"),
            Error::Robot(e) => write!(f, "robot: {e}"),
            Error::Ik(e) => write!(f, "unreachable sample: {e}"),
            Error::Mass(e) => write!(f, "masses: {e}"),
        }
    }
}

impl core::error::Error for Error {}

impl From<crate::stability::MassError> for Error {
    fn from(e: crate::stability::MassError) -> Self {
        Error::Mass(e)
    }
}

impl From<RobotError> for Error {
    fn from(e: RobotError) -> Self {
        Error::Robot(e)
    }
}

/// Checks that `v` is finite.
pub(crate) fn finite(v: f32, name: Param) -> Result<f32, Error> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::NonFinite(name))
    }
}

/// Checks that `v` is finite and `> 0`.
pub(crate) fn positive(v: f32, name: Param) -> Result<f32, Error> {
    if finite(v, name)? > 0.0 {
        Ok(v)
    } else {
        Err(Error::NotPositive(name))
    }
}

/// Checks that `v` is finite and `≥ 0`.
pub(crate) fn non_negative(v: f32, name: Param) -> Result<f32, Error> {
    if finite(v, name)? >= 0.0 {
        Ok(v)
    } else {
        Err(Error::Negative(name))
    }
}

/// Checks that every component of `v` is finite.
pub(crate) fn finite_vec(v: Vec3, name: Param) -> Result<Vec3, Error> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::NonFinite(name))
    }
}

/// Checks that every component of the four feet is finite.
pub(crate) fn finite_feet(feet: &[Vec3; 4], name: Param) -> Result<(), Error> {
    for f in feet {
        finite_vec(*f, name)?;
    }
    Ok(())
}

/// `x − floor(x)` in `[0, 1)` for finite `x` (guards the rounding of tiny negative values to 1).
#[inline]
pub(crate) fn fract01(x: f32) -> f32 {
    let r = x - crate::math::floor(x);
    if !(0.0..1.0).contains(&r) {
        0.0
    } else {
        r
    }
}

/// A gait or path phase in `[0, 1)`; always finite.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Phase(f32);

impl Phase {
    /// Phase 0 (lift-off of every path).
    pub const ZERO: Phase = Phase(0.0);

    /// Wraps any finite value into `[0, 1)` (`1.25` → `0.25`, `−0.25` → `0.75`).
    pub fn new(value: f32) -> Result<Phase, Error> {
        Ok(Phase(fract01(finite(value, Param::Phase)?)))
    }

    /// Wraps a value already known to be finite.
    #[inline]
    pub(crate) fn wrap(value: f32) -> Phase {
        Phase(if value.is_finite() {
            fract01(value)
        } else {
            0.0
        })
    }

    /// The value in `[0, 1)`.
    #[inline]
    pub const fn value(self) -> f32 {
        self.0
    }
}

/// Whether a foot is on the ground.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Contact {
    /// The foot bears load and does not move in the world frame.
    #[default]
    Stance,
    /// The foot is in the air (or, for a path under a held body, in its lifted part).
    Swing,
}

impl Contact {
    /// `stance` or `swing`.
    pub const fn name(self) -> &'static str {
        match self {
            Contact::Stance => "stance",
            Contact::Swing => "swing",
        }
    }
}

/// What a motion prescribes at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Body pose in the world frame.
    pub pose: Pose,
    /// The four feet in the world frame, order FL, FR, RL, RR, m.
    pub feet_in_world: [Vec3; 4],
    /// Contact state of each foot, order FL, FR, RL, RR.
    pub contact: [Contact; 4],
}

impl Frame {
    /// The zero pose, the four feet at the origin, in stance.
    pub const ZERO: Frame = Frame {
        pose: Pose::rotation(0.0, 0.0, 0.0),
        feet_in_world: [Vec3::ZERO; 4],
        contact: [Contact::Stance; 4],
    };
}

/// A motion: body pose and feet as a pure function of time.
pub trait Motion {
    /// The robot the motion was built (and validated) for.
    fn robot(&self) -> &Robot;

    /// Rotation order and pivot the motion's poses are meant for.
    fn body_config(&self) -> BodyConfig;

    /// The frame at time `t_s` (s) on math backend `M` (`motion.frame::<DefaultMath>(t_s)` for
    /// the default, [`DefaultMath`](crate::math::DefaultMath)). Only a non-finite `t_s` fails.
    fn frame<M: Math>(&self, t_s: f32) -> Result<Frame, Error>;

    /// Period (s) of the joint angles, i.e. of the feet relative to the body, if the motion is
    /// periodic. The body itself may keep turning or moving (yaw turn, gait).
    fn period_s(&self) -> Option<f32>;
}

/// Frame and joint angles of `motion` at `t_s` on backend `M`: the motion's frame solved by
/// [`crate::body::Solver::inverse`] under `policy`
/// (`motion::solve::<DefaultMath>(&motion, t_s, policy)` for the default backend,
/// [`DefaultMath`](crate::math::DefaultMath)).
pub fn solve<M: Math>(
    motion: &impl Motion,
    t_s: f32,
    policy: ReachPolicy,
) -> Result<(Frame, BodySolution), Error> {
    let frame = motion.frame::<M>(t_s)?;
    let sol = body::Solver::<M>::with_math(motion.robot())
        .inverse(
            &frame.pose,
            &motion.body_config(),
            &frame.feet_in_world,
            policy,
        )
        .map_err(Error::Ik)?;
    Ok((frame, sol))
}

/// Any of the motions of this module, for choosing one at run time.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum AnyMotion {
    /// A sway about one axis (seed 001 eq. 6–8; seed 000's pose sweeps).
    Sway(laws::Sway),
    /// Seed 001's yaw turn (eq. 9–11).
    YawTurn(laws::YawTurn),
    /// Feet following a foot path under a fixed body (seed 000 §3.2).
    LegPaths(laws::LegPaths),
    /// A trot / walk gait.
    Gait(gait::Gait),
    /// A statically stable yaw turn: one leg at a time, the body shifted first.
    StableTurn(laws::StableTurn),
}

impl Motion for AnyMotion {
    fn robot(&self) -> &Robot {
        match self {
            AnyMotion::Sway(m) => m.robot(),
            AnyMotion::YawTurn(m) => m.robot(),
            AnyMotion::LegPaths(m) => m.robot(),
            AnyMotion::Gait(m) => m.robot(),
            AnyMotion::StableTurn(m) => m.robot(),
        }
    }

    fn body_config(&self) -> BodyConfig {
        match self {
            AnyMotion::Sway(m) => m.body_config(),
            AnyMotion::YawTurn(m) => m.body_config(),
            AnyMotion::LegPaths(m) => m.body_config(),
            AnyMotion::Gait(m) => m.body_config(),
            AnyMotion::StableTurn(m) => m.body_config(),
        }
    }

    fn frame<M: Math>(&self, t_s: f32) -> Result<Frame, Error> {
        match self {
            AnyMotion::Sway(m) => m.frame::<M>(t_s),
            AnyMotion::YawTurn(m) => m.frame::<M>(t_s),
            AnyMotion::LegPaths(m) => m.frame::<M>(t_s),
            AnyMotion::Gait(m) => m.frame::<M>(t_s),
            AnyMotion::StableTurn(m) => m.frame::<M>(t_s),
        }
    }

    fn period_s(&self) -> Option<f32> {
        match self {
            AnyMotion::Sway(m) => m.period_s(),
            AnyMotion::YawTurn(m) => m.period_s(),
            AnyMotion::LegPaths(m) => m.period_s(),
            AnyMotion::Gait(m) => m.period_s(),
            AnyMotion::StableTurn(m) => m.period_s(),
        }
    }
}

/// Checks that the four feet are reachable at `pose` (used by the constructors' quick checks);
/// a failure is blamed on `parameter`.
pub(crate) fn check_reach(
    robot: &Robot,
    pose: &Pose,
    config: &BodyConfig,
    feet_in_world: &[Vec3; 4],
    parameter: Param,
) -> Result<(), Error> {
    let solver = body::Solver::new(robot);
    let local = solver.feet_in_hips(pose, config, feet_in_world);
    for leg in LegId::ALL {
        let solution = solver
            .leg()
            .inverse(leg, local[leg.index()], ReachPolicy::Reject);
        solution.map_err(|e| Error::BeyondReach {
            parameter,
            leg,
            kind: e.kind,
        })?;
    }
    Ok(())
}
