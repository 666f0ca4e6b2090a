//! The panel's device session on the simulated device, without a browser: the checks before
//! sending, the jog, the onboard motions, and the link-loss rule when the controlling page
//! goes away.

use kin_core::body::Pose;
use kin_core::motion::laws::Axis;
use kin_core::Robot;
use quad_host::client::{AngleCheck, Client, ClientConfig};
use quad_host::link::{self, sim::SimConfig, Link, Target};
use quad_protocol::MotionCommand;
use quad_protocol::{LinkLossAction, LinkTimeout, NackReason, Request, RobotPreset, ServoId};
use quad_web::device::{Error, Session};
use quad_web::motion::VelocityMsg;
use quad_web::msg::ClientMsg;
use std::time::Duration;

fn session(action: LinkLossAction) -> Session<Box<dyn Link>> {
    let target = Target::Sim {
        preset: RobotPreset::Shahriar2023,
        config: SimConfig::default(),
        storage: None,
    };
    let mut client = Client::new(
        link::open(&target).unwrap(),
        ClientConfig::sim(Duration::ZERO),
    );
    client.hello().unwrap();
    client
        .ack(Request::SetLinkTimeout(LinkTimeout {
            timeout_ms: 0,
            action,
        }))
        .unwrap();
    Session::connect(client, Some(Robot::shahriar2023()), AngleCheck::Exact).unwrap()
}

#[test]
fn a_pose_the_host_rejects_is_not_sent() {
    let mut s = session(LinkLossAction::Hold);
    let before = s.state(0.0);
    let err = s.set_pose(Pose::rotation(1.5, 0.0, 0.0), 1).unwrap_err();
    assert!(matches!(err, Error::HostRejects(_)), "{err}");
    let after = s.state(0.0);
    assert_eq!(after.poses_sent, 0);
    assert_eq!(after.link.frames_sent, before.link.frames_sent);
    assert_eq!(after.angles_rad, before.angles_rad);
    s.set_pose(Pose::rotation(0.1, 0.0, 0.0), 2).unwrap();
    assert_eq!(s.state(0.0).pose_id, 2);
    assert_eq!(s.state(0.0).poses_sent, 1);
}

#[test]
fn a_jog_moves_the_pulse_by_its_step() {
    let mut s = session(LinkLossAction::Hold);
    s.set_outputs(true).unwrap();
    let servo = ServoId::ALL[1];
    let p0 = s.state(0.0).pulses_us[1];
    s.jog(servo, 10).unwrap();
    s.jog(servo, -1).unwrap();
    assert_eq!(s.state(0.0).pulses_us[1] - p0, 9.0);
    // A centre beyond the travel is refused before it is sent.
    let frames = s.state(0.0).link.frames_sent;
    let err = s.set_center(servo, 2700).unwrap_err();
    assert!(matches!(err, Error::BadCalibration { .. }), "{err}");
    assert_eq!(s.state(0.0).link.frames_sent, frames);
}

#[test]
fn losing_the_controlling_page_applies_the_link_loss_rule() {
    let mut s = session(LinkLossAction::Disable);
    s.set_outputs(true).unwrap();
    assert!(s.state(0.0).flags.outputs_enabled);
    s.control_lost().unwrap();
    assert!(!s.state(0.0).flags.outputs_enabled);

    let mut s = session(LinkLossAction::Hold);
    s.set_outputs(true).unwrap();
    s.control_lost().unwrap();
    assert!(s.state(0.0).flags.outputs_enabled);
}

/// Lets the device run (link time) until no motion runs; at most `limit`.
fn run_to_idle(s: &mut Session<Box<dyn Link>>, limit: Duration) {
    let t0 = s.link_elapsed();
    loop {
        s.idle(Duration::from_millis(50)).unwrap();
        s.poll().unwrap();
        if s.state(0.0).motion.kind.is_none() {
            return;
        }
        assert!(
            s.link_elapsed() - t0 < limit,
            "still running: {:?}",
            s.state(0.0).motion
        );
    }
}

fn sway(amplitude_rad: f32, period_s: f32) -> ClientMsg {
    ClientMsg::StartMotion {
        motion: MotionCommand::Sway {
            axis: Axis::Roll,
            amplitude_rad,
            period_s,
            duration_s: None,
        },
    }
}

#[test]
fn motions_run_on_the_device_and_report_its_engine() {
    let mut s = session(LinkLossAction::Hold);
    let stand = ClientMsg::StartMotion {
        motion: MotionCommand::StandUp,
    };
    s.command(&stand).unwrap();
    let m = s.state(0.0).motion;
    assert_eq!(m.kind, Some("stand_up"));
    assert!(
        s.state(0.0).flags.outputs_enabled,
        "a stand-up switches them on"
    );
    run_to_idle(&mut s, Duration::from_secs(10));
    let stance = s.state(0.0).angles_rad;

    // A roll sway: the readback follows the device's motion, its status the engine's.
    s.command(&sway(0.1, 1.0)).unwrap();
    assert_eq!(s.state(0.0).motion.kind, Some("sway"));
    assert_eq!(s.state(0.0).pose, None, "a motion replaces the held pose");
    let mut moved = false;
    let mut phases = Vec::new();
    for _ in 0..30 {
        s.idle(Duration::from_millis(50)).unwrap();
        s.poll().unwrap();
        let st = s.state(0.0);
        moved |= st.angles_rad != stance;
        phases.push(st.motion.phase);
    }
    assert!(moved, "the sway moved the joints");
    assert!(phases.iter().all(|p| (0.0..1.0).contains(p)), "{phases:?}");
    assert!(phases.windows(2).any(|w| w[1] > w[0]), "{phases:?}");
    // A second start is refused while it runs: the device's typed nack, in words.
    let err = s.command(&stand).unwrap_err();
    assert!(
        matches!(
            err,
            Error::MotionRefused {
                reason: NackReason::MotionRunning,
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("stop it first"), "{err}");
    // Stop: the period ends, the ramp back to the stance, idle.
    s.command(&ClientMsg::StopMotion).unwrap();
    let stage = s.state(0.0).motion.stage;
    assert!(["stopping", "leave"].contains(&stage), "{stage}");
    run_to_idle(&mut s, Duration::from_secs(10));
    let m = s.state(0.0).motion;
    assert_eq!((m.kind, m.fault), (None, None));
    for (a, b) in s.state(0.0).angles_rad.iter().zip(&stance) {
        assert!((a - b).abs() < 1e-4, "back at the stance: {a} vs {b}");
    }
}

#[test]
fn a_parameter_the_device_refuses_is_named_and_moves_nothing() {
    let mut s = session(LinkLossAction::Hold);
    s.command(&ClientMsg::StartMotion {
        motion: MotionCommand::StandUp,
    })
    .unwrap();
    run_to_idle(&mut s, Duration::from_secs(10));
    let before = s.state(0.0);
    // An amplitude no leg reaches: the device's nack, naming the page's field.
    let err = s.command(&sway(1.5, 2.0)).unwrap_err();
    assert!(matches!(err, Error::MotionRefused { .. }), "{err}");
    assert!(err.to_string().contains("amplitude_rad"), "{err}");
    assert_eq!(err.field(), Some("amplitude_rad"));
    let after = s.state(0.0);
    assert!(
        after.link.frames_sent > before.link.frames_sent,
        "it was sent"
    );
    assert_eq!(after.angles_rad, before.angles_rad);
    assert_eq!(after.motion.kind, None);
    // A velocity without a walk.
    let err = s
        .command(&ClientMsg::SetVelocity {
            velocity: VelocityMsg {
                forward_m_s: 0.05,
                lateral_m_s: 0.0,
                yaw_rate_rad_s: 0.0,
            },
        })
        .unwrap_err();
    assert!(
        matches!(
            err,
            Error::MotionRefused {
                reason: NackReason::NotWalking,
                ..
            }
        ),
        "{err}"
    );
    // A period of 0 is the page message's own check: nothing sent.
    let frames = s.state(0.0).link.frames_sent;
    let err = s.command(&sway(0.1, 0.0)).unwrap_err();
    assert!(matches!(err, Error::Motion { .. }), "{err}");
    assert_eq!(err.field(), Some("period_s"));
    assert_eq!(s.state(0.0).link.frames_sent, frames);
}

#[test]
fn losing_the_controlling_page_stops_a_running_motion_cleanly() {
    let mut s = session(LinkLossAction::Hold);
    s.command(&ClientMsg::StartMotion {
        motion: MotionCommand::StandUp,
    })
    .unwrap();
    run_to_idle(&mut s, Duration::from_secs(10));
    s.command(&sway(0.1, 1.0)).unwrap();
    s.idle(Duration::from_millis(300)).unwrap();
    s.control_lost().unwrap();
    let stage = s.state(0.0).motion.stage;
    assert!(["stopping", "leave"].contains(&stage), "{stage}");
    run_to_idle(&mut s, Duration::from_secs(10));
    assert!(
        s.state(0.0).flags.outputs_enabled,
        "hold keeps the outputs on"
    );

    // `disable`: the outputs go off, which cancels the motion.
    let mut s = session(LinkLossAction::Disable);
    s.command(&ClientMsg::StartMotion {
        motion: MotionCommand::StandUp,
    })
    .unwrap();
    run_to_idle(&mut s, Duration::from_secs(10));
    s.command(&sway(0.1, 1.0)).unwrap();
    s.control_lost().unwrap();
    s.poll().unwrap();
    assert!(!s.state(0.0).flags.outputs_enabled);
    assert_eq!(s.state(0.0).motion.kind, None);
}

/// A session on the simulated device whose sensor reads `source` (see `SimLink::attach_imu`).
fn session_with_imu(source: quad_host::emu::SharedImuSource) -> Session<Box<dyn Link>> {
    let config = quad_device::Config::for_preset(RobotPreset::Shahriar2023).unwrap();
    let mut sim = link::sim::SimLink::new(
        SimConfig::default(),
        config,
        link::sim::EepromImage::erased(),
    )
    .unwrap();
    sim.attach_imu(source);
    let client = Client::new(
        Box::new(sim) as Box<dyn Link>,
        ClientConfig::sim(Duration::ZERO),
    );
    Session::connect(client, Some(Robot::shahriar2023()), AngleCheck::Exact).unwrap()
}

#[test]
fn the_sensor_report_reaches_the_state_and_the_switch_sets_leveling() {
    let mut s = session(LinkLossAction::Hold);
    // Read at connection: level and still, its gyro bias being measured for a second.
    let imu = s.state(0.0).imu.expect("a report from a 2.3 device");
    assert_eq!(imu.health, "starting");
    assert!(!imu.leveling);
    s.idle(Duration::from_millis(1200)).unwrap();
    let frames = s.state(0.0).link.frames_sent;
    s.read_imu().unwrap();
    let state = s.state(0.0);
    assert_eq!(state.link.frames_sent, frames + 1, "one GetImu");
    let imu = state.imu.unwrap();
    assert_eq!(imu.health, "ok");
    assert!(
        imu.roll_rad.abs() < 0.01 && imu.pitch_rad.abs() < 0.01,
        "{imu:?}"
    );
    assert!(imu.samples > 0);
    let imu_rtt_ms = state.link.rtt_ms;
    s.poll().unwrap();
    let poll_rtt_ms = s.state(0.0).link.rtt_ms;
    println!(
        "GetImu round trip {imu_rtt_ms:.2} ms, GetMotion {poll_rtt_ms:.2} ms (simulated line, 115200 baud)"
    );
    // The switch: on, as the device reports it; the other settings kept; off again.
    s.command(&ClientMsg::SetBalance { leveling: true })
        .unwrap();
    let report = *s.imu().unwrap();
    assert!(report.config.leveling);
    assert_eq!(
        quad_protocol::BalanceConfig {
            leveling: false,
            ..report.config
        },
        quad_protocol::BalanceConfig::DEFAULT
    );
    assert!(s.state(0.0).imu.unwrap().leveling);
    s.set_balance(false).unwrap();
    assert!(!s.state(0.0).imu.unwrap().leveling);
}

#[test]
fn without_a_sensor_the_switch_is_refused_in_words() {
    use quad_device::imu::{ImuFault, ImuReading};
    use quad_device::sim::imu::Feed;
    let mut s = session_with_imu(quad_host::emu::SharedImuSource::new(Feed(|_t: f64| {
        ImuReading::Fault(ImuFault::Absent)
    })));
    s.idle(Duration::from_millis(200)).unwrap();
    s.read_imu().unwrap();
    assert_eq!(s.state(0.0).imu.unwrap().health, "absent");
    let err = s.set_balance(true).unwrap_err();
    assert!(
        matches!(err, Error::BalanceRefused(NackReason::ImuAbsent)),
        "{err}"
    );
    let words = err.to_string();
    assert!(
        words.contains("refused SetBalance") && words.contains("no sensor"),
        "{words}"
    );
    assert_eq!(err.field(), None);
    let imu = s.state(0.0).imu.unwrap();
    assert!(!imu.leveling, "nothing changed");
    assert_eq!(imu.health, "absent");
    // Switching off is no refusal.
    s.set_balance(false).unwrap();
}

/// Poses streamed in `span` of link time, reading the sensor every `imu_every` (if any), as
/// the server's device thread interleaves its reads with a page's stream of poses.
fn poses_streamed(span: Duration, imu_every: Option<Duration>) -> u32 {
    let mut s = session(LinkLossAction::Hold);
    let t0 = s.link_elapsed();
    let mut next_imu = t0;
    let mut n = 0u32;
    while s.link_elapsed() - t0 < span {
        if let Some(every) = imu_every {
            if s.link_elapsed() >= next_imu {
                s.read_imu().unwrap();
                next_imu += every;
            }
        }
        let roll_rad = 0.1 * ((n % 20) as f32 / 20.0);
        s.set_pose(Pose::rotation(roll_rad, 0.0, 0.0), n + 1)
            .unwrap();
        n += 1;
    }
    n
}

#[test]
fn reading_the_sensor_at_its_rate_leaves_the_pose_stream_its_line() {
    let span = Duration::from_secs(5);
    let alone = poses_streamed(span, None);
    let with_imu = poses_streamed(span, Some(quad_web::balance::IMU_PERIOD));
    let ratio = f64::from(with_imu) / f64::from(alone);
    println!(
        "poses in {} s of a 115200 baud simulated line: {alone} alone, {with_imu} with the sensor read every {} ms ({:.1} %)",
        span.as_secs(),
        quad_web::balance::IMU_PERIOD.as_millis(),
        ratio * 100.0
    );
    assert!(ratio >= 0.9, "{ratio}");
}

/// The guide's view in the state.
fn guide(s: &Session<Box<dyn Link>>) -> quad_host::ops::calibrate::guide::View {
    s.state(0.0).guide.expect("a guide")
}

fn key(s: &mut Session<Box<dyn Link>>, name: &str) {
    let cmd = ClientMsg::parse(&format!(r#"{{"type":"guide_key","key":"{name}"}}"#)).unwrap();
    s.command(&cmd).unwrap();
}

#[test]
fn the_guided_calibration_walks_the_steps_and_saves() {
    let mut s = session(LinkLossAction::Hold);
    assert!(matches!(
        s.command(&ClientMsg::parse(r#"{"type":"guide_key","key":"n"}"#).unwrap()),
        Err(Error::NoGuide)
    ));
    s.command(&ClientMsg::GuideStart).unwrap();
    let v = guide(&s);
    assert_eq!(v.step, "posture");
    // The outputs came on through the stand-up; the device holds the posture.
    assert!(s.state(0.0).flags.outputs_enabled);
    assert_eq!(s.state(0.0).angles_rad, v.posture_rad);
    // A second start while one runs is refused.
    assert!(matches!(
        s.command(&ClientMsg::GuideStart),
        Err(Error::Guide(_))
    ));
    key(&mut s, "n");
    let p0 = s.state(0.0).pulses_us[0];
    key(&mut s, "]");
    key(&mut s, "-");
    let v = guide(&s);
    assert_eq!(
        (v.servo.as_deref(), v.center_us),
        (Some("FL_abduction"), Some(1518))
    );
    assert_eq!(s.state(0.0).pulses_us[0] - p0, 18.0);
    assert_eq!(s.state(0.0).calibration[0].center_us, 1518);
    for k in ["t", "n", "n", "n"] {
        key(&mut s, k);
    }
    assert_eq!(guide(&s).step, "save");
    key(&mut s, "s");
    assert_eq!(guide(&s).step, "saved");
    assert!(!s.state(0.0).flags.calibration_unsaved);
    s.read_calibration().unwrap();
    assert_eq!(s.state(0.0).calibration[0].center_us, 1518);
}

#[test]
fn a_guide_aborts_when_the_controlling_page_goes_away() {
    let mut s = session(LinkLossAction::Hold);
    s.command(&ClientMsg::GuideStart).unwrap();
    key(&mut s, "n");
    key(&mut s, "]");
    // A refusal is the guide's message, not a failed command: beyond the travel's end.
    for _ in 0..60 {
        key(&mut s, "]");
    }
    let v = guide(&s);
    let m = v.message.expect("a message");
    assert!(m.contains("SetCalibration"), "{m}");
    assert_eq!(s.state(0.0).calibration[0].center_us, 2500);
    s.control_lost().unwrap();
    assert_eq!(guide(&s).step, "aborted");
    s.read_calibration().unwrap();
    assert_eq!(s.state(0.0).calibration[0].center_us, 1500);
}

/// A client of the simulated shahriar2023 device.
fn sim_client() -> Client<Box<dyn Link>> {
    let target = Target::Sim {
        preset: RobotPreset::Shahriar2023,
        config: SimConfig::default(),
        storage: None,
    };
    Client::new(
        link::open(&target).unwrap(),
        ClientConfig::sim(Duration::ZERO),
    )
}

#[test]
fn without_a_robot_the_panel_plans_with_the_device_s_own_and_another_is_refused_naming_it() {
    let s = Session::connect(sim_client(), None, AngleCheck::Exact).expect("the device's robot");
    assert_eq!(s.robot(), &Robot::shahriar2023());
    assert_eq!(s.robot_name(), "shahriar2023");
    let Err(e) = Session::connect(sim_client(), Some(Robot::fernando2025()), AngleCheck::Exact)
    else {
        panic!("a device holding shahriar2023 accepted fernando2025");
    };
    assert!(matches!(e, Error::Robot(_)), "{e}");
    assert!(e.to_string().contains("shahriar2023"), "{e}");
}
