//! What protocol 2.3 appended, through the device on the in-memory fakes: the motion ack's
//! frame numbers ([`MotionFrames`]) — sent to a host of minor 3 or later only, the run frame
//! from which a velocity command applies in its own answer, the frame at which a stop took
//! effect (a `StopMotion` or the walk's velocity timeout).

mod common;

use common::*;
use kin_core::motion::gait::Pattern;
use quad_device::{engine::FRAME_S, Config};
use quad_protocol::{
    DeviceToHost, MotionCommand, MotionFrames, MotionStage, MotionStatus, Request,
};

fn rig(host_version: u16) -> (Dev, VirtualClock) {
    let (mut dev, clock) = clocked_device();
    let hello = ask(
        &mut dev,
        0,
        Request::Hello {
            version: host_version,
        },
    );
    assert!(matches!(hello, DeviceToHost::HelloAck { .. }), "{hello:?}");
    (dev, clock)
}

fn parts(a: DeviceToHost) -> (MotionStatus, Option<MotionFrames>) {
    match a {
        DeviceToHost::MotionAck { status, frames, .. } => (status, frames),
        other => panic!("not a motion ack: {other:?}"),
    }
}

/// The run frame a status reports in `t_s`.
fn run_frame(s: &MotionStatus) -> u16 {
    (s.t_s / FRAME_S).round() as u16
}

fn trot(dev: &mut Dev, clock: &VirtualClock, timeout_ms: u16) {
    ask(dev, 1, Request::StartMotion(MotionCommand::StandUp));
    frames(dev, clock, 300);
    let h = Config::fernando2025().pose_config.stance_height_m;
    let mut walk = MotionCommand::walk(Pattern::Trot, h);
    if let MotionCommand::Walk {
        velocity_timeout_ms,
        ..
    } = &mut walk
    {
        *velocity_timeout_ms = timeout_ms;
    }
    let (s, f) = parts(ask(dev, 2, Request::StartMotion(walk)));
    assert_eq!(s.stage, MotionStage::Approach);
    assert_eq!(f.and_then(|f| f.stop_frame), None);
}

fn velocity(forward_m_s: f32) -> Request {
    Request::SetVelocity {
        forward_m_s,
        lateral_m_s: 0.0,
        yaw_rate_rad_s: 0.0,
    }
}

#[test]
fn a_two_two_host_gets_the_motion_ack_of_two_two() {
    let (mut dev, clock) = rig(0x0202);
    trot(&mut dev, &clock, 1_000);
    for seq in 10..14 {
        frames(&mut dev, &clock, 7);
        let (_, f) = parts(ask(&mut dev, seq, velocity(0.02)));
        assert_eq!(f, None);
    }
}

#[test]
fn velocity_commands_and_the_stop_report_the_frame_they_took_effect() {
    let (mut dev, clock) = rig(0x0203);
    assert_eq!(dev.peer_minor(), 3);
    trot(&mut dev, &clock, 1_000);
    // The approach counts its ramp's steps (none when the walk starts at the stance).
    let mut last_step = 0;
    let run = loop {
        frames(&mut dev, &clock, 1);
        let (s, f) = parts(ask(&mut dev, 3, Request::GetMotion));
        let f = f.expect("frames to a 2.3 host");
        if s.stage != MotionStage::Approach {
            break (s, f);
        }
        assert!(f.frame >= last_step, "{f:?}");
        last_step = f.frame;
    };
    assert_eq!(run.0.stage, MotionStage::Run);
    for (seq, v) in (10..).zip([0.02, 0.04, 0.0, 0.03]) {
        frames(&mut dev, &clock, 9);
        let (s, f) = parts(ask(&mut dev, seq, velocity(v)));
        let f = f.unwrap();
        assert_eq!(s.stage, MotionStage::Run);
        // The answer's frame is the run frame the velocity applies from: the status' time.
        assert_eq!(f.frame, run_frame(&s), "{s:?} {f:?}");
        assert_eq!(Some(f.frame as u32), dev.motion_status().velocity_frame);
        assert_eq!(f.stop_frame, None);
    }
    frames(&mut dev, &clock, 5);
    let (s, f) = parts(ask(&mut dev, 20, Request::StopMotion));
    let f = f.unwrap();
    let stop = run_frame(&s);
    assert_eq!(s.stage, MotionStage::Stopping);
    assert_eq!(f.stop_frame, Some(stop));
    // Later answers keep it while the frames go on.
    frames(&mut dev, &clock, 10);
    let (s, f) = parts(ask(&mut dev, 21, Request::GetMotion));
    let f = f.unwrap();
    assert_eq!(f.stop_frame, Some(stop));
    assert_eq!(f.frame, stop + 10);
    assert_eq!(f.frame, run_frame(&s));
    // Idle: frame 0, no stop.
    frames(&mut dev, &clock, 600);
    let (s, f) = parts(ask(&mut dev, 22, Request::GetMotion));
    assert_eq!(s.stage, MotionStage::Idle);
    assert_eq!(
        f,
        Some(MotionFrames {
            frame: 0,
            stop_frame: None
        })
    );
}

#[test]
fn the_velocity_timeout_reports_its_stop_frame() {
    let (mut dev, clock) = rig(0x0203);
    trot(&mut dev, &clock, 200);
    // The approach, then the run with one command and silence.
    loop {
        frames(&mut dev, &clock, 1);
        if parts(ask(&mut dev, 3, Request::GetMotion)).0.stage == MotionStage::Run {
            break;
        }
    }
    frames(&mut dev, &clock, 3);
    let (s, _) = parts(ask(&mut dev, 4, velocity(0.03)));
    let from = run_frame(&s);
    // 200 ms of silence: the tick after more than 10 frames stops the walk.
    frames(&mut dev, &clock, 12);
    let status = dev.motion_status();
    assert_eq!(status.stop_frame, Some(from as u32 + 10), "{status:?}");
    assert_eq!(status.stage, MotionStage::Stopping);
}
