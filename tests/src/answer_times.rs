//! How long the emulated firmware takes to answer each kind of request: from the request's
//! first byte on the line to the answer's last byte, in simulated time, at the line rate of
//! the firmware it runs. The cases cover every request kind and every motion, in an order in
//! which each acts (and the longest variants of each: the body poses the IK works hardest on,
//! an unreachable pose, every sway axis, every foot path, both gaits).

use crate::wire::{frame, timed_answer};
use kin_core::motion::gait::{GaitParams, Pattern};
use kin_core::motion::laws::Axis;
use kin_core::motion::path::PathKind;
use kin_core::{LegId, Pose, ReachPolicy, RotationOrder};
use quad_host::link::emulator::EmulatorLink;
use quad_host::link::Link;
use quad_protocol::{
    timing, BalanceConfig, DeviceToHost, LegSet, LinkLossAction, LinkTimeout, MotionCommand,
    PoseConfig, Request, SafeState, ServoId, PROTOCOL_VERSION,
};
use std::time::Duration;

/// The stance height of the default robot, m.
const STANCE_HEIGHT_M: f32 = 0.277;

/// The longest any answer may take before the measurement calls it lost.
pub const PATIENCE: Duration = Duration::from_secs(5);

/// One measured exchange.
#[derive(Debug, Clone)]
pub struct Measured {
    /// What was sent.
    pub request: Request,
    /// Its row of the answer-time table.
    pub kind: timing::Kind,
    /// What came back.
    pub answer: DeviceToHost,
    /// Request's first byte on the line → answer's last byte.
    pub elapsed: Duration,
}

/// A step of the workload: a request, [`POLL_GAP`] of silence, or waiting until the running
/// motion has ended.
enum Step {
    Send(Request),
    Pause,
    WaitIdle,
}

fn sway(axis: Axis) -> Request {
    Request::StartMotion(MotionCommand::Sway {
        axis,
        amplitude_rad: 0.15,
        period_s: 2.0,
        duration_s: None,
    })
}

fn foot_path(path: PathKind, legs: LegSet) -> Request {
    Request::StartMotion(MotionCommand::FootPath {
        path,
        legs,
        stride_m: 0.06,
        step_height_m: 0.03,
        duty_factor: 0.5,
        cycle_s: 2.0,
        duration_s: None,
    })
}

fn walk(gait: Pattern) -> Request {
    Request::StartMotion(MotionCommand::Walk {
        gait,
        body_height_m: STANCE_HEIGHT_M,
        step_height_m: GaitParams::DEFAULT_STEP_HEIGHT_FRACTION * STANCE_HEIGHT_M,
        cycle_s: GaitParams::DEFAULT_CYCLE_S,
        velocity_timeout_ms: 1000,
    })
}

/// Every kind of request, the motions each started and stopped.
fn workload() -> Vec<Step> {
    use Step::{Pause, Send, WaitIdle};
    let servo = ServoId::ALL[11];
    // The running motion polled at several phases of its frames, then stopped.
    let stop = |steps: &mut Vec<Step>| {
        for _ in 0..6 {
            steps.push(Pause);
            steps.push(Send(Request::GetMotion));
        }
        steps.push(Send(Request::StopMotion));
        steps.push(WaitIdle);
    };
    let mut steps = vec![
        Send(Request::Hello {
            version: PROTOCOL_VERSION,
        }),
        Send(Request::GetState),
        Send(Request::SetLinkTimeout(LinkTimeout {
            timeout_ms: 0,
            action: LinkLossAction::Hold,
        })),
        Send(Request::SetPoseConfig(PoseConfig {
            stance_height_m: STANCE_HEIGHT_M,
            order: RotationOrder::Zyx,
            policy: ReachPolicy::Reject,
        })),
        Send(Request::SetOutputs { enabled: true }),
    ];
    for pose in [
        Pose::default(),
        Pose::rotation(0.1, -0.05, 0.08),
        Pose {
            roll_rad: -0.2,
            pitch_rad: 0.15,
            yaw_rad: -0.2,
            x_m: 0.02,
            y_m: -0.02,
            z_m: 0.03,
        },
        // Out of reach: the nack names the leg.
        Pose {
            z_m: -0.3,
            ..Pose::default()
        },
    ] {
        steps.push(Send(Request::SetBodyPose(pose)));
    }
    steps.push(Send(Request::SetFeet {
        feet_in_body_m: core::array::from_fn(|i| {
            let x = if i < 2 { 0.3 } else { -0.3 };
            let y = if i % 2 == 0 { 0.184 } else { -0.184 };
            [x, y, -STANCE_HEIGHT_M]
        }),
    }));
    steps.push(Send(Request::SetJoints {
        angles_rad: [
            0.0, 0.5, -1.0, 0.0, 0.5, -1.0, 0.0, 0.5, -1.0, 0.0, 0.5, -1.0,
        ],
    }));
    steps.push(Send(Request::SetJointSpeedLimit {
        joint_speed_limit_rad_s: 6.0,
    }));
    // The balance requests (2.3): the firmware without a sensor takes every setting but
    // leveling.
    let balance = |safe_state| {
        Request::SetBalance(BalanceConfig {
            safe_state,
            ..BalanceConfig::DEFAULT
        })
    };
    steps.push(Send(Request::GetImu));
    steps.push(Send(balance(SafeState::Off)));
    steps.push(Send(balance(SafeState::Rest)));
    steps.push(Send(Request::GetCalibration { servo }));
    // The calibration sent back is the one read (see `measure`).
    steps.push(Send(Request::GetCalibration { servo }));
    steps.push(Send(Request::SaveCalibration));
    steps.push(Send(Request::StartMotion(MotionCommand::StandUp)));
    steps.push(WaitIdle);
    for axis in [Axis::Roll, Axis::Pitch, Axis::Yaw] {
        steps.push(Send(sway(axis)));
        // The balance requests while the motion's frames run.
        for request in [Request::GetImu, balance(SafeState::Rest)] {
            steps.push(Pause);
            steps.push(Send(request));
        }
        stop(&mut steps);
    }
    steps.push(Send(Request::StartMotion(MotionCommand::YawTurn {
        yaw_rate_rad_s: 0.2,
        step_period_s: 1.0,
        lift_height_m: 0.03,
        duration_s: None,
    })));
    stop(&mut steps);
    steps.push(Send(Request::StartMotion(MotionCommand::StableTurn {
        yaw_per_cycle_rad: 0.2,
        cycle_s: 2.0,
        lift_height_m: 0.03,
        shift_fraction: 0.8,
        duration_s: None,
    })));
    stop(&mut steps);
    for path in PathKind::ALL {
        for legs in [LegSet::All, LegSet::One(LegId::FL)] {
            steps.push(Send(foot_path(path, legs)));
            stop(&mut steps);
        }
    }
    for gait in [Pattern::Trot, Pattern::Walk] {
        steps.push(Send(walk(gait)));
        steps.push(Send(Request::SetVelocity {
            forward_m_s: 0.02,
            lateral_m_s: 0.0,
            yaw_rate_rad_s: 0.05,
        }));
        stop(&mut steps);
    }
    steps.push(Send(Request::StartMotion(MotionCommand::Sit)));
    steps.push(WaitIdle);
    steps.push(Send(Request::StartMotion(MotionCommand::Rest)));
    steps.push(WaitIdle);
    steps.push(Send(Request::SetOutputs { enabled: false }));
    // The robot's requests (2.4), with the robot the firmware holds (nothing changes).
    steps.push(Send(Request::GetRobot));
    steps.push(Send(Request::SetRobot(
        quad_device::Config::shahriar2023().description(),
    )));
    steps.push(Send(Request::SaveRobot));
    steps
}

/// Runs the workload on `link` (a freshly booted firmware) and returns every exchange.
///
/// # Panics
/// When an answer does not come within [`PATIENCE`], or a request the workload expects to act
/// is refused (other than the unreachable pose).
pub fn measure(link: &mut EmulatorLink) -> Vec<Measured> {
    let mut out = Vec::new();
    let mut seq = 1u16;
    let mut calibration = None;
    for step in workload() {
        let request = match step {
            Step::WaitIdle => {
                wait_idle(link, &mut seq, &mut out);
                continue;
            }
            Step::Pause => {
                pause(link, POLL_GAP);
                continue;
            }
            // The second read turns into a write of what the first read.
            Step::Send(Request::GetCalibration { servo }) if calibration.is_some() => {
                Request::SetCalibration {
                    servo,
                    calibration: calibration.take().expect("read"),
                }
            }
            Step::Send(request) => request,
        };
        // A velocity command is repeated at several phases of the walk's frames.
        let times = if matches!(request, Request::SetVelocity { .. }) {
            8
        } else {
            1
        };
        for _ in 0..times {
            let m = exchange(link, &mut seq, request);
            if let DeviceToHost::Calibration { calibration: c, .. } = m.answer {
                calibration = Some(c);
            }
            let refused = matches!(m.answer, DeviceToHost::Nack { .. });
            let unreachable = matches!(request, Request::SetBodyPose(p) if p.z_m < -0.2);
            assert_eq!(refused, unreachable, "{request:?} → {:?}", m.answer);
            out.push(m);
            if times > 1 {
                pause(link, POLL_GAP);
            }
        }
    }
    out
}

/// The pause between two polls of a running motion: not a divisor of the 20 ms servo frame,
/// so that the polls land at every phase of the frame's computation.
const POLL_GAP: Duration = Duration::from_millis(37);

/// Lets `gap` of line time pass with nothing sent.
fn pause(link: &mut EmulatorLink, gap: Duration) {
    let mut none = [0u8; 1];
    let n = link.recv(&mut none, gap).expect("recv");
    assert_eq!(n, 0, "a byte nobody asked for");
}

/// Sends `request` and returns the measured exchange.
fn exchange(link: &mut EmulatorLink, seq: &mut u16, request: Request) -> Measured {
    let (answer, elapsed) = timed_answer(link, &frame(*seq, request), PATIENCE)
        .unwrap_or_else(|| panic!("no answer to {request:?} within {PATIENCE:?}"));
    *seq = seq.wrapping_add(1);
    Measured {
        request,
        kind: timing::Kind::of(&request),
        answer,
        elapsed,
    }
}

/// Polls `GetMotion` every [`POLL_GAP`] until no motion runs (20 s at most); the polls are
/// measured too.
fn wait_idle(link: &mut EmulatorLink, seq: &mut u16, out: &mut Vec<Measured>) {
    for _ in 0..540 {
        pause(link, POLL_GAP);
        let m = exchange(link, seq, Request::GetMotion);
        let idle = match m.answer {
            DeviceToHost::MotionAck { status, .. } => status.kind.is_none(),
            other => panic!("GetMotion: {other:?}"),
        };
        out.push(m);
        if idle {
            return;
        }
    }
    panic!("the motion did not end");
}

/// The longest of `measured` per kind, in table order.
pub fn worst(measured: &[Measured]) -> Vec<(timing::Kind, Duration)> {
    timing::Kind::ALL
        .iter()
        .map(|&k| {
            let t = measured
                .iter()
                .filter(|m| m.kind == k)
                .map(|m| m.elapsed)
                .max()
                .unwrap_or_else(|| panic!("no case of {k:?}"));
            (k, t)
        })
        .collect()
}
