//! The engine's status and errors on the wire (quad-protocol's motion messages; the engine
//! takes the protocol's [`quad_protocol::MotionCommand`] as its request).

use super::{Error, Status};
use kin_core::motion;
use kin_core::preflight::FailureKind;
use kin_core::Unreachable;
use quad_protocol::{
    MotionFrames, MotionParam, MotionStatus, NackReason, ParamProblem, PreflightFault, ReachFault,
};

impl From<Status> for MotionStatus {
    fn from(s: Status) -> MotionStatus {
        MotionStatus {
            kind: s.kind,
            stage: s.stage,
            t_s: s.t_s,
            phase: s.phase,
            fault: s.fault.map(NackReason::from),
        }
    }
}

impl From<Status> for MotionFrames {
    /// The frame numbers of `s`, each modulo [`MotionFrames::MODULUS`] (the wire's).
    fn from(s: Status) -> MotionFrames {
        MotionFrames {
            frame: MotionFrames::wrap(s.frame),
            stop_frame: s.stop_frame.map(MotionFrames::wrap),
        }
    }
}

/// The wire name of a kin-core or engine parameter.
pub fn motion_param(param: motion::Param) -> MotionParam {
    use motion::Param as P;
    match param {
        P::AmplitudeRad => MotionParam::AmplitudeRad,
        P::PeriodS => MotionParam::PeriodS,
        P::DurationS => MotionParam::DurationS,
        // The yaw turn's rate and the velocity command's: both counter-clockwise positive.
        P::YawRateRadS | P::YawRadS => MotionParam::YawRateRadS,
        P::StepPeriodS => MotionParam::StepPeriodS,
        P::LiftHeightM => MotionParam::LiftHeightM,
        P::StrideM => MotionParam::StrideM,
        P::StepHeightM => MotionParam::StepHeightM,
        P::DutyFactor => MotionParam::DutyFactor,
        P::CycleS => MotionParam::CycleS,
        P::Path => MotionParam::Path,
        // A walk's body height is its gait's stance height.
        P::StanceHeightM => MotionParam::BodyHeightM,
        P::VelocityTimeoutMs => MotionParam::VelocityTimeoutMs,
        P::ForwardMS => MotionParam::ForwardMS,
        P::LateralMS => MotionParam::LateralMS,
        P::Velocity => MotionParam::Velocity,
        P::JointSpeedLimitRadS => MotionParam::JointSpeedLimitRadS,
        // The feet a law starts from: the device's stance.
        P::FeetInWorld | P::StanceFeet => MotionParam::Stance,
        P::ReachRadiusM => MotionParam::ReachRadiusM,
        P::YawPerCycleRad => MotionParam::YawPerCycleRad,
        P::ShiftFraction => MotionParam::ShiftFraction,
        _ => MotionParam::Other,
    }
}

fn reach_fault(u: Unreachable) -> PreflightFault {
    match u {
        Unreachable::JointLimit(j) => PreflightFault::JointLimit(j),
        Unreachable::NonFinite => PreflightFault::NonFinite,
        Unreachable::TooFar => PreflightFault::Reach(ReachFault::TooFar),
        Unreachable::TooClose => PreflightFault::Reach(ReachFault::TooClose),
        Unreachable::InsideOffset => PreflightFault::Reach(ReachFault::InsideOffset),
        _ => PreflightFault::Reach(ReachFault::Other),
    }
}

impl From<Error> for NackReason {
    fn from(e: Error) -> NackReason {
        match e {
            Error::Parameter(p) => {
                // One lookup of the parameter's wire name for all the problems (each inlined
                // lookup was a table of its own, in SRAM as well as flash on the AVR).
                let (param, problem) = match p {
                    motion::Error::NonFinite(n) => (n, ParamProblem::NonFinite),
                    motion::Error::NotPositive(n) => (n, ParamProblem::NotPositive),
                    motion::Error::Negative(n) => (n, ParamProblem::Negative),
                    motion::Error::OutOfRange { parameter, .. } => {
                        (parameter, ParamProblem::OutOfRange)
                    }
                    motion::Error::BeyondReach { parameter, .. } => {
                        (parameter, ParamProblem::BeyondReach)
                    }
                    motion::Error::Ik(e) => return e.into(),
                    _ => return NackReason::InvalidArgument,
                };
                NackReason::InvalidParameter {
                    param: motion_param(param),
                    problem,
                }
            }
            Error::Preflight(f) => NackReason::Preflight {
                leg: f.leg,
                fault: match f.kind {
                    FailureKind::Unreachable(u) => reach_fault(u),
                    FailureKind::Singular { .. } => PreflightFault::Singular,
                    _ => PreflightFault::Other,
                },
            },
            Error::ServoRange { servo, fault } => NackReason::ServoRange {
                leg: servo.leg,
                joint: servo.joint,
                fault,
            },
            Error::OutputsOff => NackReason::OutputsDisabled,
            Error::Busy => NackReason::MotionRunning,
            Error::NotWalking => NackReason::NotWalking,
            Error::Ik(e) => e.into(),
            Error::NotUpright => NackReason::NotUpright,
        }
    }
}
