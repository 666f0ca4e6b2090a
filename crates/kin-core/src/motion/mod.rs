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
//!   feet following a path under a fixed body (seed 000 §3.2).
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
use crate::math::{DefaultMath, Math};
use crate::robot::{LegId, Robot, RobotError};
use crate::vec::Vec3;
use crate::ReachPolicy;
use core::fmt;

pub mod gait;
pub mod laws;
pub mod path;
pub mod walker;

/// Why a motion parameter or a motion sample was refused. Every variant names the parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Error {
    /// The named parameter is NaN or infinite.
    NonFinite(&'static str),
    /// The named duration, period or rate is zero or negative.
    NotPositive(&'static str),
    /// The named length or height is negative.
    Negative(&'static str),
    /// The named parameter is outside its admissible range (`expected` says which).
    OutOfRange {
        /// The parameter.
        parameter: &'static str,
        /// The admissible range, human-readable (e.g. `"in (0, 1)"`).
        expected: &'static str,
    },
    /// The named parameter puts a foot of `leg` out of its reach.
    BeyondReach {
        /// The parameter responsible.
        parameter: &'static str,
        /// The leg that cannot reach.
        leg: LegId,
        /// Why it cannot.
        kind: Unreachable,
    },
    /// The robot description is invalid.
    Robot(RobotError),
    /// A sample of the motion cannot be reached (inverse kinematics refused it).
    Ik(IkError),
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
        }
    }
}

impl core::error::Error for Error {}

impl From<RobotError> for Error {
    fn from(e: RobotError) -> Self {
        Error::Robot(e)
    }
}

/// Checks that `v` is finite.
pub(crate) fn finite(v: f32, name: &'static str) -> Result<f32, Error> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::NonFinite(name))
    }
}

/// Checks that `v` is finite and `> 0`.
pub(crate) fn positive(v: f32, name: &'static str) -> Result<f32, Error> {
    if finite(v, name)? > 0.0 {
        Ok(v)
    } else {
        Err(Error::NotPositive(name))
    }
}

/// Checks that `v` is finite and `≥ 0`.
pub(crate) fn non_negative(v: f32, name: &'static str) -> Result<f32, Error> {
    if finite(v, name)? >= 0.0 {
        Ok(v)
    } else {
        Err(Error::Negative(name))
    }
}

/// Checks that every component of `v` is finite.
pub(crate) fn finite_vec(v: Vec3, name: &'static str) -> Result<Vec3, Error> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::NonFinite(name))
    }
}

/// `x − floor(x)` in `[0, 1)` for finite `x` (guards the rounding of tiny negative values to 1).
#[inline]
pub(crate) fn fract01(x: f32) -> f32 {
    let r = x - libm::floorf(x);
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
        Ok(Phase(fract01(finite(value, "phase")?)))
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

/// A motion: body pose and feet as a pure function of time.
pub trait Motion {
    /// The robot the motion was built (and validated) for.
    fn robot(&self) -> &Robot;

    /// Rotation order and pivot the motion's poses are meant for.
    fn body_config(&self) -> BodyConfig;

    /// The frame at time `t_s` (s) on math backend `M`. Only a non-finite `t_s` fails.
    fn frame_with<M: Math>(&self, t_s: f32) -> Result<Frame, Error>;

    /// [`Motion::frame_with`] on the [`DefaultMath`] backend.
    fn frame(&self, t_s: f32) -> Result<Frame, Error> {
        self.frame_with::<DefaultMath>(t_s)
    }

    /// Period (s) of the joint angles, i.e. of the feet relative to the body, if the motion is
    /// periodic. The body itself may keep turning or moving (yaw turn, gait).
    fn period_s(&self) -> Option<f32>;
}

/// Frame and joint angles of `motion` at `t_s` on backend `M`: the motion's frame solved by
/// [`crate::body::Solver::inverse`] under `policy`.
pub fn solve_with<M: Math, T: Motion>(
    motion: &T,
    t_s: f32,
    policy: ReachPolicy,
) -> Result<(Frame, BodySolution), Error> {
    let frame = motion.frame_with::<M>(t_s)?;
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

/// [`solve_with`] on the [`DefaultMath`] backend.
pub fn solve<T: Motion>(
    motion: &T,
    t_s: f32,
    policy: ReachPolicy,
) -> Result<(Frame, BodySolution), Error> {
    solve_with::<DefaultMath, T>(motion, t_s, policy)
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
}

impl Motion for AnyMotion {
    fn robot(&self) -> &Robot {
        match self {
            AnyMotion::Sway(m) => m.robot(),
            AnyMotion::YawTurn(m) => m.robot(),
            AnyMotion::LegPaths(m) => m.robot(),
            AnyMotion::Gait(m) => m.robot(),
        }
    }

    fn body_config(&self) -> BodyConfig {
        match self {
            AnyMotion::Sway(m) => m.body_config(),
            AnyMotion::YawTurn(m) => m.body_config(),
            AnyMotion::LegPaths(m) => m.body_config(),
            AnyMotion::Gait(m) => m.body_config(),
        }
    }

    fn frame_with<M: Math>(&self, t_s: f32) -> Result<Frame, Error> {
        match self {
            AnyMotion::Sway(m) => m.frame_with::<M>(t_s),
            AnyMotion::YawTurn(m) => m.frame_with::<M>(t_s),
            AnyMotion::LegPaths(m) => m.frame_with::<M>(t_s),
            AnyMotion::Gait(m) => m.frame_with::<M>(t_s),
        }
    }

    fn period_s(&self) -> Option<f32> {
        match self {
            AnyMotion::Sway(m) => m.period_s(),
            AnyMotion::YawTurn(m) => m.period_s(),
            AnyMotion::LegPaths(m) => m.period_s(),
            AnyMotion::Gait(m) => m.period_s(),
        }
    }
}

/// Checks that the four feet are reachable at `pose` on backend `M` (used by the constructors'
/// quick checks); a failure is blamed on `parameter`.
pub(crate) fn check_reach<M: Math>(
    robot: &Robot,
    pose: &Pose,
    config: &BodyConfig,
    feet_in_world: &[Vec3; 4],
    parameter: &'static str,
) -> Result<(), Error> {
    let solver = body::Solver::<M>::with_math(robot);
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
