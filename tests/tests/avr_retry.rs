//! Every request safe to retry, on the firmware in simavr: each kind of request is sent, its
//! answer dropped (as a lossy line would), and the same frame sent again; the retry must get
//! the same answer and the request must act once (a `StartMotion` retried while its motion
//! runs gets its `MotionAck` again, not `MotionRunning`). A repeated `seq` with other bytes is
//! a new request. Simulated time; the firmware is built once per test process.

use integration_tests::wire::{self, frame};
use kin_core::motion::gait::{GaitParams, Pattern};
use kin_core::motion::laws::Axis;
use kin_core::{Pose, ReachPolicy, RotationOrder};
use quad_host::emu::build;
use quad_host::link::emulator::{EmulatorConfig, EmulatorLink};
use quad_protocol::{
    DeviceToHost, LinkLossAction, LinkTimeout, MotionCommand, NackReason, PoseConfig, Request,
    ServoId, PROTOCOL_VERSION,
};
use std::time::Duration;

/// How long an answer may take (an EEPROM save the longest).
const TIMEOUT: Duration = Duration::from_secs(3);

/// How long the line is watched after the answer, for a second one.
const AFTER: Duration = Duration::from_millis(40);

/// Sends `bytes` and returns the one answer that arrives within [`TIMEOUT`] (checking for
/// [`AFTER`] more that no second one follows).
fn exchange(link: &mut EmulatorLink, bytes: &[u8]) -> DeviceToHost {
    let answers = wire::answers(link, bytes, TIMEOUT, Some(AFTER));
    assert_eq!(answers.len(), 1, "one answer to one request: {answers:?}");
    answers[0]
}

/// Every kind of request, in an order in which each acts.
fn workload() -> Vec<Request> {
    let servo = ServoId::ALL[11];
    let h = 0.277;
    vec![
        Request::Hello {
            version: PROTOCOL_VERSION,
        },
        Request::GetState,
        Request::SetLinkTimeout(LinkTimeout {
            timeout_ms: 0,
            action: LinkLossAction::Hold,
        }),
        Request::SetPoseConfig(PoseConfig {
            stance_height_m: h,
            order: RotationOrder::Zyx,
            policy: ReachPolicy::Reject,
        }),
        Request::SetOutputs { enabled: true },
        Request::SetBodyPose(Pose {
            roll_rad: 0.05,
            ..Pose::default()
        }),
        Request::SetJointSpeedLimit {
            joint_speed_limit_rad_s: 3.0,
        },
        Request::GetCalibration { servo },
        Request::StartMotion(MotionCommand::StandUp),
        Request::GetMotion,
        Request::StopMotion,
        Request::StartMotion(MotionCommand::Sway {
            axis: Axis::Roll,
            amplitude_rad: 0.1,
            period_s: 2.0,
            duration_s: None,
        }),
        Request::StopMotion,
        Request::StartMotion(MotionCommand::Walk {
            gait: Pattern::Trot,
            body_height_m: h,
            step_height_m: GaitParams::DEFAULT_STEP_HEIGHT_FRACTION * h,
            cycle_s: GaitParams::DEFAULT_CYCLE_S,
            velocity_timeout_ms: 1000,
        }),
        Request::SetVelocity {
            forward_m_s: 0.02,
            lateral_m_s: 0.0,
            yaw_rate_rad_s: 0.0,
        },
        Request::StopMotion,
        Request::SetOutputs { enabled: false },
        Request::SaveCalibration,
    ]
}

/// Polls `GetMotion` (sequence numbers from 60,000 on) until no motion runs.
fn wait_idle(link: &mut EmulatorLink) {
    for seq in 60_000..60_200u16 {
        match exchange(link, &frame(seq, Request::GetMotion)) {
            DeviceToHost::MotionAck { status, .. } if status.kind.is_none() => return,
            DeviceToHost::MotionAck { .. } => {}
            other => panic!("GetMotion: {other:?}"),
        }
    }
    panic!("the motion did not stop");
}

#[test]
fn every_request_retried_after_a_lost_answer_gets_the_same_answer_and_acts_once() {
    let elf = build::firmware_elf(build::FIRMWARE).unwrap_or_else(|e| panic!("{e}"));
    let mut link =
        EmulatorLink::boot(&elf, EmulatorConfig::new(115_200)).unwrap_or_else(|e| panic!("{e}"));
    let mut kinds = 0;
    for (i, request) in workload().into_iter().enumerate() {
        let seq = 100 + i as u16;
        let bytes = frame(seq, request);
        let lost = exchange(&mut link, &bytes);
        assert!(
            !matches!(lost, DeviceToHost::Nack { .. }),
            "{request:?} must act: {lost:?}"
        );
        let retried = exchange(&mut link, &bytes);
        assert_eq!(retried, lost, "the retry of {request:?}");
        kinds += 1;
        if let Request::StopMotion = request {
            wait_idle(&mut link);
        }
        if let Request::StartMotion(_) = request {
            // Had it acted again, the running motion would have refused it.
            assert!(matches!(retried, DeviceToHost::MotionAck { .. }));
        }
    }
    assert_eq!(kinds, 18);
}

#[test]
fn a_repeated_seq_with_other_bytes_is_a_new_request() {
    let elf = build::firmware_elf(build::FIRMWARE).unwrap_or_else(|e| panic!("{e}"));
    let mut link =
        EmulatorLink::boot(&elf, EmulatorConfig::new(115_200)).unwrap_or_else(|e| panic!("{e}"));
    let hello = Request::Hello {
        version: PROTOCOL_VERSION,
    };
    assert!(matches!(
        exchange(&mut link, &frame(1, hello)),
        DeviceToHost::HelloAck { .. }
    ));
    let enable = Request::SetOutputs { enabled: true };
    assert!(matches!(
        exchange(&mut link, &frame(3, enable)),
        DeviceToHost::Ack { .. }
    ));
    let sway = |amplitude_rad| {
        Request::StartMotion(MotionCommand::Sway {
            axis: Axis::Pitch,
            amplitude_rad,
            period_s: 2.0,
            duration_s: None,
        })
    };
    let first = exchange(&mut link, &frame(2, sway(0.05)));
    assert!(matches!(first, DeviceToHost::MotionAck { .. }), "{first:?}");
    // The same seq, another amplitude: a new request, refused while the first sway runs.
    assert!(matches!(
        exchange(&mut link, &frame(2, sway(0.06))),
        DeviceToHost::Nack {
            seq: Some(2),
            reason: NackReason::MotionRunning
        }
    ));
    // The first request again after another one in between: no longer the last answered,
    // so a new request too.
    assert!(matches!(
        exchange(&mut link, &frame(2, sway(0.05))),
        DeviceToHost::Nack {
            seq: Some(2),
            reason: NackReason::MotionRunning
        }
    ));
}
