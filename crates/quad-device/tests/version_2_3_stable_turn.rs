//! What protocol 2.3 appended, through the device on the in-memory fakes: the statically stable
//! yaw turn (`MotionCommand::StableTurn`), reported as its own kind to a host of minor 3 and as
//! the yaw turn to an older host.

mod common;

use common::*;
use quad_device::Config;
use quad_protocol::{
    DeviceToHost, MotionCommand, MotionKind, MotionParam, MotionStage, NackReason, ParamProblem,
    Request, PROTOCOL_VERSION,
};

fn rig(host_version: u16) -> (Dev, VirtualClock) {
    let (mut dev, clock) = clocked_device();
    assert!(matches!(
        ask(
            &mut dev,
            0,
            Request::Hello {
                version: host_version
            }
        ),
        DeviceToHost::HelloAck { info, .. } if info.version == PROTOCOL_VERSION
    ));
    (dev, clock)
}

fn stable_turn() -> MotionCommand {
    let h = Config::shahriar2023().pose_config.stance_height_m;
    MotionCommand::stable_turn(h, None)
}

#[test]
fn the_stable_turn_runs_and_is_reported_by_its_kind_to_a_two_three_host() {
    let (mut dev, clock) = rig(0x0203);
    ask(&mut dev, 1, Request::StartMotion(MotionCommand::StandUp));
    frames(&mut dev, &clock, 500);
    let started = status(ask(&mut dev, 2, Request::StartMotion(stable_turn())));
    assert_eq!(started.kind, Some(MotionKind::StableTurn));
    frames(&mut dev, &clock, 300);
    let running = status(ask(&mut dev, 3, Request::GetMotion));
    assert_eq!(running.kind, Some(MotionKind::StableTurn));
    assert_eq!(running.stage, MotionStage::Run);
    assert_eq!(running.fault, None);
}

#[test]
fn a_two_two_host_sees_a_running_stable_turn_as_the_yaw_turn() {
    let (mut dev, clock) = rig(0x0203);
    ask(&mut dev, 1, Request::StartMotion(MotionCommand::StandUp));
    frames(&mut dev, &clock, 500);
    ask(&mut dev, 2, Request::StartMotion(stable_turn()));
    frames(&mut dev, &clock, 100);
    ask(&mut dev, 3, Request::Hello { version: 0x0202 });
    let seen = status(ask(&mut dev, 4, Request::GetMotion));
    assert_eq!(seen.kind, Some(MotionKind::YawTurn));
    assert_eq!(seen.stage, MotionStage::Run);
}

#[test]
fn a_stable_turn_out_of_range_is_refused_naming_its_field() {
    let (mut dev, _) = rig(PROTOCOL_VERSION);
    let MotionCommand::StableTurn {
        yaw_per_cycle_rad,
        cycle_s,
        lift_height_m,
        duration_s,
        ..
    } = stable_turn()
    else {
        unreachable!()
    };
    let bad = MotionCommand::StableTurn {
        yaw_per_cycle_rad,
        cycle_s,
        lift_height_m,
        shift_fraction: 1.5,
        duration_s,
    };
    let answer = ask(&mut dev, 5, Request::StartMotion(bad));
    assert!(
        matches!(
            answer,
            DeviceToHost::Nack {
                reason: NackReason::InvalidParameter {
                    param: MotionParam::ShiftFraction,
                    problem: ParamProblem::OutOfRange
                },
                ..
            }
        ),
        "{answer:?}"
    );
}
