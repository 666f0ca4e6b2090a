//! The motion requests of the wire through the device: started, reported, stopped and refused
//! with a nack naming the parameter, nothing moved by a refusal.

mod common;

use common::*;
use kin_core::motion::gait::Pattern;
use kin_core::motion::laws::Axis;
use kin_core::motion::path::PathKind;
use quad_protocol::{
    DeviceToHost, LegSet, MotionCommand, MotionKind, MotionParam, MotionStage, NackReason,
    ParamProblem, Request,
};

fn rig() -> (Dev, VirtualClock) {
    let (mut dev, clock) = clocked_device();
    hello(&mut dev);
    (dev, clock)
}

fn refused(a: DeviceToHost) -> NackReason {
    match a {
        DeviceToHost::Nack { reason, .. } => reason,
        other => panic!("not a nack: {other:?}"),
    }
}

#[test]
fn stand_up_sway_stop_and_sit_over_the_wire() {
    let (mut dev, clock) = rig();
    let s = status(ask(
        &mut dev,
        1,
        Request::StartMotion(MotionCommand::StandUp),
    ));
    assert_eq!(s.kind, Some(MotionKind::StandUp));
    assert_eq!(s.stage, MotionStage::Approach);
    assert!(dev.outputs_enabled());
    frames(&mut dev, &clock, 500);
    assert_eq!(status(ask(&mut dev, 2, Request::GetMotion)).kind, None);
    let sway = MotionCommand::Sway {
        axis: Axis::Roll,
        amplitude_rad: 0.1,
        period_s: 4.0,
        duration_s: None,
    };
    assert_eq!(
        status(ask(&mut dev, 3, Request::StartMotion(sway))).kind,
        Some(MotionKind::Sway)
    );
    // A second start is refused, the sway keeps running.
    assert_eq!(
        refused(ask(&mut dev, 4, Request::StartMotion(MotionCommand::Sit))),
        NackReason::MotionRunning
    );
    frames(&mut dev, &clock, 150);
    let s = status(ask(&mut dev, 5, Request::GetMotion));
    assert_eq!(
        (s.kind, s.stage),
        (Some(MotionKind::Sway), MotionStage::Run)
    );
    assert!((0.0..1.0).contains(&s.phase) && s.t_s > 0.0);
    assert_eq!(
        status(ask(&mut dev, 6, Request::StopMotion)).stage,
        MotionStage::Stopping
    );
    frames(&mut dev, &clock, 1_000);
    assert_eq!(status(ask(&mut dev, 7, Request::GetMotion)).kind, None);
    assert_eq!(
        status(ask(&mut dev, 8, Request::StartMotion(MotionCommand::Sit))).kind,
        Some(MotionKind::Sit)
    );
}

#[test]
fn walk_takes_velocity_commands_and_refuses_them_when_not_walking() {
    let (mut dev, clock) = rig();
    let v = Request::SetVelocity {
        forward_m_s: 0.02,
        lateral_m_s: 0.0,
        yaw_rate_rad_s: 0.0,
    };
    assert_eq!(refused(ask(&mut dev, 1, v)), NackReason::NotWalking);
    ask(&mut dev, 2, Request::StartMotion(MotionCommand::StandUp));
    frames(&mut dev, &clock, 500);
    let h = dev.config().pose_config.stance_height_m;
    let walk = MotionCommand::Walk {
        gait: Pattern::Trot,
        body_height_m: h,
        step_height_m: 0.15 * h,
        cycle_s: 0.8,
        velocity_timeout_ms: 500,
    };
    assert_eq!(
        status(ask(&mut dev, 3, Request::StartMotion(walk))).kind,
        Some(MotionKind::Walk)
    );
    // Refreshed at 10 Hz, within the timeout.
    for seq in 100..120 {
        frames(&mut dev, &clock, 5);
        assert_eq!(status(ask(&mut dev, seq, v)).kind, Some(MotionKind::Walk));
    }
    let too_fast = Request::SetVelocity {
        forward_m_s: 50.0,
        lateral_m_s: 0.0,
        yaw_rate_rad_s: 0.0,
    };
    assert_eq!(
        refused(ask(&mut dev, 5, too_fast)),
        NackReason::InvalidParameter {
            param: MotionParam::ForwardMS,
            problem: ParamProblem::OutOfRange,
        }
    );
}

#[test]
fn refused_parameters_name_the_parameter_and_move_nothing() {
    let (mut dev, clock) = rig();
    // The outputs are off: only stand-up may start.
    let path = |cycle_s: f32| MotionCommand::FootPath {
        path: PathKind::Rectangle,
        legs: LegSet::All,
        stride_m: 0.05,
        step_height_m: 0.02,
        duty_factor: 0.5,
        cycle_s,
        duration_s: Some(3.0),
    };
    assert_eq!(
        refused(ask(&mut dev, 1, Request::StartMotion(path(2.0)))),
        NackReason::OutputsDisabled
    );
    ask(&mut dev, 2, Request::StartMotion(MotionCommand::StandUp));
    frames(&mut dev, &clock, 500);
    let before = *dev.output_angles().unwrap();
    let cases = [
        (path(0.0), MotionParam::CycleS, ParamProblem::NotPositive),
        (path(f32::NAN), MotionParam::CycleS, ParamProblem::NonFinite),
        (
            MotionCommand::Sway {
                axis: Axis::Pitch,
                amplitude_rad: 0.1,
                period_s: -1.0,
                duration_s: None,
            },
            MotionParam::PeriodS,
            ParamProblem::NotPositive,
        ),
        (
            MotionCommand::Sway {
                axis: Axis::Pitch,
                amplitude_rad: 0.1,
                period_s: 5.0,
                duration_s: Some(0.0),
            },
            MotionParam::DurationS,
            ParamProblem::NotPositive,
        ),
        (
            MotionCommand::YawTurn {
                yaw_rate_rad_s: f32::INFINITY,
                step_period_s: 6.0,
                lift_height_m: 0.02,
                duration_s: None,
            },
            MotionParam::YawRateRadS,
            ParamProblem::NonFinite,
        ),
    ];
    for (seq, (cmd, param, problem)) in cases.into_iter().enumerate() {
        assert_eq!(
            refused(ask(&mut dev, 10 + seq as u16, Request::StartMotion(cmd))),
            NackReason::InvalidParameter { param, problem },
            "{cmd:?}"
        );
    }
    // Beyond reach: a sway of 1.5 rad fails the constructor's reach check or the preflight.
    let wide = MotionCommand::Sway {
        axis: Axis::Roll,
        amplitude_rad: 1.5,
        period_s: 5.0,
        duration_s: None,
    };
    match refused(ask(&mut dev, 30, Request::StartMotion(wide))) {
        NackReason::InvalidParameter {
            param: MotionParam::AmplitudeRad,
            problem: ParamProblem::BeyondReach,
        }
        | NackReason::Preflight { .. } => {}
        other => panic!("{other:?}"),
    }
    assert_eq!(
        refused(ask(
            &mut dev,
            31,
            Request::SetJointSpeedLimit {
                joint_speed_limit_rad_s: 0.0
            }
        )),
        NackReason::InvalidParameter {
            param: MotionParam::JointSpeedLimitRadS,
            problem: ParamProblem::NotPositive,
        }
    );
    frames(&mut dev, &clock, 10);
    assert_eq!(
        dev.output_angles(),
        Some(&before),
        "a refusal moved a servo"
    );
    assert_eq!(status(ask(&mut dev, 32, Request::GetMotion)).kind, None);
}
